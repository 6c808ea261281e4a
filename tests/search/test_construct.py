"""The one greedy strategy: first least cost per decision, lazy decisions, the deadline."""

from __future__ import annotations

import math

import numpy as np

from jaxspline.base import clock
from jaxspline.search.construct import first_least, greedy_pass


def test_first_least_takes_the_earliest_of_equal_costs():
    assert first_least([]) == -1
    assert first_least(np.zeros(0)) == -1
    assert first_least([3.0, 1.0, 2.0, 1.0]) == 1
    assert first_least([0.0, -0.0]) == 0  # equal costs: the earlier candidate
    assert first_least([-math.inf, 5.0, -math.inf]) == 0
    assert first_least(np.array([2.0, -1.0, -1.0, 0.5])) == 1
    rng = np.random.default_rng(0)
    for _ in range(200):  # the list and the array paths agree, with many ties
        c = rng.integers(-3, 3, size=int(rng.integers(1, 9))).astype(float)
        ref = min(range(c.size), key=lambda k: (c[k], k))
        assert first_least(c.tolist()) == first_least(c) == ref


def test_greedy_pass_reads_each_decision_after_the_previous_commit():
    """A chain of decisions that depend on the commits: pick the smallest number
    greater than the last one picked; the decisions end when one commits nothing."""
    pool = [5, 3, 8, 1, 9, 4]
    path: list[int] = []

    def decisions():
        while True:
            n = len(path)
            yield path[-1] if path else -math.inf
            if len(path) == n:
                return

    def choices(last):
        cands = [x for x in pool if x > last]
        return cands, [float(x) for x in cands]

    assert greedy_pass(decisions(), choices, path.append) == len(pool)
    assert path == sorted(pool)


def test_greedy_pass_deadline_and_stop():
    taken: list[int] = []

    def choices(d):
        return [d], [0.0]

    # a passed deadline: no decision at all; +inf: every one, even after a stop request
    assert greedy_pass(range(10), choices, taken.append, deadline=-math.inf) == 0
    assert taken == []
    clock.request_stop()
    try:
        assert greedy_pass(range(200), choices, taken.append) == 200
        taken.clear()
        assert greedy_pass(range(200), choices, taken.append, deadline=1e300) == 0
    finally:
        clock.clear_stop()
    none = greedy_pass(range(5), lambda d: ([], []), taken.append)
    assert none == 0 and taken == []
