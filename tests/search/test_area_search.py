"""The search on area problems against brute force and HiGHS.

Synthetic problems (:mod:`_synth_area`): a :class:`jaxspline.search.Problem` with a
:class:`jaxspline.search.cover.CoverTable`, rest-to-rest satellites with a step-function
slew model, point targets and area strips. References, none reading the search's own
state: coverage and value recounted from the rows kept as Python sets; feasibility
(overlap, transition times, the duty window's exact maximum, the action cap, points at
most once) from the option records; the best plan by enumerating every feasible plan of
each satellite and choosing one per satellite with HiGHS (``scipy.optimize.milp``); the
best runs of a pass by enumerating every set of runs.
"""

from __future__ import annotations

import functools
import itertools
import math
import random
import sys
import time

import numpy as np
import pytest
from _synth_area import enumerate_plans, feasible, make, optimum, plan_value

from jaxspline.search import Timeline, greedy, greedy_order, lagrangian, lns, upper_bound
from jaxspline.search.area_fill import area_index, fill
from jaxspline.search.area_moves import local_moves, reopt_pass
from jaxspline.search.pass_bound import area_dp, pass_layout
from jaxspline.search.pass_dp import best_runs

DEADLINE_S = 60.0  # far beyond what these tiny searches take: the iteration caps decide


def _deadline() -> float:
    return time.monotonic() + DEADLINE_S


def _recount(s, plan):
    """(count per sample, covered share per area) of a plan, from the option records."""
    cnt = np.zeros(s.weight.size, np.int64)
    for c in plan:
        if s.opts[c].area:
            cnt[list(s.opts[c].samples)] += 1
    cv = s.pb.cover
    share = np.bincount(cv.area, weights=np.where(cnt > 0, cv.share, 0.0), minlength=cv.n_areas)
    return cnt, share


def _assert_state(s, tl):
    """The timeline's coverage bookkeeping equals a recount of its plan."""
    plan = tl.plan()
    cnt, share = _recount(s, plan)
    np.testing.assert_array_equal(tl.cover.cnt, cnt)
    assert tl.value == pytest.approx(plan_value(s, plan), abs=1e-9)
    assert tl.cover.value == pytest.approx(float(s.weight[cnt > 0].sum()), abs=1e-9)
    np.testing.assert_allclose(tl.cover.area_share, share, atol=1e-12)
    open_w = np.where(cnt == 0, s.weight, 0.0)
    want = [sum(open_w[i] for i in row) for row in s.rows]
    np.testing.assert_allclose(tl.cover.row_gain, want, atol=1e-9)
    assert tl.n_area == sum(s.opts[c].area for c in plan)
    assert tl.n_observations == len(plan)
    m = s.pb.cover.area_min
    short = np.nansum(np.clip(m - share, 0.0, None))
    assert tl.cover.shortfall() == pytest.approx(short, abs=1e-12)


