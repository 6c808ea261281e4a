"""aeossp_standard through the one planning pipeline (``jaxspline.plan``).

References are independent of the planner: the checker's own SGP4 + frame chain
(``jaxspline.aeossp.check.Ephemeris``), a per-start brute force of the options, a
dense 1-s re-integration of the battery, the independent checker
``jaxspline.aeossp.check.check_solution`` for complete plans, subset enumeration for
the per-satellite DP, and plan enumeration (repeats included) for the bound.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import importlib.util
import itertools
import math
import time
from pathlib import Path

import numpy as np
import pytest

from jaxspline import build_problem, plan
from jaxspline.aeossp.adapter import AEOSSP_MARGINS, case_scenario, solve_case
from jaxspline.base.elements import (
    R_EARTH,
    WGS84_F,
    circular_orbit_over,
    geodetic_to_ecef,
    gmst,
    julian_date,
)
from jaxspline.geometry.frames import earth_rotation_angle, ecef_to_geodetic, rot_z
from jaxspline.geometry.orbit import orbit_position
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.config import PlannerConfig
from jaxspline.readers.mission import POINT, Power, Satellite, Scenario, make_targets
from jaxspline.search import (
    BatteryModel,
    BoundStatus,
    dp_forward,
    dp_paths,
    dp_prepare,
    mip_bound,
    upper_bound,
)

DATA = Path("/work/shared/data/aeossp_standard/train/case_0001")
SMALL_LIMIT_S = 5.0  # a short limit: it holds, and the plan is valid and not empty
needs_data = pytest.mark.skipif(not DATA.is_dir(), reason="aeossp training data not available")


@pytest.fixture(scope="module")
def full_case():
    from jaxspline.aeossp.case import load_case

    return load_case(DATA)


@pytest.fixture(scope="module")
def small_case(full_case):
    """3 satellites (2 visible, 1 infrared), 150 tasks they can observe, full 12 h horizon."""
    vis = [s for s in full_case.satellites if s.sensor_type == "visible"][:2]
    ir = [s for s in full_case.satellites if s.sensor_type == "infrared"][:1]
    sub = dataclasses.replace(full_case, case_id="small", satellites=tuple(vis + ir))
    seen = np.unique(build_problem(case_scenario(sub)).opportunities.options.route)
    rng = np.random.default_rng(0)
    pick = np.sort(rng.choice(seen, size=150, replace=False))
    return dataclasses.replace(sub, tasks=tuple(full_case.tasks[i] for i in pick))


@pytest.fixture(scope="module")
def small_prep(small_case):
    return build_problem(case_scenario(small_case))


def _checker_geometry(eph, task_ecef, ts):
    """(off-nadir [deg], elevation sine) of task_ecef [.., 3] from the checker's ephemeris."""
    from jaxspline.aeossp.check import angle_deg

    r = eph.ecef(ts)
    d = task_ecef - r
    up = np.sum(-d * task_ecef, axis=-1) / np.linalg.norm(task_ecef, axis=-1)
    return angle_deg(-r, d), up / np.linalg.norm(d, axis=-1)


# ------------------------------------------------------------------ options
@needs_data
def test_options_valid_under_checker_geometry(small_case, small_prep):
    """Every option passes the checker's geometry at every 5 s instant (limit - margin/2)."""
    from jaxspline.aeossp.check import Ephemeris, geodetic_to_ecef

    o = small_prep.opportunities.options
    assert len(small_prep.opportunities) > 500
    tasks, sats = small_case.tasks, small_case.satellites
    step = small_case.geometry_step_s
    half = 0.5 * math.degrees(AEOSSP_MARGINS.off_nadir)
    for k, sat in enumerate(sats):
        ids = np.flatnonzero(o.sat == k)
        assert ids.size > 50
        eph = Ephemeris(sat, small_case.horizon_start)
        ts, owner = [], []
        for c in ids.tolist():
            task = tasks[o.route[c]]
            t0, t1 = float(o.t_start[c]), float(o.t_end[c])
            assert t0 % small_case.action_step_s == 0.0
            assert t1 - t0 == task.required_duration_s
            assert small_case.seconds(task.release_time) <= t0
            assert t1 <= small_case.seconds(task.due_time)
            assert 0.0 <= t0 and t1 <= small_case.duration_s
            assert task.required_sensor_type == sat.sensor_type
            inst = np.union1d(np.arange(t0, t1, step), [t1])
            ts.append(inst)
            owner.append(np.full(inst.size, c))
        ts, owner = np.concatenate(ts), np.concatenate(owner)
        p = np.array(
            [
                geodetic_to_ecef(t.latitude_deg, t.longitude_deg, t.altitude_m)
                for t in (tasks[i] for i in o.route[owner])
            ]
        )
        off, sine = _checker_geometry(eph, p, ts)
        assert off.max() <= sat.max_off_nadir_deg - half
        assert sine.min() > 0.5 * AEOSSP_MARGINS.horizon


