"""``wgpuviewer export``: every exportable technique's module compiles in a bare wgpu-py compute pipeline next to
a user's entry point (and user names that would clash without the prefix), and its hits equal the probe's on the
same rays; the maps ``--maps`` writes bind to the same hits; the command's files and its one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
import wgpu

from wgpuviewer.core.structs import Struct
from wgpuviewer.export import API, export_wgsl, exportable
from wgpuviewer.export.command import main as export_main
from wgpuviewer.export.rename import module_names
from wgpuviewer.export.textures import params_values, slot_textures, texel_type
from wgpuviewer.probe import probe
from wgpuviewer.relief.maps import MAP_SLOTS
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.textures import builtin_height

pytestmark = pytest.mark.requires_gpu

RAY = Struct("UserRay", [("uv", "vec2f"), ("view", "vec3f")], "storage")
HIT = Struct("UserHit", [("uv", "vec2f"), ("depth", "f32"), ("fetches", "u32"), ("capped", "u32")], "storage")
#: A user's own module: names the export's internals would clash with, were they not prefixed, and an entry point.
USER = RAY.wgsl() + HIT.wgsl() + """
struct TraceResult { x: f32 }
const MAX_LAYERS: u32 = 1u;
fn trace(x: f32) -> f32 { return x; }
fn depth_at(x: f32) -> f32 { return x; }
@group(0) @binding(0) var<storage, read> rays: array<UserRay>;
@group(0) @binding(1) var<storage, read_write> hits: array<UserHit>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if id.x >= arrayLength(&rays) { return; }
    let h = relief_trace(rays[id.x].uv, rays[id.x].view, 0.0);
    hits[id.x] = UserHit(h.uv, h.depth, h.fetches, u32(h.capped));
}
"""
SCALE = 0.08
N = 128


@pytest.fixture(scope="module")
def rays():
    rng = np.random.default_rng(3)
    uv = rng.random((N, 2))
    theta = np.radians(rng.uniform(0.0, 88.0, N))  # up to near grazing
    phi = rng.uniform(0.0, 2 * np.pi, N)
    view = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
    return uv, view


@pytest.fixture(scope="module")
def height():
    return builtin_height("bricks", (32, 32))


def run_export(gpu, export, height, uv, view, textures=None) -> np.ndarray:
    """The export's hits on the rays through a plain wgpu pipeline with explicit layouts, as a user would bind it."""
    device = gpu.device
    textures = textures or {n: t.create_view() for n, t in slot_textures(gpu, export, height, SCALE).items()}
    C = wgpu.ShaderStage.COMPUTE
    io_layout = device.create_bind_group_layout(entries=[
        {"binding": 0, "visibility": C, "buffer": {"type": "read-only-storage"}},
        {"binding": 1, "visibility": C, "buffer": {"type": "storage"}}])
    material_layout = device.create_bind_group_layout(entries=[
        {"binding": 0, "visibility": C, "buffer": {"type": "uniform"}},
        {"binding": 1, "visibility": C, "sampler": {"type": "filtering"}},
        *({"binding": 2 + i, "visibility": C, **MAP_SLOTS[n].layout} for i, n in enumerate(export.textures))])
    module = device.create_shader_module(code=export.code + USER)
    pipeline = device.create_compute_pipeline(
        layout=device.create_pipeline_layout(bind_group_layouts=[io_layout, material_layout]),
        compute={"module": module, "entry_point": "main"})
    data = np.zeros(len(uv), RAY.dtype)
    data["uv"], data["view"] = uv, view
    ray_buf = device.create_buffer_with_data(data=RAY.pack_many(data), usage="STORAGE")
    hit_buf = device.create_buffer(size=len(uv) * HIT.size, usage="STORAGE | COPY_SRC")
    uniform = device.create_buffer_with_data(
        data=export.params.pack(params_values(gpu, export, height, SCALE)), usage="UNIFORM")
    sampler = device.create_sampler(mag_filter="linear", min_filter="linear", address_mode_u="repeat",
                                    address_mode_v="repeat")
    groups = [device.create_bind_group(layout=io_layout, entries=[
        {"binding": 0, "resource": {"buffer": ray_buf}}, {"binding": 1, "resource": {"buffer": hit_buf}}]),
        device.create_bind_group(layout=material_layout, entries=[
            {"binding": 0, "resource": {"buffer": uniform}}, {"binding": 1, "resource": sampler},
            *({"binding": 2 + i, "resource": textures[n]} for i, n in enumerate(export.textures))])]
    encoder = device.create_command_encoder()
    compute = encoder.begin_compute_pass()
    compute.set_pipeline(pipeline)
    for index, group in enumerate(groups):
        compute.set_bind_group(index, group)
    compute.dispatch_workgroups(-(-len(uv) // 64))
    compute.end()
    device.queue.submit([encoder.finish()])
    return HIT.unpack(device.queue.read_buffer(hit_buf), len(uv))


def assert_hits_equal(hits, expected, name):
    assert np.array_equal(hits["uv"], expected.uv.astype(np.float32)), name
    assert np.array_equal(hits["depth"], expected.depth), name
    assert np.array_equal(hits["fetches"], expected.fetches), name
    assert np.array_equal(hits["capped"] != 0, expected.capped), name


@pytest.mark.parametrize("name", exportable())
def test_export_matches_the_probe(gpu, height, rays, name):
    settings = dict(TECHNIQUES[name].contract_params[0]) if TECHNIQUES[name].contract_params else {}
    export = export_wgsl(name, settings)
    expected = probe(name, height, *rays, SCALE, **settings)
    assert_hits_equal(run_export(gpu, export, height, *rays), expected, name)
    # parameters kept as uniforms trace the same rays the same way
    uniform = export_wgsl(name, settings, uniform_params=True)
    assert_hits_equal(run_export(gpu, uniform, height, *rays), expected, f"{name} with uniform parameters")


def test_every_module_scope_name_is_prefixed():
    for name in exportable():
        names = module_names(export_wgsl(name).code)
        assert "relief_trace" in names and "ReliefHit" in names
        assert all(n in API or n.startswith(("relief_", "Relief", "RELIEF_")) for n in names), name


def test_the_command_writes_the_module_and_the_maps_it_binds(gpu, tmp_path, rays):
    height = builtin_height("bumps", (32, 32))
    np.save(tmp_path / "bumps.npy", height)
    out = tmp_path / "out" / "maxmip.wgsl"
    assert export_main(["maxmip", "--group", "2", "--set", "max_steps=64", "-o", str(out),
                        "--maps", str(tmp_path / "bumps.npy"), "--height-scale", str(SCALE)]) == 0
    code = out.read_text()
    assert "@group(2) @binding(2) var relief_depth_tex" in code and "max_steps = 64" in code
    assert "maptools batch --kinds maxmip HEIGHT -o DIR` writes DIR/STEM.maxmip.npz" in code
    export = export_wgsl("maxmip", {"max_steps": 64})
    params = json.loads((out.parent / "bumps.relief_params.json").read_text())
    assert params["depth_width"] == 32 and params["height_scale"] == SCALE
    views = {}
    for name in export.textures:  # upload the files as a user would, and trace with them
        with np.load(out.parent / f"bumps.{name}.texture.npz") as z:
            levels = [z[f"level{i}"] for i in range(len(z.files) - 3)]
            fmt = str(z["format"])
        dtype, channels = texel_type(fmt)
        texture = gpu.device.create_texture(size=(levels[0].shape[1], levels[0].shape[0], 1), format=fmt,
                                            usage="TEXTURE_BINDING | COPY_DST", mip_level_count=len(levels))
        for m, a in enumerate(levels):
            gpu.device.queue.write_texture({"texture": texture, "mip_level": m}, a.astype(dtype),
                                           {"bytes_per_row": a.shape[1] * channels * dtype.itemsize},
                                           (a.shape[1], a.shape[0], 1))
        views[name] = texture.create_view()
    hits = run_export(gpu, export, height, *rays, textures=views)
    assert_hits_equal(hits, probe("maxmip", height, *rays, SCALE, max_steps=64), "maxmip from --maps files")


def test_errors_are_one_line_with_exit_2(tmp_path, capsys):
    assert export_main(["basic", "-o", str(tmp_path / "x.wgsl")]) == 2
    assert export_main(["pom", "--set", "layers=0", "-o", str(tmp_path / "x.wgsl")]) == 2
    assert export_main(["pom", "--set", "layers", "-o", str(tmp_path / "x.wgsl")]) == 2
    assert export_main(["nope", "-o", str(tmp_path / "x.wgsl")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 4 and "traces no rays" in lines[0] and "layers" in lines[1] and "NAME=VALUE" in lines[2]
    assert not (tmp_path / "x.wgsl").exists()
