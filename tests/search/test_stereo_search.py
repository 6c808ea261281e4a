"""The search on stereo products, against brute force on small synthetic problems.

A synthetic problem: satellites with looks of stereo targets (random times and lines of
sight, a rest-to-rest slew law ``need = 2 + 10 theta`` s between looks), random products
(pairs and triples of one target's looks, random values) and a few point targets. The
references, written here from the definitions:

* a plan's value: each point target's value once, each stereo target's most valuable
  product whose looks are all in the plan;
* a plan's feasibility: per satellite no overlap and every gap at least the slew law's
  time between the two lines of sight;
* the optimum: every subset of looks and points of a tiny problem.
"""

from __future__ import annotations

import itertools
import math
import random
import time

import numpy as np
import pytest

from jaxspline.search import Timeline, greedy, lns
from jaxspline.search.battery import BatteryModel
from jaxspline.search.lagrangian import lagrangian
from jaxspline.search.problem import Problem
from jaxspline.search.stereo import (
    BACKUP_FAIL,
    ProductTable,
    add_backups,
    drop_stray_looks,
    upgrade_product,
)
from jaxspline.search.store import NearPairs

SLEW_S, SLEW_S_PER_RAD = 2.0, 10.0


class _Law:
    """The synthetic slew law as the problem's table (``scalar`` and vectorized call)."""

    def scalar(self, theta: float) -> float:
        return SLEW_S + SLEW_S_PER_RAD * theta

    def __call__(self, theta):
        return SLEW_S + SLEW_S_PER_RAD * np.asarray(theta)


def _unit(rng):
    v = rng.normal(size=3)
    v[2] = -abs(v[2]) - 2.0  # looking down-ish: angles of a few tens of degrees
    return tuple(v / np.linalg.norm(v))


def _angle(a, b) -> float:
    return math.acos(max(-1.0, min(1.0, float(np.dot(a, b)))))


def synth(seed: int, n_sats=2, n_stereo=4, looks_per=5, n_points=3, horizon=400.0, sure=True):
    """A random problem; returns (Problem, options). ``sure=False``: each product gets a
    random confidence in [0.5, 1]."""
    rng = np.random.default_rng(seed)
    opts = []  # (sat, start, end, target, los)
    n_t = n_points + n_stereo
    for t in range(n_points):
        for _ in range(2):
            s = float(rng.integers(0, int(horizon) - 10))
            opts.append((int(rng.integers(n_sats)), s, s + 5.0, t, _unit(rng)))
    for j in range(n_stereo):
        t = n_points + j
        for _ in range(looks_per):
            s = float(rng.integers(0, int(horizon) - 10))
            opts.append((int(rng.integers(n_sats)), s, s + 3.0, t, _unit(rng)))
    opts.sort(key=lambda o: (o[0], o[1], o[3]))
    n = len(opts)
    target_options = [[] for _ in range(n_t)]
    for c, o in enumerate(opts):
        target_options[o[3]].append(c)
    looks, ptarget, pvalue = [], [], []
    for j in range(n_stereo):
        t = n_points + j
        cands = target_options[t]
        for size in (2, 3):
            for combo in itertools.combinations(cands, size):
                if rng.random() < 0.35:
                    looks.append(combo)
                    ptarget.append(t)
                    pvalue.append(float(rng.uniform(0.5, 1.0)) * (1.1 if size == 3 else 1.0))
    stereo_targets = np.arange(n_points, n_t)
    conf = None if sure else np.random.default_rng(seed + 1).uniform(0.5, 1.0, len(looks))
    table = ProductTable(looks, ptarget, pvalue, [o[3] for o in opts], stereo_targets, n_t,
                         confidence=conf)  # fmt: skip
    point_value = [float(rng.uniform(0.5, 2.0)) for _ in range(n_points)]
    value = point_value + [table.best_value(int(t)) for t in stereo_targets]
    src, dst, need = [], [], []
    law = _Law()
    for i, a in enumerate(opts):
        for k, b in enumerate(opts):
            if a[0] != b[0] or i == k or a[3] >= n_points or b[3] >= n_points:
                continue
            gap = b[1] - a[2]
            req = law.scalar(_angle(a[4], b[4]))
            if 0.0 <= gap < 1e3 and gap >= req:
                src.append(i), dst.append(k), need.append(req)
    sat = [o[0] for o in opts]
    lo = [int(np.searchsorted(sat, k, "left")) for k in range(n_sats)]
    hi = [int(np.searchsorted(sat, k, "right")) for k in range(n_sats)]
    pb = Problem(
        n_sats=n_sats,
        target_value=value,
        option_target=[o[3] for o in opts],
        option_sat=sat,
        option_start=[o[1] for o in opts],
        option_end=[o[2] for o in opts],
        option_first=[0.0] * n,
        option_start_los=[o[4] for o in opts],
        option_end_los=[o[4] for o in opts],
        tables=[law] * n_sats,
        pairs=NearPairs.from_arrays(
            n, np.array(src, np.int64), np.array(dst, np.int64), np.array(need)
        ),
        far=[1e3] * n_sats,
        battery=BatteryModel(np.ones((n_sats, 2), bool), [None] * n_sats, 1e6),
        target_options=target_options,
        sat_lo=lo,
        sat_hi=hi,
        sat_starts=[[o[1] for o in opts[a:b]] for a, b in zip(lo, hi, strict=True)],
        near_slack=10.0,
        stereo=table,
    )
    return pb, opts


