"""The scene benchmark (``wgpuviewer scene-bench``): whole scenes as a user sees them, judged in screen pixels and
NVIDIA FLIP against the exact tracer's render of the same view, with each configuration's fetches and GPU time
against ``basic`` (docs/benchmarks.md's "Whole scenes" publishes a full run).

- ``command``: the command and its options (``STUDY``);
- ``scenes``: the default scenes and the views each is seen from;
- ``measure``: one view's per-pixel measures (footprint, hit error in pixels, FLIP, PSNR, fetches);
- ``configs``: the configurations drawn (the exact tracer, the goal's two);
- ``run``: suites, the loop, results.csv;
- ``report``: report.md, the Pareto plot and the worst pixels' crops;
- ``docs``: docs/benchmarks.md's block from the committed run.

May import ``core``, ``harness``, ``relief``, the scene modules, the technique registry and ``bench`` (its height
maps, its parameter labels); no other study.
"""

from .command import STUDY

__all__ = ["STUDY"]
