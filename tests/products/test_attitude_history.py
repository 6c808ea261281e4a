"""Attitude history of a plan, its join check and the CCSDS AEM export, against references.

A hand-made plan (no search: compiling the planner would dominate the test time) of
three satellites on one circular orbit over central Europe (one per maneuver model),
each imaging four point targets and a strip along its ground track. References:

* boundaries: the per-channel angles of :func:`jaxspline.pointing.pointing_state` (its
  own compiled path, a circular-orbit scene instead of the planner's Hermite table) and
  the unit line of sight computed in numpy;
* rates: scipy's ``solve_ivp`` integrating q' = ½ q∘ω with the exported ω (quintic
  Hermite through ω, ε, ε' of the samples);
* limit check: finite differences of the joins' quaternions (brute force, 4001
  samples per join) and numpy Euler angles;
* AEM: re-read through ``ccsds-ndm``.
"""

import datetime as dt

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import BPoly

from jaxspline.base.elements import (
    GMST_RATE,
    circular_orbit_over,
    geodetic_to_ecef,
    gmst,
    julian_date,
)
from jaxspline.geometry.frames import rot_z
from jaxspline.geometry.orbit import orbit_state
from jaxspline.geometry.pointing import Scene, pointing_state
from jaxspline.kernels.attitude import attitude_angle, quat_to_dcm
from jaxspline.kernels.joins import Maneuver, maneuver_eval
from jaxspline.kernels.limits import AxisLimits
from jaxspline.planner.flown_joins import NADIR, join_limits, plan_joins, reject_unflyable
from jaxspline.planner.result import Observations, PlanResult
from jaxspline.products.aem import aem_file_name, read_aem, write_aems
from jaxspline.products.attitude_history import attitude_history, plan_scene
from jaxspline.readers.config import PlannerConfig
from jaxspline.readers.mission import FlexMode, Satellite, Scenario, make_targets

EPOCH = dt.datetime(2026, 4, 14, 12, 30, tzinfo=dt.UTC)
DURATION = 900.0
OVER = (46.0, 15.0, 450.0)  # sub-satellite point [deg, deg] at t [s]
# (lat, lon) [deg] of the point targets, imaged for POINT_S from the start times below
POINTS = [(55.0, 17.0), (50.0, 12.0), (46.0, 15.5), (40.5, 14.0)]
STARTS = [300.0, 380.0, 450.0, 530.0]
POINT_S = 10.0
STRIP = (37.0, 15.0, 50e3, 185.0)  # lat, lon [deg], length [m], azimuth [deg]
STRIP_START = 610.0
SPEED = 7000.0  # [m/s]
ANGLE_TOL = 1e-9  # [rad]
INTEGRATION_TOL = 1e-8  # [rad]


def _scenario():
    gmst0 = float(gmst(julian_date(EPOCH)))
    orb = circular_orbit_over(np.radians(OVER[0]), np.radians(OVER[1]), OVER[2], gmst0)
    deg = np.radians
    sats = (
        Satellite("pc", orb, "per_channel", AxisLimits(deg([3.0, 3.0, 2.0]), deg([1.5, 1.5, 1.0]))),
        Satellite("ea", orb, "eigen_axis", AxisLimits(deg(1.8), deg(0.4)), settle=2.0),
        Satellite(
            "fx",
            orb,
            "flexible",
            AxisLimits(deg(1.5), deg(0.3)),
            settle=1.0,
            flex=FlexMode(2 * np.pi * 0.5, 0.01, deg(0.006)),
        ),
    )
    lat = [p[0] for p in POINTS] + [STRIP[0]]
    lon = [p[1] for p in POINTS] + [STRIP[1]]
    tg = make_targets(
        [0, 0, 0, 0, 1],
        deg(lat),
        deg(lon),
        duration=[POINT_S] * 4 + [0.0],
        length=[0.0] * 4 + [STRIP[2]],
        azimuth=[0.0] * 4 + [deg(STRIP[3])],
    )
    return Scenario("hist", EPOCH, DURATION, sats, tg, PlannerConfig(scan_speeds=(SPEED,)))


def _result(sc):
    n_sat, n_obs = len(sc.satellites), len(STARTS) + 1
    sat = np.repeat(np.arange(n_sat), n_obs)
    target = np.tile(np.arange(n_obs), n_sat)
    start = np.tile(STARTS + [STRIP_START], n_sat)
    end = start + np.tile([POINT_S] * 4 + [STRIP[2] / SPEED], n_sat)
    speed = np.tile([0.0] * 4 + [SPEED], n_sat)
    z = np.zeros(sat.size)
    nan = np.full(sat.size, np.nan)
    obs = Observations(sat, target, start, end, z, z, np.ones(sat.size), speed, nan, nan)
    return PlanResult(sc, obs, 1.0, 1.0, 0.0, True, {"valid": True}, {}, {})


@pytest.fixture(scope="module")
def case():
    sc = _scenario()
    res = _result(sc)
    return sc, res, attitude_history(res, step=1.0)


