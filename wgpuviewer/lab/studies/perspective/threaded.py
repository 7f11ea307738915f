"""The paper's parallel forms on real threads (numba ``prange``): are k interleaved threads per span, or two threads
from both ends, faster than one pixel at a time on a CPU's cores?

Two placements, each a scalar build (LLVM's vectorisers off, as ``compiled``'s scalar build: the threads are the
only parallelism):

- ``lanes``: the paper's own form: within each span, ``parallel_k``'s k lanes (or ``two_ended``'s two ends) are the
  iterations of a ``prange``, so the span's pixels are shared out among the threads;
- ``spans``: any method's span loop, unchanged, with the spans shared out among the threads (what a CPU renderer
  does with rows), for ``direct``, ``incremental`` and the parallel forms alike.

Both write the scalar build's uv and flags bit for bit (``check``; a test pins it). ``measure`` times them at 1, 2
and all of the machine's threads, round robin with the single-threaded ``scalar`` and ``simd`` builds of
``compiled`` on the same frame, and gives ``threads.csv``'s rows (``THREADS_TABLE``)."""

from __future__ import annotations

import os
import time

import numpy as np

from wgpuviewer.lab.harness.table import Column, Table

from .compiled import _vectorisers, arguments, build, numba_module
from .geometry import Spans
from .loops import MAX_LANES, helpers, loop_sources
from .methods import METHODS, Result

#: The methods timed on threads: the paper's parallel forms and the two baselines.
THREADED = ("direct", "incremental", *(n for n in METHODS if n.startswith("parallel_")), "two_ended")
PLACEMENTS = ("lanes", "spans")
CHUNKS_PER_THREAD = 4  # spans placement: span blocks per thread (uneven rows still balance)

THREADS_TABLE = Table("perspective threads", (
    Column("method", str), Column("placement", str, "lanes: a span's lanes on threads; spans: spans on threads; "
                                                     "scalar / simd: compiled's single-threaded builds"),
    Column("threads", int), Column("cores", int, "the machine's logical CPUs"),
    Column("span_length", int, "pixels"), Column("spans", int),
    Column("ns_per_texel", float, "ns, median over repeats"), Column("spread", float, "IQR / median"),
    Column("ratio_scalar_direct", float, "x the scalar build's direct, same round"),
    Column("speedup", float, "x the same method and placement at 1 thread, same round"),
    Column("identical", bool, "uv and flags equal the scalar build's bit for bit"),
))


