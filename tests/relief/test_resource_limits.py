"""GPU resource limits as user errors: a frame or map too large for the adapter is refused before anything is loaded
or generated (its size is known in advance: the render size, a height file's header, a builtin's size), and the
adapter running out of memory where a texture or buffer is made is a one-line error naming the option or scene
key and the memory it needed. Hints name only what the user can change where they are."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
import wgpu

from tests.relief.scenes import material_scene
from wgpuviewer import cli, textures
from wgpuviewer.core import gpu as core_gpu
from wgpuviewer.core.compute import Compute
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import format_bytes
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.relief.targets import frame_bytes
from wgpuviewer.scene import parse_scene


class _Device:
    """The real device, but with other ``limits`` and creation calls whose label starts with ``fail`` raising
    ``error``: a forced failure, the same on every adapter."""

    def __init__(self, device, limits=None, fail: str | None = None, error: Exception | None = None):
        self._device, self._limits, self._fail, self._error = device, limits, fail, error

    def __getattr__(self, name):
        return getattr(self._device, name)

    @property
    def limits(self):
        return {**self._device.limits, **(self._limits or {})}

    def _create(self, name, **kwargs):
        if self._fail is not None and str(kwargs.get("label", "")).startswith(self._fail):
            raise self._error
        return getattr(self._device, name)(**kwargs)

    def create_texture(self, **kwargs):
        return self._create("create_texture", **kwargs)

    def create_buffer(self, **kwargs):
        return self._create("create_buffer", **kwargs)


OUT_OF_MEMORY = [wgpu.GPUOutOfMemoryError("Out of memory"),  # the WebGPU error
                 wgpu.GPUValidationError("Validation Error\n\nCaused by:\n  In wgpuDeviceCreateTexture\n"
                                         "    Not enough memory left.")]  # what wgpu-native raises on Vulkan


def other_gpu(gpu, **device) -> core_gpu.Gpu:
    return dataclasses.replace(gpu, device=_Device(gpu.device, **device), cache={})


def one_line(capsys) -> str:
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip() and not line.startswith("notice:")]
    assert len(err) == 1 and "Traceback" not in err[0], err
    assert err[0].startswith("wgpuviewer: error: "), err
    return err[0]


@pytest.fixture
def no_builtins(monkeypatch):
    """Builtin textures must not be generated (their size alone decides)."""
    textures.clear_cache()

    def generated(*args):
        pytest.fail(f"a builtin was generated: {args}")

    monkeypatch.setattr(textures, "builtin_height", generated)
    monkeypatch.setattr(textures, "builtin_albedo", generated)
    yield
    textures.clear_cache()


def scene(height: str, techniques=("pom",)) -> str:
    return material_scene(list(techniques), f"albedo = [0.5, 0.5, 0.5]\nheight = {height}")


# --- the frame ---------------------------------------------------------------------------------------------------


def test_the_largest_render_size_beyond_the_adapter_is_refused_naming_size_at_once(gpu, capsys, tmp_path):
    """The QA case: 16384x16384 is inside --size's range; where its targets cannot be read back, it is refused
    before any map is built, not an internal error."""
    from wgpuviewer.relief.targets import readback_bytes

    if readback_bytes(16384, 16384, "rgba32uint") <= gpu.device.limits["max-buffer-size"]:
        pytest.skip("this adapter reads back a 16384x16384 frame")
    out = tmp_path / "x.png"
    assert cli.main(["render", "-o", str(out), "--size", "16384x16384"]) == 2
    line = one_line(capsys)
    assert line.startswith("wgpuviewer: error: --size 16384x16384: its rgba32uint target is read back through a "
                           "4.0 GiB buffer, more than this adapter's largest buffer"), line
    assert not out.exists()


def test_a_frame_beyond_the_largest_buffer_is_refused_before_any_map_is_built(gpu, capsys, tmp_path, monkeypatch,
                                                                           no_builtins):
    from wgpuviewer.relief.targets import check_frame_size

    small = other_gpu(gpu, limits={"max-buffer-size": 2**20})
    monkeypatch.setattr(core_gpu, "get_gpu", lambda *a, **k: small)
    assert cli.main(["render", "-o", str(tmp_path / "x.png"), "--size", "512x512"]) == 2
    line = one_line(capsys)
    assert line == ("wgpuviewer: error: --size 512x512: its rgba32uint target is read back through a 4.0 MiB buffer, "
                    "more than this adapter's largest buffer of 1.0 MiB; use at most 256x256"), line
    check_frame_size(small, (256, 256))  # the size it suggests fits
    with pytest.raises(UserError, match=r"^render size 600x200: .*; use at most 440x146$"):  # the API, same shape
        check_frame_size(small, (600, 200))
    check_frame_size(small, (440, 146))


@pytest.mark.parametrize("error", OUT_OF_MEMORY, ids=["oom", "validation"])
def test_a_frame_the_adapter_cannot_allocate_names_the_size_and_the_memory(gpu, error, capsys, tmp_path, monkeypatch):
    failing = other_gpu(gpu, fail="offscreen:data", error=error)
    s = parse_scene(scene("'builtin:flat0'", ("basic",)))
    need = re.escape(format_bytes(frame_bytes((40, 30))))  # every offscreen target and the depth attachment
    with pytest.raises(UserError, match=rf"^render size 40x30 needs {need} of GPU memory, more than .* could "
                                        r"allocate; use a smaller size$"):
        Renderer(s, failing).render("basic", (40, 30))
    monkeypatch.setattr(core_gpu, "get_gpu", lambda *a, **k: failing)
    assert cli.main(["render", "-o", str(tmp_path / "x.png"), "--size", "40x30", "--technique", "basic"]) == 2
    assert one_line(capsys).startswith(f"wgpuviewer: error: --size 40x30 needs {format_bytes(frame_bytes((40, 30)))} "
                                       "of GPU memory")


def test_other_wgpu_errors_stay_internal_errors(gpu):
    """Only the adapter running out of memory is the user's to fix; any other validation error is a bug."""
    failing = other_gpu(gpu, fail="offscreen:data", error=wgpu.GPUValidationError("Invalid usage"))
    with pytest.raises(wgpu.GPUValidationError):
        Renderer(parse_scene(scene("'builtin:flat0'", ("basic",))), failing).render("basic", (8, 8))