def _basis(sc, t):
    """Orbital axes (rows) in TEME from the analytic circular orbit (numpy)."""
    r, v = (np.asarray(x) for x in orbit_state(sc.satellites[0].orbit, jnp.asarray(t)))
    z = -r / np.linalg.norm(r, axis=-1, keepdims=True)
    y = -np.cross(r, v)
    y /= np.linalg.norm(y, axis=-1, keepdims=True)
    return np.stack([np.cross(y, z), y, z], -2)


def _angles(c):
    b = c[..., :, 2]
    return np.stack(
        [
            np.arctan2(-b[..., 1], np.hypot(b[..., 0], b[..., 2])),
            np.arctan2(b[..., 0], b[..., 2]),
            np.arctan2(c[..., 1, 0], c[..., 1, 1]),
        ],
        -1,
    )


def _at(h, t):
    i = np.searchsorted(h.t, t)
    assert np.all(np.abs(h.t[i] - t) < 1e-9)  # every boundary is a sample
    return i


def test_boundaries_match_planned_angles(case):
    sc, res, att = case
    obs = res.observations
    gmst0 = float(gmst(julian_date(EPOCH)))
    ref_scene = Scene(sc.satellites[0].orbit, gmst0)
    pts = np.asarray(geodetic_to_ecef(sc.targets.lat, sc.targets.lon, sc.targets.alt))
    for k, s in enumerate(sc.satellites):
        h = att.histories[s.name]
        m = (obs.sat == k) & (sc.targets.kind[obs.target] == 0)
        t = np.concatenate([obs.start[m], obs.end[m]])
        tgt = np.concatenate([obs.target[m], obs.target[m]])
        q = h.q[_at(h, t)]
        c = _basis(sc, t) @ np.asarray(quat_to_dcm(q))
        if s.model == "per_channel":
            ref = np.asarray(pointing_state(ref_scene, pts[tgt], t)[0])
            assert np.abs(_angles(c) - ref).max() < ANGLE_TOL
        else:  # boresight along the line of sight, zero yaw
            r = np.asarray(orbit_state(sc.satellites[0].orbit, jnp.asarray(t))[0])
            g = rot_z(-(gmst0 + GMST_RATE * t), pts[tgt])
            los = (g - r) / np.linalg.norm(g - r, axis=-1, keepdims=True)
            zb = np.einsum(
                "nij,nj->ni", np.asarray(quat_to_dcm(q)), np.tile([0, 0, 1.0], (t.size, 1))
            )
            err = np.arctan2(np.linalg.norm(np.cross(zb, los), axis=-1), np.sum(zb * los, -1))
            assert err.max() < ANGLE_TOL
            assert np.abs(_angles(c)[:, 2]).max() < ANGLE_TOL


def test_integrated_rates_reproduce_quaternions(case):
    _, _, att = case
    for name, h in att.histories.items():
        polys = [
            BPoly.from_derivatives(h.t, np.stack([h.omega[:, i], h.accel[:, i], h.jerk[:, i]], -1))
            for i in range(3)
        ]

        def rhs(t, q, polys=polys):
            w = np.array([p(t) for p in polys])
            qw, qv = q[0], q[1:]
            return 0.5 * np.concatenate([[-qv @ w], qw * w + np.cross(qv, w)])

        sol = solve_ivp(rhs, (h.t[0], h.t[-1]), h.q[0], method="DOP853", t_eval=h.t,
                        rtol=1e-12, atol=1e-13)  # fmt: skip
        q = sol.y.T / np.linalg.norm(sol.y.T, axis=-1, keepdims=True)
        err = np.asarray(attitude_angle(q, h.q))
        assert err.max() < INTEGRATION_TOL, (name, err.max())


def test_continuity_at_junctions(case):
    sc, res, att = case
    j = att.joins
    scene = plan_scene(sc)
    from jaxspline.planner.flown_joins import _laws
    from jaxspline.products.attitude_history import observation_laws

    obs = res.observations
    params = observation_laws(sc, obs.target, obs.speed)
    mode = np.array([1.0 if s.model == "per_channel" else 0.0 for s in sc.satellites])
    from jaxspline.planner.attitude_laws import law_states

    man = Maneuver(j.q_ref, j.coeffs, j.t_end - j.t_start)
    for side, idx, tt, tau in ((0, j.before, j.t_start, 0.0), (1, j.after, j.t_end, None)):
        law, t0 = _laws(idx, obs.start, params, mode[j.sat])
        ref = law_states(scene, j.sat, law, t0, tt)
        got = maneuver_eval(man, man.duration if tau is None else np.zeros(len(j)))
        assert np.asarray(attitude_angle(got[0], ref[0])).max() < ANGLE_TOL, side
        for a, b in zip(got[1:3], ref[1:3], strict=True):
            assert np.abs(np.asarray(a) - b).max() < 1e-11, side
        assert np.abs(np.asarray(got[3]) - ref[3]).max() < 1e-8, side  # ε' by central difference
    # and the history itself: no jump between neighbouring samples around each junction
    for name, h in att.histories.items():
        step = np.asarray(attitude_angle(h.q[1:], h.q[:-1]))
        w = np.linalg.norm(h.omega, axis=-1)
        assert np.all(step <= 1.05 * np.maximum(w[1:], w[:-1]) * np.diff(h.t) + 1e-9), name