@needs_data
def test_options_complete_against_brute_force(small_case, small_prep):
    """Options of 40 tasks == every grid start whose every instant passes the planner's
    margins on the checker's ephemeris (thresholds +-1e-6 deg / 1e-8: frame differences)."""
    from jaxspline.aeossp.check import Ephemeris, geodetic_to_ecef

    o = small_prep.opportunities.options
    got = {
        (int(r), int(k), float(s))
        for r, k, s in zip(o.route, o.sat, o.t_start, strict=True)
        if r < 40
    }
    step = small_case.action_step_s
    grid = np.arange(0.0, small_case.duration_s + step / 2, step)
    m_off = math.degrees(AEOSSP_MARGINS.off_nadir)
    tight, loose = set(), set()
    for k, sat in enumerate(small_case.satellites):
        eph = Ephemeris(sat, small_case.horizon_start)
        for ti, task in enumerate(small_case.tasks[:40]):
            if task.required_sensor_type != sat.sensor_type:
                continue
            p = geodetic_to_ecef(task.latitude_deg, task.longitude_deg, task.altitude_m)
            off, sine = _checker_geometry(eph, p, grid)
            n_dur = int(round(task.required_duration_s / step))
            a = math.ceil(small_case.seconds(task.release_time) / step)
            b = math.floor((small_case.seconds(task.due_time) - task.required_duration_s) / step)
            b = min(b, grid.size - 1 - n_dur)
            for out, tol in ((tight, -1.0), (loose, 1.0)):
                ok = (off <= sat.max_off_nadir_deg - m_off + tol * 1e-6) & (
                    sine > AEOSSP_MARGINS.horizon - tol * 1e-8
                )
                run = np.concatenate([[0], np.cumsum(ok)])
                for s in range(a, b + 1):
                    if run[s + n_dur + 1] - run[s] == n_dur + 1:
                        out.add((ti, k, s * step))
    assert len(tight) > 20
    assert tight <= got <= loose, (sorted(tight - got)[:5], sorted(got - loose)[:5])


