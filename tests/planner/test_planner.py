"""``jaxspline.plan`` on small multi-satellite instances (per_channel, eigen_axis, flexible).

References are independent of the planner's search: an exact mixed-integer program
over the planner's own options and transition model (one path per satellite through
the feasible transitions, each target at most once; HiGHS via scipy), and, for
eigen-axis satellites, slews recomputed from the analytic orbits, the targets (strip
ends included) and the bang-coast-bang formula.
"""

from __future__ import annotations

import datetime as dt
import functools
import json
import math

import numpy as np
import pytest

from jaxspline import build_problem, plan
from jaxspline.base.elements import circular_orbit_over, geodetic_to_ecef, gmst, julian_date
from jaxspline.geometry.frames import earth_rotation_angle, ecef_to_geodetic, ecef_to_teme, rot_z
from jaxspline.geometry.orbit import orbit_position, orbit_state
from jaxspline.kernels.limits import AxisLimits
from jaxspline.kernels.slew import bang_coast_bang_time
from jaxspline.readers.config import PlannerConfig
from jaxspline.readers.mission import POINT, STRIP, FlexMode, Satellite, Scenario, make_targets
from jaxspline.search import BoundStatus

EPOCH = dt.datetime(2026, 6, 21, 10, 0, tzinfo=dt.UTC)
G0 = float(gmst(julian_date(EPOCH)))
PASSES = (300.0, 500.0, 700.0)  # [s] each satellite passes near (46 N, 15 E) then


def _subsatellite(orb, ts):
    r = np.asarray(orbit_position(orb, np.asarray(ts, np.float64)))
    lat, lon, _ = ecef_to_geodetic(rot_z(earth_rotation_angle(G0, np.asarray(ts)), r))
    return np.asarray(lat), np.asarray(lon)


def _scenario(seed, n_points, n_strips, off_nadir_deg, exact_max_options):
    """Three satellites (one per model), targets scattered around their ground tracks,
    17 min horizon, 10 s action grid, integer values 1..5."""
    rng = np.random.default_rng(seed)
    off = math.radians(off_nadir_deg)
    orbs = [
        circular_orbit_over(
            math.radians(46.0 + rng.uniform(-1, 1)),
            math.radians(15.0 + rng.uniform(-1, 1)),
            tp,
            G0,
            altitude=550e3,
        )
        for tp in PASSES
    ]
    sats = (
        Satellite(
            "pc",
            orbs[0],
            model="per_channel",
            limits=AxisLimits(np.radians([1.5, 1.5, 3.0]), np.radians([0.5, 0.5, 1.0])),
            off_nadir_max=off,
        ),
        Satellite(
            "ea",
            orbs[1],
            model="eigen_axis",
            limits=AxisLimits(np.radians(1.0), np.radians(0.3)),
            off_nadir_max=off,
            settle=2.0,
        ),
        Satellite(
            "fx",
            orbs[2],
            model="flexible",
            limits=AxisLimits(np.radians(2.0), np.radians(0.05)),
            off_nadir_max=off,
            settle=1.0,
            flex=FlexMode(freq=2 * np.pi * 0.5, damping=0.01, tolerance=1e-6),
        ),
    )
    lat, lon = [], []
    for k, orb in enumerate(orbs):
        m = n_points // 3 + (k < n_points % 3)
        a, o = _subsatellite(orb, rng.uniform(PASSES[k] - 150.0, PASSES[k] + 150.0, m))
        lat += list(a + np.radians(rng.uniform(-1.5, 1.5, m)))
        lon += list(o + np.radians(rng.uniform(-1.5, 1.5, m)))
    for j in range(n_strips):
        a, o = _subsatellite(orbs[j % 3], [PASSES[j % 3] + rng.uniform(-60.0, 60.0)])
        lat.append(float(a[0]) + math.radians(rng.uniform(-0.5, 0.5)))
        lon.append(float(o[0]) + math.radians(rng.uniform(-0.5, 0.5)))
    n = len(lat)
    kind = [POINT] * n_points + [STRIP] * n_strips
    tg = make_targets(
        kind,
        lat,
        lon,
        duration=rng.choice([5.0, 10.0, 15.0], n),
        length=np.where(np.array(kind) == STRIP, rng.uniform(20e3, 40e3, n), 0.0),
        azimuth=np.radians(rng.uniform(0.0, 360.0, n)),
        value=rng.integers(1, 6, n).astype(float),
    )
    pc = PlannerConfig(time_step=10.0, scan_speeds=(6000.0,), exact_max_options=exact_max_options)
    return Scenario(f"multi{seed}", EPOCH, 1000.0, sats, tg, pc)


