"""The cost measures of relief/accuracy.py."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.errors import InputError
from wgpuviewer.relief.accuracy import simd_tile_cost


def test_simd_tile_cost_is_the_mean_of_tile_maxima():
    f = np.zeros((4, 16))
    f[0, 0] = 10  # one slow lane makes its whole 8x4 tile pay 10
    f[:, 8:] = 3
    assert simd_tile_cost(f) == pytest.approx((10 + 3) / 2)
    assert simd_tile_cost(f, tile=(1, 1)) == pytest.approx(f.mean())  # one lane per group: the plain mean


def test_simd_tile_cost_partial_tiles_and_coverage():
    f = np.arange(5 * 9, dtype=float).reshape(5, 9)
    # tiles (8x4): rows 0-3 x cols 0-7, 0-3 x 8, 4 x 0-7, 4 x 8
    expected = np.mean([f[0:4, 0:8].max(), f[0:4, 8].max(), f[4, 0:8].max(), f[4, 8]])
    assert simd_tile_cost(f) == pytest.approx(expected)
    covered = np.zeros_like(f, bool)
    covered[0, 0] = True
    assert simd_tile_cost(f, covered=covered) == 0.0  # only the covered lane counts, in the only live tile
    assert np.isnan(simd_tile_cost(f, covered=np.zeros_like(covered)))
    with pytest.raises(InputError):
        simd_tile_cost(np.zeros(5))
