"""Several ray batches through one probe call. Each call builds the technique's bind group: its height-derived maps
read back from the map cache and uploaded (the 3D distance volumes are megabytes), so a test that traces several
angles or azimuths traces them in one call and checks each batch on its own. Every ray is traced on its own, so a
batch's hits are the ones a call of its own gives."""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from wgpuviewer.relief.probe import ProbeResult, probe


def probe_batches(technique: str, height: np.ndarray, batches: list[tuple[np.ndarray, np.ndarray]],
                  height_scale: float = 0.05, **params) -> list[ProbeResult]:
    """``probe`` of every (uv, view) batch in ``batches`` in one call; the results in the order of ``batches``."""
    uvs = [np.asarray(u, np.float64).reshape(-1, 2) for u, _ in batches]
    views = [np.asarray(v, np.float64).reshape(-1, 3) for _, v in batches]
    assert all(len(u) == len(v) for u, v in zip(uvs, views)), "a batch needs one view per entry point"
    got = probe(technique, height, np.concatenate(uvs), np.concatenate(views), height_scale, **params)
    cuts = np.cumsum([len(u) for u in uvs])[:-1]
    parts = {f.name: np.split(getattr(got, f.name), cuts) for f in fields(ProbeResult)}
    return [ProbeResult(**{name: split[i] for name, split in parts.items()}) for i in range(len(batches))]