def ref_value(pb: Problem, plan) -> float:
    """The value of a plan by the definition (module docstring)."""
    chosen = set(plan)
    total = 0.0
    st = pb.stereo
    for t in range(pb.n_targets):
        if t in set(st.stereo_targets.tolist()):
            got = [st.value[p] for p in range(len(st)) if st.target[p] == t
                   and set(st.looks[p]) <= chosen]  # fmt: skip
            total += max(got, default=0.0)
        elif any(pb.option_target[c] == t for c in chosen):
            total += pb.target_value[t]
    return total


def ref_feasible(pb: Problem, opts, plan) -> bool:
    """No overlap and every gap at least the slew law's time, satellite by satellite;
    a point target at most once."""
    law = _Law()
    points = [pb.option_target[c] for c in plan if not pb.is_look(c)]
    if len(points) != len(set(points)):
        return False
    for k in range(pb.n_sats):
        line = sorted((c for c in plan if opts[c][0] == k), key=lambda c: opts[c][1])
        for a, b in itertools.pairwise(line):
            if opts[b][1] - opts[a][2] < law.scalar(_angle(opts[a][4], opts[b][4])) - 1e-9:
                return False
    return True


@pytest.mark.parametrize("seed", range(6))
def test_value_follows_inserts_and_removals(seed):
    pb, _ = synth(seed)
    tl = Timeline(pb)
    rng = random.Random(seed)
    looks = [c for c in range(pb.n_options) if pb.is_look(c)]
    for _ in range(60):
        plan = tl.plan()
        if plan and rng.random() < 0.4:
            c = rng.choice(plan)
            tl.remove(c)
        else:
            c = rng.choice(looks)
            if c not in plan and tl.check(c) is not None:
                tl.insert(c)
        assert tl.value == pytest.approx(ref_value(pb, tl.plan()), abs=1e-9)
    tl.undo_to(0)
    assert tl.plan() == [] and tl.value == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_greedy_and_lns_keep_plans_feasible_and_values_true(seed):
    pb, opts = synth(seed, n_stereo=6, looks_per=6)
    tl = Timeline(pb)
    greedy(tl, math.inf)
    plan = tl.plan()
    assert ref_feasible(pb, opts, plan)
    assert tl.value == pytest.approx(ref_value(pb, plan), abs=1e-9)
    g = tl.value
    lns(tl, time.monotonic() + 0.5, random.Random(seed), max_iters=300)
    plan = tl.plan()
    assert ref_feasible(pb, opts, plan)
    assert tl.value == pytest.approx(ref_value(pb, plan), abs=1e-9)
    assert tl.value >= g - 1e-9
    drop_stray_looks(tl, pb.stereo.stereo_targets.tolist())
    assert tl.value == pytest.approx(ref_value(pb, tl.plan()), abs=1e-9)
    used = {c for t in pb.stereo.stereo_targets.tolist() if tl.stereo.best[t] >= 0
            for c in pb.stereo.looks[tl.stereo.best[t]]}  # fmt: skip
    assert {c for c in tl.plan() if pb.is_look(c)} <= used  # no look without a product


def _optimum(pb: Problem, opts) -> float:
    """Best value over every subset of options (tiny problems only)."""
    best = 0.0
    n = pb.n_options
    for mask in range(1 << n):
        plan = [c for c in range(n) if mask >> c & 1]
        if ref_feasible(pb, opts, plan):
            best = max(best, ref_value(pb, plan))
    return best


