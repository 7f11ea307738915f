"""contact against relief at equal fetches: the two finishes of the same linear search (relief's binary search of
the bracket, contact's second linear search of it, both ended by the same secant), each given the same extra
fetches beyond the search, on the benchmark's maps and view angles, against the float64 exact hit
(``wgpuviewer contact``; docs/techniques.md's contact section publishes a full run from
``benchmarks/contact_vs_relief``).

- ``command``: the command and its options (``STUDY``);
- ``run``: the suites, the measurement, results.csv and report.md;
- ``docs``: the generated block of docs/techniques.md (``BLOCKS``).

May import ``core``, ``harness``, ``relief``, the technique registry (auto's SIMD tiles of rays) and ``bench`` (its
height maps); no other study.
"""

from .command import STUDY

__all__ = ["STUDY"]