# --- textures and maps -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("error", OUT_OF_MEMORY[:1], ids=["oom"])
def test_a_texture_the_adapter_cannot_allocate_is_reported_against_its_scene_key(gpu, error):
    s = parse_scene(material_scene(["pom"], "albedo = 'builtin:bumps'\nheight = { builtin = 'bumps', size = [8, 8] }"))
    renderer = Renderer(s, other_gpu(gpu, fail="m.albedo", error=error))
    with pytest.raises(UserError, match=r"^<scene>: materials.m.albedo = 'builtin:bumps': its albedo map cannot be "
                                        r"built: m.albedo needs 682.\d KiB of GPU memory, more than .* could "
                                        r"allocate; use a smaller texture$"):
        renderer.texture("m", "albedo")
    renderer = Renderer(s, other_gpu(gpu, fail="m.distance", error=error))  # a 3D map: against the height key
    with pytest.raises(UserError, match=r"^<scene>: materials.m.height = \{'builtin': 'bumps', 'size': \[8, 8\]\}: "
                                        r"its distance map cannot be built: m.distance needs 2.0 KiB of GPU memory"):
        renderer.texture("m", "distance")


def test_core_texture_creation_reports_memory_in_one_line(gpu):
    failing = other_gpu(gpu, fail="huge", error=OUT_OF_MEMORY[1])
    # the base level is never read before the texture exists: a broadcast array costs nothing
    base = np.broadcast_to(np.float32(0.5), (4096, 2048, 4))
    with pytest.raises(UserError, match=r"^huge needs 128.0 MiB of GPU memory, more than .* could allocate; use a "
                                        r"smaller texture$"):
        core_gpu.create_texture(failing, [base], "rgba32float", "huge")

def test_a_pyramid_atlas_beyond_the_2d_limit_names_the_tallest_map_that_fits(gpu, no_builtins):
    small = other_gpu(gpu, limits={"max-texture-dimension-2d": 64})
    s = parse_scene(scene("{ builtin = 'bumps', size = [48, 48] }", ("maxmip",)))
    with pytest.raises(UserError, match=r"its maxmip map cannot be built: the maxmip atlas of a 48x48 height map is "
                                        r"96 rows, more than this adapter's limit of 64 texels per side; use a height "
                                        r"map of at most 32 rows$"):
        Renderer(s, small).prepare("maxmip")


def test_2d_maps_beyond_the_gpu_kernels_buffers_are_built_on_the_cpu(gpu, tmp_path, monkeypatch):
    """maptools' GPU kernels bind the map whole; where that is beyond the adapter's storage limit a scene's map is
    made by the CPU reference (maptools' own hint, --backend cpu, is not an option of a scene)."""
    monkeypatch.setenv("WGPUVIEWER_CACHE_DIR", str(tmp_path / "cache"))  # generated, not found in the cache
    s = parse_scene(scene("{ builtin = 'bumps', size = [32, 32] }", ("maxmip",)))
    monkeypatch.setattr(Compute, "max_buffer", property(lambda self: 1024))  # 32x32 floats: 4 KiB
    image = Renderer(s, gpu).render("maxmip", (32, 24))
    assert image.covered.mean() > 0.2


# --- maptools names its own options -------------------------------------------------------------------------------
