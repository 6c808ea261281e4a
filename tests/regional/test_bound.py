"""The Lagrangian bound and the per-pass DP against independent references.

References: the optimum of the plan problem by scipy's HiGHS MILP (every strip of every
group, pairwise maneuver conflicts on each satellite, the action cap; duty and battery
left out, which only raises the optimum), and exhaustive enumeration of run sets for the
pass DP.
"""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest
from _synth_cover import make_problem, rules
from scipy.optimize import Bounds, LinearConstraint, milp

from jaxspline.search.coverage_bound import lagrangian_bound, lagrangian_value, pass_layout
from jaxspline.search.coverage_passdp import best_runs, gap_slots
from jaxspline.search.coverage_rules import maneuver_scalar
from jaxspline.search.coverage_state import PlanState


def all_strips(prob):
    """Every strip (g, a, b) a plan may use: inside its group, within the length limits."""
    out = []
    for g in range(prob.n_groups):
        sat = int(prob.group_sat[g])
        s0, n = int(prob.group_slot0[g]), int(prob.group_nslots[g])
        for a in range(s0, s0 + n):
            for b in range(a + prob.min_slots(sat), min(s0 + n, a + prob.max_slots(sat)) + 1):
                out.append((g, a, b))
    return out


def milp_optimum(prob):
    """Best coverage of any plan (maneuver gaps and the cap; no duty or battery)."""
    strips = all_strips(prob)
    st = PlanState(prob)
    cover = [st.samples(*s) for s in strips]
    m, n = len(strips), prob.n_samples
    rows, cols, vals = [], [], []
    for i, smp in enumerate(cover):  # y_j - sum_i x_i <= 0
        rows += list(smp)
        cols += [i] * len(smp)
        vals += [-1.0] * len(smp)
    rows += list(range(n))
    cols += [m + j for j in range(n)]
    vals += [1.0] * n
    a_cov = np.zeros((n, m + n))
    a_cov[rows, cols] = vals
    cons = [LinearConstraint(a_cov, -np.inf, 0.0)]
    cap = np.zeros((1, m + n))
    cap[0, :m] = 1.0
    cons.append(LinearConstraint(cap, 0.0, prob.max_actions))
    pairs = []
    for i, j in itertools.combinations(range(m), 2):
        (gi, ai, bi), (gj, aj, bj) = strips[i], strips[j]
        sat = int(prob.group_sat[gi])
        if sat != int(prob.group_sat[gj]):
            continue
        man = maneuver_scalar(
            prob.rules[sat], abs(prob.group_roll[gi] - prob.group_roll[gj]), prob.margins
        )
        ok = (aj - bi) * prob.slot_s >= man or (ai - bj) * prob.slot_s >= man
        if not ok:
            pairs.append((i, j))
    if pairs:
        conf = np.zeros((len(pairs), m + n))
        for k, (i, j) in enumerate(pairs):
            conf[k, i] = conf[k, j] = 1.0
        cons.append(LinearConstraint(conf, 0.0, 1.0))
    c = np.concatenate([np.zeros(m), -prob.weight])
    integ = np.concatenate([np.ones(m), np.zeros(n)])
    res = milp(c, constraints=cons, integrality=integ, bounds=Bounds(0, 1))
    assert res.success
    return -res.fun


# three random instances by default, three more as slow variants
@pytest.mark.parametrize(
    "seed", [0, 1, 2, *(pytest.param(s, marks=pytest.mark.slow) for s in range(3, 6))]
)
def test_bound_never_below_milp_optimum(seed):
    prob = make_problem(
        seed,
        n_sats=2,
        passes_per_sat=2,
        n_rolls=3,
        n_slots=5,
        nx=10,
        ny=8,
        max_actions=2 + seed % 3,
        sat_rules=[rules(max_dur_s=40.0), rules(min_dur_s=10.0, settle_s=12.0)],
    )
    opt = milp_optimum(prob)
    lay = pass_layout(prob)
    rng = np.random.default_rng(seed)
    for _ in range(20):  # every multiplier vector gives a valid bound
        lam = prob.weight * rng.uniform(0.0, 1.0, prob.n_samples) * (rng.random() < 0.8)
        val, d = lagrangian_value(prob, lay, lam)
        assert val >= opt - 1e-12
        # the reported value is that of the DP's own choice: sum (w - lam)^+ + lam . z
        z = d + (lam < prob.weight)
        assert val == pytest.approx(np.clip(prob.weight - lam, 0, None).sum() + lam @ z, abs=1e-12)
    res = lagrangian_bound(prob, target=0.9 * opt, deadline=time.perf_counter() + 5.0)
    assert res.bound >= opt - 1e-12
    assert res.bound <= lagrangian_value(prob, lay, 0.5 * prob.weight, with_grad=False)[0] + 1e-12


def brute_runs(vals, allowed, gaps, lmin, lmax, rmax, price):
    """Exhaustive best run set (time-ordered runs, gaps between consecutive ones)."""
    g_n, t_n = vals.shape
    runs = [
        (g, s, t)
        for g in range(g_n)
        for s in range(t_n)
        for t in range(s + lmin, min(t_n, s + lmax) + 1)
        if allowed[g, s:t].all()
    ]
    best = 0.0

    def rec(last, total, count):
        nonlocal best
        best = max(best, total)
        if count == rmax:
            return
        for g, s, t in runs:
            if last is None or s - last[2] >= gaps[last[0], g]:
                rec((g, s, t), total + vals[g, s:t].sum() - price, count + 1)

    rec(None, 0.0, 0)
    return best


@pytest.mark.parametrize("seed", range(8))
def test_pass_dp_matches_enumeration(seed):
    rng = np.random.default_rng(seed)
    g_n, t_n = int(rng.integers(1, 4)), int(rng.integers(3, 8))
    vals = rng.uniform(0, 1, (g_n, t_n)) * (rng.random((g_n, t_n)) < 0.8)
    allowed = rng.random((g_n, t_n)) < 0.85
    rolls = np.sort(rng.uniform(18, 38, g_n))
    gaps = gap_slots(rules(), rolls, 3.0, make_problem(0).margins)
    lmin, lmax, rmax = int(rng.integers(1, 3)), int(rng.integers(2, 5)), int(rng.integers(1, 4))
    lmax = max(lmax, lmin)
    price = float(rng.uniform(0, 0.3))
    val, runs = best_runs(vals, allowed, gaps, lmin, lmax, rmax, price)
    assert val == pytest.approx(brute_runs(vals, allowed, gaps, lmin, lmax, rmax, price), abs=1e-12)
    # the returned runs are feasible and worth the value
    assert len(runs) <= rmax
    total = 0.0
    for k, (g, s, t) in enumerate(runs):
        assert lmin <= t - s <= lmax and allowed[g, s:t].all()
        if k:
            pg, _, pt = runs[k - 1]
            assert s - pt >= gaps[pg, g]
        total += vals[g, s:t].sum() - price
    assert total == pytest.approx(val, abs=1e-12)
