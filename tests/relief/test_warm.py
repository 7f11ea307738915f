"""`wgpuviewer warm` fills the map cache under the keys the renderer looks up (a render afterwards builds nothing),
for a scene or a material folder; maps a scene names (`[materials.X.maps]`, written by `maptools batch`) are served
from their files, and one that is not the map the renderer asks for is one line naming its key and the fix."""

from __future__ import annotations

import numpy as np
import pytest

from maptools import cache
from maptools import cli as maptools_cli
from tests.maptools.helpers import smooth_tileable
from wgpuviewer import cli, textures

TECHNIQUES = ("pom_adaptive", "maxmip", "cone", "distance")  # complexity, maxmip, cone and distance maps + normals


def scene(folder, maps: str = "") -> str:
    """A 16x16 height file and a scene with it on a plane (normals derived from it), its path."""
    np.save(folder / "h.npy", smooth_tileable(16, 16, 3))
    path = folder / "s.toml"
    path.write_text(f"""
[scene]
techniques = {list(TECHNIQUES)}
[camera]
position = [0.0, 1.2, 1.5]
target = [0.0, 0.0, 0.0]
[materials.m]
albedo = [0.5, 0.5, 0.5]
height = "h.npy"
height_scale = 0.06
{maps}
[[objects]]
type = "plane"
material = "m"
size = [2.0, 2.0]
""".replace("'", '"'))
    return str(path)


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "cache"))
    textures.clear_cache()
    yield
    textures.clear_cache()


def render(scene_path: str, technique: str, out) -> list[cache.Served]:
    """Render ``technique`` (32x24); the maps the cache served meanwhile."""
    with cache.recording() as served:
        assert cli.main(["render", scene_path, "--technique", technique, "-o", str(out), "--size", "32x24"]) == 0
    return served


def test_a_render_after_warm_builds_no_map(tmp_path, capsys, adapter):
    path = scene(tmp_path)
    assert cli.main(["warm", path]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == ["pom_adaptive: 2 built, 0 already cached", "maxmip: 1 built, 1 already cached",
                     "cone: 1 built, 2 already cached", "distance: 1 built, 2 already cached",
                     f"map cache: {tmp_path / 'cache'}"], lines
    for technique in TECHNIQUES:
        served = render(path, technique, tmp_path / f"{technique}.png")
        assert served and {s.source for s in served} == {"cache"}, (technique, served)
    capsys.readouterr()
    assert cli.main(["warm", path, "--techniques", "cone,maxmip"]) == 0
    assert capsys.readouterr().out.splitlines()[:2] == ["cone: 0 built, 3 already cached",
                                                        "maxmip: 0 built, 2 already cached"]


def test_warm_a_material_folder_on_the_default_scene(tmp_path, capsys, adapter):
    folder = tmp_path / "set"
    folder.mkdir()
    np.save(folder / "rock_albedo.npy", np.full((16, 16, 3), 0.5, np.float32))
    np.save(folder / "rock_height.npy", smooth_tileable(16, 16, 4))
    assert cli.main(["warm", str(folder), "--techniques", "pom_adaptive,basic"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("pom_adaptive: ") and lines[0].endswith(" built, 0 already cached"), lines
    assert lines[1] == "basic: needs no generated map", lines  # the albedo, the normals: read, not generated
    with cache.recording() as served:
        assert cli.main(["render", "--material", str(folder), "--technique", "pom_adaptive", "-o",
                         str(tmp_path / "x.png"), "--size", "32x24"]) == 0
    assert {s.source for s in served} == {"cache"}
    assert cli.main(["warm", str(folder), "--material", str(folder)]) == 2
    assert cli.main(["warm", str(folder), "--techniques", "pom,nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "a folder is a material folder; give it or --material, not both" in err[0], err
    assert "nope" in err[1], err


def batch(tmp_path, *options) -> None:
    assert maptools_cli.main(["batch", str(tmp_path / "h.npy"), "-o", str(tmp_path / "maps"), "--kinds",
                              "complexity,cone,distance", "--backend", "cpu", *options]) == 0


NAMED = """[materials.m.maps]
complexity = "maps/h.complexity.png"
cone = "maps/h.cone.npy"
distance = "maps/h.distance.npy"
"""


def test_maps_the_scene_names_are_served_from_their_files(tmp_path, capsys, adapter):
    path = scene(tmp_path, NAMED)
    batch(tmp_path)  # the batch's defaults: not what the renderer asks for
    out = tmp_path / "x.png"
    assert cli.main(["render", path, "--technique", "cone", "-o", str(out), "--size", "32x24"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"wgpuviewer: error: {path}: materials.m.maps.cone = 'maps/h.cone.npy': built with max_ratio=16.0, "
                   "filter=bilinear; the renderer needs max_ratio=32.0, filter=nearest: rebuild it (maptools batch "
                   f"{tmp_path / 'h.npy'} -o {tmp_path / 'maps'} --kinds cone --set cone.max_ratio=32.0 "
                   "--set cone.filter=nearest)"], err
    assert not out.exists()
    assert cli.main(["warm", path]) == 1  # every technique but maxmip is refused; warm goes on and says so
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in lines if "FAILED" in line] == ["pom_adaptive", "cone", "distance"]
    assert any(line.startswith("maxmip: ") and "FAILED" not in line for line in lines), lines
    batch(tmp_path, "--set", "complexity.border=repeat", "--set", "cone.max_ratio=32", "--set", "cone.filter=nearest",
          "--set", "distance.height_scale=0.06")
    for technique, kind in (("pom_adaptive", "complexity"), ("cone", "cone"), ("distance", "distance")):
        served = render(path, technique, tmp_path / f"{technique}.png")
        assert {s.kind for s in served if s.source == "file"} == {kind}, served
        assert not [s for s in served if s.source == "built" and s.kind == kind], served
    capsys.readouterr()
    assert cli.main(["warm", path, "--techniques", "distance"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == "distance: 0 built, 2 already cached, 1 from files the scene names"
