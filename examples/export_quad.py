"""A relief-mapped quad drawn by plain wgpu-py with a technique exported by ``wgpuviewer export``.

This program knows nothing of wgpuviewer: it reads the exported module, the textures it binds and a normal map,
and draws one quad, offscreen, to a PNG. Make its inputs from a height map HEIGHT (PNG or .npy) with::

    maptools batch HEIGHT -o maps --kinds normal --set normal.y=directx   # maps/STEM.normal.png
    wgpuviewer export pom --set layers=32 -o maps/pom.wgsl --maps HEIGHT  # the module, maps/STEM.*.texture.npz
    python examples/export_quad.py maps/pom.wgsl maps/STEM -o quad.png

The module's bindings live in @group(1) (the export's default); this program's own (the normal map and its
sampler) in @group(0). The fragment shader calls ``relief_trace`` with the pixel's uv and a fixed view direction
in tangent space (a quad seen from 50 degrees off its normal), then shades the hit with the normal map.
"""

from __future__ import annotations

import argparse
import json
import struct
from pathlib import Path

import numpy as np
import wgpu
from PIL import Image

# The program's own part: a fullscreen triangle pair, the view, the shading. relief_trace comes from the export.
PROGRAM = """
@group(0) @binding(0) var normal_map: texture_2d<f32>;
@group(0) @binding(1) var normal_sampler: sampler;

struct Varyings { @builtin(position) position: vec4f, @location(0) uv: vec2f }

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> Varyings {
    let corner = vec2f(f32((i << 1u) & 2u), f32(i & 2u));  // (0,0) (2,0) (0,2): one triangle over the screen
    return Varyings(vec4f(corner * 2.0 - 1.0, 0.0, 1.0), corner * TILES);
}

@fragment
fn fs_main(in: Varyings) -> @location(0) vec4f {
    let view_ts = normalize(vec3f(0.55, 0.35, 0.76));  // towards the eye, in tangent space
    let hit = relief_trace(in.uv, view_ts, 0.0);
    let n = normalize(textureSampleLevel(normal_map, normal_sampler, hit.uv, 0.0).xyz * 2.0 - 1.0);
    let light = normalize(vec3f(-0.4, 0.5, 0.77));
    let shade = 0.15 + 0.85 * max(dot(n, light), 0.0) * (1.0 - 0.5 * hit.depth);
    return vec4f(vec3f(shade), 1.0);
}
"""


def upload(device, levels: list[np.ndarray], fmt: str):
    """A sampled texture with the given mip levels ((H, W, C) arrays in the format's texel type)."""
    h, w = levels[0].shape[:2]
    texture = device.create_texture(size=(w, h, 1), format=fmt, mip_level_count=len(levels),
                                    usage=wgpu.TextureUsage.TEXTURE_BINDING | wgpu.TextureUsage.COPY_DST)
    for m, a in enumerate(levels):
        a = np.ascontiguousarray(a)
        device.queue.write_texture({"texture": texture, "mip_level": m}, a,
                                   {"bytes_per_row": a.strides[0], "rows_per_image": a.shape[0]},
                                   (a.shape[1], a.shape[0], 1))
    return texture


def exported_textures(device, stem: Path) -> dict[int, object]:
    """binding -> texture view, from the STEM.SLOT.texture.npz files ``wgpuviewer export --maps`` wrote."""
    views = {}
    for path in sorted(stem.parent.glob(f"{stem.name}.*.texture.npz")):
        with np.load(path) as z:
            levels = [z[f"level{i}"] for i in range(sum(name.startswith("level") for name in z.files))]
            fmt, dimension, binding = str(z["format"]), str(z["dimension"]), int(z["binding"])
        if dimension != "2d":
            raise SystemExit(f"{path}: a {dimension} texture; this example uploads 2D textures only")
        views[binding] = upload(device, levels, fmt).create_view()
    return views


def uniform_bytes(values: dict) -> bytes:
    """ReliefParams from STEM.relief_params.json: its scalar fields in order (f32 for reals, u32 for counts),
    padded to 16 bytes."""
    data = b"".join(struct.pack("<f" if isinstance(v, float) else "<I", v) for v in values.values())
    return data + bytes(-len(data) % 16)


def draw(module_path: Path, stem: Path, size: int, tiles: float) -> np.ndarray:
    adapter = wgpu.gpu.request_adapter_sync(power_preference="high-performance")
    # an r32float depth map is filtered where the adapter can (the export then wrote r32float, else r16float)
    device = adapter.request_device_sync(required_features=[f for f in ["float32-filterable"] if f in adapter.features])
    code = module_path.read_text() + f"const TILES: f32 = {tiles:.6f};\n" + PROGRAM
    shader = device.create_shader_module(code=code)
    pipeline = device.create_render_pipeline(
        layout="auto", vertex={"module": shader, "entry_point": "vs_main"},
        fragment={"module": shader, "entry_point": "fs_main", "targets": [{"format": "rgba8unorm"}]},
        primitive={"topology": "triangle-list"})
    sampler = device.create_sampler(mag_filter="linear", min_filter="linear", address_mode_u="repeat",
                                    address_mode_v="repeat")
    normal = upload(device, [np.asarray(Image.open(stem.parent / f"{stem.name}.normal.png").convert("RGBA"))],
                    "rgba8unorm")
    params = json.loads((stem.parent / f"{stem.name}.relief_params.json").read_text())
    uniform = device.create_buffer_with_data(data=uniform_bytes(params), usage=wgpu.BufferUsage.UNIFORM)
    own = device.create_bind_group(layout=pipeline.get_bind_group_layout(0), entries=[
        {"binding": 0, "resource": normal.create_view()}, {"binding": 1, "resource": sampler}])
    relief = device.create_bind_group(layout=pipeline.get_bind_group_layout(1), entries=[
        {"binding": 0, "resource": {"buffer": uniform}}, {"binding": 1, "resource": sampler},
        *({"binding": b, "resource": view} for b, view in exported_textures(device, stem).items())])
    target = device.create_texture(size=(size, size, 1), format="rgba8unorm",
                                   usage=wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC)
    encoder = device.create_command_encoder()
    rpass = encoder.begin_render_pass(color_attachments=[{"view": target.create_view(), "load_op": "clear",
                                                          "store_op": "store", "clear_value": (0, 0, 0, 1)}])
    rpass.set_pipeline(pipeline)
    rpass.set_bind_group(0, own)
    rpass.set_bind_group(1, relief)
    rpass.draw(3)
    rpass.end()
    device.queue.submit([encoder.finish()])
    raw = device.queue.read_texture({"texture": target}, {"bytes_per_row": size * 4, "rows_per_image": size},
                                    (size, size, 1))
    return np.frombuffer(raw, np.uint8).reshape(size, size, 4)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("module", type=Path, help="the exported module, OUT.wgsl")
    parser.add_argument("stem", type=Path, help="DIR/STEM of the maps: STEM.normal.png, STEM.*.texture.npz, "
                        "STEM.relief_params.json")
    parser.add_argument("-o", "--output", type=Path, default=Path("quad.png"), help="the PNG to write")
    parser.add_argument("--size", type=int, default=512, help="image size in pixels, square (default 512)")
    parser.add_argument("--tiles", type=float, default=2.0, help="texture repeats across the quad (default 2)")
    args = parser.parse_args(argv)
    Image.fromarray(draw(args.module, args.stem, args.size, args.tiles)).save(args.output)
    print(args.output)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