# ----------------------------------------------------------------- (a) bookkeeping
@pytest.mark.parametrize("seed", [0, 1])
def test_timeline_coverage_bookkeeping_equals_a_recount(seed):
    """Random inserts (where check allows), removals, undos and restores: counts, value,
    shares, row gains and shortfall equal a recount; check() == the rules recounted."""
    s = make(seed, n_sats=2, max_actions=6, duty=(60.0, 40.0), area_min=[0.5, 0.3])
    pb, cv = s.pb, s.pb.cover
    tl = Timeline(pb)
    rng = random.Random(seed)
    area_ids = [c for c, o in enumerate(s.opts) if o.area]
    checked = accepted = 0
    for step in range(300):
        mark = len(tl.log)
        u = rng.random()
        if u < 0.55:
            c = rng.randrange(pb.n_options)
            plan = tl.plan()
            ok = tl.check(c) is not None
            want = c not in plan and feasible(s, [*plan, c])
            assert ok == want, (step, c, plan)
            checked += 1
            if ok:
                tl.insert(c)
                accepted += 1
        elif u < 0.8 and tl.plan():
            tl.remove(rng.choice(tl.plan()))
        elif u < 0.9:
            tl.undo_to(max(0, mark - rng.randrange(0, 3)))
        else:
            tl.commit()
        _assert_state(s, tl)
        if tl.cover is not None and step % 25 == 0:
            for c in rng.sample(area_ids, 6):  # exact gains and losses of windows
                o = s.opts[c]
                g, a, b = o.window
                cnt, _ = _recount(s, tl.plan())
                new = [i for i in o.samples if cnt[i] == 0]
                assert tl.cover.gain(g, a, b) == pytest.approx(s.weight[new].sum(), abs=1e-12)
                if c in tl.plan():
                    only = [i for i in o.samples if cnt[i] == 1]
                    assert tl.cover.loss(c) == pytest.approx(s.weight[only].sum(), abs=1e-12)
                assert cv.option_of(g, a, b) == c
    assert checked > 100 and 10 < accepted
    plan = tl.plan()
    tl.restore(list(reversed(plan)))
    _assert_state(s, tl)
    assert sorted(tl.plan()) == sorted(plan) and feasible(s, tl.plan())


# ----------------------------------------------------------------- (b) pass DP
def _brute_runs(vals, allowed, gaps, lmin, lmax, rmax, price):
    """Best value of any set of runs (enumerated in time order)."""
    g_n, t_n = vals.shape
    runs = [
        (g, a, a + n)
        for g in range(g_n)
        for n in range(lmin, lmax + 1)
        for a in range(0, t_n - n + 1)
        if allowed[g, a : a + n].all()
    ]
    runs.sort(key=lambda r: r[1])
    best = 0.0

    def grow(last, used, total):
        nonlocal best
        best = max(best, total)
        if used == rmax:
            return
        for g, a, b in runs:
            if last is not None and a - last[2] < gaps[last[0], g]:
                continue
            if last is not None and a < last[2]:
                continue
            grow((g, a, b), used + 1, total + vals[g, a:b].sum() - price)

    grow(None, 0, 0.0)
    return best


@pytest.mark.parametrize("seed", range(12))
def test_best_runs_equals_enumeration(seed):
    rng = np.random.default_rng(seed)
    g_n, t_n = int(rng.integers(1, 4)), int(rng.integers(3, 10))
    vals = rng.normal(0.5, 1.0, (g_n, t_n))
    allowed = rng.random((g_n, t_n)) < 0.85
    gaps = rng.integers(1, 4, (g_n, g_n))
    lmin = int(rng.integers(1, 3))
    lmax = lmin + int(rng.integers(0, 3))
    rmax = int(rng.integers(1, 4))
    price = float(rng.choice([0.0, 0.3]))
    value, runs = best_runs(vals, allowed, gaps, lmin, lmax, rmax, price)
    want = _brute_runs(vals, allowed, gaps, lmin, lmax, rmax, price)
    assert value == pytest.approx(want, abs=1e-9)
    # the runs returned are a feasible set worth that value
    assert len(runs) <= rmax
    total = 0.0
    for i, (g, a, b) in enumerate(runs):
        assert lmin <= b - a <= lmax and allowed[g, a:b].all()
        if i:
            pg, _, pb_ = runs[i - 1]
            assert a - pb_ >= gaps[pg, g]
        total += vals[g, a:b].sum() - price
    assert total == pytest.approx(value, abs=1e-9)


# ----------------------------------------------------------------- (c) bounds
def _strip_credit(s, c, credit):
    """A strip's credit: its rows' credits (rows in the window of its group)."""
    cv = s.pb.cover
    r0, r1 = cv.option_rows(c)
    return float(credit[r0:r1].sum())


