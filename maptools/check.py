"""``maptools check``: each kind's GPU map against its CPU reference with the kind's tolerance. The GPU map is always
computed whole; where the CPU reference is slow (minutes on a 512^2 map), it is computed at a stated, seeded random
sample of values only and compared there, unless the whole comparison is asked for."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from .registry import Comparison, all_kinds, get_kind


def sampled_kinds() -> list[str]:
    """The kinds whose CPU reference is sampled by default (``Kind.sampled``)."""
    return [name for name, kind in all_kinds().items() if kind.sampled is not None]


#: Values sampled per sampled kind by default: on a 512^2 map each sampled CPU reference then takes 1-2 s on 2 cores
#: (distance 1.6 s, cone 0.9 s on camera.png), against 43 s and 13 s for the whole references.
DEFAULT_SAMPLE = 4096
DEFAULT_SEED = 0


def sample_index(shape: tuple[int, ...], n: int, seed: int) -> tuple[np.ndarray, ...]:
    """``min(n, size)`` distinct positions of an array of ``shape``, drawn uniformly with ``seed``, in memory order,
    as a tuple of index arrays."""
    size = math.prod(shape)
    flat = np.sort(np.random.default_rng(seed).choice(size, size=min(n, size), replace=False))
    return np.unravel_index(flat, shape)


def value_count(result) -> int:
    """Values in a map (a maximum pyramid: over all its levels)."""
    return sum(np.size(a) for a in result) if isinstance(result, list) else int(np.size(result))


@dataclass(frozen=True)
class KindCheck:
    kind: str
    comparison: Comparison
    compared: int  # values compared
    total: int  # values in the map
    sampled: bool  # compared at a random sample (else every value)
    gpu_s: float
    cpu_s: float

    def describe(self, seed: int) -> str:
        """Where the comparison looked and what each side cost."""
        where = (f"CPU reference at {self.compared} of {self.total} values, random with seed {seed}" if self.sampled
                 else f"all {self.total} values")
        return f"{where}; GPU {self.gpu_s:.2f} s, CPU {self.cpu_s:.2f} s"


def check_kind(name: str, height: np.ndarray, opts: dict, sample: int | None, seed: int,
               progress: Callable[[str], None] = lambda phase: None) -> KindCheck:
    """Kind ``name``'s GPU map of ``height`` against its CPU reference: at ``sample`` random values (seed ``seed``)
    when the kind has a sampled reference and the map holds more values, else at every value (``sample`` None:
    always). ``progress`` hears each phase before it starts."""
    kind = get_kind(name)
    progress("GPU")
    t0 = time.perf_counter()
    gpu_map = kind.gpu(height, **opts)
    gpu_s = time.perf_counter() - t0
    total = value_count(gpu_map)
    sampled = kind.sampled if sample is not None and sample < total else None
    progress("CPU sample" if sampled else "CPU")
    t0 = time.perf_counter()
    if sampled is None:
        c = kind.compare(kind.cpu(height, **opts), gpu_map, opts)
        compared = total
    else:
        shape = sampled.shape(height.shape, opts)
        if np.shape(gpu_map) != shape:
            c = Comparison(math.inf, math.inf, False, f"GPU map shape {np.shape(gpu_map)}, expected {shape}")
        else:
            index = sample_index(shape, sample, seed)
            c = kind.compare(sampled.values(height, index, **opts), np.asarray(gpu_map)[index], opts)
        compared = sample
    return KindCheck(name, c, compared, total, sampled is not None, gpu_s, time.perf_counter() - t0)


def check_kinds(height: np.ndarray, kinds: list[str], options: dict[str, dict], sample: int | None, seed: int,
                progress: Callable[[str, int, int], None] = lambda label, done, total: None) -> Iterator[KindCheck]:
    """``check_kind`` for each kind in turn; ``progress(label, done, total)`` counts the phases (two per kind)."""
    total = 2 * len(kinds)
    for n, name in enumerate(kinds):
        def phase(what: str, name=name, first=2 * n) -> None:
            progress(f"{name}: {what}", first + (what != "GPU"), total)

        yield check_kind(name, height, options[name], sample, seed, phase)
    progress("done", total, total)