# ------------------------------------------------------------------ battery
@needs_data
@pytest.mark.parametrize("guard", [0, 1])
def test_battery_profile_against_dense_integration(small_case, guard):
    """BatteryModel.profile == a 0.1-s re-integration (loads at the sub-steps' midpoints,
    charge per step as the model's sunlight rule, clamp per step)."""
    from jaxspline.aeossp.check import Ephemeris, sunlit
    from jaxspline.readers.mission import Power

    dt_ = small_case.geometry_step_s
    n = int(3 * 3600 / dt_)  # 3 h: two shadow passes
    eph = Ephemeris(small_case.satellites[0], small_case.horizon_start)
    grid = np.arange(n + 1) * dt_
    lit = sunlit(eph.gcrf(grid), eph.unix(grid))
    assert 0 < lit.sum() < lit.size
    # the case's battery (clamped at capacity early on) and a small one that runs low
    case_sat = small_case.satellites[0]
    powers = [
        Power(
            capacity_wh=case_sat.battery_capacity_wh,
            initial_wh=case_sat.initial_battery_wh,
            idle_w=case_sat.idle_power_w,
            imaging_w=case_sat.imaging_power_w,
            slew_w=case_sat.slew_power_w,
            charge_w=case_sat.sunlit_charge_power_w,
        ),
        Power(
            capacity_wh=40.0, initial_wh=38.0, idle_w=25.0, imaging_w=300, slew_w=150, charge_w=70
        ),
    ]
    bm = BatteryModel(np.stack([lit, lit]), powers, dt_, margin_wh=0.0, guard=guard)
    starts = [3.0, 100.0, 402.5, 1500.0, 6000.0, 9000.0]
    ends = [13.0, 130.0, 418.0, 1512.0, 6090.0, 9040.0]
    man = [10.0, 20.0, 33.5, 7.0, 61.2, 0.0]
    for k, p in enumerate(powers):
        lev = bm.profile(k, starts, ends, man)
        img = list(zip(starts, ends, strict=True))
        slw = [(max(s - m, 0.0), s) for s, m in zip(starts, man, strict=True)]
        sub_s = 0.1  # every time above is a whole multiple of it
        mids = (np.arange(round(dt_ / sub_s)) + 0.5) * sub_s
        b, out = p.initial_wh, [p.initial_wh]
        for i in range(n):
            lo, hi = max(0, i - guard), min(n, i + 1 + guard)
            chg = p.charge_w if lit[lo : hi + 1].all() else 0.0
            t = i * dt_ + mids
            load = p.idle_w + sum(p.imaging_w * ((a <= t) & (t < z)) for a, z in img)
            load = load + sum(p.slew_w * ((a <= t) & (t < z)) for a, z in slw)
            b = min(p.capacity_wh, b + float(np.sum(chg - load)) * sub_s / 3600.0)
            out.append(b)
        np.testing.assert_allclose(lev, out, rtol=0, atol=1e-9)
    small = bm.profile(1, starts, ends, man)
    assert small.min() < 35.0 and small.max() == 40.0  # runs low, and the clamp acts


# ------------------------------------------------------------------ solve_case
@needs_data
def test_solve_small_case_valid_by_checker(small_case):
    from jaxspline.aeossp.check import check_solution

    t0 = time.monotonic()
    sol, res = solve_case(small_case, time_limit=SMALL_LIMIT_S, progress=False)
    wall = time.monotonic() - t0
    assert wall <= SMALL_LIMIT_S + 2.0
    assert res.report["valid"] and res.report["dropped_total"] == 0
    assert len(sol["actions"]) == len(res.observations) > 40
    rep = check_solution(small_case, sol)
    assert rep.valid, [v.message for v in rep.violations[:5]]
    assert rep.metrics["WCR"] == pytest.approx(res.value / res.total_value, abs=1e-9)
    assert res.total_value == pytest.approx(sum(t.weight for t in small_case.tasks))
    assert res.value <= res.bound and res.gap == pytest.approx(res.bound - res.value)


@needs_data
def test_solve_deterministic_for_seed(small_case):
    kw = dict(time_limit=60.0, progress=False, seed=3, max_iters=100)
    a, ra = solve_case(small_case, **kw)
    b, rb = solve_case(small_case, **kw)
    assert a == b
    assert len(a["actions"]) > 0
    assert (ra.value, ra.bound) == (rb.value, rb.bound)
    assert ra.report["dropped_total"] == 0


@needs_data
def test_solve_rejects_bad_time_limit(small_case):
    with pytest.raises(ValueError, match="time_limit"):
        solve_case(small_case, time_limit=0.0, progress=False)