def _best_area_credit(s, credit, cap):
    """The best sum of strip credits over the feasible plans of area strips, at most
    ``cap`` strips in all (per satellite by count, then every split of the cap)."""
    per_sat = []
    for k in range(s.pb.n_sats):
        best = {}
        for p in enumerate_plans(s, k, most=cap):
            if any(not s.opts[c].area for c in p):
                continue
            v = sum(_strip_credit(s, c, credit) for c in p)
            best[len(p)] = max(best.get(len(p), -math.inf), v)
        per_sat.append(best)
    top = -math.inf
    for counts in itertools.product(*(sorted(b) for b in per_sat)):
        if sum(counts) <= cap:
            top = max(top, sum(b[n] for b, n in zip(per_sat, counts, strict=True)))
    return top


@pytest.mark.parametrize(
    "seed,kw",
    [
        (0, {}),
        (1, {"min_slots": 2, "max_slots": 3}),
        (2, {"n_sats": 2, "max_actions": 3}),
        (3, {"passes": 2, "groups": 2, "pass_slots": 5}),
        (4, {"n_sats": 2, "max_actions": 2, "min_slots": 2}),
    ],
)
def test_area_dp_bounds_every_plan_of_strips(seed, kw):
    """area_dp at random row credits (either sign) >= the best feasible plan's credit."""
    s = make(seed, n_points=0, **kw)
    cv = s.pb.cover
    cap = s.max_actions if s.max_actions is not None else 10**6
    lay = pass_layout(cv, s.max_actions)
    rng = np.random.default_rng(seed)
    for _ in range(4):
        credit = rng.normal(0.3, 1.0, cv.n_rows)
        value, rows = area_dp(cv, lay, credit)
        want = _best_area_credit(s, credit, cap)
        assert value >= want - 1e-9, (value, want)
        assert value == pytest.approx(float(credit[rows].sum()), abs=1e-9)
    # all credits positive: the relaxation is tight when strips cannot be merged
    value, _ = area_dp(cv, lay, np.abs(rng.normal(1.0, 0.1, cv.n_rows)))
    assert value >= _best_area_credit(s, np.ones(cv.n_rows), cap) * 0.9 - 1e-9


@pytest.mark.parametrize(
    "seed,kw",
    [
        (10, {}),
        (11, {"n_sats": 2, "max_actions": 4}),
        (12, {"n_sats": 2, "duty": (60.0, 30.0)}),
        (13, {"passes": 2, "groups": 2, "pass_slots": 5, "min_slots": 2}),
    ],
)
def test_upper_bound_with_areas_is_above_the_optimum(seed, kw):
    """The Lagrangian bound (targets and samples priced) >= the best plan (HiGHS)."""
    s = make(seed, **kw)
    best, chosen = optimum(s)
    assert feasible(s, chosen) and plan_value(s, chosen) == pytest.approx(best, abs=1e-7)
    tl = Timeline(s.pb)
    greedy(tl, _deadline())
    for iters in (1, 40):
        res = upper_bound(s.pb, tl.value, _deadline(), max_iters=iters)
        assert res.bound >= best - 1e-7, (iters, res.bound, best)


@pytest.mark.parametrize("seed,kw", [(14, {"n_sats": 2}), (15, {"min_slots": 2, "passes": 2})])
def test_lagrangian_phase_with_areas_repairs_feasible_plans_under_its_bound(seed, kw):
    """The search's Lagrangian phase: its plan (repaired from the DP paths, the areas' runs
    among them) keeps every rule and is worth what it claims; its bound is above the best."""
    s = make(seed, **kw)
    best, _ = optimum(s)
    tl = Timeline(s.pb)
    greedy(tl, _deadline())
    res = lagrangian(tl, _deadline(), greedy_order(tl), max_iters=24)
    assert feasible(s, tl.plan()) and tl.plan() == res.best
    assert tl.value == pytest.approx(plan_value(s, tl.plan()), abs=1e-9)
    assert tl.value <= best + 1e-9 and res.bound >= best - 1e-7
    _assert_state(s, tl)