def test_limit_check_against_finite_differences(case):
    sc, _, att = case
    j = att.joins
    n = 4001
    for i in range(len(j)):
        T = j.t_end[i] - j.t_start[i]
        tau = np.linspace(0.0, T, n)
        man = Maneuver(
            np.repeat(j.q_ref[i : i + 1], n, 0), np.repeat(j.coeffs[i : i + 1], n, 0), np.full(n, T)
        )
        q = np.array(maneuver_eval(man, tau)[0])
        q *= np.sign(np.sum(q * q[:1], -1))[:, None]
        h = tau[1] - tau[0]
        dq = np.gradient(q, h, axis=0, edge_order=2)
        w = 2 * (q[:, :1] * dq[:, 1:] - dq[:, :1] * q[:, 1:] - np.cross(q[:, 1:], dq[:, 1:]))
        e = np.gradient(w, h, axis=0, edge_order=2)
        in_ = slice(None)  # second-order differences everywhere, the ends included
        assert np.linalg.norm(w[in_], axis=-1).max() == pytest.approx(j.peak_rate[i], rel=1e-3)
        assert np.linalg.norm(e[in_], axis=-1).max() == pytest.approx(
            j.peak_accel[i], rel=2e-3, abs=1e-9
        )
        norm, chan = join_limits(sc.satellites[j.sat[i]])
        if j.ok[i] and chan is None:  # the brute-force peaks respect the limits too
            assert np.linalg.norm(w, axis=-1).max() <= norm.rate
            assert np.linalg.norm(e, axis=-1).max() <= norm.accel
        if chan is None:
            assert j.ratio[i, 0] == pytest.approx(j.peak_rate[i] / norm.rate)
            continue
        ang = np.unwrap(
            _angles(_basis(sc, j.t_start[i] + tau) @ np.asarray(quat_to_dcm(q))), axis=0
        )
        rate = np.gradient(ang, h, axis=0, edge_order=2)
        acc = np.gradient(rate, h, axis=0, edge_order=2)
        assert np.max(np.abs(rate[in_]) / chan.rate) == pytest.approx(j.ratio[i, 0], rel=1e-3)
        assert np.max(np.abs(acc[in_]) / chan.accel) == pytest.approx(
            j.ratio[i, 1], rel=5e-3, abs=1e-6
        )


def test_aem_round_trip(case, tmp_path):
    sc, res, att = case
    paths = write_aems(res, att, tmp_path)
    assert [p.name for p in paths] == [aem_file_name(s.name) for s in sc.satellites]
    with pytest.raises(FileExistsError, match="--force"):
        write_aems(res, att, tmp_path)
    for p in paths:
        name, epochs, q, w = read_aem(p)
        h = att.histories[name]
        assert np.array_equal(q, h.q)  # repr-printed doubles come back exactly
        np.testing.assert_allclose(w, h.omega, rtol=1e-15, atol=1e-20)  # deg/s in the file
        t = np.array([(dt.datetime.fromisoformat(e) - EPOCH).total_seconds() for e in epochs])
        assert np.abs(t - h.t).max() < 1e-6  # datetime parses microseconds; the file has ns


def test_rejection_drops_the_later_observation(case):
    sc, res, att = case
    obs = res.observations
    from jaxspline.products.attitude_history import observation_laws

    # a second observation 1 s after the first one of each satellite cannot be joined
    params = observation_laws(sc, obs.target, obs.speed)
    first = np.flatnonzero(np.r_[True, obs.sat[1:] != obs.sat[:-1]])
    extra = obs.end[first] + 1.0
    sat = np.concatenate([obs.sat, obs.sat[first]])
    start = np.concatenate([obs.start, extra])
    end = np.concatenate([obs.end, extra + POINT_S])
    p = np.concatenate([params, params[first + 3]])
    scene = plan_scene(sc)
    joins = plan_joins(scene, sc.satellites, sat, start, end, p)
    assert (~joins.ok).sum() >= len(sc.satellites)

    class Opp:
        options = type("O", (), {"sat": sat, "t_start": start, "t_end": end})
        params = p

    dropped, summary = reject_unflyable(sc, scene, Opp, list(range(sat.size)))
    assert set(dropped) >= set(range(obs.sat.size, sat.size)) - set()  # the inserted ones
    assert summary["violating"] == 0
    assert att.summary["joins"] == len(att.joins) and NADIR in att.joins.before


def test_bad_input_names_the_field(case):
    _, res, _ = case
    with pytest.raises(ValueError, match="step"):
        attitude_history(res, step=0.0)
    with pytest.raises(ValueError, match="sat, start, end, params"):
        plan_joins(None, res.scenario.satellites, [0], [1.0, 2.0], [2.0], np.zeros((1, 8)))
