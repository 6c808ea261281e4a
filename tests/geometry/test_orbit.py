"""Orbit geometry against published values, SGP4's own vectors and autodiff references."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from sgp4.api import Satrec
from sgp4.propagation import gstime

from jaxspline.base.elements import (
    MU_EARTH,
    R_EARTH,
    circular_orbit,
    circular_orbit_over,
    geodetic_to_ecef,
    gmst,
    julian_date,
    sso_inclination,
)
from jaxspline.geometry.frames import ecef_to_geodetic, sun_direction, teme_to_ecef
from jaxspline.geometry.orbit import (
    orbit_position,
    orbit_state,
    padded_orbit,
    propagate_tle,
    tabulate_orbits,
    tle_orbit,
)

# Vallado's SGP4 verification TLE (satellite 00005) and tcppver.out states (km, km/s)
TLE5 = (
    "1 00005U 58002B   00179.78495062  .00000023  00000-0  28098-4 0  4753",
    "2 00005  34.2682 348.7242 1859667 331.7664  19.3264 10.82419157413667",
)
TLE5_STATES = {
    0.0: ((7022.46529266, -1400.08296755, 0.03995155), (1.893841015, 6.405893759, 4.534807250)),
    360.0: (
        (-7154.03120202, -3783.17682504, -3536.19412294),
        (4.741887409, -4.151817765, -2.093935425),
    ),
}
ISS = (
    "1 25544U 98067A   08264.51782528 -.00002182  00000-0 -11606-4 0  2927",
    "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537",
)


def test_sso_inclination_600km():
    # hand computation: n = 1.08310e-3 rad/s, cos i = -1.99099e-7 / 1.46943e-6 -> 97.787 deg
    assert np.degrees(sso_inclination(600e3)) == pytest.approx(97.787, abs=5e-3)
    assert np.degrees(sso_inclination(800e3)) == pytest.approx(98.603, abs=5e-3)


def test_circular_orbit_radius_speed_period():
    orb = circular_orbit(600e3, np.radians(97.8), 0.3, 1.1, j2_drift=False)
    a = R_EARTH + 600e3
    period = 2 * np.pi * np.sqrt(a**3 / MU_EARTH)
    t = jnp.linspace(0.0, 5000.0, 11)
    r, v = orbit_state(orb, t)
    np.testing.assert_allclose(np.linalg.norm(r, axis=-1), a, rtol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(v, axis=-1), np.sqrt(MU_EARTH / a), rtol=1e-13)
    np.testing.assert_allclose(np.sum(np.asarray(r) * np.asarray(v), -1), 0.0, atol=1e-3)
    np.testing.assert_allclose(orbit_position(orb, period + t), orbit_position(orb, t), atol=1e-6)
    assert 5790 < period < 5810  # 96.7 min at 600 km


def test_circular_velocity_matches_autodiff():
    orb = circular_orbit(600e3)  # SSO with J2 nodal drift

    def pos(t):
        return orbit_position(orb, t)

    for t in (0.0, 123.4, 4000.0):
        _, v_ad = jax.jvp(pos, (jnp.asarray(t),), (jnp.asarray(1.0),))
        np.testing.assert_allclose(orbit_state(orb, t)[1], v_ad, rtol=1e-13, atol=1e-9)


def test_sso_node_drift_is_one_turn_per_year():
    orb = circular_orbit(600e3)
    assert float(orb.raan_rate) * 365.2421897 * 86400 == pytest.approx(2 * np.pi, rel=1e-12)


def test_circular_orbit_over_places_the_subsatellite_point():
    jd0 = julian_date("2026-06-21T10:00:00Z")
    g0 = float(gmst(jd0))
    g300 = float(gmst(jd0, 300.0 / 86400.0))  # the Earth's rotation angle 300 s later
    for desc in (True, False):
        orb = circular_orbit_over(np.radians(46.0), np.radians(15.0), 300.0, g0, descending=desc)
        r = orbit_position(orb, 300.0)
        re = np.asarray(teme_to_ecef(r, g300))
        lat_gc = np.arctan2(re[2], np.hypot(re[0], re[1]))
        assert np.degrees(lat_gc) == pytest.approx(46.0, abs=1e-10)
        assert np.degrees(np.arctan2(re[1], re[0])) == pytest.approx(15.0, abs=1e-9)
        # heading: descending means z decreasing
        _, v = orbit_state(orb, 300.0)
        assert (float(v[2]) < 0) == desc


@pytest.mark.parametrize("tsince", sorted(TLE5_STATES))
def test_propagate_tle_matches_sgp4_verification_vectors(tsince):
    sat = Satrec.twoline2rv(*TLE5)
    jd = sat.jdsatepoch + np.zeros(1)
    fr = sat.jdsatepochF + tsince / 1440.0
    r, v, err = propagate_tle(*TLE5, jd, fr, gravity="wgs72")  # the set's constants
    r_ref, v_ref = TLE5_STATES[tsince]
    assert err[0] == 0
    np.testing.assert_allclose(r[0] / 1e3, r_ref, atol=1e-6)  # 1 mm
    np.testing.assert_allclose(v[0] / 1e3, v_ref, atol=1e-8)


def test_tle_orbit_interpolates_sgp4():
    sat = Satrec.twoline2rv(*ISS)
    epoch = sat.jdsatepoch + sat.jdsatepochF + 0.1
    orb = tle_orbit(*ISS, epoch, 600.0, step=20.0)
    t = np.linspace(3.3, 597.1, 37)  # off the knots
    jd = np.full(t.shape, np.floor(epoch))
    r_ref, v_ref, _ = propagate_tle(*ISS, jd, (epoch - jd) + t / 86400.0)
    r, v = orbit_state(orb, jnp.asarray(t))
    assert np.max(np.linalg.norm(np.asarray(r) - r_ref, axis=-1)) < 0.5  # m
    assert (
        np.max(np.linalg.norm(np.asarray(v) - v_ref, axis=-1)) < 0.1
    )  # m/s (knot accelerations: two-body + J2, not SGP4)


def test_gmst_matches_vallado_and_sgp4():
    # Vallado Example 3-5: 1992-08-20 12:14 UT1 -> GMST 152.578787886 deg
    jd = julian_date("1992-08-20T12:14:00")
    assert np.degrees(gmst(jd)) == pytest.approx(152.578787886, abs=1e-6)
    for jd in (2451545.0, 2460000.3, 2461212.91666):
        assert float(gmst(jd)) == pytest.approx(gstime(jd), abs=1e-9)


def test_teme_to_ecef_velocity_is_the_derivative():
    orb = circular_orbit(600e3, raan=0.7)
    g0 = 1.3

    def ecef(t):
        return teme_to_ecef(orbit_position(orb, t), g0 + 7.292115146706979e-5 * t)

    t = jnp.asarray(250.0)
    r, v = orbit_state(orb, t)
    _, v_ecef = teme_to_ecef(r, g0 + 7.292115146706979e-5 * t, v)
    _, v_ad = jax.jvp(ecef, (t,), (jnp.asarray(1.0),))
    np.testing.assert_allclose(v_ecef, v_ad, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize(
    ("lat", "lon", "h", "xyz"),
    [
        (0.0, 0.0, 0.0, (6378137.0, 0.0, 0.0)),
        (90.0, 0.0, 0.0, (0.0, 0.0, 6356752.314245)),
        (0.0, 90.0, 1000.0, (0.0, 6379137.0, 0.0)),
        (45.0, 0.0, 0.0, (4517590.878849, 0.0, 4487348.408866)),
    ],
)
def test_geodetic_to_ecef_wgs84_points(lat, lon, h, xyz):
    r = geodetic_to_ecef(np.radians(lat), np.radians(lon), h)
    np.testing.assert_allclose(r, xyz, atol=1e-5)


def test_ecef_to_geodetic_round_trip():
    rng = np.random.default_rng(1)
    lat = rng.uniform(-1.5, 1.5, 50)
    lon = rng.uniform(-3.1, 3.1, 50)
    h = rng.uniform(-100.0, 9e5, 50)
    la, lo, hh = ecef_to_geodetic(geodetic_to_ecef(lat, lon, h))
    np.testing.assert_allclose(la, lat, atol=1e-11)
    np.testing.assert_allclose(lo, lon, atol=1e-12)
    np.testing.assert_allclose(hh, h, atol=1e-4)


@pytest.mark.parametrize(
    ("when", "lam"),
    [
        ("2024-03-20T03:06:00", 0.0),  # March equinox (UTC, to the minute)
        ("2024-06-20T20:51:00", 90.0),  # June solstice
        ("2024-09-22T12:44:00", 180.0),  # September equinox
        ("2024-12-21T09:20:00", 270.0),  # December solstice
    ],
)
def test_sun_direction_at_equinoxes_and_solstices(when, lam):
    s = sun_direction(julian_date(when))
    assert np.linalg.norm(s) == pytest.approx(1.0, abs=1e-14)
    eps = np.radians(23.4393)
    lam_got = np.degrees(np.arctan2(s[1] * np.cos(eps) + s[2] * np.sin(eps), s[0])) % 360.0
    diff = (lam_got - lam + 180.0) % 360.0 - 180.0
    assert abs(diff) < 0.015
    dec = np.degrees(np.arcsin(s[2]))
    assert dec == pytest.approx(
        np.degrees(np.arcsin(np.sin(eps) * np.sin(np.radians(lam)))), abs=0.015
    )


def test_float32_orbit_follows_dtype():
    orb = jax.tree.map(lambda x: jnp.asarray(x, jnp.float32), circular_orbit(600e3))
    r = orbit_position(orb, jnp.float32(100.0))
    assert r.dtype == jnp.float32
    r64 = orbit_position(circular_orbit(600e3), 100.0)
    np.testing.assert_allclose(r, r64, rtol=1e-6)


def test_value_errors_name_the_argument():
    with pytest.raises(ValueError, match="altitude"):
        circular_orbit(-5.0)
    with pytest.raises(ValueError, match="inclination"):
        circular_orbit(600e3, inclination=4.0)
    with pytest.raises(ValueError, match="epoch"):
        julian_date("not a date")
    with pytest.raises(ValueError, match="tle"):
        propagate_tle("1 garbage", "2 garbage", np.array([2451545.0]))
    with pytest.raises(ValueError, match="orbit"):
        orbit_position("not an orbit", 0.0)


def test_circular_elements_stay_float64_when_jax_is_in_float32():
    """A scenario read before the planner switches float64 on keeps its elements exact."""
    with jax.enable_x64(False):
        orbs = (circular_orbit(600e3, 1.7, 0.3, 1.2), circular_orbit_over(0.8, 0.2, 900.0, 1.1))
    for orb in orbs:
        for name, x in orb._asdict().items():
            assert np.asarray(x).dtype == np.float64, name
    assert float(orbs[0].inclination) == 1.7 and float(orbs[0].arg_lat) == 1.2


def test_padded_table_interpolates_exactly_as_the_table():
    """Padding to power-of-two sizes changes no value, inside the knots and past both ends
    (the end pieces extrapolate from the true last knot, not from the padding)."""
    srcs = [circular_orbit(550e3, 1.7, 0.1 * k, 0.5 * k) for k in range(3)]
    orb = tabulate_orbits(srcs, 2461000.5, 1000.0, 10.0).orbit
    pad = padded_orbit(orb)
    assert pad.r.shape[:2] == (4, 128) and int(pad.n) == orb.t.shape[0]
    rng = np.random.default_rng(3)
    t = np.r_[rng.uniform(-30.0, 1040.0, 200), np.asarray(orb.t)[-1], 1060.0]
    sat = rng.integers(0, 3, t.size)
    for f in (orbit_position, orbit_state):
        want = jax.jit(f)(orb, jnp.asarray(t), jnp.asarray(sat))
        got = jax.jit(f)(pad, jnp.asarray(t), jnp.asarray(sat))
        for w, g in zip(jax.tree.leaves(want), jax.tree.leaves(got), strict=True):
            np.testing.assert_array_equal(np.asarray(g), np.asarray(w))