# ----------------------------------------------------------------- (d) rules kept
@pytest.mark.parametrize(
    "seed,kw",
    [
        (20, {"n_sats": 2, "max_actions": 3, "n_points": 0}),
        (21, {"duty": (50.0, 20.0), "pass_slots": 8}),
        (22, {"n_sats": 2, "max_actions": 5, "duty": (60.0, 20.0), "passes": 2, "n_points": 0}),
        (23, {"n_sats": 2, "duty": (60.0, 25.0), "passes": 2}),
    ],
)
def test_fill_and_moves_keep_the_cap_and_the_duty(seed, kw):
    """fill, the pass re-plans, the local moves and the LNS keep the action cap and the
    imaging duty (recounted: the exact most imaging time in any window of one period)."""
    s = make(seed, **kw)
    pb = s.pb
    ix = area_index(pb)
    tl = Timeline(pb)
    fill(tl, ix, _deadline())
    assert feasible(s, tl.plan()) and tl.n_observations > 0
    if s.max_actions is not None and s.duty is None:
        assert tl.n_observations == s.max_actions  # strips gain: the cap binds
    greedy(tl, _deadline())
    assert feasible(s, tl.plan())
    for p in range(len(ix.passes)):
        reopt_pass(tl, ix, p)
        assert feasible(s, tl.plan()), p
    local_moves(tl, ix)
    assert feasible(s, tl.plan())
    _assert_state(s, tl)
    start = tl.value
    lns(tl, _deadline(), random.Random(seed), max_iters=150)
    assert feasible(s, tl.plan()) and tl.value >= start - 1e-9
    _assert_state(s, tl)
    if s.duty is not None:  # the duty binds: without it, fill breaks it
        free = make(seed, **{**kw, "duty": None})
        tl = Timeline(free.pb)
        fill(tl, area_index(free.pb), _deadline())
        assert not feasible(s, tl.plan())


def test_a_full_cap_takes_no_strip():
    s = make(30, n_sats=2, max_actions=2, n_points=0)
    tl = Timeline(s.pb)
    ix = area_index(s.pb)
    assert fill(tl, ix, _deadline()) == 2
    assert fill(tl, ix, _deadline()) == 0
    assert all(tl.check(c) is None for c in range(s.pb.n_options))


@pytest.mark.parametrize("seed", [20, 42])
def test_point_insertions_keep_the_action_cap(seed):
    s = make(seed, n_sats=2, max_actions=3)
    tl = Timeline(s.pb)
    fill(tl, area_index(s.pb), _deadline())  # the strips take the whole cap
    assert tl.n_observations == 3
    for t in range(len(s.point_value)):
        assert tl.insert_choices(t) == ([], []), t
    greedy(tl, _deadline())
    lns(tl, _deadline(), random.Random(seed), max_iters=100)
    assert tl.n_observations <= 3 and feasible(s, tl.plan())


def test_fill_shortens_strips_to_the_duty():
    """Duty 20 s per 60 s, strips of 10-30 s: every satellite can take a 10-20 s strip
    in each pass, fill gives one satellite none."""
    s = make(22, n_sats=2, passes=2, n_points=0, max_actions=5, duty=(60.0, 20.0))
    tl = Timeline(s.pb)
    fill(tl, area_index(s.pb), _deadline())
    assert feasible(s, tl.plan())
    assert {s.opts[c].sat for c in tl.plan()} == {0, 1}


def _meets_min_exists(s) -> bool:
    """Whether some feasible plan of the single satellite covers each area's least share
    (enumerated)."""
    cv = s.pb.cover
    for p in enumerate_plans(s, 0):
        cnt, share = _recount(s, p)
        if np.all(~np.isfinite(cv.area_min) | (share >= cv.area_min - 1e-12)):
            return True
    return False


