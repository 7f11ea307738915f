"""WGSL loading and composition.

A shader module = generated ``TraceParams`` struct + ``prelude.wgsl`` + the technique's file
(+ a ``shading_normal`` snippet for rendering) + an entry-point file (``render.wgsl`` or
``probe.wgsl``). The WGSL files ship in the package as ``wgpuviewer.wgsl``.
"""

from __future__ import annotations

from importlib.resources import files

import numpy as np

from .techniques import TRACE_FIELDS, Technique

WGSL = files("wgpuviewer.wgsl")


def read_wgsl(name: str) -> str:
    return (WGSL / name).read_text(encoding="utf-8")


def trace_params_struct() -> str:
    fields = list(TRACE_FIELDS)
    fields += [f"_pad{i}" for i in range(-len(fields) % 4)]  # uniform size: multiple of 16 bytes
    body = "".join(f"    {name}: f32,\n" for name in fields)
    return f"struct TraceParams {{\n{body}}}\n"


def trace_params_size() -> int:
    return 4 * (len(TRACE_FIELDS) + (-len(TRACE_FIELDS) % 4))


def compose(technique: Technique, entry: str) -> str:
    """Source of the module for ``technique`` with entry file ``entry`` ('render' or 'probe')."""
    parts = [trace_params_struct(), read_wgsl("prelude.wgsl"), read_wgsl(technique.wgsl_file)]
    if entry == "render":
        parts.append(read_wgsl("normal_from_map.wgsl" if "normal" in technique.textures else "normal_flat.wgsl"))
    parts.append(read_wgsl(f"{entry}.wgsl"))
    return "\n".join(parts)


def pack_trace_params(height_scale: float, depth_shape: tuple, params: dict) -> np.ndarray:
    """TraceParams uniform data (field order from techniques.TRACE_FIELDS; booleans as 0/1)."""
    values = {"height_scale": height_scale, "depth_width": depth_shape[1], "depth_height": depth_shape[0], **params}
    data = np.zeros(trace_params_size() // 4, np.float32)
    for i, name in enumerate(TRACE_FIELDS):
        data[i] = float(values.get(name, 0.0))
    return data
