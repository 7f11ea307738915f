"""One source of truth for the GPU interface: the registry and core.structs generate what WGSL must agree on
(TraceParams, the render entry's Frame and Object, the parameter constants, the binding lines of a technique's
texture slots, the entries' own records: the probe's rays and hits, the filter probe's samples and results, the
error view's Blit, the offscreen targets' DataOut), and the entry files declare none of them. A throw-away technique
with a new parameter and a new map slot, one folder found by discovery, renders and probes without touching any other
file, its hits read back field by field where the GPU wrote them."""

from __future__ import annotations

import re

import numpy as np
import pytest

from tests.relief.scenes import plane_scene
from tests.relief.technique_folder import technique_folder
from wgpuviewer.core.structs import FragmentOutputs
from wgpuviewer.core.wgsl import read_wgsl
from wgpuviewer.relief import filter_probe, maps, probe, shaders, targets
from wgpuviewer.relief.maps import MAP_SLOTS
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import parse_scene
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.viewer import error_view

#: Every entry file and the records Python generates for it (composed in before it: the entry never declares them).
ENTRY_RECORDS = {
    "entry/render.wgsl": (shaders.FRAME, shaders.OBJECT, targets.DATA_OUT),
    "entry/probe.wgsl": (probe.PROBE_RAY, probe.PROBE_HIT),
    "entry/filter_probe.wgsl": (filter_probe.FILTER_SAMPLE, filter_probe.FILTER_OUT),
    "entry/gradient_probe.wgsl": (filter_probe.GRADIENT_SAMPLE, filter_probe.GRADIENT_VALUE),
    "entry/error_view.wgsl": (error_view.BLIT,),
}


def test_render_uniforms_are_generated():
    """Frame's layout (camera 64 bytes after the matrix, the counts and scales packed after it, the lights at the
    next 16 bytes) and the render interface declaring Frame, Light and Object, which render.wgsl does not."""
    assert shaders.FRAME.offsets == {"view_proj": 0, "camera_pos": 64, "light_count": 80, "mode": 84,
                                     "cost_scale": 88, "layer_lo": 92, "layer_hi": 96, "lights": 112}
    assert shaders.FRAME.size == 112 + 32 * shaders.MAX_LIGHTS and shaders.OBJECT.size == 144
    text = shaders.interface(TECHNIQUES["pom"], "render").text
    assert shaders.FRAME.wgsl_all() in text and shaders.OBJECT.wgsl() in text
    assert "struct " not in shaders.interface(TECHNIQUES["pom"], "probe").text.replace("struct TraceParams", "")


@pytest.mark.parametrize("entry", ENTRY_RECORDS)
def test_entry_files_declare_no_generated_record(entry):
    source = read_wgsl(entry)
    for record in ENTRY_RECORDS[entry]:
        assert not re.search(rf"struct {record.name}\b", source), record.name


def test_data_out_is_generated_from_the_offscreen_targets():
    """fs_data's outputs and the offscreen formats are one list: location = position, each type fit for its
    format (WebGPU's sample type and channel rule, refused by name otherwise)."""
    assert targets.OFFSCREEN_FORMATS == targets.DATA_OUT.formats == (
        targets.COLOR_FORMAT, targets.DATA_FORMAT, targets.LAYERS_FORMAT, targets.FILTER_FORMAT,
        targets.VIEW_DEPTH_FORMAT)
    assert targets.DATA_OUT.wgsl() == ("struct DataOut {\n    @location(0) color: vec4f,\n"
                                        "    @location(1) data: vec4u,\n    @location(2) layers: u32,\n"
                                        "    @location(3) filtering: vec4u,\n    @location(4) view_depth: u32,\n}\n")
    FragmentOutputs("Fine", [("a", "vec4f", "bgra8unorm-srgb"), ("b", "vec2i", "rg16sint"), ("c", "u32", "r8uint")])
    for target, words in [(("a", "vec2f", "rgba8unorm"), "needs f32 with at least 4 components"),
                          (("a", "vec4f", "rgba32uint"), "needs u32"),
                          (("a", "vec4u", "r32sint"), "needs i32"),
                          (("a", "f32", "depth32float"), "not a colour format"),
                          (("a", "mat4x4f", "rgba8unorm"), "a scalar or vector")]:
        with pytest.raises(ValueError, match=f"fragment outputs Bad: 'a' \\({target[1]}\\) to {target[2]}: .*{words}"):
            FragmentOutputs("Bad", [target])


