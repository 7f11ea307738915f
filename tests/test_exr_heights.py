"""EXR heights as a user brings them (written with the openexr package): the renderer and maptools read them
through core.images and get exactly what the same heights give as a float .npy."""

from __future__ import annotations

import numpy as np
import pytest

from maptools import cli as maptools_cli
from tests.core.test_images import write_exr
from tests.relief.scenes import material_scene
from wgpuviewer.relief.renderer import Renderer
from wgpuviewer.scene import load_scene


def _heights() -> np.ndarray:
    """A small relief whose values are exact in half precision (the EXR stores halves)."""
    y, x = np.mgrid[0:32, 0:32]
    return (np.round(0.5 + 0.4 * np.sin(x / 3.0) * np.cos(y / 4.0), 3)).astype(np.float16).astype(np.float32)


@pytest.mark.requires_gpu
def test_a_scene_renders_an_exr_height_like_the_same_npy(gpu, tmp_path):
    heights = _heights()
    write_exr(tmp_path / "h.exr", {"Y": heights.astype(np.float16)})
    np.save(tmp_path / "h.npy", heights)
    renders = []
    for name in ("h.exr", "h.npy"):
        path = tmp_path / f"{name}.toml"
        path.write_text(material_scene(["pom"], f'albedo = [0.7, 0.7, 0.7]\nheight = "{name}"\nheight_scale = 0.08',
                                       position=(0.0, 0.9, 0.9)))
        renders.append(Renderer(load_scene(path), gpu).render("pom", (32, 24)))
    exr, npy = renders
    assert exr.covered.mean() > 0.5
    assert exr.color.tobytes() == npy.color.tobytes() and exr.data.tobytes() == npy.data.tobytes()


def test_maptools_makes_the_same_map_from_an_exr(tmp_path, capsys):
    heights = _heights()
    write_exr(tmp_path / "h.exr", {"R": heights, "G": heights, "B": heights})  # equal colour channels: that one
    np.save(tmp_path / "h.npy", heights)
    for name in ("h.exr", "h.npy"):
        assert maptools_cli.main(["generate", "normal", str(tmp_path / name), "-o", str(tmp_path / f"{name}.n.npy"),
                                  "--backend", "cpu"]) == 0
    capsys.readouterr()
    np.testing.assert_array_equal(np.load(tmp_path / "h.exr.n.npy"), np.load(tmp_path / "h.npy.n.npy"))
