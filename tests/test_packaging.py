"""The wheel is complete by construction: built from the checkout and installed (not editable) into a fresh virtual
environment, every subcommand's ``--help`` of ``wgpuviewer`` and ``maptools`` and one tiny render run from outside the
checkout, and the wheel holds every package folder, every WGSL file and every scene."""

from __future__ import annotations

import argparse
import json
import os
import site
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

import maptools.cli
import wgpuviewer.cli

ROOT = Path(__file__).resolve().parent.parent


def subcommands(parser: argparse.ArgumentParser) -> list[list[str]]:
    """Every command path of the parser, nested ones (``generate KIND``) included, read from argparse."""
    return [[name, *rest] for action in parser._actions if isinstance(action, argparse._SubParsersAction)
            for name, child in action.choices.items() for rest in [[], *subcommands(child)]]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(wheel path, bin folder, environment) of a fresh venv holding only the wheel; the dev environment's
    site-packages join its path through a .pth file for the dependencies (a listed folder's own .pth files are not
    processed, so the dev install's editable finder stays off)."""
    tmp = tmp_path_factory.mktemp("packaging")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
                    "-w", str(tmp / "dist"), str(ROOT)], check=True, capture_output=True)
    (wheel,) = (tmp / "dist").glob("wgpuviewer-*.whl")
    env_dir = tmp / "env"
    venv.create(env_dir, with_pip=False)
    python = env_dir / "bin" / "python"
    fresh_site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                                     check=True, capture_output=True, text=True).stdout.strip())
    (fresh_site / "dev_dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps",
                    str(wheel)], check=True, capture_output=True)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    return wheel, env_dir / "bin", env, fresh_site


def test_wheel_lists_every_package_wgsl_file_and_scene(installed):
    wheel = installed[0]
    names = set(zipfile.ZipFile(wheel).namelist())
    expected = {p.relative_to(ROOT).as_posix() for room in ("wgpuviewer", "maptools")
                for p in (ROOT / room).rglob("__init__.py")}
    expected |= {"wgpuviewer/" + p.relative_to(ROOT).as_posix() for p in (ROOT / "wgsl").rglob("*.wgsl")}
    expected |= {p.relative_to(ROOT).as_posix() for p in (ROOT / "wgpuviewer" / "techniques").glob("*/*.wgsl")}
    expected |= {"wgpuviewer/" + p.relative_to(ROOT).as_posix() for p in (ROOT / "scenes").glob("*.toml")}
    assert {"wgpuviewer/lab/studies/refined_distance/__init__.py", "wgpuviewer/lab/harness/__init__.py"} <= expected
    assert not expected - names, f"missing from the wheel: {sorted(expected - names)}"


def test_installed_package_runs_outside_the_checkout(installed, tmp_path):
    _, bin_dir, env, fresh_site = installed
    where = subprocess.run([str(bin_dir / "python"), "-c", "import wgpuviewer, maptools; print(wgpuviewer.__file__);"
                            " print(maptools.__file__)"], cwd=tmp_path, env=env, check=True, capture_output=True,
                           text=True).stdout.split()
    assert all(Path(p).is_relative_to(fresh_site) for p in where), where
    for tool in ("wgpuviewer", "maptools"):  # the installed entry points
        run = subprocess.run([str(bin_dir / tool), "--help"], cwd=tmp_path, env=env, capture_output=True, text=True,
                             timeout=60)
        assert run.returncode == 0 and "usage:" in run.stdout, (tool, run.stderr[-2000:])
    commands = {"wgpuviewer": subcommands(wgpuviewer.cli.build_parser()[0]),
                "maptools": subcommands(maptools.cli.build_parser())}
    assert all(commands.values()), commands
    # Every subcommand's --help in one process of the fresh environment (a process each costs a minute on 2 cores).
    run = subprocess.run([str(bin_dir / "python"), "-c", HELP_ALL, json.dumps(commands)], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    done = [line.split()[1:] for line in run.stdout.splitlines() if line.startswith("help-ok ")]
    assert done == [[tool, *path] for tool, paths in commands.items() for path in paths]


HELP_ALL = """
import importlib, json, sys
for tool, paths in json.loads(sys.argv[1]).items():
    main = importlib.import_module(tool + ".cli").main
    for path in paths:
        try:
            code = main([*path, "--help"])
        except SystemExit as done:
            code = done.code
        if code not in (0, None):
            sys.exit(f"{tool} {' '.join(path)} --help exits {code}")
        print("help-ok", tool, *path)
"""


@pytest.mark.requires_gpu
def test_installed_package_renders(installed, tmp_path):
    _, bin_dir, env, _ = installed
    run = subprocess.run([str(bin_dir / "wgpuviewer"), "render", "-o", "x.png", "--size", "32x24"], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    assert (tmp_path / "x.png").stat().st_size > 0