def _exact_optimum(pb) -> float:
    """Independent exact optimum of the planner's candidate model (battery relaxed).

    A 0/1 program: per option y_j (taken), per feasible transition i -> j of one
    satellite x_ij (``0 <= start_j - end_i``, ``pb.need(i, j) <= gap``), per option that
    may come first s_j (``pb.option_first[j] <= start_j``). Inflow ``s_j + sum_i x_ij = y_j``,
    outflow ``sum_k x_jk <= y_j``, at most one first option per satellite (a DAG: one
    path each), each target at most once. Maximize ``sum_j w_target(j) y_j``.
    """
    pytest.importorskip("scipy.optimize")  # the test extra
    import scipy.sparse as sps
    from scipy.optimize import Bounds, LinearConstraint, milp

    n = pb.n_options
    arcs = [
        (i, j)
        for k in range(pb.n_sats)
        for i in range(pb.sat_lo[k], pb.sat_hi[k])
        for j in range(pb.sat_lo[k], pb.sat_hi[k])
        if i != j
        and pb.option_start[j] - pb.option_end[i] >= 0.0
        and pb.need(i, j) <= pb.option_start[j] - pb.option_end[i]
    ]
    first = [j for j in range(n) if pb.option_first[j] <= pb.option_start[j]]
    na = len(arcs)
    rows, cols, vals = [], [], []

    def put(r, c, v):
        rows.append(r)
        cols.append(c)
        vals.append(v)

    for j in range(n):
        put(j, j, -1.0)  # inflow row j
        put(n + j, j, -1.0)  # outflow row n + j
    for a, (i, j) in enumerate(arcs):
        put(j, n + a, 1.0)
        put(n + i, n + a, 1.0)
    for f, j in enumerate(first):
        put(j, n + na + f, 1.0)
        put(2 * n + pb.option_sat[j], n + na + f, 1.0)
    for t, opts in enumerate(pb.target_options):
        for j in opts:
            put(2 * n + pb.n_sats + t, j, 1.0)
    m = 2 * n + pb.n_sats + pb.n_targets
    lo = np.r_[np.zeros(n), np.full(n, -np.inf), np.zeros(m - 2 * n)]
    hi = np.r_[np.zeros(2 * n), np.ones(m - 2 * n)]
    nv = n + na + len(first)
    a_mat = sps.csr_array((vals, (rows, cols)), shape=(m, nv))
    cost = np.zeros(nv)
    cost[:n] = -np.asarray(pb.target_value)[np.asarray(pb.option_target)]
    res = milp(
        cost,
        constraints=LinearConstraint(a_mat, lo, hi),
        integrality=np.ones(nv),
        bounds=Bounds(0.0, 1.0),
    )
    assert res.success, res.message
    return float(-res.fun)


def _aim_point(sc, target, t0, t, speed):
    """ECEF aim point of a target at time t of an observation started at t0 [m].

    A strip is scanned from its start point along the great circle of radius |g0|
    leaving in the direction of its azimuth (geodetic north / east), at ``speed``.
    """
    tg = sc.targets
    lat, lon = tg.lat[target], tg.lon[target]
    g0 = np.asarray(geodetic_to_ecef(lat, lon, tg.alt[target]))
    if tg.kind[target] != STRIP:
        return g0
    north = np.array(
        [-math.sin(lat) * math.cos(lon), -math.sin(lat) * math.sin(lon), math.cos(lat)]
    )
    east = np.array([-math.sin(lon), math.cos(lon), 0.0])
    az = tg.azimuth[target]
    rad = np.linalg.norm(g0)
    u = g0 / rad
    d = math.cos(az) * north + math.sin(az) * east
    d -= (d @ u) * u
    d /= np.linalg.norm(d)
    arc = speed * (t - t0) / rad
    return rad * (u * math.cos(arc) + d * math.sin(arc))


def _los(sat, g_ecef, t):
    r, _ = orbit_state(sat.orbit, float(t))
    g = np.asarray(ecef_to_teme(g_ecef, earth_rotation_angle(G0, float(t))))
    return g - np.asarray(r), -np.asarray(r)


