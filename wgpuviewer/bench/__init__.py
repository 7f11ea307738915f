"""``wgpuviewer bench``: speed against error of every technique. The run (run), the full-screen relief views and
their float64 reference (view), GPU frame timing (timing) and the report with its plots (report).

May import: ``wgpuviewer.core``, ``wgpuviewer.relief``, the scene modules and ``maptools``; nothing imports the
benchmark but the CLI.
"""
