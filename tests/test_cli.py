"""CLI behaviour: outputs, exit codes (0 ok, 2 user error, one line, no traceback)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from wgpuviewer.cli import main

ROOT = Path(__file__).resolve().parent.parent


def run_cli(*args, env=None, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "wgpuviewer", *args], capture_output=True, text=True, timeout=300,
        env={**os.environ, **(env or {})}, cwd=cwd,
    )


def assert_user_error(result, *fragments):
    assert result.returncode == 2, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.startswith("wgpuviewer: error:")]
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def test_render_png_and_npy(tmp_path, adapter):
    png, npy = tmp_path / "out" / "a.png", tmp_path / "a.npy"
    assert main(["render", "-o", str(png), "--technique", "pom", "--size", "80x48"]) == 0
    picture = cv2.imread(str(png))
    assert picture.shape == (48, 80, 3)
    assert main(["render", "-o", str(npy), "--size", "80x48", "--mode", "uv"]) == 0
    data = np.load(npy)
    assert data.shape == (48, 80, 2) and data.dtype == np.float32
    assert not list(tmp_path.glob("**/.*"))  # no temp files left behind
    assert png.stat().st_mode & 0o044  # readable by others, like any file the user writes


def test_render_is_byte_identical_across_runs(tmp_path, adapter):
    """A fresh process (python -m wgpuviewer) and the test process (its device shared with other tests) write the
    same bytes."""
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    args = ["render", str(ROOT / "scenes" / "default.toml"), "--size", "64x40", "-o"]
    assert run_cli(*args, str(a)).returncode == 0
    assert main([*args, str(b)]) == 0
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize(
    "args,fragments",
    [
        (["render", "-o", "x.png", "--technique", "nope"], ["--technique", "'nope'", "unknown technique"]),
        (["render", "-o", "x.png", "--size", "big"], ["--size", "'big'", "WIDTHxHEIGHT"]),
        (["render", "-o", "x.png", "--size", "0x10"], ["--size", "'0x10'"]),
        (["render", "-o", "x.jpg"], ["x.jpg", ".png", ".npy"]),
        (["render", "missing.toml", "-o", "x.png"], ["missing.toml"]),
        (["view", "missing.toml"], ["missing.toml"]),
        (["missing.toml"], ["missing.toml"]),  # no command: view
        (["render", "-o", "/proc/no/such/a.png", "--size", "8x8"], ["/proc/no/such/a.png", "cannot write"]),
        (["accuracy", "--out", "o", "--rays", "0"], ["--rays"]),
        (["bench", "--out", "o", "--heightmaps", ","], ["--heightmaps"]),
    ],
)
def test_user_errors_exit_2_with_one_line(tmp_path, monkeypatch, capsys, args, fragments):
    """In this process (``main`` returns the exit status; the run_cli tests below go through ``python -m
    wgpuviewer`` and its exit status)."""
    monkeypatch.chdir(tmp_path)
    code = main(args)
    assert_user_error(SimpleNamespace(returncode=code, stderr=capsys.readouterr().err), *fragments)


def test_bad_scene_value_names_file_key_and_value(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text((ROOT / "scenes" / "default.toml").read_text().replace("fov = 55.0", "fov = 500.0"))
    assert_user_error(run_cli("render", str(scene), "-o", str(tmp_path / "x.png")), "bad.toml", "camera.fov", "500")
    assert not (tmp_path / "x.png").exists()


def test_backend_without_adapter_exits_2_with_the_fix(tmp_path):
    backend = "dx12" if sys.platform != "win32" else "metal"
    result = run_cli("render", "-o", str(tmp_path / "x.png"), "--backend", backend)
    assert_user_error(result, "no GPU adapter", backend)


def test_backend_environment_variable_is_validated(tmp_path):
    result = run_cli("info", env={"WGPUVIEWER_BACKEND": "vulcan"})
    assert_user_error(result, "WGPUVIEWER_BACKEND", "vulcan", "vulkan")


def test_info_and_techniques(adapter, capsys):
    assert main(["info"]) == 0
    out = capsys.readouterr().out
    assert "chosen (auto):" in out and "relevant features:" in out
    assert main(["techniques"]) == 0
    out = capsys.readouterr().out
    for name in ("basic", "normal", "parallax", "steep", "pom", "layers", "offset_limiting"):
        assert name in out


def test_view_without_display_renders_a_png(tmp_path, adapter, monkeypatch, capsys):
    """Without a display ``view`` renders the scene offscreen at the window size of the settings (small here)."""
    config = tmp_path / "config"
    config.mkdir()
    (config / "settings.toml").write_text("version = 1\nwidth = 160\nheight = 100\n")
    env = {"DISPLAY": "", "WAYLAND_DISPLAY": "", "WGPUVIEWER_CONFIG_DIR": str(config)}
    result = run_cli("view", env=env, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "no display" in result.stdout
    out = tmp_path / "out" / "default_pom.png"
    assert out.exists() and result.stdout.strip().endswith(str(Path("out") / "default_pom.png"))
    assert cv2.imread(str(out)).shape == (100, 160, 3)
    # no arguments at all = view the default scene (in this process)
    out.unlink()
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    monkeypatch.chdir(tmp_path)
    assert main([]) == 0
    assert "no display" in capsys.readouterr().out and out.exists()


def test_every_study_folder_is_a_registered_subcommand():
    """A folder under wgpuviewer/lab/studies/ is a command without any list to edit: the harness finds it."""
    from wgpuviewer import cli

    folders = sorted(p.name for p in (ROOT / "wgpuviewer" / "lab" / "studies").iterdir() if (p / "__init__.py").is_file())
    assert folders  # filtering, perspective, refined_distance, ...
    _, commands = cli.build_parser()
    for folder in folders:
        assert folder.replace("_", "-") in commands, folder
    assert {"view", "render", "techniques", "filters", "accuracy", "bench", "info"} <= set(commands)


def test_a_discovered_study_runs_with_the_shared_options_and_its_command_line(monkeypatch, capsys, tmp_path):
    from wgpuviewer.lab.harness import study as harness_study

    seen = {}

    class Probe:
        name = "probe-study"
        help = "records what it was given"

        def add_arguments(self, parser):
            harness_study.add_measurement_options(parser, "output folder", "smoke or full")
            parser.add_argument("--angles")

        def options(self, args):
            seen.update(vars(args))
            return args.angles

        def run(self, options, out):
            seen.update(options=options, folder=out)
            return 0

    monkeypatch.setattr(harness_study, "discover", lambda: [Probe()])
    monkeypatch.chdir(tmp_path)  # the harness makes --out before the run
    assert main(["probe-study", "--out", "my runs", "--suite", "smoke", "--angles", "1,2"]) == 0
    assert seen["command_line"] == "wgpuviewer probe-study --out 'my runs' --suite smoke --angles 1,2"
    assert seen["suite"] == "smoke" and seen["out"] == "my runs" and seen["backend"] is None and not seen["quiet"]
    assert seen["options"] == "1,2" and seen["folder"] == Path("my runs") and (tmp_path / "my runs").is_dir()
    assert main(["probe-study", "--suite", "smoke"]) == 2  # --out is required, as for every measuring command
    assert "required: --out" in capsys.readouterr().err


