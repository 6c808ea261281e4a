"""Routes: windows, boundary states, options and scan feasibility against independent references."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxspline.base.elements import circular_orbit_over, geodetic_to_ecef, gmst, julian_date
from jaxspline.geometry.pointing import Scene, off_nadir, pointing_angles
from jaxspline.geometry.routes import (
    POINT,
    STRIP,
    make_route_set,
    make_route_spec,
    strip_direction,
)
from jaxspline.kernels.limits import AxisLimits
from jaxspline.screen.options import RouteOptions, build_route_options

JD = julian_date("2026-06-21T10:00:00Z")
G0 = float(gmst(JD))
SCENE = Scene(circular_orbit_over(np.radians(46.0), np.radians(15.0), 300.0, G0), jnp.asarray(G0))
LIM = np.radians(45.0)
SPEC = make_route_spec(
    kind=[POINT, POINT, STRIP, STRIP, POINT],
    lat=np.radians([47.0, 45.0, 46.5, 44.5, 10.0]),
    lon=np.radians([15.5, 13.0, 16.0, 14.0, 15.0]),  # the last one is never visible
    azimuth=np.radians([0.0, 0.0, 195.0, 20.0, 0.0]),  # strip 3 runs against the flight
    length=[0.0, 0.0, 40e3, 30e3, 0.0],
    duration=[6.0, 5.0, 0.0, 0.0, 5.0],
    value=[3.0, 1.0, 5.0, 2.0, 4.0],
)


@functools.cache
def _routes():
    """The routes of SPEC (built on first use, not while the run collects the tests)."""
    return make_route_set(SCENE, SPEC, 0.0, 600.0, LIM, nominal_speed=7000.0)


LIMITS = AxisLimits(np.radians([2.0, 2.0, 2.0]), np.radians([1.0, 1.0, 1.0]))


def _mid_t0():
    lo, hi = np.asarray(_routes().t0_min[:4]), np.asarray(_routes().t0_max[:4])
    return jnp.asarray(0.5 * (lo + hi))


def test_windows_and_visibility():
    lo, hi = np.asarray(_routes().t0_min), np.asarray(_routes().t0_max)
    assert np.all(lo[:4] < hi[:4])
    assert lo[4] == np.inf and hi[4] == -np.inf  # 10 N is out of view on this pass
    r_e = np.asarray(geodetic_to_ecef(np.asarray(_routes().lat), np.asarray(_routes().lon), 0.0))
    for k in range(4):
        assert float(off_nadir(SCENE, r_e[k], lo[k])) == pytest.approx(LIM, abs=1e-8)
        dur = float(_routes().duration[k])
        assert float(off_nadir(SCENE, r_e[k], hi[k] + dur)) == pytest.approx(LIM, abs=1e-8)


def test_strip_against_the_flight_is_reversed():
    # strip 2 (azimuth 195 deg on a descending pass heading ~190 deg) keeps its direction,
    # strip 3 (azimuth 20 deg) is scanned from its far end towards the south
    az = np.degrees(np.asarray(_routes().azimuth))
    assert az[2] == pytest.approx(195.0, abs=1e-9)
    assert abs(((az[3] - 200.0) + 180.0) % 360.0 - 180.0) < 1.0
    assert float(_routes().lat[3]) > SPEC.lat[3]


def test_point_states_match_pointing_and_t0_derivative_is_the_rate():
    route = jnp.asarray([0, 1, 2, 3])
    t0 = _mid_t0()
    t1, sa, sr, ea, er = _routes().states(route, t0)
    np.testing.assert_allclose(t1, t0 + np.asarray(_routes().duration)[np.asarray(route)])
    tgt = np.asarray(geodetic_to_ecef(np.asarray(_routes().lat), np.asarray(_routes().lon), 0.0))
    ref = np.asarray(pointing_angles(SCENE, tgt[:2], t0[:2]))
    np.testing.assert_allclose(sa[:2], ref, atol=1e-13)
    # a tracked point does not depend on t0 except through time: d(start angle)/dt0 = rate
    jac = _jacobian()
    d = np.stack([jac[k, :3, k] for k in range(2)])
    np.testing.assert_allclose(d, np.asarray(sr)[:2], rtol=1e-10, atol=1e-14)


def test_strip_end_points_at_the_great_circle_end():
    route = jnp.asarray([0, 1, 2, 3])
    t0 = _mid_t0()
    t1, _, _, ea, _ = _routes().states(route, t0)
    for k, r in [(2, 2), (3, 3)]:
        # independent numpy great circle on the sphere through the start point
        rs = _routes()
        lat, lon, az = (float(np.asarray(x)[r]) for x in (rs.lat, rs.lon, rs.azimuth))
        g0 = np.asarray(geodetic_to_ecef(lat, lon, 0.0))
        rad = np.linalg.norm(g0)
        u = g0 / rad
        d = strip_direction(lat, lon, az)
        d = d - (d @ u) * u
        d /= np.linalg.norm(d)
        delta = float(_routes().length[r]) / rad
        end = rad * (u * np.cos(delta) + d * np.sin(delta))
        ref = np.asarray(pointing_angles(SCENE, end, float(t1[k])))
        np.testing.assert_allclose(np.asarray(ea)[k, :2], ref[:2], atol=1e-11)


def _states_flat(x):
    _, sa, sr, ea, er = _routes().states(jnp.asarray([0, 1, 2, 3]), x)
    return jnp.concatenate([sa, sr, ea, er], axis=1)


_JAC = []


def _jacobian():
    if not _JAC:
        _JAC.append(np.asarray(jax.jit(jax.jacfwd(_states_flat))(_mid_t0())))
    return _JAC[0]


def test_states_gradient_matches_finite_differences():
    t0 = _mid_t0()
    jac = _jacobian()
    diag = np.stack([jac[k, :, k] for k in range(4)])
    h = 0.05
    f = _states_flat
    fd = (
        -np.asarray(f(t0 + 2 * h))
        + 8 * np.asarray(f(t0 + h))
        - 8 * np.asarray(f(t0 - h))
        + np.asarray(f(t0 - 2 * h))
    ) / (12 * h)
    np.testing.assert_allclose(diag, fd, rtol=1e-6, atol=1e-11)
    assert np.isfinite(diag).all()


def test_options_grid_scan_ok_and_model_agree():
    speeds = (4000.0, 7000.0)
    opts, info = build_route_options(
        _routes(), LIMITS, LIM, n_t0=3, scan_speeds=speeds, epoch_jd=JD, sun_elevation_min=None
    )
    assert isinstance(opts, RouteOptions)
    route = np.asarray(opts.route)
    # 2 points x 3 t0 + 2 strips x 3 t0 x 2 speeds; the invisible route has none
    assert route.size == 2 * 3 + 2 * 3 * 2
    assert 4 not in route
    t0 = np.asarray(opts.t_start)
    assert np.all(t0 >= np.asarray(_routes().t0_min)[route] - 1e-9)
    assert np.all(t0 <= np.asarray(_routes().t0_max)[route] + 1e-9)
    strip = np.asarray(_routes().kind)[route] == STRIP
    np.testing.assert_allclose(
        (np.asarray(opts.t_end) - t0)[strip],
        np.asarray(_routes().length)[route][strip] / info.speed[strip],
    )
    # peak rates over the scan bound the boundary rates, and scan_ok follows the limits
    assert np.all(info.peak_rate >= np.abs(np.asarray(opts.start_rate)) - 1e-15)
    ok = np.asarray(opts.scan_ok)
    expect = (info.peak_rate <= LIMITS.rate).all(1) & (info.peak_accel <= LIMITS.accel).all(1)
    expect &= info.max_off_nadir <= LIM + 1e-9
    np.testing.assert_array_equal(ok, expect)
    assert np.all(np.degrees(info.sun_elevation) > 40.0)  # June, 10 UTC, central Europe
    # the RouteModel reproduces the table for the chosen speeds
    sel = np.flatnonzero(strip & (info.speed == 4000.0))
    sel = sel[np.unique(route[sel], return_index=True)[1]]  # one option per strip route
    sel = np.concatenate([sel, sel])  # K = 4, the shape compiled above
    model = _routes().with_speeds(route[sel], info.speed[sel])
    t1, sa, sr, ea, er = model.states(jnp.asarray(route[sel]), jnp.asarray(t0[sel]))
    np.testing.assert_allclose(t1, np.asarray(opts.t_end)[sel], rtol=1e-13)
    np.testing.assert_allclose(ea, np.asarray(opts.end_angle)[sel], atol=1e-12)
    np.testing.assert_allclose(er, np.asarray(opts.end_rate)[sel], atol=1e-14)
    # tiny limits or a Sun that must be at the zenith: nothing is feasible
    tiny = AxisLimits(np.full(3, 1e-6), np.full(3, 1e-6))
    opts2, _ = build_route_options(_routes(), tiny, LIM, n_t0=3, scan_speeds=speeds)
    assert not np.asarray(opts2.scan_ok).any()
    opts3, _ = build_route_options(
        _routes(), LIMITS, LIM, n_t0=3, scan_speeds=speeds, epoch_jd=JD, sun_elevation_min=1.5
    )
    assert not np.asarray(opts3.scan_ok).any()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"kind": [2], "lat": [0.0], "lon": [0.0]}, "kind"),
        ({"kind": [0], "lat": [2.0], "lon": [0.0], "duration": 1.0}, "lat"),
        ({"kind": [0], "lat": [0.1], "lon": [0.0], "duration": 0.0}, "duration"),
        ({"kind": [1], "lat": [0.1], "lon": [0.0], "length": -1.0}, "length"),
        ({"kind": [0], "lat": [0.1], "lon": [np.nan], "duration": 1.0}, "lon"),
        ({"kind": [0], "lat": [0.1], "lon": [0.0], "duration": 1.0, "value": 0.0}, "value"),
        (
            {"kind": [0], "lat": [0.1], "lon": [0.0], "duration": 1.0, "t0_lo": 5, "t0_hi": 1},
            "t0_lo",
        ),
        ({"kind": [0, 0], "lat": [0.1, 0.2, 0.3], "lon": [0.0], "duration": 1.0}, "broadcast"),
    ],
)
def test_make_route_spec_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        make_route_spec(**kwargs)


def test_build_options_argument_errors():
    with pytest.raises(ValueError, match="n_t0"):
        build_route_options(_routes(), LIMITS, LIM, n_t0=0)
    with pytest.raises(ValueError, match="scan_speeds"):
        build_route_options(_routes(), LIMITS, LIM, scan_speeds=(0.0,))