@pytest.mark.parametrize("seed", [60, 66, 68, 69])
def test_the_search_meets_the_least_shares_where_a_plan_does(seed):
    """Area 1 asks for half its weight: where some plan covers that much (enumerated), the
    greedy and the LNS end with no shortfall (it ranks first in the score)."""
    s = make(seed, max_actions=3, n_points=0, area_min=[np.nan, 0.5])
    assert _meets_min_exists(s)
    tl = Timeline(s.pb)
    greedy(tl, _deadline())
    lns(tl, _deadline(), random.Random(seed), max_iters=300)
    assert feasible(s, tl.plan()) and tl.cover.shortfall() == 0.0


def test_points_do_not_keep_an_area_below_its_least_share():
    s = make(60, area_min=[np.nan, 0.5])  # three point targets, no cap
    assert _meets_min_exists(s)
    tl = Timeline(s.pb)
    greedy(tl, _deadline())
    lns(tl, _deadline(), random.Random(60), max_iters=300)
    assert feasible(s, tl.plan()) and tl.cover.shortfall() == 0.0


# ----------------------------------------------------------------- (e) LNS
@pytest.mark.parametrize(
    "seed,kw",
    [
        (40, {}),
        (41, {"min_slots": 2}),
        (42, {"n_sats": 2, "max_actions": 4, "n_points": 0}),
        (43, {"n_points": 0, "passes": 2, "groups": 2, "pass_slots": 5}),
    ],
)
def test_lns_never_loses_and_reaches_the_optimum(seed, kw):
    s = make(seed, **kw)
    best, _ = optimum(s)
    tl = Timeline(s.pb)
    greedy(tl, _deadline())
    start = tl.value
    assert feasible(s, tl.plan())
    lns(tl, _deadline(), random.Random(seed), max_iters=400)
    assert feasible(s, tl.plan())
    assert tl.value >= start - 1e-9
    assert tl.value == pytest.approx(best, abs=1e-7), (start, tl.value, best)


def test_point_moves_with_areas_lose_nothing_at_zero_threshold():
    """Threshold acceptance at threshold 0: a move that loses value is undone (as it is
    without areas, where score()[0] is the value)."""
    import importlib

    lns_mod = importlib.import_module("jaxspline.search.lns")
    s = make(50, n_sats=1)
    tl = Timeline(s.pb)
    greedy(tl, _deadline())
    points = [c for c in tl.plan() if not s.opts[c].area]
    assert points
    walk = lns_mod._Walk(tl, [t for t in s.pb.exclusive_targets() if tl.target_options[t]])
    base, before = tl.score(), tl.value
    mark = len(tl.log)
    tl.remove(points[0])  # a move that loses a point target's value
    lns_mod._accept(tl, walk, base, mark, 0.0, 1, random.Random(0))
    assert tl.value == pytest.approx(before)


@pytest.mark.parametrize("seed,cap", [(0, 2), (4, 3), (6, 4), (7, 3)])
def test_the_action_cap_price_keeps_the_bound_above_the_optimum_and_tightens_it(
    seed, cap, monkeypatch
):
    """Points and strips under one action cap: the bound with the cap priced is above
    the best plan (HiGHS over every plan) and below the bound that leaves the points'
    DPs uncapped (the price off)."""
    s = make(seed, n_sats=2, max_actions=cap, n_points=6)
    best, _ = optimum(s)
    tl = Timeline(s.pb)
    greedy(tl, _deadline())
    priced = upper_bound(s.pb, tl.value, _deadline(), max_iters=200).bound
    prices = sys.modules["jaxspline.search.lagrangian"].Prices
    off = functools.partialmethod(prices.__init__, price_cap=False)
    monkeypatch.setattr(prices, "__init__", off)
    plain = upper_bound(s.pb, tl.value, _deadline(), max_iters=200).bound
    assert best - 1e-7 <= priced < plain - 1.0, (best, priced, plain)
