"""Satellite sweeps against independent references.

References: a longest path over every pair of a satellite's options in start order (the
best sequence over the targets no other satellite images, transitions by the problem's
rules, O(n^2)), and a from-scratch re-simulation of the battery (:mod:`test_timeline_battery`).
"""

from __future__ import annotations

import itertools
import math
import random

import numpy as np
import pytest
from test_timeline_battery import DT, _problem, _resimulate, assemble

from jaxspline.search import BatteryModel, Timeline, greedy
from jaxspline.search.dp import dp_prepare
from jaxspline.search.sweep import sweep, sweeps


def _no_repeat_problem(rng, n_sats=3, n_targets=40, horizon=600.0, far=40.0):
    """No battery; each target has at most one option per satellite (so a satellite's
    best sequence never images a target twice); near pairs as the screen stores them
    (feasible: required time <= gap; the others left out)."""
    opts = []
    for t in range(n_targets):
        for k in rng.choice(n_sats, size=int(rng.integers(1, n_sats + 1)), replace=False):
            s = float(rng.integers(0, int(horizon) - 40))
            opts.append((int(k), s, s + float(rng.integers(2, 25)), t))
    opts.sort()
    n = len(opts)
    sat = [o[0] for o in opts]
    near = {}
    for i, j in itertools.product(range(n), repeat=2):
        gap = opts[j][1] - opts[i][2]
        if sat[i] == sat[j] and 0.0 <= gap < far and rng.random() < 0.8:
            near[i * n + j] = float(rng.uniform(0.0, gap))  # stored pairs are feasible
    n_steps = int(horizon / DT)
    battery = BatteryModel(np.ones((n_sats, n_steps + 1), bool), [None] * n_sats, DT)
    return assemble(rng, opts, near, n_sats, n_targets, far, battery)


def _fits(pb, seq) -> list | None:
    """Maneuver times of the sequence ``seq`` (start order) by the rules, None when a
    transition is too short."""
    man = []
    for i, x in enumerate(seq):
        need = pb.option_first[x] if i == 0 else pb.need(seq[i - 1], x)
        gap = pb.option_start[x] - (0.0 if i == 0 else pb.option_end[seq[i - 1]])
        if gap < need:
            return None
        man.append(need)
    return man


def _best_alone(pb, assigned, k) -> float:
    """Satellite k's best sequence over the targets no other satellite images: longest
    path over its options in start order, every pair tried (O(n^2), by the rules)."""
    taken = {t for t, c in enumerate(assigned) if c >= 0 and pb.option_sat[c] != k}
    ids = [c for c in range(pb.sat_lo[k], pb.sat_hi[k]) if pb.option_target[c] not in taken]
    ids.sort(key=lambda c: pb.option_start[c])
    best = {}
    for j in ids:
        w = pb.target_value[pb.option_target[j]]
        v = w if pb.option_first[j] <= pb.option_start[j] else -math.inf
        for i in ids:
            if i in best and pb.option_start[j] - pb.option_end[i] >= max(pb.need(i, j), 0.0):
                v = max(v, best[i] + w)
        best[j] = v
    return max([0.0, *best.values()])


@pytest.mark.parametrize("empty", [False, True])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_sweeps_end_with_every_satellite_at_its_best_sequence(seed, empty):
    """No battery, no repeats: when the sweeps stop, each satellite's plan is worth what
    the best sequence over the targets the others leave it is worth (from a greedy start
    in random target order, where some satellite is below it, or from the empty plan,
    as the search's start)."""
    rng = np.random.default_rng(seed)
    pb = _no_repeat_problem(rng)
    tl = Timeline(pb)
    order = list(range(pb.n_targets))
    random.Random(seed).shuffle(order)  # a start far from each satellite's best
    if not empty:
        greedy(tl, math.inf, order)
    start = tl.value
    rounds = sweeps(tl, dp_prepare(pb), math.inf, random.Random(seed))
    assert 1 <= rounds < 30
    assert tl.value >= start
    for k in range(pb.n_sats):
        own = sum(pb.target_value[pb.option_target[c]] for c in tl.lines[k])
        assert own == pytest.approx(_best_alone(pb, tl.assigned, k)), k
    assert tl.value > start


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sweep_never_lowers_the_score_and_keeps_the_battery(seed):
    """With batteries that bind: every round keeps or raises the score, and the plan's
    maneuvers and battery (re-simulated from scratch) still hold."""
    rng = np.random.default_rng(50 + seed)
    n_steps = int(rng.integers(80, 200))
    pb, lit = _problem(rng, n_steps, n_sats=3, n_targets=80)
    tl = Timeline(pb)
    greedy(tl, math.inf)
    d = dp_prepare(pb)
    py = random.Random(seed)
    for _ in range(4):
        before = tl.score()
        sweep(tl, d, py)
        assert tl.score() >= before
    for k in range(pb.n_sats):
        seq = tl.lines[k]
        man = _fits(pb, seq)
        assert man is not None
        obs = [(pb.option_start[c], pb.option_end[c], m) for c, m in zip(seq, man, strict=True)]
        level = _resimulate(pb.battery.powers[k], lit[k], obs, n_steps)
        assert level.min() >= pb.battery.margin_wh - 1e-9
    assigned = [c for c in tl.assigned if c >= 0]
    assert len(assigned) == len({pb.option_target[c] for c in assigned})
