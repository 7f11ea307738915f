"""``wgpuviewer bench``: speed against error of every technique. The command (command: ``STUDY``, registered by
the CLI like a study), the run (run), the full-screen relief views and their float64 reference (view), GPU frame
timing (config_timing), the report (report) and its plots (plots).

May import: ``wgpuviewer.core``, ``wgpuviewer.lab.harness``, ``wgpuviewer.relief``, the scene modules and
``maptools``; the CLI registers the command, and studies may measure on its views and height maps.
"""

from .command import STUDY

__all__ = ["STUDY"]
