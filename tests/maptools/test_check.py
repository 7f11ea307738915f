"""``maptools check``: the sampled CPU references equal the whole ones at their indices, and the check compares at a
stated seeded sample, reports a mismatch there, shows its progress, and compares every value with --full."""

from __future__ import annotations

import dataclasses
import types

import numpy as np
import pytest

from maptools import check, cli, registry
from maptools.kinds.cone import cpu as cn
from maptools.kinds.distance_refined import cpu as rf
from maptools.volume import cpu as dist
from tests.maptools.helpers import adversarial_maps, smooth_tileable
from wgpuviewer.lab.studies.refined_distance import reliefs

#: Small adversarial maps (flat, spike, step, wall, checker, 1x1, NPOT and odd sizes, 8/16-bit) and one non-square one.
MAPS = {name: h for name, h in adversarial_maps().items() if h.size <= 4000}
MAPS["smooth_23x37"] = smooth_tileable(23, 37, 7)


def random_index(shape, n: int, seed: int) -> tuple[np.ndarray, ...]:
    """n random positions (repeats allowed), some written as negative indices."""
    rng = np.random.default_rng(seed)
    return tuple(np.where(rng.random(n) < 0.3, -1, 0) * s + rng.integers(0, s, n) for s in shape)


@pytest.mark.parametrize("opts", [{"slices": 4, "height_scale": 0.3}, {"slices": 3, "subcells": 1},
                                  {"slices": 2, "height_scale": 1.0, "subcells": 8}])
@pytest.mark.parametrize("name", list(MAPS))
def test_distance_sample_equals_full(name, opts):
    assert_sample_equals_full(dist.distance, dist.sample_reference, name, opts)


@pytest.mark.parametrize("opts", [{"filter": "nearest"}, {"filter": "bilinear"}, {"max_ratio": 2.5}])
@pytest.mark.parametrize("name", list(MAPS))
def test_cone_sample_equals_full(name, opts):
    assert_sample_equals_full(cn.cone, cn.sample_reference, name, opts)


def assert_sample_equals_full(reference, sample_reference, name: str, opts: dict) -> None:
    """The sampled reference at 200 seeded indices equals the whole reference there, value and dtype."""
    h = MAPS[name]
    full = reference(h, **opts)
    index = random_index(full.shape, 200, len(name))
    values = sample_reference(h, index, **opts)
    assert values.dtype == full.dtype and np.array_equal(values, full[index])


@pytest.mark.parametrize("opts", [{"slices": 4, "height_scale": 0.3, "sectors": 2, "bands": 3, "reach": 6.0},
                                  {"slices": 3, "height_scale": 0.5, "sectors": 4, "bands": 2, "reach": 5.0,
                                   "visibility": "on", "subcells": 2},
                                  {"slices": 5, "height_scale": 0.4, "sectors": 1, "bands": 1, "visibility": "on"}])
@pytest.mark.parametrize("name", ["spike", "step", "checker", "smooth_23x37", "plate"])
def test_refined_sample_equals_full(name, opts):
    h = reliefs.plate(24) if name == "plate" else MAPS[name]
    full = rf.distance_refined(h, progress=False, **opts)
    index = random_index(full.shape, 300, len(name))
    values = rf.sample_reference(h, index, **opts)
    assert values.dtype == full.dtype and np.array_equal(values, full[index])


def test_sample_keeps_the_index_shape_and_refuses_bad_indices():
    h = smooth_tileable(9, 14, 2)
    full = dist.distance(h, slices=2)
    index = (np.array([[0, 1], [1, 0]]), np.array([[3, 8], [0, -1]]), np.array([[13, 0], [-14, 5]]))
    assert np.array_equal(dist.sample_reference(h, index, slices=2), full[index])
    assert cn.sample_reference(h, (np.array([], np.int64), np.array([], np.int64))).shape == (0,)
    with pytest.raises(IndexError):
        dist.sample_reference(h, (np.array([2]), np.array([0]), np.array([0])), slices=2)
    with pytest.raises(IndexError):
        cn.sample_reference(h, (np.array([0]), np.array([-15])))
    with pytest.raises(IndexError):
        cn.sample_reference(h, (np.array([0.5]), np.array([1])))


def test_sample_index_is_seeded_distinct_and_bounded():
    a = check.sample_index((3, 5, 7), 40, 1)
    flat = np.ravel_multi_index(a, (3, 5, 7))
    assert len(set(flat.tolist())) == 40 and np.all(np.diff(flat) > 0)
    assert all(np.array_equal(x, y) for x, y in zip(a, check.sample_index((3, 5, 7), 40, 1)))
    assert not np.array_equal(flat, np.ravel_multi_index(check.sample_index((3, 5, 7), 40, 2), (3, 5, 7)))
    assert check.sample_index((2, 3), 100, 0)[0].size == 6


