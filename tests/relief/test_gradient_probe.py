"""The explicit-gradient probe (relief.filter_probe.explicit_gradient_support): its decision on given reads, and
what it measures on this machine's adapter."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.relief import filter_probe
from wgpuviewer.relief.filter_probe import (
    SAMPLER_KINDS,
    GradientProbe,
    explicit_gradient_note,
    explicit_gradient_probe,
    explicit_gradient_support,
    ignored_gradients,
)

#: What honoured gradients read (level 0 of the stripes: 1, any coarser level: 0.5).
HONOURED_ISO = {"tiny": 1.0, "huge": 0.5, "thin": 0.5, "round": 0.5}
HONOURED_ANISO = {"tiny": 1.0, "huge": 0.5, "thin": 0.97, "round": 0.5}


def test_the_decision_accepts_reads_that_follow_the_gradients():
    assert ignored_gradients(HONOURED_ISO, HONOURED_ANISO) == []
    probe = GradientProbe("a GPU", HONOURED_ISO, HONOURED_ANISO)
    assert probe.honoured and probe.ignored == []


@pytest.mark.parametrize("sampler, pair, value, phrase", [
    ("isotropic", "tiny", 0.5, "length with an isotropic sampler"),
    ("anisotropic", "huge", 1.0, "length with an anisotropic sampler"),
    ("anisotropic", "thin", 0.5, "shape"),
    ("anisotropic", "thin", 0.7, "shape"),  # a level change smaller than level 0 against a coarse one
    ("anisotropic", "tiny", float("nan"), "length with an anisotropic sampler"),
])
def test_the_decision_names_what_is_ignored(sampler, pair, value, phrase):
    reads = {"isotropic": dict(HONOURED_ISO), "anisotropic": dict(HONOURED_ANISO)}
    reads[sampler][pair] = value
    ignored = ignored_gradients(reads["isotropic"], reads["anisotropic"])
    assert len(ignored) == 1 and ignored[0].startswith(phrase), ignored


def test_the_decision_per_sampler():
    reads = dict(HONOURED_ANISO, thin=0.5)
    assert ignored_gradients(HONOURED_ISO, reads, "isotropic") == []
    assert len(ignored_gradients(HONOURED_ISO, reads, "anisotropic")) == 1
    probe = GradientProbe("a GPU", HONOURED_ISO, reads)
    assert probe.honoured_by("isotropic") and not probe.honoured_by("anisotropic") and not probe.honoured
    with pytest.raises(ValueError, match="sampler = 'linear'"):
        ignored_gradients(HONOURED_ISO, reads, "linear")


def test_the_decision_refuses_equal_reads():
    """An adapter that reads one value whatever the gradients (lavapipe's anisotropic sampler) honours nothing."""
    same = dict.fromkeys(HONOURED_ISO, 0.82)
    assert len(ignored_gradients(HONOURED_ISO, same)) == 2
    assert len(ignored_gradients(same, same)) == 3


def test_probe_texture_levels_differ_as_the_decision_assumes():
    levels = filter_probe.texture_levels(filter_probe.gradient_probe_texture())
    i, j = filter_probe.GRADIENT_TEXEL
    assert levels[0][j, i, 0] == 1.0 and levels[0][j + 1, i, 0] == 0.0
    for level in levels[1:]:
        assert (level[..., 0] == 0.5).all()


def test_probe_on_this_adapter(gpu):
    """Run once per device (cached), and the verdict is the decision on the reads it made. The isotropic sampler
    follows the gradients on every adapter (the trilinear filter's twin test relies on it). On lavapipe the
    anisotropic sampler reads one value whatever the gradients: not honoured, and the note names the adapter."""
    probe = explicit_gradient_probe(gpu)
    assert explicit_gradient_probe(gpu) is probe
    assert all(np.isfinite(list(reads.values())).all() for reads in (probe.isotropic, probe.anisotropic))
    assert explicit_gradient_support(gpu) == (ignored_gradients(probe.isotropic, probe.anisotropic) == [])
    assert probe.isotropic["tiny"] == pytest.approx(1.0, abs=0.02)
    assert probe.isotropic["huge"] == pytest.approx(0.5, abs=0.02)
    note = explicit_gradient_note(gpu)
    assert (note == "") == explicit_gradient_support(gpu)
    for kind in SAMPLER_KINDS:
        assert explicit_gradient_support(gpu, kind) == probe.honoured_by(kind)
        assert (explicit_gradient_note(gpu, kind) == "") == probe.honoured_by(kind)
    if "llvmpipe" in gpu.summary:
        aniso = probe.anisotropic
        assert aniso["tiny"] == aniso["huge"] == aniso["thin"] == aniso["round"]
        assert not explicit_gradient_support(gpu) and not explicit_gradient_support(gpu, "anisotropic")
        assert explicit_gradient_support(gpu, "isotropic")
        assert note == explicit_gradient_note(gpu, "anisotropic")
        assert note.startswith(gpu.summary) and note.endswith("through an anisotropic sampler there is not measured "
                                                              "validly.")
