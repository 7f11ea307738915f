"""Relief on curved surfaces: how far the tangent-plane trace (what every relief technique computes: the base
surface taken as flat at the fragment) lands from the hit on the height field actually displaced inward along the
normal of a sphere or a cylinder of radius R, in float64, as a function of S/R (height scale over radius) and the
view angle (``wgpuviewer curved``; docs/curved.md publishes a full run).

- ``command``: the command and its options (``STUDY``);
- ``geometry``: the curved surfaces' texture charts, the curved exact first hit (march, bracket, bisection) and the
  comparison with the tangent-plane hit of ``relief.reference``;
- ``run``: the suites, results.csv, the fitted rule, report.md and the plots.

May import ``core``, ``harness``, ``relief`` and ``bench`` (the benchmark's height maps); no other study. It
starts no GPU.
"""

from .command import STUDY

__all__ = ["STUDY"]
