"""float64 twins of WGSL searches that tests compare the GPU against (beyond wgpuviewer.relief.reference's exact hit)."""

from __future__ import annotations

import numpy as np

from wgpuviewer.core.sampling import bilinear


def pom_from(height, uv0, view, height_scale, t0, n, depth_range):
    """float64 POM over [max(t0, lo), hi] (n layers, bilinear repeat sampling; (lo, hi): the map's depth range):
    pom_search's arithmetic."""
    span = view[:, :2] / view[:, 2:3] * height_scale
    depth = 1.0 - height
    t0 = np.clip(np.maximum(t0, depth_range[0]), 0.0, 1.0)
    step = (np.maximum(depth_range[1], t0) - t0) / n
    t_hit = np.full(len(uv0), np.nan)
    prev = None
    for i in range(n + 1):
        t = t0 + i * step
        d = bilinear(depth, uv0 - span * t[:, None])
        if prev is None:
            first = t >= d
            t_hit[first] = t0[first]
        else:
            new = np.isnan(t_hit) & (t >= d)
            after, before = d - t, prev - (t - step)
            w = np.clip(after / np.where(after - before < -1e-12, after - before, -1.0), 0.0, 1.0)
            t_hit[new] = (t - w * step)[new]
        prev = d
    return t_hit


#: The ways the relief search ends on its final bracket [free, solid] (common/binary.wgsl): the solid end, the
#: midpoint, or the secant through the two ends' depths (no fetch beyond the search's own in any of them).
RELIEF_FINISHES = ("solid", "midpoint", "secant")


def relief_from(height, uv0, view, height_scale, linear_steps, binary_steps, depth_range, finish="secant",
                t_range=None):
    """float64 relief search: ``linear_steps`` equal layers of the depth range (lo, hi) (``t_range``: another
    interval to march, e.g. (0, 1) for the textbook search over the whole depth), the bracket [last layer above,
    first layer on or below] halved ``binary_steps`` times, then ``finish`` (RELIEF_FINISHES). Returns the layer
    depth t of the result and the fetches per ray (every ray on every path: the finish costs none)."""
    span = view[:, :2] / view[:, 2:3] * height_scale
    depth = 1.0 - height
    lo, hi = depth_range if t_range is None else t_range
    step = (hi - lo) / linear_steps

    def depth_at(t):
        return bilinear(depth, uv0 - span * t[:, None])

    n = len(uv0)
    t_solid, d_solid = np.full(n, lo), depth_at(np.full(n, lo))
    t_free, d_free = t_solid.copy(), d_solid.copy()
    layer = np.zeros(n, np.int64)
    searching = t_solid < d_solid
    fetches = np.ones(n, np.int64)
    for i in range(1, linear_steps + 1):
        if not searching.any():
            break
        t = np.full(n, lo + i * step)
        d = np.where(searching, depth_at(t), d_solid)
        t_free = np.where(searching, t_solid, t_free)
        d_free = np.where(searching, d_solid, d_free)
        t_solid = np.where(searching, t, t_solid)
        d_solid = np.where(searching, d, d_solid)
        fetches += searching
        layer = np.where(searching, i, layer)
        searching &= t < d
    bracketed = layer > 0  # layer 0: the entry point is on or below the surface, the result is lo
    for _ in range(binary_steps):
        mid = 0.5 * (t_free + t_solid)
        d = depth_at(mid)
        solid = mid >= d
        t_solid, d_solid = np.where(solid, mid, t_solid), np.where(solid, d, d_solid)
        t_free, d_free = np.where(solid, t_free, mid), np.where(solid, d_free, d)
    fetches += binary_steps * bracketed
    if finish == "solid":
        t_hit = t_solid
    elif finish == "midpoint":
        t_hit = 0.5 * (t_free + t_solid)
    elif finish == "secant":  # the line through (t_free, d_free) and (t_solid, d_solid) meets t = d
        above, below = d_free - t_free, d_solid - t_solid  # > 0 and <= 0 where bracketed
        w = np.clip(above / np.where(bracketed, above - below, 1.0), 0.0, 1.0)
        t_hit = t_free + w * (t_solid - t_free)
    else:
        raise ValueError(f"finish = {finish!r}: expected one of {RELIEF_FINISHES}")
    return np.where(bracketed, t_hit, lo), fetches


def contact_from(height, uv0, view, height_scale, linear_steps, refine_steps, depth_range):
    """float64 contact-refinement search (techniques/contact/contact.wgsl): ``linear_steps`` equal layers of the
    depth range (lo, hi), then sub-steps 1 .. refine_steps - 1 of the bracket [last layer above, first layer on or
    below] up to the first one on or below the surface, then relief's secant through the final sub-bracket. Returns
    the layer depth t of the result and the fetches per ray."""
    span = view[:, :2] / view[:, 2:3] * height_scale
    depth = 1.0 - height
    lo, hi = depth_range
    step = (hi - lo) / linear_steps

    def depth_at(t):
        return bilinear(depth, uv0 - span * t[:, None])

    n = len(uv0)
    t_solid, d_solid = np.full(n, lo), depth_at(np.full(n, lo))
    t_free, d_free = t_solid.copy(), d_solid.copy()
    fetches = np.ones(n, np.int64)
    searching = t_solid < d_solid
    bracketed = searching.copy()  # else the entry point is on or below the surface: the result is lo
    for i in range(1, linear_steps + 1):
        t = np.full(n, lo + i * step)
        d = np.where(searching, depth_at(t), d_solid)
        t_free, d_free = np.where(searching, t_solid, t_free), np.where(searching, d_solid, d_free)
        t_solid, d_solid = np.where(searching, t, t_solid), np.where(searching, d, d_solid)
        fetches += searching
        searching &= t < d
    base, sub = t_free.copy(), (t_solid - t_free) / refine_steps
    refining = bracketed.copy()
    for k in range(1, refine_steps):
        t = base + k * sub
        d = np.where(refining, depth_at(t), 0.0)
        fetches += refining
        solid = refining & (t >= d)
        t_solid, d_solid = np.where(solid, t, t_solid), np.where(solid, d, d_solid)
        free = refining & ~solid
        t_free, d_free = np.where(free, t, t_free), np.where(free, d, d_free)
        refining = free
    above, below = d_free - t_free, d_solid - t_solid
    w = np.clip(above / np.where(bracketed & (above - below > 0), above - below, 1.0), 0.0, 1.0)
    w = np.where(above - below > 0, w, 0.0)
    return np.where(bracketed, t_free + w * (t_solid - t_free), lo), fetches