@needs_data
def test_solve_degenerate_cases(small_case):
    """No tasks / no satellite with the required sensor: an empty, valid plan, fast."""
    from jaxspline.aeossp.check import check_solution

    empty = dataclasses.replace(small_case, tasks=())
    t0 = time.monotonic()
    sol, res = solve_case(empty, time_limit=30.0, progress=False)
    assert sol == {"actions": []}
    assert res.value == 0.0 and res.report["valid"]
    assert time.monotonic() - t0 < 10.0
    assert check_solution(empty, sol).valid
    ir_only = dataclasses.replace(
        small_case,
        satellites=tuple(s for s in small_case.satellites if s.sensor_type == "infrared"),
        tasks=tuple(t for t in small_case.tasks if t.required_sensor_type == "visible")[:20],
    )
    t0 = time.monotonic()
    sol, res = solve_case(ir_only, time_limit=30.0, progress=False)
    assert sol == {"actions": []}
    assert res.stats["options"] == 0 and res.value == 0.0
    assert time.monotonic() - t0 < 10.0
    assert check_solution(ir_only, sol).valid


# ------------------------------------------------------------------ per-satellite DP
@needs_data
def test_dp_paths_exact_against_brute_force(small_prep):
    """Per-satellite DP optimum == exhaustive search over all subsets of 11 options."""
    pb = small_prep.problem
    d = dp_prepare(pb)
    rng = np.random.default_rng(1)
    k = int(np.argmax(np.subtract(pb.sat_hi, pb.sat_lo)))
    lo, hi = pb.sat_lo[k], pb.sat_hi[k]
    starts = np.asarray(pb.option_start)
    longest = 0
    for trial in range(4):
        # a cluster within 15 min (near pairs, overlaps, infeasible pairs) plus 3 anywhere
        a = int(rng.integers(lo, hi))
        ids = np.arange(lo, hi)
        near = ids[(starts[ids] >= starts[a]) & (starts[ids] <= starts[a] + 900.0)]
        pick = set(rng.choice(near, size=min(8, near.size), replace=False).tolist())
        pick |= set(rng.choice(ids, size=11 - len(pick), replace=False).tolist())
        pick = sorted(pick)
        w = np.full(pb.n_options, -1e6)  # never worth taking
        w[pick] = rng.uniform(0.5, 2.0, len(pick))
        paths, vals = dp_paths(pb, d, w)
        best, best_len = 0.0, 0
        for mask in range(1, 1 << len(pick)):
            seq = sorted(
                (pick[i] for i in range(len(pick)) if mask >> i & 1),
                key=lambda c: pb.option_start[c],
            )
            ok = pb.option_first[seq[0]] <= pb.option_start[seq[0]]
            for p, q in zip(seq[:-1], seq[1:], strict=True):
                gap = pb.option_start[q] - pb.option_end[p]
                if not (ok and gap >= 0.0 and pb.need(p, q) <= gap):
                    ok = False
                    break
            if ok and float(w[seq].sum()) > best:
                best, best_len = float(w[seq].sum()), len(seq)
        longest = max(longest, best_len)
        assert vals[k] == pytest.approx(best, abs=1e-9), trial
        assert sum(vals) == pytest.approx(best, abs=1e-9)
        path = paths[k]
        assert float(w[path].sum()) == pytest.approx(best, abs=1e-9)
        assert pb.option_first[path[0]] <= pb.option_start[path[0]]
        for p, q in zip(path[:-1], path[1:], strict=True):
            assert pb.option_start[q] - pb.option_end[p] >= pb.need(p, q)
    assert longest >= 3  # the optimum chained several options at least once


# ------------------------------------------------------------------ bound with repeats
EPOCH = dt.datetime(2026, 6, 21, 10, 0, tzinfo=dt.UTC)
G0 = float(gmst(julian_date(EPOCH)))
LAT0, LON0 = math.radians(46.0), math.radians(15.0)


def _subsatellite(orb, ts):
    r = np.asarray(orbit_position(orb, np.asarray(ts, np.float64)))
    lat, lon, _ = ecef_to_geodetic(rot_z(earth_rotation_angle(G0, np.asarray(ts)), r))
    return np.asarray(lat), np.asarray(lon)


def _los(orb, g_ecef, t):
    """Unit inertial line of sight from the satellite to ground point g_ecef at time t."""
    r = np.asarray(orbit_position(orb, float(t)))
    u = np.asarray(rot_z(-earth_rotation_angle(G0, t), g_ecef)) - r
    return u / np.linalg.norm(u)