def _lane_loops(jit, ftype):
    """parallel_k with its lanes, and two_ended with its two ends, as prange iterations within each span."""
    from numba import prange

    h = helpers(jit, ftype)
    put, span, advance = h.put, h.span, h.advance

    def parallel(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        lanes = min(max(param, 1), MAX_LANES)
        stride_u, stride_v, stride_q = au * ftype(lanes), av * ftype(lanes), aq * ftype(lanes)
        length = out_u.shape[1]
        for s in range(x0.size):
            su, sv, sq, lo, hi = span(k, x0, y, first, end, s)
            for j in prange(lanes):
                wu, wv, q = su, sv, sq
                for _ in range(j):  # lane j starts j steps of formula (4) along, as the scalar loop starts it
                    wu, wv, q = advance(wu, wv, q, au, av, aq)
                for n in range(j, length, lanes):
                    put(out_u[s], out_v[s], out_f[s], n, wu, wv, q, (n >= lo) & (n < hi))
                    wu, wv, q = wu + stride_u, wv + stride_v, q + stride_q

    def two_ended(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        au, av, aq = k[0, 0], k[1, 0], k[2, 0]
        length = out_u.shape[1]
        half = (length + 1) // 2
        last = ftype(length - 1)
        for s in range(x0.size):
            su, sv, sq, lo, hi = span(k, x0, y, first, end, s)
            for e in prange(2):
                if e == 0:
                    wu, wv, q = su, sv, sq
                    for n in range(half):
                        put(out_u[s], out_v[s], out_f[s], n, wu, wv, q, (n >= lo) & (n < hi))
                        wu, wv, q = advance(wu, wv, q, au, av, aq)
                else:
                    wu, wv, q = su + au * last, sv + av * last, sq + aq * last
                    for i in range(length - half):
                        n = length - 1 - i
                        put(out_u[s], out_v[s], out_f[s], n, wu, wv, q, (n >= lo) & (n < hi))
                        wu, wv, q = advance(wu, wv, q, -au, -av, -aq)

    return {"parallel": parallel, "two_ended": two_ended}


def _span_loop(numba, inner):
    """``inner`` (a span loop) with the spans shared out among the threads in blocks."""
    prange, threads = numba.prange, numba.get_num_threads

    def loop(k, a_lo, ratio, fx_step, fx_start, x0, y, first, end, param, out_u, out_v, out_f):
        count = x0.size
        chunks = max(1, min(count, threads() * CHUNKS_PER_THREAD))
        for c in prange(chunks):
            a, b = c * count // chunks, (c + 1) * count // chunks
            inner(k, a_lo, ratio, fx_step, fx_start[a:b], x0[a:b], y[a:b], first[a:b], end[a:b], param,
                  out_u[a:b], out_v[a:b], out_f[a:b])
    return loop


class ThreadedBuild:
    """The threaded loops in float32, compiled when first asked for (``loop``)."""

    def __init__(self):
        self._loops: dict[tuple[str, str], object] = {}

    def loop(self, name: str, placement: str):
        numba = numba_module()
        kernel = METHODS[name].kernel
        if placement == "lanes" and kernel not in ("parallel", "two_ended"):
            raise ValueError(f"method {name}: only the parallel forms put lanes on threads")
        key = (kernel, placement)
        if key not in self._loops:
            jit = numba.njit(fastmath=False, error_model="numpy", nogil=True)
            pjit = numba.njit(fastmath=False, error_model="numpy", nogil=True, parallel=True)
            with _vectorisers(False):
                if placement == "lanes":
                    self._loops[key] = pjit(_lane_loops(jit, np.float32)[kernel])
                else:
                    self._loops[key] = pjit(_span_loop(numba, jit(loop_sources(jit, np.float32)[kernel])))
                args = arguments(name, np.eye(3), _tiny_spans())
                self._loops[key](*args.tuple())  # compiled now, with the vectorisers off
        return self._loops[key]


_SHARED: list[ThreadedBuild] = []


def threaded_build() -> ThreadedBuild:
    """The process's threaded loops (each compiled once per process, shared by every run and test)."""
    if not _SHARED:
        _SHARED.append(ThreadedBuild())
    return _SHARED[0]


def _tiny_spans() -> Spans:
    return Spans(np.zeros(2, np.int64), np.arange(2, dtype=np.int64), 4)


def check(threaded: ThreadedBuild, name: str, placement: str, coefficients, spans: Spans) -> bool:
    """Whether the threaded loop writes the scalar build's uv and flags bit for bit on ``spans``."""
    want = arguments(name, coefficients, spans)
    build("scalar").loop(METHODS[name].kernel, np.float32)(*want.tuple())
    got = arguments(name, coefficients, spans)
    threaded.loop(name, placement)(*got.tuple())
    return all(np.array_equal(a.view(np.uint8), b.view(np.uint8)) for a, b in
               ((got.u, want.u), (got.v, want.v), (got.flagged, want.flagged)))


def thread_counts() -> tuple[int, ...]:
    """1, 2 and every thread numba may use (numba's default: the machine's logical CPUs), without repeats."""
    return tuple(sorted({1, min(2, numba_module().config.NUMBA_NUM_THREADS), numba_module().config.NUMBA_NUM_THREADS}))


def _configurations(methods) -> list[tuple[str, str, int]]:
    """(method, placement, threads): the single-threaded builds, then every threaded loop at every thread count."""
    out = [(n, b, 1) for n in methods for b in ("scalar", "simd")]
    for t in thread_counts():
        out += [(n, "spans", t) for n in methods]
        out += [(n, "lanes", t) for n in methods if METHODS[n].kernel in ("parallel", "two_ended")]
    return out


def _callable(threaded: ThreadedBuild, name: str, placement: str, threads: int, args: tuple):
    numba = numba_module()
    if placement in ("scalar", "simd"):
        loop = build(placement).loop(METHODS[name].kernel, np.float32)
        return lambda: loop(*args)
    loop = threaded.loop(name, placement)

    def call():
        numba.set_num_threads(threads)
        loop(*args)
    return call


def measure(coefficients, spans: Spans, repeats: int, sample_seconds: float, methods=THREADED) -> list[dict]:
    """threads.csv's rows for ``methods`` (``direct`` first: the ratios' base): every configuration timed per texel,
    round robin (the order rotating each round), each sample a run of back-to-back calls lasting ``sample_seconds``."""
    numba = numba_module()
    threaded = threaded_build()
    configs = _configurations(methods)
    outputs = Result(*(np.empty((spans.count, spans.length), t) for t in (np.float32, np.float32, bool)))
    calls, counts = {}, {}
    for name, placement, threads in configs:
        call = _callable(threaded, name, placement, threads, arguments(name, coefficients, spans, outputs).tuple())
        call()  # warm-up
        t = time.perf_counter()
        call()
        calls[(name, placement, threads)] = call
        counts[(name, placement, threads)] = max(1, int(np.ceil(sample_seconds / max(time.perf_counter() - t, 1e-9))))
    samples = {c: [] for c in configs}
    texels = spans.count * spans.length
    for r in range(repeats):
        for c in configs[r % len(configs):] + configs[:r % len(configs)]:
            t = time.perf_counter()
            for _ in range(counts[c]):
                calls[c]()
            samples[c].append((time.perf_counter() - t) / counts[c] / texels * 1e9)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    ns = {c: np.array(s) for c, s in samples.items()}
    base = ns[("direct", "scalar", 1)]
    rows = []
    for name, placement, threads in configs:
        mine = ns[(name, placement, threads)]
        one = ns.get((name, placement, 1), mine)
        q75, q25 = np.percentile(mine, [75, 25])
        same = True if placement == "scalar" else check(threaded, name, placement, coefficients, spans) \
            if placement in PLACEMENTS else _simd_identical(name, coefficients, spans)
        rows.append({"method": name, "placement": placement, "threads": threads, "cores": os.cpu_count() or 1,
                     "span_length": spans.length, "spans": spans.count, "ns_per_texel": float(np.median(mine)),
                     "spread": float((q75 - q25) / np.median(mine)), "ratio_scalar_direct": float(np.median(mine / base)),
                     "speedup": float(np.median(one / mine)), "identical": bool(same)})
    return rows


def _simd_identical(name: str, coefficients, spans: Spans) -> bool:
    want, got = arguments(name, coefficients, spans), arguments(name, coefficients, spans)
    build("scalar").loop(METHODS[name].kernel, np.float32)(*want.tuple())
    build("simd").loop(METHODS[name].kernel, np.float32)(*got.tuple())
    return bool(np.array_equal(got.u, want.u) and np.array_equal(got.v, want.v)
                and np.array_equal(got.flagged, want.flagged))
