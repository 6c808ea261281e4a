"""Timing primitives: compile time apart from run time, repetitions, median and spread."""

from __future__ import annotations

import statistics
import time
from dataclasses import asdict, dataclass

import jax


@dataclass(frozen=True)
class Timing:
    """Wall-clock seconds of repeated runs of one workload (after compilation)."""

    n: int  # candidates per run
    median_s: float
    min_s: float
    max_s: float
    reps: int
    compile_s: float = 0.0

    @property
    def rate(self) -> float:
        """Candidates per second at the median run time."""
        return self.n / self.median_s

    @property
    def rate_spread(self) -> tuple[float, float]:
        """(slowest, fastest) candidates per second over the repetitions."""
        return self.n / self.max_s, self.n / self.min_s

    def to_dict(self) -> dict:
        d = asdict(self)
        d["rate"] = self.rate
        d["rate_lo"], d["rate_hi"] = self.rate_spread
        return d


def _block(x):
    return jax.block_until_ready(x)


def time_call(fn, n: int, reps: int = 5, min_time: float = 0.0) -> Timing:
    """Time ``fn()`` (compiled and warmed) ``reps`` times; a run repeats until ``min_time`` s."""
    _block(fn())
    runs = []
    for _ in range(reps):
        k, t0 = 0, time.perf_counter()
        while True:
            _block(fn())
            k += 1
            dt = time.perf_counter() - t0
            if dt >= min_time:
                break
        runs.append(dt / k)
    return Timing(n, statistics.median(runs), min(runs), max(runs), reps)


def time_jax(jitted, args, n: int, reps: int = 5, min_time: float = 0.05) -> Timing:
    """Compile ``jitted`` for ``args`` (timed separately), then time steady-state calls."""
    t0 = time.perf_counter()
    compiled = jitted.lower(*args).compile()
    compile_s = time.perf_counter() - t0
    t = time_call(lambda: compiled(*args), n, reps=reps, min_time=min_time)
    return Timing(t.n, t.median_s, t.min_s, t.max_s, t.reps, compile_s)