def _ground_along(orb, u, t):
    """(lat, lon) of the point of the WGS84 ellipsoid seen along direction u at time t."""
    r = np.asarray(orbit_position(orb, float(t)))
    scale = np.array([1.0, 1.0, 1.0 / (1.0 - WGS84_F)]) / R_EARTH
    p, q = r * scale, u * scale
    a, b, c = q @ q, 2.0 * p @ q, p @ p - 1.0
    lam = (-b - math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    lat, lon, _ = ecef_to_geodetic(rot_z(earth_rotation_angle(G0, t), r + lam * u))
    return float(lat), float(lon)


def _eigen_sats(passes, rate_deg, accel_deg, off_deg, settle):
    orbs = [circular_orbit_over(LAT0, LON0, tp, G0, altitude=500e3) for tp in passes]
    return orbs, tuple(
        Satellite(
            f"s{k}",
            orb,
            model="eigen_axis",
            limits=AxisLimits(np.radians(rate_deg), np.radians(accel_deg)),
            off_nadir_max=math.radians(off_deg),
            settle=settle,
        )
        for k, orb in enumerate(orbs)
    )


def _bridge_scenario(seed):
    """Two slow satellites pass over a target B 150 s apart. For each satellite k, Y_k
    ends (pinned window) where B's line of sight starts and Z_k starts where it ends:
    Y_k -> Z_k directly is a slew of ~ B's sweep in too short a gap, Y_k -> B -> Z_k
    is two tiny slews. Each satellite needs its own B, so imaging B twice pays."""
    rng = np.random.default_rng(seed)
    passes = (200.0, 350.0)
    orbs, sats = _eigen_sats(passes, 0.4, 0.1, 30.0, 1.0)
    lat_b = LAT0 + math.radians(rng.uniform(-0.3, 0.3))
    lon_b = LON0 + math.radians(rng.uniform(-0.3, 0.3))
    g_b = np.asarray(geodetic_to_ecef(lat_b, lon_b, 0.0))
    d_b, d, delta = 20.0, 10.0, 5.0
    lat, lon, lo, hi, dur = [lat_b], [lon_b], [0.0], [600.0], [d_b]
    for orb, tp in zip(orbs, passes, strict=True):
        s_b = 5.0 * round((tp - d_b / 2 + rng.uniform(-10.0, 10.0)) / 5.0)
        t1, t2 = s_b - delta, s_b + d_b + delta
        for (a, o), w in (
            (_ground_along(orb, _los(orb, g_b, s_b), t1), (t1 - d, t1)),
            (_ground_along(orb, _los(orb, g_b, s_b + d_b), t2), (t2, t2 + d)),
        ):
            lat.append(a)
            lon.append(o)
            lo.append(w[0])
            hi.append(w[1])
            dur.append(d)
    t_x = rng.uniform(150.0, 400.0)  # a distractor near the first track, 80 s window
    a, o = _subsatellite(orbs[0], [t_x])
    lat.append(float(a[0]) + math.radians(rng.uniform(-0.4, 0.4)))
    lon.append(float(o[0]) + math.radians(rng.uniform(-0.4, 0.4)))
    lo.append(t_x - 40.0)
    hi.append(t_x + 40.0)
    dur.append(d)
    value = rng.integers(1, 4, len(lat)).astype(float)
    tg = make_targets(POINT, lat, lon, duration=dur, value=value, t_lo=lo, t_hi=hi)
    return Scenario(f"bridge{seed}", EPOCH, 600.0, sats, tg, PlannerConfig(time_step=5.0))


def _random_scenario(seed):
    """1-2 slow satellites, 6 point targets scattered around the first ground track."""
    rng = np.random.default_rng(100 + seed)
    n_sat = 1 + seed % 2
    _, sats = _eigen_sats((300.0, 380.0)[:n_sat], 0.5, 0.1, 14.0, 1.0)
    n = 6
    lat, lon = _subsatellite(sats[0].orbit, rng.uniform(200.0, 400.0, n))
    tg = make_targets(
        POINT,
        lat + np.radians(rng.uniform(-0.6, 0.6, n)),
        lon + np.radians(rng.uniform(-0.6, 0.6, n)),
        duration=rng.choice([15.0, 20.0, 25.0], n),
        value=rng.integers(1, 4, n).astype(float),
    )
    return Scenario(f"tiny{seed}", EPOCH, 600.0, sats, tg, PlannerConfig(time_step=5.0))


def _enumerate_plans(pb):
    """Best plan value (repeats allowed, each target counted once) and best without repeats.

    Per satellite, the target sets of all feasible sequences of its options (dynamic
    programming over (last option, target set); transitions by ``pb.need``, first by
    ``pb.option_first``; no battery); then every combination of one set per satellite.
    """
    best = {}
    for repeats in (True, False):
        per_sat = []
        for k in range(pb.n_sats):
            ids = sorted(range(pb.sat_lo[k], pb.sat_hi[k]), key=lambda c: pb.option_start[c])
            sets = {}
            for j in ids:
                bit = 1 << pb.option_target[j]
                s = {bit} if pb.option_first[j] <= pb.option_start[j] else set()
                for i in ids:
                    gap = pb.option_start[j] - pb.option_end[i]
                    if i != j and gap >= 0.0 and pb.need(i, j) <= gap:
                        s |= {m | bit for m in sets.get(i, ()) if repeats or not m & bit}
                sets[j] = s
            per_sat.append({0}.union(*sets.values()))
        top = 0.0
        for combo in itertools.product(*per_sat):
            union = 0
            for m in combo:
                if not repeats and union & m:
                    break
                union |= m
            else:
                top = max(top, sum(w for t, w in enumerate(pb.target_value) if union >> t & 1))
        best[repeats] = top
    return best[True], best[False]


# one bridge and two random instances by default; the other seeds are slow variants
@pytest.mark.parametrize(
    "make, seed",
    [(_bridge_scenario, 0), (_random_scenario, 0), (_random_scenario, 1)]
    + [pytest.param(_bridge_scenario, s, marks=pytest.mark.slow) for s in (1, 2)]
    + [pytest.param(_random_scenario, s, marks=pytest.mark.slow) for s in (2, 3)],
)
def test_bound_covers_plans_with_repeats(make, seed):
    """plan().bound >= the best plan imaging targets repeatedly; value == best without."""
    sc = make(seed)
    pb = build_problem(sc).problem
    assert 0 < pb.n_options <= sc.planner.exact_max_options
    with_rep, without = _enumerate_plans(pb)
    if make is _bridge_scenario:
        assert with_rep > without  # the construction makes a repeated B pay
    res = plan(sc, time_limit=20.0, progress=False)
    assert res.report["valid"] and res.report["dropped_total"] == 0
    assert res.stats["exact"]
    assert res.value == pytest.approx(without, abs=1e-9)
    assert res.bound >= with_rep - 1e-9


@pytest.mark.parametrize(
    "make, seed",
    [(_bridge_scenario, s) for s in range(3)] + [(_random_scenario, s) for s in range(4)],
)
def test_mip_bound_is_the_optimum_with_repeats(make, seed):
    """The chain-network 0/1 program (far pairs through waiting chains, repeats counted
    once) solved to optimality == the enumerated best plan with repeats."""
    pytest.importorskip("scipy.optimize")
    pb = build_problem(make(seed)).problem
    with_rep, _ = _enumerate_plans(pb)
    res = mip_bound(pb, time_limit=60.0, rel_gap=0.0)
    assert res.status == BoundStatus.OPTIMAL
    assert res.value == pytest.approx(with_rep, abs=1e-9)
    assert res.bound == pytest.approx(with_rep, abs=1e-6)


def test_energy_priced_bound_covers_the_battery_optimum():
    """Battery as priced interval budgets: the bound stays >= the exact optimum with the
    battery (branch and bound) and is tighter than the bound that drops the battery."""
    tighter = 0
    for seed in range(4):
        sc = _random_scenario(seed)
        power = Power(
            capacity_wh=50.0,
            initial_wh=6.0,
            idle_w=1.0,
            imaging_w=300.0,
            slew_w=100.0,
            charge_w=0.0,
        )
        sc = dataclasses.replace(
            sc, satellites=tuple(dataclasses.replace(s, power=power) for s in sc.satellites)
        )
        res = plan(sc, time_limit=20.0, progress=False)
        assert res.stats["exact"] and res.report["valid"]
        pb = build_problem(sc).problem
        kw = dict(plan_value=res.value, deadline=math.inf, max_iters=300)
        with_energy = upper_bound(pb, energy=True, **kw).bound
        without = upper_bound(pb, energy=False, **kw).bound
        assert with_energy >= res.value - 1e-9
        assert with_energy <= without + 1e-9
        tighter += with_energy < without - 1e-6
    assert tighter >= 2


def _lagrangian_value(pb, lam, merge_repeats):
    """UB(lam) = sum of the satellites' DP values + sum of the prices."""
    w = np.asarray(pb.target_value)[np.asarray(pb.option_target)] - lam[pb.option_target]
    _, vals = dp_paths(pb, dp_prepare(pb), w, merge_repeats=merge_repeats)
    return sum(vals) + lam.sum()


@pytest.mark.parametrize(
    "make, seed",
    [(_bridge_scenario, s) for s in range(3)] + [(_random_scenario, s) for s in range(8)],
)
def test_merged_repeats_bound_covers_the_optimum(make, seed):
    """The strengthened relaxation (a run of one target's options credited once) at ANY
    prices in [0, w] >= the best plan with repeats (enumerated; == the HiGHS optimum,
    see above), and never above the plain relaxation at the same prices; iterated, it
    stays between the optimum and the plain bound."""
    pb = build_problem(make(seed)).problem
    with_rep, _ = _enumerate_plans(pb)
    rng = np.random.default_rng(seed)
    tv = np.asarray(pb.target_value)
    for lam in [np.zeros_like(tv), tv, *(tv * rng.uniform(0, 1, tv.size) for _ in range(20))]:
        strong = _lagrangian_value(pb, lam, True)
        assert strong >= with_rep - 1e-9
        assert strong <= _lagrangian_value(pb, lam, False) + 1e-9
    kw = dict(plan_value=with_rep, deadline=math.inf, max_iters=300)
    strong = upper_bound(pb, merge_repeats=True, **kw).bound
    assert with_rep - 1e-9 <= strong <= upper_bound(pb, merge_repeats=False, **kw).bound + 1e-9
    if importlib.util.find_spec("scipy") is not None:
        assert strong >= mip_bound(pb, time_limit=60.0, rel_gap=0.0).value - 1e-6


@pytest.mark.parametrize("make, seed", [(_bridge_scenario, 0), (_random_scenario, 1)])
@pytest.mark.parametrize("merge_repeats", [False, True])
def test_jax_dp_forward_equals_numpy(make, seed, merge_repeats):
    """The lax.scan forward pass == the numpy one bit for bit (values, arc costs, paths,
    several value vectors in one scan)."""
    from jaxspline.search.dp_jax import JaxDP

    pb = build_problem(make(seed)).problem
    d = dp_prepare(pb)
    rng = np.random.default_rng(seed)
    w = np.asarray(pb.target_value)[np.asarray(pb.option_target)] * rng.uniform(0, 1, pb.n_options)
    arc = rng.uniform(0.0, 0.5, len(pb.pairs))
    jd = JaxDP(pb, d)
    for a in (None, arc):
        ref = dp_forward(pb, d, w, a, merge_repeats)
        assert np.array_equal(jd.forward(w, a, merge_repeats), ref)
        assert jd.paths(w, a, None, merge_repeats) == dp_paths(pb, d, w, a, None, merge_repeats)
    if merge_repeats:  # K value vectors in one scan: each row as numpy gives it alone
        ws = w * rng.uniform(0, 1, (3, pb.n_options))
        many = jd.forward_many(ws, arc, merge_repeats)
        for k in range(3):
            assert np.array_equal(many[k], dp_forward(pb, d, ws[k], arc, merge_repeats))
