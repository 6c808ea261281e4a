"""Incremental battery tests of the search timeline against full re-simulation.

References: a step-by-step re-simulation of the clamped battery recursion written
here from the rules (charge while sunlit at both ends of a step, idle always, imaging
on the steps an observation meets, slew on the maneuver window's steps, clamp at
capacity), over the whole horizon, for every tested insertion; for a complete
battery-bound plan, the independent aeossp checker.
"""

from __future__ import annotations

import dataclasses
import math
import random
from pathlib import Path

import numpy as np
import pytest

from jaxspline.aeossp.adapter import AEOSSP_MARGINS
from jaxspline.readers.mission import Power
from jaxspline.search import BatteryModel, Problem, Timeline, greedy, lns
from jaxspline.search.store import NearPairs

DT = 5.0  # [s] battery step
TIE = 1e-7  # [Wh] levels this close to the margin are not compared (rounding)


def _random_model(rng, n, n_sats=1, charge_max=400.0):
    """BatteryModel with random shadows and a small battery that both spills and runs low."""
    lit = np.ones((n_sats, n + 1), bool)
    for k in range(n_sats):
        for _ in range(rng.integers(1, 4)):
            a = int(rng.integers(0, n))
            lit[k, a : a + int(rng.integers(5, n // 3))] = False
    powers = []
    for _ in range(n_sats):
        cap = float(rng.uniform(8.0, 40.0))
        powers.append(
            Power(
                capacity_wh=cap,
                initial_wh=float(rng.uniform(0.5, 1.0)) * cap,  # >= 4 Wh: above the margin
                idle_w=float(rng.uniform(0.0, 60.0)),
                imaging_w=float(rng.uniform(50.0, 600.0)),
                slew_w=float(rng.uniform(20.0, 400.0)),
                charge_w=float(rng.uniform(0.0, charge_max)),
            )
        )
    m = float(rng.uniform(0.0, 1.0))  # + clamp_wh (at most 2.9 Wh here) stays < 4 Wh
    return BatteryModel(lit, powers, DT, margin_wh=m, guard=0), lit


def _share(a, b, i):
    """Seconds of [a, b) inside step i."""
    return max(0.0, min(b, (i + 1) * DT) - max(a, i * DT))


def _resimulate(p, lit, obs, n):
    """Level at every grid instant; obs = [(start, end, maneuver)], step by step, each
    step loaded by its exact overlap with the observations and maneuver windows."""
    load = np.zeros(n)  # [J] per step
    for s, e, man in obs:
        for i in range(n):
            load[i] += p.imaging_w * _share(s, e, i) + p.slew_w * _share(max(s - man, 0.0), s, i)
    b, out = p.initial_wh, [p.initial_wh]
    for i in range(n):
        charge = p.charge_w if (lit[i] and lit[i + 1]) else 0.0
        b = min(p.capacity_wh, b + ((charge - p.idle_w) * DT - load[i]) / 3600.0)
        out.append(b)
    return np.array(out)


def _random_obs(rng, n, count):
    """Non-overlapping observations on a 1 s grid (off the battery grid too)."""
    t = float(rng.integers(0, 40))
    out = []
    for _ in range(count):
        man = float(rng.integers(0, 40))
        s = t + man + float(rng.integers(0, 60))
        e = s + float(rng.integers(1, 40))
        if e >= n * DT:
            break
        out.append((s, e, man))
        t = e
    return out


def test_loads_are_the_exact_overlaps():
    """BatteryModel.loads == per step the imaging and slew power times the seconds of
    the step inside the observations / maneuver windows (clipped), summed in a loop."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        n = int(rng.integers(20, 200))
        bm, _ = _random_model(rng, n)
        p = bm.powers[0]
        obs = _random_obs(rng, n, int(rng.integers(0, 12)))
        starts, ends, man = (
            (np.array(x, float) for x in zip(*obs, strict=True)) if obs else ([],) * 3
        )
        man = np.asarray(man) * rng.uniform(0.0, 3.0)  # maneuvers reaching past the start
        ref = np.zeros(n)
        for s, e, m in zip(starts, ends, man, strict=True):
            for i in range(n):
                ref[i] += p.imaging_w * _share(s, e, i) + p.slew_w * _share(max(s - m, 0.0), s, i)
        np.testing.assert_allclose(bm.loads(0, starts, ends, man), ref / 3600.0, atol=1e-12)


def test_change_ok_matches_resimulation():
    """change_ok == re-simulation for random load changes (either sign), 4000 cases."""
    rng = np.random.default_rng(1)
    decided = spilled = low = 0
    for _ in range(4000):
        n = int(rng.integers(20, 200))
        bm, lit = _random_model(rng, n)
        p = bm.powers[0]
        obs = _random_obs(rng, n, int(rng.integers(0, 8)))
        lv = bm.levels(0, *zip(*obs, strict=True)) if obs else bm.levels(0, [], [], [])
        np.testing.assert_allclose(lv.level, _resimulate(p, lit[0], obs, n), atol=1e-9)
        changes = []
        full = np.flatnonzero(lv.level[:-1] >= p.capacity_wh - 1e-12)
        for _ in range(int(rng.integers(1, 4))):
            lo = int(rng.integers(0, n))
            hi = min(n, lo + int(rng.integers(0, 60)))
            w = float(rng.choice([-1.0, 1.0]) * rng.uniform(10.0, 800.0))
            if full.size and rng.random() < 0.5:  # straddle a spill, sized to the slack
                lo = int(max(0, rng.choice(full) - rng.integers(0, 10)))
                hi = min(n, lo + int(rng.integers(1, 40)))
                slack = max(lv.tail_min[lo] - bm.margin_wh, 0.1) * rng.uniform(0.5, 3.0)
                w = slack / ((hi - lo) * DT / 3600.0)
            changes.append((lo, hi, w))
        got = bm.change_ok(0, lv, changes)
        load = np.zeros(n)
        for lo, hi, w in changes:
            load[lo:hi] += w
        b, ref = p.initial_wh, [p.initial_wh]
        for i in range(n):
            b = min(p.capacity_wh, b + lv.net[i] - load[i] * DT / 3600.0)
            ref.append(b)
        ref_min = min(ref)
        spilled += bool(np.any(np.isclose(ref, p.capacity_wh)))
        low += ref_min < bm.margin_wh
        if got is None:  # only when the old profile dips below the margin after the change
            assert lv.level.min() < bm.margin_wh + 1e-9
            continue
        decided += 1
        if abs(ref_min - bm.margin_wh) > TIE:
            assert got == (ref_min >= bm.margin_wh), (changes, ref_min, bm.margin_wh)
    assert decided > 3500 and spilled > 1000 and 500 < low < 3500


def assemble(rng, opts, near, n_sats, n_targets, far, battery) -> Problem:
    """A Problem from sorted options ``(sat, start, end, target)`` and near pairs
    ``{i * n + j: need}`` (random values 1-5 and first maneuvers 0-30 s from ``rng``)."""
    n = len(opts)
    sat = [o[0] for o in opts]
    target_options = [[] for _ in range(n_targets)]
    for i, o in enumerate(opts):
        target_options[o[3]].append(i)
    lo = [sat.index(k) if k in sat else n for k in range(n_sats)]
    hi = [n - sat[::-1].index(k) if k in sat else n for k in range(n_sats)]
    keys = np.fromiter(near, np.int64, len(near))
    need = np.fromiter(near.values(), np.float64, len(near))
    return Problem(
        n_sats=n_sats,
        target_value=[float(w) for w in rng.integers(1, 6, n_targets)],
        option_target=[o[3] for o in opts],
        option_sat=sat,
        option_start=[o[1] for o in opts],
        option_end=[o[2] for o in opts],
        option_first=[float(rng.uniform(0.0, 30.0)) for _ in opts],
        option_start_los=[(0.0, 0.0, 1.0)] * n,
        option_end_los=[(0.0, 0.0, 1.0)] * n,
        tables=[None] * n_sats,
        pairs=NearPairs.from_arrays(n, keys // n, keys % n, need),
        far=[far] * n_sats,
        battery=battery,
        target_options=target_options,
        sat_lo=lo,
        sat_hi=hi,
        sat_starts=[[o[1] for o in opts[a:b]] for a, b in zip(lo, hi, strict=True)],
    )


def _problem(rng, n_steps, n_sats=2, n_targets=60, far=40.0, repeats=0.0):
    """A per-channel-style Problem: random options, random near transition times.

    ``repeats``: chance that a target's next option follows its previous one on the
    same satellite (a repeat, 0-9 s later).
    """
    bm, lit = _random_model(rng, n_steps, n_sats, charge_max=150.0)
    horizon = n_steps * DT
    opts = []
    for t in range(n_targets):
        for _ in range(int(rng.integers(1, 4))):
            k = int(rng.integers(0, n_sats))
            s = float(rng.integers(0, int(horizon) - 40))
            if repeats and opts and opts[-1][3] == t and rng.random() < repeats:
                k, s = opts[-1][0], min(opts[-1][2] + float(rng.integers(0, 10)), horizon - 40)
            opts.append((k, s, s + float(rng.integers(2, 30)), t))
    opts.sort()
    sat = [o[0] for o in opts]
    n = len(opts)
    near = {}
    for i in range(n):
        for j in range(n):
            gap = opts[j][1] - opts[i][2]
            if sat[i] == sat[j] and 0.0 <= gap < far and rng.random() < 0.8:
                near[i * n + j] = float(rng.uniform(0.0, far))
    pb = assemble(rng, opts, near, n_sats, n_targets, far, bm)
    return pb, lit


def _brute_insert(tl, c, lit, n_steps):
    """(fits in time, battery fits) of inserting c, from scratch."""
    pb = tl.pb
    k = pb.option_sat[c]
    if tl.assigned[pb.option_target[c]] >= 0:
        return False, None
    seq = sorted([*tl.lines[k], c], key=lambda x: pb.option_start[x])
    man = []
    for i, x in enumerate(seq):
        need = pb.option_first[x] if i == 0 else pb.need(seq[i - 1], x)
        gap = pb.option_start[x] - (0.0 if i == 0 else pb.option_end[seq[i - 1]])
        if gap < need:
            return False, None
        man.append(need)
    obs = [(pb.option_start[x], pb.option_end[x], m) for x, m in zip(seq, man, strict=True)]
    lev = _resimulate(pb.battery.powers[k], lit[k], obs, n_steps)
    return True, float(lev.min())


def _removal_compared(tl, k, pos, ok, lit, n_steps) -> bool:
    """Assert ``ok`` (``Timeline.removal_ok`` after a removal at ``pos``) against the
    re-simulated timeline; False where the level is too close to the margin to tell."""
    pb = tl.pb
    line = tl.lines[k]
    fits = pos >= len(line) or (
        pb.option_start[line[pos]] - (pb.option_end[line[pos - 1]] if pos else 0.0)
        >= tl.maneuver_into(k, pos)
    )
    obs = [
        (pb.option_start[x], pb.option_end[x], tl.maneuver_into(k, i)) for i, x in enumerate(line)
    ]
    level = float(_resimulate(pb.battery.powers[k], lit[k], obs, n_steps).min())
    if fits and abs(level - pb.battery.margin_wh) <= TIE:
        return False
    assert ok == (fits and level >= pb.battery.margin_wh), (k, pos, level)
    return True


# three random instances by default, three more as slow variants
@pytest.mark.parametrize(
    "seed", [0, 1, 2, *(pytest.param(s, marks=pytest.mark.slow) for s in range(3, 6))]
)
def test_timeline_check_matches_brute_force(seed):
    """Timeline.check (incremental battery) == from-scratch re-simulation of the new
    timeline, for every option at every state of random insert / remove / undo runs."""
    rng = np.random.default_rng(100 + seed)
    n_steps = int(rng.integers(60, 240))
    pb, lit = _problem(rng, n_steps)
    tl = Timeline(pb)
    py = random.Random(seed)
    compared = battery_cut = removals = 0
    for _step in range(60):
        for c in range(pb.n_options):
            fits, level = _brute_insert(tl, c, lit, n_steps)
            got = tl.check(c)
            if not fits:
                assert got is None and not tl.battery_failed
                continue
            if abs(level - pb.battery.margin_wh) <= TIE:
                continue
            compared += 1
            assert (got is not None) == (level >= pb.battery.margin_wh), (c, level)
            assert tl.battery_failed == (got is None)
            battery_cut += got is None
        # the greedy's candidates are check's feasible options, in every id span asked
        spans = [(0, pb.n_options), *zip(pb.sat_lo, pb.sat_hi, strict=True)]
        spans.append((pb.n_options // 3, 2 * pb.n_options // 3))
        for t in range(pb.n_targets):
            for span in (None, *spans):
                lo, hi = span or (0, pb.n_options)
                want = [
                    (c, cost + 0.02 * pb.option_end[c])
                    for c in pb.target_options[t]
                    if lo <= c < hi and (cost := tl.check(c)) is not None
                ]
                assert list(zip(*tl.insert_choices(t, span=span), strict=True)) == want
        for k in range(pb.n_sats):  # the stored maneuvers and the refreshed levels, exactly
            line = tl.lines[k]
            starts = [pb.option_start[x] for x in line]
            ends = [pb.option_end[x] for x in line]
            man = [
                pb.option_first[x] if i == 0 else pb.need(line[i - 1], x)
                for i, x in enumerate(line)
            ]
            assert (tl.line_starts[k], tl.line_ends[k], tl.maneuvers[k]) == (starts, ends, man)
            want = pb.battery.levels(k, starts, ends, man).level
            np.testing.assert_array_equal(tl.battery_level(k), want)
        for k in range(pb.n_sats):  # the cached levels follow the timeline
            obs = [(pb.option_start[x], pb.option_end[x], 0.0) for x in tl.lines[k]]
            obs = [(s, e, tl.maneuver_into(k, i)) for i, (s, e, _) in enumerate(obs)]
            ref = _resimulate(pb.battery.powers[k], lit[k], obs, n_steps)
            np.testing.assert_allclose(tl.battery_level(k), ref, atol=1e-9)
        mark = len(tl.log)
        r = py.random()
        if r < 0.6:
            for _ in range(3):
                ok = [c for c in range(pb.n_options) if tl.check(c) is not None]
                if ok:
                    tl.insert(py.choice(ok))
        elif r < 0.8 and tl.n_observations:
            k = py.choice([k for k in range(pb.n_sats) if tl.lines[k]])
            pos = py.randrange(len(tl.lines[k]))
            tl.remove(tl.lines[k][pos])
            ok = tl.removal_ok(k, pos)
            removals += _removal_compared(tl, k, pos, ok, lit, n_steps)
            if not ok:
                tl.undo_to(mark)
        elif tl.n_observations:
            tl.undo_to(0)
        _assert_debt_bounds(tl, lit, n_steps)
        if py.random() < 0.5:
            tl.commit()
    assert compared > 1000 and battery_cut > 50 and removals > 5


def _assert_debt_bounds(tl, lit, n_steps):
    """The kept (past) battery profiles less the debt never exceed the current suffix
    minima, re-simulated."""
    pb = tl.pb
    for k in range(pb.n_sats):
        past = tl.levels[k]
        if past is None:
            continue
        obs = [
            (pb.option_start[x], pb.option_end[x], tl.maneuver_into(k, i))
            for i, x in enumerate(tl.lines[k])
        ]
        now = _resimulate(pb.battery.powers[k], lit[k], obs, n_steps)
        suffix_min = np.minimum.accumulate(now[::-1])[::-1]
        assert np.all(past.tail_min - tl.debt[k] <= suffix_min + 1e-9), k


@pytest.mark.parametrize("seed", range(3))
def test_debt_bounds_the_profile_through_removals(seed):
    """Full timelines lose observations one by one with their profiles kept: a removal
    lengthens the successor's maneuver when the new pair needs more time, and the debt
    must cover that load (the O(1) tests of ``check`` and ``removal_ok`` rely on it)."""
    rng = np.random.default_rng(300 + seed)
    n_steps = int(rng.integers(60, 240))
    pb, lit = _problem(rng, n_steps)
    tl = Timeline(pb)
    py = random.Random(seed)
    longer = 0
    for _round in range(8):
        while ok := [c for c in range(pb.n_options) if tl.check(c) is not None]:
            tl.insert(py.choice(ok))
        for k in range(pb.n_sats):
            tl.battery_level(k)  # fresh profiles, no debt
        tl.commit()
        for _ in range(tl.n_observations // 2):
            k = py.choice([k for k in range(pb.n_sats) if tl.lines[k]])
            pos = py.randrange(len(tl.lines[k]))
            before = tl.maneuvers[k][pos + 1] if pos + 1 < len(tl.lines[k]) else math.inf
            tl.remove(tl.lines[k][pos])
            longer += pos < len(tl.lines[k]) and tl.maneuvers[k][pos] > before
            _assert_debt_bounds(tl, lit, n_steps)
        if py.random() < 0.5:
            tl.undo_to(0)
        else:
            tl.commit()
    assert longer >= 3


@pytest.mark.parametrize("seed", range(3))
def test_withdrawn_options_are_never_offered(seed):
    """A timeline that withdraws options never images them and leaves the Problem as
    built; its greedy and LNS equal those on a problem built without those options."""
    rng = np.random.default_rng(200 + seed)
    pb, _ = _problem(rng, 200)
    before = [list(x) for x in pb.target_options]
    out = np.zeros(pb.n_options, bool)
    out[rng.choice(pb.n_options, pb.n_options // 3, replace=False)] = True
    without = [[c for c in x if not out[c]] for x in before]
    plans = []
    for tl in (Timeline(pb, out), Timeline(dataclasses.replace(pb, target_options=without))):
        greedy(tl, math.inf)
        lns(tl, math.inf, random.Random(seed), 300)
        plans.append(list(tl.assigned))
    assert plans[0] == plans[1] and any(c >= 0 for c in plans[0])
    assert not any(out[c] for c in plans[0] if c >= 0)
    assert pb.target_options == before
    with pytest.raises(ValueError, match="withdrawn"):
        Timeline(pb, out[:-1])


DATA = Path("/work/shared/data/aeossp_standard/train/case_0001")


@pytest.mark.skipif(not DATA.is_dir(), reason="aeossp training data not available")
def test_battery_bound_plan_is_valid_under_the_checker():
    """3 satellites, 367 tasks, 12 h, 10 % initial charge and 30 % charging: the battery
    binds, the plan stays valid under the independent aeossp checker."""
    from jaxspline.aeossp.adapter import solve_case
    from jaxspline.aeossp.case import load_case
    from jaxspline.aeossp.check import check_solution

    case = load_case(DATA)
    sats = tuple(
        dataclasses.replace(
            s,
            initial_battery_wh=0.1 * s.initial_battery_wh,
            sunlit_charge_power_w=0.3 * s.sunlit_charge_power_w,
        )
        for s in case.satellites[:3]
    )
    case = dataclasses.replace(case, case_id="bound", satellites=sats, tasks=case.tasks[::5])
    sol, res = solve_case(case, time_limit=60.0, progress=False, max_iters=800)
    assert res.report["valid"] and res.report["dropped_total"] == 0
    assert res.stats["greedy_value"] <= res.value <= res.bound
    rep = check_solution(case, sol)
    assert rep.valid, [v.message for v in rep.violations[:5]]
    assert len(sol["actions"]) > 20
    low = min(v["min_battery_wh"] for v in rep.satellites.values())
    assert 0.0 <= low < AEOSSP_MARGINS.battery_wh + 5.0  # the battery binds
