"""Peak memory of a render stays within a small multiple of the texture bytes it uploads (README: "Memory").

Measured with tracemalloc (numpy's arrays included) around a cold render: builtin generation, the derived normal
map (a fresh map cache), mip chains and uploads, and for maxmip its pyramid. Textures are converted and uploaded
in row bands, builtins generated in row bands, and nothing keeps a float copy it does not need.
"""

from __future__ import annotations

import tracemalloc

import pytest

from wgpuviewer import textures
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import parse_scene

#: The bound the README states: peak traced memory <= this many times the bytes uploaded to textures.
PEAK_PER_UPLOADED_BYTE = 2.5
SIZE = 1024

SCENE = f"""
[scene]
techniques = ["pom", "maxmip"]
[camera]
position = [0.0, 1.0, 2.0]
target = [0.0, 0.0, 0.0]
[materials.m]
albedo = {{ builtin = "bricks", size = [{SIZE}, {SIZE}] }}
height = {{ builtin = "bricks", size = [{SIZE}, {SIZE}] }}
[[objects]]
type = "plane"
material = "m"
size = [2.0, 2.0]
"""

_BYTES_PER_TEXEL = {"rgba16float": 8, "rgba8unorm": 4, "r32float": 4, "r16float": 2}


def uploaded_bytes(renderer: Renderer) -> int:
    total = 0
    for texture in renderer._textures.values():
        w, h = texture.size[:2]
        for level in range(texture.mip_level_count):
            total += max(w >> level, 1) * max(h >> level, 1) * _BYTES_PER_TEXEL[texture.format]
    return total


@pytest.mark.requires_gpu
def test_peak_memory_is_a_small_multiple_of_the_uploaded_texture_bytes(gpu, tmp_path, monkeypatch):
    monkeypatch.setenv("WGPUVIEWER_CACHE_DIR", str(tmp_path / "cache"))  # cold: the normal map is built
    textures.clear_cache()
    scene = parse_scene(SCENE)
    tracemalloc.start()
    try:
        renderer = Renderer(scene, gpu)
        for technique in ("pom", "maxmip"):  # the second adds its pyramid to what the first uploaded
            image = renderer.render(technique, (160, 120))
            assert image.covered.mean() > 0.2
            peak, uploaded = tracemalloc.get_traced_memory()[1], uploaded_bytes(renderer)
            assert peak <= PEAK_PER_UPLOADED_BYTE * uploaded, \
                f"{technique}: peak {peak / 2**20:.0f} MiB is {peak / uploaded:.2f}x the {uploaded / 2**20:.0f} MiB uploaded"
    finally:
        tracemalloc.stop()
        textures.clear_cache()


def test_a_map_build_peaks_near_its_input_and_output_bytes(tmp_path):
    """maptools generate normal on a 16-bit PNG: decode, float32 heights, normals, banded PNG encoding."""
    import cv2
    import numpy as np

    from maptools.cli import main

    rng = np.random.default_rng(0)
    cv2.imwrite(str(tmp_path / "h.png"), rng.integers(0, 65535, (SIZE, SIZE), dtype=np.uint16))
    tracemalloc.start()
    try:
        assert main(["generate", "normal", str(tmp_path / "h.png"), "-o", str(tmp_path / "n.png"), "--bits", "16",
                     "--backend", "cpu"]) == 0
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    float_bytes = SIZE * SIZE * (4 + 12)  # the float32 heights in, the float32 normals out
    assert peak <= 2.0 * float_bytes, f"peak {peak / 2**20:.0f} MiB is {peak / float_bytes:.2f}x"
