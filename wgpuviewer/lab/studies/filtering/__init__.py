"""The texture-filtering study (Romanyuk & Dudnyk 2017, filtering with parallax mapping): does visibility-aware
EWA on relief surfaces beat plain EWA, hardware anisotropic and trilinear filtering against a supersampled
reference, at what cost, and does the paper's cheap row-ends method keep the gain?
``wgpuviewer filtering --out DIR [--suite smoke|full]``; method and results in ``docs/filtering.md``.

Lives here: ``command`` (the command and its options: ``STUDY``), ``cpu`` (float64 twins of the filters and of
the visibility test), ``views`` (the study's scenes and their pixel geometry), ``supersample`` (the supersampled
reference), ``suites`` (configurations, cases, suites, results.csv's columns, the command's options), ``run``
(measuring), ``report`` (report.md, the Pareto plot, side-by-side crops).

May import: ``wgpuviewer.core``, ``wgpuviewer.lab.harness``, ``wgpuviewer.relief``, the scene modules and
``maptools``; never another study.
"""

from .command import STUDY

__all__ = ["STUDY"]
