"""The CPU cone map's progress (maptools.kinds.cone.cpu): ``raw_ratio`` reports the texels settled before each ring,
and ``cone`` feeds them to a terminal progress bar (``core.commands.terminal_progress``), so a 2048x2048 map on the
CPU (tens of seconds) shows how far it is."""

from __future__ import annotations

import numpy as np

from maptools.kinds.cone import cpu


def test_the_ring_walk_reports_the_texels_settled(monkeypatch):
    y, x = np.mgrid[0:32, 0:48]
    height = 0.5 + 0.5 * np.sin(2 * np.pi * x / 48) * np.cos(2 * np.pi * y / 32)  # smooth: texels settle over rings
    calls = []
    raw = cpu.raw_ratio(cpu.depth_of(height), 8.0, progress=lambda done, total: calls.append((done, total)))
    assert np.array_equal(raw, cpu.raw_ratio(cpu.depth_of(height), 8.0))  # reporting changes nothing
    done = [d for d, _ in calls]
    assert calls[0] == (0, 32 * 48) and {t for _, t in calls} == {32 * 48}
    assert done == sorted(done) and len(calls) > 2

    bars = []

    class Bar:
        def __init__(self, what, unit):
            bars.append((what, unit))

        def __enter__(self):
            return lambda label, done, total: bars.append((done, total))

        def __exit__(self, *exc):
            return False

    monkeypatch.setattr(cpu, "terminal_progress", Bar)
    cpu.cone(height, max_ratio=8.0)
    assert bars[0] == ("cone (CPU)", "texel") and bars[1:] == calls
