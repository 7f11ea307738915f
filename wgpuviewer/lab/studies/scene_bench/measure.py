"""The scene benchmark's per-pixel measures of one view: what a technique's render differs by from the exact tracer's
render of the same view, at the same pixels.

- the footprint: each pixel's 2x2 screen-to-uv Jacobian, from finite differences of the unrelieved surface's uv
  (``basic``'s hit uv: the entry point of every pixel's ray); of the forward and backward difference the shorter is
  taken, so a pixel beside an object's edge or a uv seam still gets the difference across its own surface, and a
  pixel whose neighbours on an axis are both uncovered has none (left out);
- the hit error in screen pixels: the uv difference of the technique's and the exact tracer's hits mapped through
  the inverse Jacobian (uv -> pixels), over the pixels both cover where the exact ray was not capped;
- NVIDIA FLIP (``flip_evaluator``, LDR, sRGB input, its default 67 pixels per degree) and the PSNR of the colour
  images, over the pixels either covers (a silhouette one of them lacks counts);
- fetches: mean and SIMD-tile (``relief.accuracy.simd_tile_cost``: per 8x4 tile the slowest lane's), over the
  pixels the technique covers.
"""

from __future__ import annotations

import numpy as np

from wgpuviewer.core.errors import UserError
from wgpuviewer.relief.accuracy import simd_tile_cost

#: Nothing drawn or a footprint too degenerate to invert (uv per pixel below this determinant): no pixel error.
MIN_DETERMINANT = 1e-14


def _difference(uv: np.ndarray, covered: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """d uv / d pixel along ``axis`` (1: x, 0: y) and where it exists: the shorter of the forward and backward
    differences whose both pixels are covered."""
    forward, backward = np.full(uv.shape, np.inf), np.full(uv.shape, np.inf)
    ahead = [slice(None), slice(None)]
    behind = [slice(None), slice(None)]
    ahead[axis], behind[axis] = slice(1, None), slice(None, -1)
    step = uv[tuple(ahead)] - uv[tuple(behind)]
    both = covered[tuple(ahead)] & covered[tuple(behind)]
    step = np.where(both[..., None], step, np.inf)
    forward[tuple(behind)] = step
    backward[tuple(ahead)] = step
    use_forward = np.linalg.norm(forward, axis=-1) <= np.linalg.norm(backward, axis=-1)
    chosen = np.where(use_forward[..., None], forward, backward)
    return chosen, np.isfinite(chosen).all(axis=-1)


def inverse_footprint(uv: np.ndarray, covered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H, W, 2, 2) pixels per uv (the inverse of [[du/dx, du/dy], [dv/dx, dv/dy]]) and (H, W) where it exists."""
    uv = np.asarray(uv, np.float64)
    dx, ok_x = _difference(uv, covered, 1)
    dy, ok_y = _difference(uv, covered, 0)
    jacobian = np.stack([dx, dy], axis=-1)  # columns: d uv / dx, d uv / dy
    ok = covered & ok_x & ok_y
    jacobian[~ok] = np.eye(2)
    det = np.linalg.det(jacobian)
    ok &= np.abs(det) > MIN_DETERMINANT
    jacobian[~ok] = np.eye(2)
    return np.linalg.inv(jacobian), ok


def pixel_errors(uv: np.ndarray, uv_exact: np.ndarray, inverse: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Hit error in screen pixels at the pixels of ``mask``: |J^-1 (uv - uv_exact)|."""
    delta = (np.asarray(uv, np.float64) - np.asarray(uv_exact, np.float64))[mask]
    return np.linalg.norm(np.einsum("nij,nj->ni", inverse[mask], delta), axis=-1)


def flip_map(color: np.ndarray, color_exact: np.ndarray) -> np.ndarray:
    """(H, W) FLIP error of ``color`` against ``color_exact`` ((H, W, 3) uint8 sRGB)."""
    try:
        import flip_evaluator
    except ImportError:
        raise UserError("the scene benchmark's FLIP needs flip-evaluator: pip install 'wgpuviewer[bench]'") from None

    error, _, _ = flip_evaluator.evaluate(color_exact.astype(np.float32) / 255.0, color.astype(np.float32) / 255.0,
                                          "LDR", inputsRGB=True, applyMagma=False, computeMeanError=False)
    return np.asarray(error, np.float64).reshape(color.shape[:2])


def psnr_db(color: np.ndarray, color_exact: np.ndarray, mask: np.ndarray) -> float:
    """PSNR of the sRGB colour (peak 1) over ``mask``; inf for identical pictures, NaN for an empty mask."""
    if not mask.any():
        return float("nan")
    diff = (color.astype(np.float64) - color_exact.astype(np.float64))[mask] / 255.0
    mse = float(np.mean(diff * diff))
    return float("inf") if mse == 0.0 else float(10.0 * np.log10(1.0 / mse))


def fetch_counts(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) depth fetches of a render's data target (capped rays are stored negative) and (H, W) capped."""
    raw = data[:, :, 3]
    capped = raw < 0
    return np.where(capped, -raw - 1.0, raw).astype(np.float64), capped


def fetch_stats(data: np.ndarray, covered: np.ndarray) -> dict:
    """fetches_mean and fetches_simd over the covered pixels, and the fraction of capped rays."""
    fetches, capped = fetch_counts(data)
    n = int(covered.sum())
    return {"fetches_mean": float(fetches[covered].mean()) if n else float("nan"),
            "fetches_simd": simd_tile_cost(fetches, covered=covered),
            "capped": float((capped & covered).sum() / n) if n else float("nan")}


def compare(image, exact, inverse: np.ndarray, footprint_ok: np.ndarray, exact_capped: np.ndarray) -> tuple[dict, np.ndarray]:
    """The row's measures of ``image`` (an OffscreenImage) against ``exact`` (the exact tracer's, same view) and
    the FLIP map."""
    both = image.covered & exact.covered & footprint_ok & ~exact_capped
    either = image.covered | exact.covered
    errors = pixel_errors(image.data[:, :, :2], exact.data[:, :, :2], inverse, both)
    flip = flip_map(image.color[:, :, :3], exact.color[:, :, :3])
    has = errors.size > 0
    row = {
        "px_err_p50": float(np.percentile(errors, 50)) if has else float("nan"),
        "px_err_p95": float(np.percentile(errors, 95)) if has else float("nan"),
        "px_err_over_half": float(np.mean(errors > 0.5)) if has else float("nan"),
        "flip_mean": float(flip[either].mean()) if either.any() else float("nan"),
        "psnr_db": psnr_db(image.color[:, :, :3], exact.color[:, :, :3], either),
        "pixels": int(both.sum()),
        "silhouette": float((image.covered != exact.covered).sum() / max(int(either.sum()), 1)),
        **fetch_stats(image.data, image.covered),
    }
    return row, flip

