"""The foundation every other room stands on: errors, what both CLIs share (process setup before the GPU driver
loads, one-line errors and warnings, exit codes), GPU acquisition and texture upload, atomic file writes,
the one image and height-file reader, CPU texture sampling (nearest/bilinear, repeat/clamp), colour transfer
functions and the heat ramp, the one WGSL composer, the struct generator, the compute-kernel helper, the
environment variables (env) and the record maptools batch writes beside each map (sidecar).

May import: the standard library and third-party packages only, never another part of this project
(``maptools`` relies on that: it imports ``wgpuviewer.core`` and nothing else of ``wgpuviewer``).
"""
