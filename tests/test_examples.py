"""examples/: the export example draws a relief-mapped quad headless from ``maptools batch``'s normal map and the
textures ``wgpuviewer export --maps`` wrote, and the relief shows (the picture differs from the flat relief's)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from maptools.cli import main as maptools_main
from wgpuviewer.export.command import main as export_main
from wgpuviewer.textures import builtin_height

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.requires_gpu


def load_example(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("technique", ["maxmip"])
def test_export_quad_draws_the_relief(tmp_path, technique):
    Image.fromarray((builtin_height("bricks", (64, 64)) * 255).astype(np.uint8)).save(tmp_path / "bricks.png")
    maps = tmp_path / "maps"
    assert maptools_main(["batch", str(tmp_path / "bricks.png"), "-o", str(maps), "--kinds", "normal",
                          "--set", "normal.y=directx"]) == 0
    module = maps / f"{technique}.wgsl"
    assert export_main([technique, "-o", str(module), "--maps", str(tmp_path / "bricks.png"),
                        "--height-scale", "0.1"]) == 0
    example = load_example("export_quad")
    out = tmp_path / "quad.png"
    assert example.main([str(module), str(maps / "bricks"), "-o", str(out), "--size", "64"]) == 0
    relief = np.asarray(Image.open(out))
    params = maps / "bricks.relief_params.json"
    params.write_text(json.dumps({**json.loads(params.read_text()), "height_scale": 0.0}))
    assert example.main([str(module), str(maps / "bricks"), "-o", str(out), "--size", "64"]) == 0
    flat = np.asarray(Image.open(out))
    assert relief.shape == (64, 64, 4) and relief[..., :3].std() > 5  # shaded, not one colour
    # the same maps without relief depth: the trace moved the hits
    assert np.abs(relief.astype(int) - flat).mean() > 2
