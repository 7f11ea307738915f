"""``maptools bench``: GPU vs CPU wall time per kind and size, side by side in one run (a kind with ``Kind.bench``
is timed at sizes of its own flag and with its options)."""

from __future__ import annotations

import functools
import time

import numpy as np

from wgpuviewer.core.errors import UserError

from . import gpu
from .registry import get_kind


def _sizes(text: str, flag: str) -> list[int]:
    try:
        sizes = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise UserError(f"{flag} {text!r}: expected comma-separated integers, e.g. 64,256") from None
    if any(n < 1 or n > 8192 for n in sizes):
        raise UserError(f"{flag} {text!r}: sizes must be in [1, 8192]")
    return sizes


def _best_time(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def cmd_bench(args, kinds: list[str]) -> int:
    """Best-of-N wall time of the CPU and GPU paths (GPU time includes upload and read-back)."""
    if args.repeat < 1:
        raise UserError(f"--repeat {args.repeat}: must be >= 1")
    g = gpu.runner()
    print(f"adapter: {g.gpu.summary}")
    print(f"{'kind':<17} {'size':>11} {'cpu s':>9} {'gpu s':>9} {'cpu/gpu':>8}")
    rng = np.random.default_rng(0)
    for k in kinds:
        kind = get_kind(k)
        attr, opts = (kind.bench.attr, kind.bench.options) if kind.bench else ("sizes", {})
        opts = kind.resolve(opts)
        for n in _sizes(getattr(args, attr), "--" + attr.replace("_", "-")):
            height = rng.random((n, n)).astype(np.float32)
            kind.gpu(height, **opts)  # warm-up: pipeline compilation
            tg = _best_time(functools.partial(kind.gpu, height, **opts), args.repeat)
            tc = _best_time(functools.partial(kind.cpu, height, **opts), args.repeat)
            size = f"{n}x{n}" + (f"x{opts['slices']}" if "slices" in opts else "")
            print(f"{k:<17} {size:>11} {tc:9.4f} {tg:9.4f} {tc / tg:8.2f}")
    return 0
