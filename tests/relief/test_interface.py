"""One source of truth for the GPU interface: the registry and core.structs generate what WGSL must agree on
(TraceParams, the render entry's Frame and Object, the parameter constants, the binding lines of a technique's
texture slots); what stays hand-written in WGSL (ProbeRay, ProbeHit, DataOut) is checked here against the Python
side. And a throw-away technique with a new
parameter and a new map slot renders and probes without touching any other file."""

from __future__ import annotations

import re

import numpy as np
import pytest

from tests.relief.scenes import plane_scene
from wgpuviewer.core.gpu import create_texture
from wgpuviewer.core.wgsl import read_wgsl
from wgpuviewer.relief import maps, probe, renderer, shaders
from wgpuviewer.relief.maps import MAP_SLOTS, MapSlot
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.relief.techniques import TECHNIQUES, Param, Technique
from wgpuviewer.scene import parse_scene

# --- WGSL memory layout of hand-written structs (WGSL spec, "Alignment and Size") ------------------------------

_SCALAR = {"f32": (4, 4), "u32": (4, 4), "i32": (4, 4)}
_VEC = {"2": (8, 8), "3": (12, 16), "4": (16, 16)}


def _round_up(x: int, k: int) -> int:
    return -(-x // k) * k


def struct_fields(source: str, name: str) -> list[tuple[str, str]]:
    body = re.search(rf"struct {name} \{{(.*?)\}}", source, re.S).group(1)
    fields = []
    for line in body.splitlines():
        line = line.split("//")[0].strip().rstrip(",")
        if line:
            attrs, _, decl = line.rpartition(")") if line.startswith("@") else ("", "", line)
            field, _, wgsl_type = decl.partition(":")
            fields.append((field.strip(), wgsl_type.strip()))
    return fields


def layout(source: str, wgsl_type: str, constants: dict) -> tuple[int, int]:
    """(size, align) of a WGSL type in a uniform/storage buffer."""
    if wgsl_type in _SCALAR:
        return _SCALAR[wgsl_type]
    if m := re.fullmatch(r"vec([234])([fiu])", wgsl_type):
        return _VEC[m.group(1)]
    if wgsl_type == "mat4x4f":
        return 64, 16
    if m := re.fullmatch(r"array<(\w+), (\w+)>", wgsl_type):
        size, align = layout(source, m.group(1), constants)
        count = int(constants.get(m.group(2), m.group(2)))
        return count * _round_up(size, align), align
    offset, align = 0, 1
    for _, field_type in struct_fields(source, wgsl_type):
        size, a = layout(source, field_type, constants)
        offset = _round_up(offset, a) + size
        align = max(align, a)
    return _round_up(offset, align), align


def test_render_uniforms_are_generated():
    """Frame's layout (camera 64 bytes after the matrix, the counts and scales packed after it, the lights at the
    next 16 bytes) and the render interface declaring Frame, Light and Object, which render.wgsl does not."""
    assert shaders.FRAME.offsets == {"view_proj": 0, "camera_pos": 64, "light_count": 80, "mode": 84,
                                     "cost_scale": 88, "layer_lo": 92, "layer_hi": 96, "lights": 112}
    assert shaders.FRAME.size == 112 + 32 * shaders.MAX_LIGHTS and shaders.OBJECT.size == 144
    text = shaders.interface(TECHNIQUES["pom"], "render").text
    assert shaders.FRAME.wgsl_all() in text and shaders.OBJECT.wgsl() in text
    assert "struct " not in shaders.interface(TECHNIQUES["pom"], "probe").text.replace("struct TraceParams", "")
    assert not re.search(r"struct (Frame|Light|Object) ", read_wgsl("entry/render.wgsl"))


def test_probe_structs_match_the_probe():
    source = read_wgsl("entry/probe.wgsl")
    assert layout(source, "ProbeRay", {})[0] == probe.RAY_STRIDE
    assert layout(source, "ProbeHit", {})[0] == probe.HIT_STRIDE
    # The probe unpacks ProbeHit by position: uv (2 f32), depth (f32), fetches, capped, layers (u32).
    assert [t for _, t in struct_fields(source, "ProbeHit")][:6] == ["vec2f", "f32", "u32", "u32", "u32", "u32"]


def test_data_out_matches_the_offscreen_targets():
    fields = struct_fields(read_wgsl("entry/render.wgsl"), "DataOut")
    assert [t for _, t in fields] == ["vec4f", "vec4u", "u32", "vec4u"]
    assert renderer.OFFSCREEN_FORMATS == (
        "rgba8unorm-srgb", "rgba32uint", "r32uint", "rgba32uint")  # 4 floats, 4 x u32, 1 x u32, 4 x u32


def test_generated_interface_follows_the_registry():
    for t in TECHNIQUES.values():
        text = shaders.interface(t, "render").text
        params = shaders.trace_params(t)
        assert params.wgsl() in text and params.names[: len(t.trace_fields)] == t.trace_fields
        assert params.size == shaders.trace_params_size(t) and params.size % 16 == 0
        assert len(shaders.pack_trace_params(t, 1.0, (4, 4), {})) == params.size
        for p in t.params:
            if p.kind is not bool:
                assert f"const {p.name.upper()}_MAX: f32 = " in text
        for name in t.textures:
            slot = MAP_SLOTS[name]
            assert f"@group(1) @binding({maps.binding(name)}) var {slot.wgsl_name}: {slot.wgsl_type};" in text
    bindings = [maps.binding(n) for n in MAP_SLOTS]
    assert len(set(bindings)) == len(bindings)


# --- a throw-away technique: new parameter, new map slot, no other file touched --------------------------------

TOY_WGSL = """// A throw-away technique: the hit is the entry uv moved along u by gain * the toy map's value.
// #include "common/depth.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let d = depth_at(uv0, lod);
    let shift = clamp(trace_params.gain, GAIN_MIN, GAIN_MAX) * textureSampleLevel(toy_tex, material_sampler, uv0, 0.0).r;
    return TraceResult(uv0 + vec2f(shift, 0.0), d, fetch_count, is_grazing(v), 0u);
}
"""

@pytest.fixture
def toy(tmp_path, monkeypatch):
    wgsl_file = tmp_path / "toy.wgsl"
    wgsl_file.write_text(TOY_WGSL)

    def build(gpu, depth, height_scale, label):
        return create_texture(gpu, [np.full(depth.shape, 0.25, np.float32)], gpu.depth_format, label)

    monkeypatch.setitem(MAP_SLOTS, "toy", MapSlot("toy", "texture_2d<f32>", maps.MAP_SLOTS["depth"].layout, build,
                                                  "a constant 0.25, for the interface test"))
    technique = Technique("toy", "-", "interface test", "1 depth fetch", ("albedo", "depth", "toy"),
                          (Param("gain", 1.0, 0.0, 4.0, float, "shift per map unit"),), ray_search=True,
                          wgsl=str(wgsl_file), fetch_bound=lambda p: 1)
    monkeypatch.setitem(TECHNIQUES, "toy", technique)
    return technique


def test_a_new_technique_with_a_new_parameter_and_map_renders_and_probes(gpu, toy):
    rng = np.random.default_rng(0)
    uv = rng.random((64, 2))
    got = probe.probe("toy", np.full((32, 32), 0.5), uv, [0.0, 0.0, 1.0], 0.05, gain=2.0)
    np.testing.assert_allclose(got.uv, uv + [0.5, 0.0], atol=1e-6)  # 2.0 * 0.25
    assert (got.fetches == 1).all()

    scene = parse_scene(plane_scene("toy", "gain = 0.5", position=(0.0, 0.8, 0.2), map_size=32))
    assert scene.technique_params["toy"] == {"gain": 0.5}
    image = Renderer(scene, gpu).render("toy", (32, 32))
    covered = image.covered
    assert covered.mean() > 0.5
    # The rendered hit uv is the interpolated uv moved by 0.5 * 0.25 along u (where the shift stays on the face).
    base = Renderer(scene, gpu).render(Renderer(scene, gpu).config("toy", {"gain": 0.0}), (32, 32))
    both = covered & base.covered
    np.testing.assert_allclose(image.data[both][:, 0] - base.data[both][:, 0], 0.125, atol=1e-5)