def on_cpu(monkeypatch, name: str, gpu=None) -> None:
    """Kind ``name``'s GPU path replaced by ``gpu`` (default: its CPU reference): the check runs without an adapter."""
    kind = registry.KINDS[name]
    monkeypatch.setitem(registry.KINDS, name, dataclasses.replace(kind, gpu=gpu or kind.cpu))


OPTS = {"distance": {"slices": 3, "height_scale": 0.2, "subcells": 2}}


def test_mismatch_at_a_sampled_voxel_is_reported(monkeypatch):
    h = smooth_tileable(20, 24, 3)
    opts = registry.KINDS["distance"].resolve(OPTS["distance"])
    sampled = check.sample_index((3, 20, 24), 50, 4)
    hit = tuple(int(a[17]) for a in sampled)
    missed = next(p for p in np.ndindex(3, 20, 24) if p not in set(zip(*(a.tolist() for a in sampled))))

    def altered(at):
        def gpu(height, **o):
            out = dist.distance(height, **o)
            out[at] += 0.5
            return out
        return gpu

    on_cpu(monkeypatch, "distance", altered(hit))
    r = check.check_kind("distance", h, opts, 50, 4)
    assert not r.comparison.ok and r.comparison.max_diff == pytest.approx(0.5) and r.sampled
    assert (r.compared, r.total) == (50, 3 * 20 * 24)
    on_cpu(monkeypatch, "distance", altered(missed))  # a sample states what it looked at, and looks only there
    assert check.check_kind("distance", h, opts, 50, 4).comparison.ok
    assert not check.check_kind("distance", h, opts, None, 4).comparison.ok  # the whole comparison finds it


def test_sampled_kind_checks_the_gpu_map_shape(monkeypatch):
    on_cpu(monkeypatch, "distance", lambda height, **o: dist.distance(height, **o)[:-1])
    r = check.check_kind("distance", smooth_tileable(8, 8, 1), registry.KINDS["distance"].resolve(OPTS["distance"]),
                         10, 0)
    assert not r.comparison.ok and "shape" in r.comparison.detail


def test_check_kinds_reports_each_phase(monkeypatch):
    heard = []
    kinds = ["normal", "cone"]
    for name in kinds:
        on_cpu(monkeypatch, name)
    opts = {k: registry.KINDS[k].resolve({}) for k in kinds}
    results = list(check.check_kinds(smooth_tileable(12, 16, 1), kinds, opts, 30, 0, lambda *a: heard.append(a)))
    assert heard == [("normal: GPU", 0, 4), ("normal: CPU", 1, 4), ("cone: GPU", 2, 4), ("cone: CPU sample", 3, 4),
                     ("done", 4, 4)]
    assert [r.sampled for r in results] == [False, True] and all(r.comparison.ok for r in results)


@pytest.fixture
def cpu_check(tmp_path, monkeypatch):
    """`maptools check` runnable without an adapter: every kind's GPU path is its CPU reference."""
    from maptools import gpu

    for name in registry.KINDS:
        on_cpu(monkeypatch, name)
    monkeypatch.setattr(gpu, "runner", lambda *a: types.SimpleNamespace(gpu=types.SimpleNamespace(summary="cpu")))
    path = tmp_path / "h.npy"
    np.save(path, smooth_tileable(14, 18, 5))
    return path


def test_cli_check_states_the_sample_and_each_kinds_time(cpu_check, capsys):
    argv = ["check", str(cpu_check), "--kinds", "normal,distance,cone", "--set", "distance.slices=2",
            "--sample", "40", "--seed", "7"]
    assert cli.main(argv) == 0
    out = capsys.readouterr().out.splitlines()
    assert "distance, cone: CPU reference at a random sample of 40 values per kind (seed 7;" in out[1]
    rows = {line.split()[0]: line for line in out[2:5]}
    assert "[all 756 values; GPU " in rows["normal"] and " OK " in rows["normal"]
    assert "[CPU reference at 40 of 504 values, random with seed 7; GPU " in rows["distance"]
    assert "[CPU reference at 40 of 252 values, random with seed 7; GPU " in rows["cone"]
    assert all(" s, CPU " in r and r.endswith(" s]") for r in rows.values())
    assert out[5].startswith("3 of 3 kinds within tolerance in ")


def test_cli_check_full_compares_every_value(cpu_check, capsys):
    assert cli.main(["check", str(cpu_check), "--kinds", "distance,cone", "--set", "distance.slices=2",
                     "--full"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1] == "comparing every value of every kind"
    assert "[all 504 values;" in out[2] and "[all 252 values;" in out[3]
