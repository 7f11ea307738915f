"""wgpuviewer: relief-mapping techniques on WebGPU, compared honestly (docs/architecture.md maps the rooms).

- ``core/``: errors, GPU, atomic I/O, the image reader, CPU sampling, colour, the WGSL composer (imports nothing
  else of the project);
- ``scene.py``, ``textures.py``, ``meshes.py``, ``camera.py``: scenes and what they are made of;
- ``relief/``: techniques, maps, shaders, renderer, probe, float64 reference, accuracy;
- ``viewer/``, ``bench/``, ``studies/``: the window, the benchmark, the studies (each imported only by ``cli``);
- ``probe.py``, ``reference.py``, ``accuracy.py``: the documented API, re-exported from ``relief/``.

The scene modules may import ``core`` and ``relief.techniques`` (scenes name techniques and their parameters).
"""