def _angle(u, v):
    return math.atan2(np.linalg.norm(np.cross(u, v)), float(u @ v))


def _check_eigen_axis_transitions(res) -> int:
    """Every eigen-axis maneuver (from nadir for the first) fits its gap; returns how many."""
    sc, o = res.scenario, res.observations
    count = 0
    for k, sat in enumerate(sc.satellites):
        if sat.model != "eigen_axis":
            continue
        idx = np.flatnonzero(o.sat == k)
        idx = idx[np.argsort(o.start[idx])]
        prev = None
        for i in idx.tolist():
            t0, t1, tgt, v = o.start[i], o.end[i], int(o.target[i]), o.speed[i]
            los_start, nadir = _los(sat, _aim_point(sc, tgt, t0, t0, v), t0)
            if prev is None:
                frm, gap = nadir, t0
            else:
                frm, gap = prev[0], t0 - prev[1]
            theta = _angle(frm, los_start)
            need = float(bang_coast_bang_time(theta, sat.limits.rate, sat.limits.accel))
            need += sat.settle
            assert need <= gap + 1e-9, (sat.name, i, need, gap)
            assert o.maneuver[i] == pytest.approx(need, abs=1e-6)
            assert o.slack[i] == pytest.approx(gap - need, abs=1e-6)
            prev = (_los(sat, _aim_point(sc, tgt, t0, t1, v), t1)[0], t1)
            count += 1
    return count


@functools.cache
def _solved(seed, n_points, n_strips, off_nadir_deg, exact_max_options, max_iters):
    sc = _scenario(seed, n_points, n_strips, off_nadir_deg, exact_max_options)
    optimum = _exact_optimum(build_problem(sc).problem)
    res = plan(sc, time_limit=20.0, progress=False, max_iters=max_iters)
    return sc, optimum, res


LNS_CASE = dict(n_points=20, n_strips=2, off_nadir_deg=14.0, exact_max_options=0, max_iters=1000)
EXACT_CASE = dict(n_points=15, n_strips=1, off_nadir_deg=10.0, exact_max_options=60, max_iters=2000)


# seed 2 (and its plan's consistency and refinement checks) is slow: seed 0 checks the
# same path by default
_SEED2 = pytest.mark.slow


@pytest.mark.parametrize(
    "seed",
    [
        0,
        pytest.param(2, marks=_SEED2),
        pytest.param(
            8,
            marks=[
                pytest.mark.xfail(
                    reason="search gap: LNS stays at 63 of the optimum 66 (search seeds 0-2, "
                    "also with the full 20 s budget); the optimal plan passes Timeline.check "
                    "and plan_check",
                    strict=False,
                ),
                pytest.mark.slow,  # a known miss: no check of the default run rests on it
            ],
        ),
    ],
)
def test_lagrangian_lns_path_reaches_exact_optimum(seed):
    """exact_max_options=0: greedy, Lagrangian and LNS only; value == the exact optimum."""
    sc, optimum, res = _solved(seed, **LNS_CASE)
    assert res.stats["options"] > sc.planner.exact_max_options
    assert not res.stats["exact"]
    assert res.report["valid"] and res.report["dropped_total"] == 0
    assert res.value <= optimum + 1e-9  # the plan lives in the same candidate model
    assert res.bound >= optimum - 1e-6  # Lagrangian bound
    assert optimum < res.total_value  # not every target fits: the instance has conflicts
    assert res.value == pytest.approx(optimum, abs=1e-6)


# seed 3 runs by default (its plan also feeds the consistency test); 0 and 1 are slow
@pytest.mark.parametrize(
    "seed", [pytest.param(0, marks=pytest.mark.slow), pytest.param(1, marks=pytest.mark.slow), 3]
)
def test_exact_path_matches_exact_optimum(seed):
    sc, optimum, res = _solved(seed, **EXACT_CASE)
    assert 0 < res.stats["options"] <= sc.planner.exact_max_options
    assert res.stats["exact"]
    assert res.report["valid"] and res.report["dropped_total"] == 0
    assert res.value == pytest.approx(optimum, abs=1e-6)
    assert res.bound >= optimum - 1e-6
    assert optimum < res.total_value


