"""The texture-filtering study (seed 003): does visibility-aware EWA on relief surfaces beat plain EWA, hardware
anisotropic and trilinear filtering against a supersampled reference, at what cost, and does the paper's cheap
row-ends method keep the gain? ``wgpuviewer filtering --out DIR [--suite smoke|full]``; method and results in
``docs/filtering.md``.

Lives here: ``cpu`` (float64 twins of the filters and of the visibility test), ``views`` (the study's scenes and
their pixel geometry), ``supersample`` (the supersampled reference), ``suites`` (configurations, cases, suites,
the command's options), ``run`` (measuring), ``report``
(results.csv, report.md, the Pareto plot, side-by-side crops).

May import: ``wgpuviewer.core``, ``wgpuviewer.relief``, the scene modules and ``maptools``; never another study.
"""
