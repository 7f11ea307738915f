"""Viewer parts without a window: cameras, shader hot reload, the error view, GPU timing."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest
import wgpu

from wgpuviewer.core import wgsl
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import default_scene_path, load_scene
from wgpuviewer.techniques import TECHNIQUES
from wgpuviewer.viewer.cameras import FlyCamera, OrbitCamera
from wgpuviewer.viewer.shader_reload import ShaderReloader

SIZE = (64, 40)


@pytest.fixture(scope="module")
def scene():
    return load_scene(default_scene_path())


def test_fly_camera_moves_and_resets(scene):
    fly = FlyCamera(scene.camera)
    start = fly.camera()
    forward = np.subtract(scene.camera.target, scene.camera.position)
    assert np.allclose(np.subtract(start.target, start.position), forward / np.linalg.norm(forward))
    fly.move(0.0, 0.0, 1.0)
    assert np.allclose(np.subtract(fly.camera().position, start.position), fly.forward)
    fly.look(100.0, 50.0)
    assert not np.allclose(fly.forward, forward / np.linalg.norm(forward))
    fly.look(0.0, -1e6)  # pitch is clamped short of straight up: the view never flips
    assert fly.forward[1] < 1.0 and np.isfinite(fly.forward).all()
    fly.reset()
    assert np.allclose(fly.camera().position, start.position) and np.allclose(fly.camera().target, start.target)


def test_fly_camera_sensitivity_scales_the_turn(scene):
    slow, fast = FlyCamera(scene.camera, 0.001), FlyCamera(scene.camera, 0.004)
    base = FlyCamera(scene.camera).yaw
    slow.look(10.0, 0.0)
    fast.look(10.0, 0.0)
    assert np.isclose(fast.yaw - base, 4 * (slow.yaw - base)) and fast.yaw != base


def test_orbit_camera_starts_at_the_scene_camera_and_keeps_its_distance(scene):
    orbit = OrbitCamera(scene.camera, sensitivity=0.01, zoom=0.1)
    start = orbit.camera()
    assert np.allclose(start.position, scene.camera.position) and np.allclose(start.target, scene.camera.target)
    distance = orbit.distance
    orbit.look(40.0, 25.0)
    moved = orbit.camera()
    assert not np.allclose(moved.position, start.position)
    assert np.isclose(np.linalg.norm(np.subtract(moved.position, moved.target)), distance)
    orbit.zoom(1.0)
    assert np.isclose(orbit.distance, distance * 1.1)
    orbit.zoom(-1e4)  # never through the target
    assert orbit.distance == OrbitCamera.MIN_DISTANCE
    orbit.look(0.0, 1e6)  # pitch clamped: no flip over the pole
    assert np.isfinite(orbit.position).all() and abs(orbit.pitch) < np.pi / 2
    orbit.reset()
    assert np.allclose(orbit.camera().position, scene.camera.position)


# --- shader hot reload ---------------------------------------------------------------------------


def test_broken_shader_keeps_the_last_pipeline_and_reports_file_and_line(gpu, scene, monkeypatch):
    renderer = Renderer(scene, gpu)
    before = renderer.render("pom", SIZE)
    (key,) = [k for k in renderer._pipelines if k[0] == "pom"]  # (technique, target formats)
    working = renderer._pipelines[key]
    reloader = ShaderReloader(renderer)
    good = wgsl.read_wgsl
    pom = TECHNIQUES["pom"].wgsl_file
    broken_text = good(pom) + "\nfn broken() -> f32 {\n    return 1.0 +;\n}\n"
    broken_line = broken_text.count("\n", 0, broken_text.index("return 1.0 +;")) + 1
    monkeypatch.setattr(wgsl, "read_wgsl", lambda name: broken_text if name == pom else good(name))

    errors = reloader.reload()
    assert len(errors) == 1 and errors[0].startswith(f"{pom}:{broken_line}:"), errors
    assert renderer._pipelines[key] is working  # the last working pipeline stays in use
    again = renderer.render("pom", SIZE)  # and it still draws, identically
    assert np.array_equal(again.color, before.color)

    monkeypatch.setattr(wgsl, "read_wgsl", good)  # the edit is fixed: a fresh pipeline, no error
    assert reloader.reload() == [] and reloader.errors == []
    assert renderer._pipelines[key] is not working
    assert np.array_equal(renderer.render("pom", SIZE).color, before.color)


def test_reloader_notices_edited_files(gpu, scene, tmp_path):
    shared, folders = tmp_path / "wgsl", tmp_path / "techniques"  # wgsl/ and the technique folders
    for root, name, source in ((shared, "common/trace.wgsl", "common/trace.wgsl"),
                               (folders, "pom/pom.wgsl", TECHNIQUES["pom"].wgsl_file)):
        (root / name).parent.mkdir(parents=True)
        (root / name).write_text(wgsl.read_wgsl(source))
    renderer = Renderer(scene, gpu)
    renderer.render("steep", SIZE)
    reloader = ShaderReloader(renderer, directories=(shared, folders), interval=0.0)
    assert reloader.poll(1.0) == []
    path = folders / "pom" / "pom.wgsl"
    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000))
    assert reloader.poll(2.0) == ["pom/pom.wgsl"]
    assert reloader.errors == []  # the cached steep pipeline was rebuilt
    assert reloader.poll(3.0) == []


# --- error view ----------------------------------------------------------------------------------


def test_error_map_is_zero_for_the_reference_and_positive_for_parallax(gpu, scene):
    from wgpuviewer.viewer import error_view

    renderer = Renderer(scene, gpu)
    camera = scene.camera
    reference = error_view.reference_render(renderer, SIZE, camera)
    err_parallax = error_view.error_map(renderer, renderer.config("parallax"), SIZE, camera, reference)
    err_pom = error_view.error_map(renderer, renderer.config("pom", {"layers": 8}), SIZE, camera, reference)
    covered = (err_parallax >= 0) & (err_pom >= 0)  # techniques may discard different pixels (box edges)
    assert covered.mean() > 0.3
    assert np.isfinite(err_parallax).all()
    assert err_parallax[covered].mean() > err_pom[covered].mean() > 0
    same = renderer.config("pom", {"layers": error_view.REFERENCE_LAYERS})
    assert np.abs(error_view.error_map(renderer, same, SIZE, camera, reference)[covered]).max() < 1e-3
    assert error_view.texel_size(renderer) == (512, 512)


def test_error_overlay_paints_heat_and_keeps_uncovered_pixels(gpu):
    from wgpuviewer.viewer.error_view import ErrorOverlay

    device = gpu.device
    target = device.create_texture(
        size=(8, 4, 1), format="rgba8unorm", usage=wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
    )
    values = np.array([[-1, 0, 1, 2]], np.float32).repeat(2, axis=0)  # 4x2 map stretched over 8x4
    overlay = ErrorOverlay(device, "rgba8unorm")
    overlay.upload(values)
    encoder = device.create_command_encoder()
    encoder.begin_render_pass(
        color_attachments=[{"view": target.create_view(), "load_op": "clear", "store_op": "store",
                            "clear_value": (0, 0, 1, 1)}]
    ).end()
    overlay.encode(encoder, target.create_view(), (0, 0, 8, 4), max_value=2.0)
    device.queue.submit([encoder.finish()])
    raw = device.queue.read_texture({"texture": target}, {"bytes_per_row": 32, "rows_per_image": 4}, (8, 4, 1))
    px = np.frombuffer(raw, np.uint8).reshape(4, 8, 4)
    assert (px[:, :2, :3] == [0, 0, 255]).all()  # -1: not drawn, the frame underneath stays
    assert (px[:, 2:4, :3] == [0, 0, 0]).all()  # 0 texels: black
    assert (px[:, 4:6, 0] == 255).all() and (px[:, 4:6, 1] > 100).all() and (px[:, 4:6, 2] == 0).all()  # half: yellow-ish
    assert (px[:, 6:, :3] == 255).all()  # at the range's top: white


# --- GPU timing ----------------------------------------------------------------------------------


def test_gpu_timer_reads_back_pass_times_without_blocking(gpu, scene):
    from wgpuviewer.relief.targets import COLOR_FORMAT, DEPTH_FORMAT
    from wgpuviewer.viewer.stats import GpuTimer

    if not GpuTimer.available(gpu):
        pytest.skip("adapter has no timestamp queries")
    device = gpu.device
    renderer = Renderer(scene, gpu)
    usage = wgpu.TextureUsage.RENDER_ATTACHMENT
    color = device.create_texture(size=(*SIZE, 1), format=COLOR_FORMAT, usage=usage)
    depth = device.create_texture(size=(*SIZE, 1), format=DEPTH_FORMAT, usage=usage)
    timer = GpuTimer(device, slots=2)
    times = []
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        times += timer.collect()
        measured = timer.begin_frame() is not None
        encoder = device.create_command_encoder()
        renderer.encode(encoder, [color.create_view()], depth.create_view(), (COLOR_FORMAT,), renderer.config("pom"),
                        scene.camera, SIZE, timestamp_writes=timer.writes(True, True))
        timer.encode_resolve(encoder)
        device.queue.submit([encoder.finish()])
        timer.after_submit()
        if not measured:
            assert timer.writes(True, True) is None  # all slots busy: this frame is simply not timed
        if len(times) >= 3:
            break
        time.sleep(0.01)
    assert len(times) >= 3 and all(0 < t < 10_000 for t in times), times


def test_hud_lines_say_what_auto_chooses(gpu):
    from wgpuviewer.techniques.auto.autotable import AUTO_CANDIDATES
    from wgpuviewer.viewer.hud import panel_lines

    scene = load_scene(os.path.join(os.path.dirname(__file__), "..", "relief", "golden", "scene.toml"))
    renderer = Renderer(scene, gpu)
    lines = panel_lines(renderer, "auto", (("max_error", 0.7),))
    assert lines[0] == "auto at max_error 0.7: budget 0.5 texel"
    assert set(scene.materials) <= {line.rstrip(":") for line in lines}
    names = {name for name, _ in AUTO_CANDIDATES}
    ranges = [line for line in lines if "°:" in line]
    assert ranges and all(line.split(": ")[1].split()[0].rstrip(",") in names for line in ranges)
    assert ranges[0].strip().startswith("0.0-") and lines[-1].split(":")[0].endswith("90°")