@pytest.mark.parametrize(
    ("case", "seed"), [(LNS_CASE, 0), pytest.param(LNS_CASE, 2, marks=_SEED2), (EXACT_CASE, 3)]
)
def test_plan_is_consistent_and_eigen_axis_slews_fit(case, seed):
    """Observations are time-ordered per satellite, each target once, inside the
    horizon, values sum up; eigen-axis slews recomputed independently fit their gaps."""
    sc, _, res = _solved(seed, **case)
    o = res.observations
    assert len(o) > 5
    assert len(set(o.target.tolist())) == len(o)
    assert np.all(o.start >= 0.0) and np.all(o.end <= sc.duration)
    assert res.value == pytest.approx(float(np.sum(sc.targets.value[o.target])))
    assert np.all(o.slack >= 0.0)
    for k in range(len(sc.satellites)):
        tl = res.timeline(k)
        assert np.all(tl.start[1:] >= tl.end[:-1])
    assert {int(k) for k in o.sat} == {0, 1, 2}  # every model took part
    assert _check_eigen_axis_transitions(res) >= 2


def test_plan_rejects_bad_arguments():
    sc = _scenario(0, 3, 0, 10.0, 60)
    for bad in (0.0, -1.0, math.nan, math.inf, "10"):
        with pytest.raises(ValueError, match="time_limit"):
            plan(sc, time_limit=bad, progress=False)
    with pytest.raises(ValueError, match="scenario"):
        plan("scenario.toml", time_limit=1.0, progress=False)
    for bad in (-1.0, math.nan, "5"):
        with pytest.raises(ValueError, match="certify"):
            plan(sc, time_limit=1.0, progress=False, certify=bad)


def test_certify_tightens_the_bound_to_the_optimum():
    """With certify, HiGHS solves the tiny candidate model: the bound is its optimum
    (repeats allowed, so >= the no-repeat optimum) and never above the Lagrangian one."""
    pytest.importorskip("scipy.optimize")
    sc, optimum, res = _solved(0, **LNS_CASE)
    cert = plan(sc, time_limit=20.0, progress=False, max_iters=5000, certify=30.0)
    mip = cert.stats["mip"]
    assert mip["status"] == BoundStatus.OPTIMAL
    assert cert.bound_converged
    assert optimum - 1e-6 <= cert.bound <= res.bound + 1e-9
    assert cert.bound == pytest.approx(max(mip["bound"], cert.value), abs=1e-6)


def test_result_writers_refuse_overwrite(tmp_path):
    sc, _, res = _solved(3, **EXACT_CASE)
    js, cs = tmp_path / "plan.json", tmp_path / "plan.csv"
    res.to_json(js)
    res.to_csv(cs)
    doc = json.loads(js.read_text())
    assert doc["summary"]["value"] == pytest.approx(res.value)
    assert doc["summary"]["valid"] is True
    assert len(doc["observations"]) == len(res.observations)
    assert [r["target"] for r in doc["observations"]] == [
        str(sc.targets.name[t]) for t in res.observations.target
    ]
    lines = cs.read_text().splitlines()
    assert len(lines) == 1 + len(res.observations) and lines[0].startswith("satellite,")
    for write, path in ((res.to_json, js), (res.to_csv, cs)):
        before = path.read_text()
        with pytest.raises(FileExistsError, match=path.name):
            write(path)
        assert path.read_text() == before
        write(path, force=True)


@pytest.mark.parametrize(("case", "seed"), [(LNS_CASE, 0), pytest.param(LNS_CASE, 2, marks=_SEED2)])
def test_refined_per_channel_starts_keep_the_plan_valid(case, seed):
    """Start-time refinement of the per-channel satellite: margins do not shrink, and the
    returned plan's per-channel transfers are reachable in exactly their gaps
    (recomputed with ``is_reachable`` from the observations' own states)."""

    sc, _, res = _solved(seed, **case)
    info = res.stats["refined"]
    assert set(info) == {s.name for s in sc.satellites if s.model == "per_channel"}
    for v in info.values():
        assert v["margin_after_rad"] >= v["margin_before_rad"] - 1e-12
    assert res.report["valid"] and res.report["dropped_total"] == 0
    assert np.all(res.observations.slack >= -1e-9)
    k = next(i for i, s in enumerate(sc.satellites) if s.model == "per_channel")
    starts = res.observations.start[res.observations.sat == k]
    off_grid = np.abs(starts / sc.planner.time_step - np.round(starts / sc.planner.time_step))
    kept = any(v["kept"] for v in info.values())
    assert kept == bool(np.any(off_grid > 1e-9))