@pytest.mark.parametrize("seed", range(5))
def test_lns_reaches_the_optimum_and_the_bound_is_above_it(seed):
    pb, opts = synth(seed, n_sats=1, n_stereo=3, looks_per=3, n_points=2, horizon=60.0)
    assert pb.n_options <= 14
    opt = _optimum(pb, opts)
    tl = Timeline(pb)
    greedy(tl, math.inf)
    lns(tl, time.monotonic() + 2.0, random.Random(seed), max_iters=2000)
    assert tl.value == pytest.approx(opt, abs=1e-9)
    res = lagrangian(Timeline(pb), time.monotonic() + 2.0, None, max_iters=50)
    assert res.bound >= opt - 1e-9


@pytest.mark.parametrize("seed", range(4))
def test_upgrades_only_raise_the_value_and_keep_the_plan_feasible(seed):
    pb, opts = synth(seed, n_stereo=6, looks_per=6)
    tl = Timeline(pb)
    greedy(tl, math.inf)
    rng = random.Random(seed)
    for _ in range(200):
        before = tl.value
        upgrade_product(tl, rng)
        tl.commit()
        assert tl.value >= before - 1e-12
        assert tl.value == pytest.approx(ref_value(pb, tl.plan()), abs=1e-9)
        assert ref_feasible(pb, opts, tl.plan())


def _worst_alone(seed):
    """A timeline holding only the worst product of the one stereo target (None when it
    does not fit alone in this draw)."""
    pb, _ = synth(seed, n_sats=3, n_stereo=1, looks_per=6, n_points=0, horizon=2000.0)
    st = pb.stereo
    t = int(st.stereo_targets[0])
    if len(st.target_products[t]) < 2:
        return None
    worst = st.target_products[t][-1]
    tl = Timeline(pb)
    for c in st.looks[worst]:
        if tl.check(c) is None:
            return None
        tl.insert(c)
    tl.commit()
    return tl, t, worst


def test_an_upgrade_takes_the_better_product_when_it_fits():
    found = next(x for x in map(_worst_alone, range(50)) if x is not None)
    tl, t, worst = found
    st = tl.pb.stereo
    assert tl.stereo.best[t] == worst
    assert upgrade_product(tl, random.Random(0))
    assert st.value[tl.stereo.best[t]] > st.value[worst]


def _ref_fail(pb: Problem, plan, t: int) -> float:
    """Chance that every product of target t complete in ``plan`` fails (recounted)."""
    held = set(plan)
    fail = 1.0
    for p, lk in enumerate(pb.stereo.looks):
        if pb.stereo.target[p] == t and set(lk) <= held:
            fail *= 1.0 - pb.stereo.confidence[p]
    return fail


def test_backups_lower_the_chance_of_losing_a_target_and_cost_nothing():
    """After the greedy, :func:`add_backups` adds looks only where a collected product
    could fail, keeps the plan feasible and its value, and stops only when the target
    is safe enough or no further product of it fits the plan."""
    added = 0
    for seed in range(8):
        pb, opts = synth(seed, n_stereo=6, looks_per=6, sure=False)
        tl = Timeline(pb)
        greedy(tl, math.inf)
        before, v0 = tl.plan(), tl.value
        risky = {t: _ref_fail(pb, before, t) for t in pb.stereo.stereo_targets.tolist()}
        added += add_backups(tl, pb.stereo.stereo_targets.tolist())
        plan = tl.plan()
        assert ref_feasible(pb, opts, plan)
        assert tl.value == pytest.approx(ref_value(pb, plan), abs=1e-9) and tl.value >= v0
        for t, fail0 in risky.items():
            new = [c for c in set(plan) - set(before) if pb.option_target[c] == t]
            if fail0 >= 1.0 or fail0 <= BACKUP_FAIL:  # nothing collected, or safe
                assert not new
                continue
            fail = _ref_fail(pb, plan, t)
            assert fail <= fail0
            if fail <= BACKUP_FAIL:
                continue
            for p in pb.stereo.target_products[t]:  # nothing more fits
                missing = [c for c in pb.stereo.looks[p] if c not in set(plan)]
                if not missing:
                    continue
                mark = len(tl.log)
                fits = True
                for c in missing:
                    if tl.check(c, collected=True) is None:
                        fits = False
                        break
                    tl.insert(c)
                tl.undo_to(mark)
                assert not fits, (seed, t, p)
    assert added > 0
