"""wgpuviewer: relief-mapping techniques on WebGPU, compared honestly (docs/architecture.md maps the rooms).

From Python (``api``; docs/usage.md)::

    import wgpuviewer

    image = wgpuviewer.render(technique="pom", size=(320, 180), camera={"view_angle": 70})  # (180, 320, 3)
    depth = wgpuviewer.render("scenes/default.toml", "relief", (320, 180), mode="depth")
    widget = wgpuviewer.view()  # the viewer in a Jupyter notebook

- ``core/``: errors, GPU, atomic I/O, the image reader, CPU sampling, colour, the WGSL composer (imports nothing
  else of the project);
- ``scene/``, ``textures.py``, ``meshes/``, ``camera.py``: scenes and what they are made of;
- ``techniques/``: the technique registry and one folder per technique, found without a list;
- ``relief/``: maps, shaders, renderer, probe, float64 reference, accuracy;
- ``viewer/``: the window (imported by ``cli`` and by ``api``'s ``view``);
- ``api.py``: ``render``, ``view``, ``CameraSpec`` (exported here) and ``prepare``, the one path of a render, which
  the ``render`` command takes too;
- ``cli.py``, ``cli_render.py``: the ``wgpuviewer`` command;
- ``probe.py``, ``reference.py``, ``accuracy.py``: the documented API, re-exported from ``relief/``;
- ``lab/``: the harness, bench, the studies, ``./dev gpu-suite`` and ``wgpuviewer docs`` (only ``cli`` reaches in;
  the product never imports the lab).

The scene modules may import ``core`` and ``techniques`` (scenes name techniques and their parameters).
This package imports ``api`` on first use of a name it exports, so importing any module of it (``core.commands``,
before a GPU driver or OpenCV loads) stays cheap.
"""

__all__ = ["CameraSpec", "render", "view"]


def __getattr__(name: str):
    if name in __all__:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'wgpuviewer' has no attribute {name!r}")


def __dir__():
    return sorted({*globals(), *__all__})