def test_generated_interface_follows_the_registry():
    for t in TECHNIQUES.values():
        text = shaders.interface(t, "render").text
        params = shaders.trace_params(t)
        assert params.wgsl() in text and params.names[: len(t.trace_fields)] == t.trace_fields
        assert params.size == shaders.trace_params_size(t) and params.size % 16 == 0
        assert len(shaders.pack_trace_params(t, 1.0, (4, 4), {})) == params.size
        for p in t.params:
            if p.kind is not bool:
                assert f"const {p.name.upper()}_MAX: {p.wgsl_type} = " in text
        for name in t.textures:
            slot = MAP_SLOTS[name]
            assert f"@group(1) @binding({maps.binding(name)}) var {slot.wgsl_name}: {slot.wgsl_type};" in text
    bindings = [maps.binding(n) for n in MAP_SLOTS]
    assert len(set(bindings)) == len(bindings)


# --- a throw-away technique: new parameter, new map slot, no other file touched --------------------------------

TOY_WGSL = """// A throw-away technique: the hit is the entry uv moved along u by gain * the toy map's value, at the
// depth map's depth, after 1 fetch and 3 layers, capped where the view grazes.
// #include "common/depth.wgsl"

fn trace(uv0: vec2f, v: vec3f, lod: f32) -> TraceResult {
    fetch_count = 0u;
    let d = depth_at(uv0, lod);
    let shift = clamp(trace_params.gain, GAIN_MIN, GAIN_MAX) * textureSampleLevel(toy_tex, material_sampler, uv0, 0.0).r;
    return TraceResult(uv0 + vec2f(shift, 0.0), d, fetch_count, is_grazing(v), 3u);
}
"""

TOY_INIT = '''"""A throw-away technique with its own parameter and its own map slot (a constant 0.25)."""

import numpy as np

from wgpuviewer.core.gpu import create_texture
from wgpuviewer.core.params import Param
from wgpuviewer.core.slots import FILTERABLE_2D, TEXTURE_2D, MapSlot
from wgpuviewer.techniques import Technique


def build_toy(gpu, depth, height_scale, label):
    return create_texture(gpu, [np.full(depth.shape, 0.25, np.float32)], gpu.depth_format, label)


TECHNIQUE = Technique(
    "toy", "-", "interface test", "1 depth fetch", ("albedo", "depth", "toy"),
    (Param("gain", 1.0, 0.0, 4.0, float, "shift per map unit"),), ray_search=True, order=1000,
    fetch_bound=lambda p: 1,
    slots=(MapSlot("toy", TEXTURE_2D, FILTERABLE_2D, build_toy, "a constant 0.25, for the interface test", order=1000),),
)
'''


@pytest.fixture
def toy(tmp_path):
    """The toy technique as a folder of its own, found by discovery: no other file is edited, nothing patched."""
    with technique_folder(tmp_path, "toy", TOY_INIT, TOY_WGSL) as technique:
        yield technique


def test_a_new_technique_with_a_new_parameter_and_map_renders_and_probes(gpu, toy):
    rng = np.random.default_rng(0)
    uv = rng.random((64, 2))
    grazing = np.arange(64) % 3 == 0
    view = np.where(grazing[:, None], [1.0, 0.0, 0.0], [0.0, 0.6, 0.8])
    got = probe.probe("toy", np.full((32, 32), 0.25), uv, view, 0.05, gain=2.0)
    # Every field of ProbeRay and ProbeHit where the GPU reads and writes it: the generated layout.
    np.testing.assert_allclose(got.uv, uv + [0.5, 0.0], atol=1e-6)  # 2.0 * 0.25
    np.testing.assert_allclose(got.depth, 0.75, atol=1e-4)  # depth = 1 - height (a 16-bit map holds it to 2e-5)
    assert (got.fetches == 1).all() and (got.layers == 3).all() and (got.capped == grazing).all()

    scene = parse_scene(plane_scene("toy", "gain = 0.5", position=(0.0, 0.8, 0.2), map_size=32))
    assert scene.technique_params["toy"] == {"gain": 0.5}
    image = Renderer(scene, gpu).render("toy", (32, 32))
    covered = image.covered
    assert covered.mean() > 0.5
    # The rendered hit uv is the interpolated uv moved by 0.5 * 0.25 along u (where the shift stays on the face).
    base = Renderer(scene, gpu).render(Renderer(scene, gpu).config("toy", {"gain": 0.0}), (32, 32))
    both = covered & base.covered
    np.testing.assert_allclose(image.data[both][:, 0] - base.data[both][:, 0], 0.125, atol=1e-5)
