"""Orbit geometry: circular (J2-drifting) orbits, TLE propagation, Earth rotation, Sun.

Frames. ``ECI`` here is the true-equator, mean-equinox frame of SGP4 (TEME). The
circular orbit model is expressed in the same frame. Earth-fixed coordinates are
obtained by one rotation about z by the Greenwich mean sidereal time (IAU 1982),
i.e. TEME -> pseudo-Earth-fixed; polar motion (< 15 m on the ground) and UT1 - UTC
(< 0.9 s, < 0.4 km of Earth rotation at the equator) are ignored. This is the
usual accuracy class of SGP4 itself (~1 km).

Units: metres, seconds, radians. Times ``t`` are seconds from a scenario epoch,
whose Julian date (UTC) is carried separately.

References: vector-spline paper (seeds/vector-spline-guidance-laws, example data:
600 km Sun-synchronous orbit); Vallado, *Fundamentals of Astrodynamics* (GMST,
J2 nodal regression, WGS84); Astronomical Almanac low-precision Sun formula.
"""

from __future__ import annotations

import datetime as _dt
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline._validate import check_finite, check_positive

__all__ = [
    "MU_EARTH",
    "R_EARTH",
    "J2_EARTH",
    "WGS84_F",
    "OMEGA_EARTH",
    "CircularOrbit",
    "HermiteOrbit",
    "sso_inclination",
    "circular_orbit",
    "circular_orbit_over",
    "orbit_position",
    "orbit_state",
    "julian_date",
    "gmst",
    "earth_rotation_angle",
    "teme_to_ecef",
    "geodetic_to_ecef",
    "ecef_to_geodetic",
    "propagate_tle",
    "tle_orbit",
    "sun_direction",
]

MU_EARTH = 3.986004418e14  # m^3/s^2
R_EARTH = 6378137.0  # m, WGS84 equatorial radius
J2_EARTH = 1.08262668e-3
WGS84_F = 1.0 / 298.257223563
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
OMEGA_EARTH = 7.292115146706979e-5  # rad/s, GMST rate (sidereal day 86164.0905 s)
_TROPICAL_YEAR = 365.2421897 * 86400.0  # s
_JD_UNIX0 = 2440587.5


class CircularOrbit(NamedTuple):
    """A circular orbit with secular J2 nodal regression (a pytree of scalars).

    Attributes:
      radius: orbit radius a [m].
      inclination: i [rad].
      raan: right ascension of the ascending node at t = 0 [rad].
      arg_lat: argument of latitude u at t = 0 [rad].
      mean_motion: n [rad/s] (Keplerian, sqrt(mu / a^3)).
      raan_rate: dOmega/dt [rad/s] (-1.5 n J2 (R/a)^2 cos i, or 0).

    Position in ECI: r = a [cos W cos u - sin W cos i sin u,
    sin W cos u + cos W cos i sin u, sin i sin u], u = u0 + n t, W = W0 + W' t.
    """

    radius: jnp.ndarray
    inclination: jnp.ndarray
    raan: jnp.ndarray
    arg_lat: jnp.ndarray
    mean_motion: jnp.ndarray
    raan_rate: jnp.ndarray


class HermiteOrbit(NamedTuple):
    """A tabulated orbit, interpolated by quintic Hermite pieces (C2 in t).

    Attributes:
      t: knot times [M] [s], equally spaced.
      r, v, a: position [M, 3] [m], velocity [M, 3] [m/s], acceleration [M, 3] [m/s^2]
        at the knots (from SGP4; accelerations from the two-body + J2 model).

    Between knots the position is the unique quintic matching r, v, a at both ends,
    so the interpolant and its first two derivatives are continuous. Outside the
    knot range the end pieces are extrapolated (keep the scenario inside the table).
    """

    t: jnp.ndarray
    r: jnp.ndarray
    v: jnp.ndarray
    a: jnp.ndarray


def sso_inclination(altitude: float) -> float:
    """Inclination [rad] of a circular Sun-synchronous orbit at ``altitude`` [m].

    cos i = -W'_sun / (1.5 n J2 (R/a)^2), with W'_sun = 2 pi / tropical year,
    n = sqrt(mu / a^3), a = R + h (Vallado eq. 9-41). 600 km -> 97.79 deg.
    """
    check_positive("altitude", altitude)
    a = R_EARTH + float(altitude)
    n = np.sqrt(MU_EARTH / a**3)
    cos_i = -(2.0 * np.pi / _TROPICAL_YEAR) / (1.5 * n * J2_EARTH * (R_EARTH / a) ** 2)
    if not -1.0 <= cos_i <= 1.0:
        raise ValueError(f"altitude={altitude!r} m admits no Sun-synchronous orbit")
    return float(np.arccos(cos_i))


def circular_orbit(
    altitude: float = 600e3,
    inclination: float | None = None,
    raan: float = 0.0,
    arg_lat: float = 0.0,
    j2_drift: bool = True,
) -> CircularOrbit:
    """Build a :class:`CircularOrbit` from elements (angles in rad, altitude in m).

    ``inclination=None`` gives the Sun-synchronous inclination (:func:`sso_inclination`).
    ``j2_drift`` adds the secular nodal regression W' = -1.5 n J2 (R/a)^2 cos i.
    """
    check_positive("altitude", altitude)
    for name, val in (("raan", raan), ("arg_lat", arg_lat)):
        check_finite(name, val)
    if inclination is None:
        inclination = sso_inclination(altitude)
    check_finite("inclination", inclination)
    if not 0.0 <= float(inclination) <= np.pi:
        raise ValueError(f"inclination must be in [0, pi] rad, got {inclination!r}")
    a = R_EARTH + float(altitude)
    n = np.sqrt(MU_EARTH / a**3)
    rate = -1.5 * n * J2_EARTH * (R_EARTH / a) ** 2 * np.cos(inclination) if j2_drift else 0.0
    return CircularOrbit(*(jnp.asarray(float(x)) for x in (a, inclination, raan, arg_lat, n, rate)))


def circular_orbit_over(
    lat: float,
    lon: float,
    t: float,
    gmst0: float,
    altitude: float = 600e3,
    inclination: float | None = None,
    descending: bool = True,
    j2_drift: bool = True,
) -> CircularOrbit:
    """A circular orbit whose sub-satellite point is at geocentric (lat, lon) [rad] at time t [s].

    sin(lat) = sin i sin u gives u (ascending or descending branch); the node follows
    from lon + theta(t) = W + atan2(cos i sin u, cos u), theta(t) = gmst0 + w_E t.
    """
    base = circular_orbit(altitude, inclination, 0.0, 0.0, j2_drift)
    inc = float(base.inclination)
    s = np.sin(lat) / np.sin(inc)
    if abs(s) > 1.0:
        raise ValueError(f"lat={np.degrees(lat)!r} deg is not reachable with inclination {inc!r}")
    u = np.arcsin(s)
    if descending:
        u = np.pi - u
    raan_t = lon + gmst0 + OMEGA_EARTH * t - np.arctan2(np.cos(inc) * np.sin(u), np.cos(u))
    u0 = u - float(base.mean_motion) * t
    raan0 = raan_t - float(base.raan_rate) * t
    return base._replace(
        raan=jnp.asarray(np.mod(raan0, 2 * np.pi)), arg_lat=jnp.asarray(np.mod(u0, 2 * np.pi))
    )


def _circular_position(orb: CircularOrbit, t):
    u = orb.arg_lat + orb.mean_motion * t
    w = orb.raan + orb.raan_rate * t
    cu, su, cw, sw = jnp.cos(u), jnp.sin(u), jnp.cos(w), jnp.sin(w)
    ci, si = jnp.cos(orb.inclination), jnp.sin(orb.inclination)
    return orb.radius * jnp.stack([cw * cu - sw * ci * su, sw * cu + cw * ci * su, si * su], -1)


def _circular_velocity(orb: CircularOrbit, t):
    u = orb.arg_lat + orb.mean_motion * t
    w = orb.raan + orb.raan_rate * t
    cu, su, cw, sw = jnp.cos(u), jnp.sin(u), jnp.cos(w), jnp.sin(w)
    ci, si = jnp.cos(orb.inclination), jnp.sin(orb.inclination)
    du = jnp.stack([-cw * su - sw * ci * cu, -sw * su + cw * ci * cu, si * cu], -1)
    dw = jnp.stack([-sw * cu - cw * ci * su, cw * cu - sw * ci * su, jnp.zeros_like(su)], -1)
    return orb.radius * (orb.mean_motion * du + orb.raan_rate * dw)


def _hermite_basis(orb: HermiteOrbit, t, deriv: bool):
    t = jnp.asarray(t)
    h = orb.t[1] - orb.t[0]
    k = jnp.clip(jnp.floor((t - orb.t[0]) / h).astype(jnp.int32), 0, orb.t.shape[0] - 2)
    s = ((t - orb.t[k]) / h)[..., None]
    s2, s3, s4 = s**2, s**3, s**4
    if deriv:  # d/ds of the quintic Hermite basis, then d/dt = (1/h) d/ds
        b = (
            (-30 * s2 + 60 * s3 - 30 * s4) / h,
            1 - 18 * s2 + 32 * s3 - 15 * s4,
            (s - 4.5 * s2 + 6 * s3 - 2.5 * s4) * h,
            (30 * s2 - 60 * s3 + 30 * s4) / h,
            -12 * s2 + 28 * s3 - 15 * s4,
            (1.5 * s2 - 4 * s3 + 2.5 * s4) * h,
        )
    else:
        s5 = s**5
        b = (
            1 - 10 * s3 + 15 * s4 - 6 * s5,
            (s - 6 * s3 + 8 * s4 - 3 * s5) * h,
            (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * h**2,
            10 * s3 - 15 * s4 + 6 * s5,
            (-4 * s3 + 7 * s4 - 3 * s5) * h,
            (0.5 * s3 - s4 + 0.5 * s5) * h**2,
        )
    return (
        b[0] * orb.r[k]
        + b[1] * orb.v[k]
        + b[2] * orb.a[k]
        + b[3] * orb.r[k + 1]
        + b[4] * orb.v[k + 1]
        + b[5] * orb.a[k + 1]
    )


def orbit_position(orbit, t):
    """Satellite position [..., 3] [m] in ECI (TEME) at time(s) t [s]; differentiable in t."""
    if isinstance(orbit, HermiteOrbit):
        return _hermite_basis(orbit, t, False)
    if isinstance(orbit, CircularOrbit):
        return _circular_position(orbit, t)
    raise ValueError(f"orbit must be a CircularOrbit or HermiteOrbit, got {type(orbit).__name__}")


def orbit_state(orbit, t):
    """(position [..., 3] [m], velocity [..., 3] [m/s]) in ECI at time(s) t [s].

    The velocity is the analytic time derivative of :func:`orbit_position` (so that
    pointing kernels need no nested autodiff for it); differentiable in t.
    """
    if isinstance(orbit, HermiteOrbit):
        return _hermite_basis(orbit, t, False), _hermite_basis(orbit, t, True)
    if isinstance(orbit, CircularOrbit):
        return _circular_position(orbit, t), _circular_velocity(orbit, t)
    raise ValueError(f"orbit must be a CircularOrbit or HermiteOrbit, got {type(orbit).__name__}")


def julian_date(when) -> float:
    """Julian date (UTC) of a datetime or ISO-8601 string (naive = UTC)."""
    if isinstance(when, str):
        try:
            when = _dt.datetime.fromisoformat(when.strip())
        except ValueError as exc:
            raise ValueError(f"epoch must be an ISO-8601 date-time, got {when!r}") from exc
    if not isinstance(when, _dt.datetime):
        raise ValueError(f"epoch must be a datetime or ISO string, got {when!r}")
    if when.tzinfo is None:
        when = when.replace(tzinfo=_dt.UTC)
    return _JD_UNIX0 + when.timestamp() / 86400.0


def gmst(jd_ut1):
    """Greenwich mean sidereal time [rad] in [0, 2 pi) at Julian date(s) (UT1; UTC used).

    IAU 1982: GMST[s] = 67310.54841 + (876600 h + 8640184.812866) T + 0.093104 T^2
    - 6.2e-6 T^3, T = (JD - 2451545) / 36525 (Vallado eq. 3-47).
    """
    jd = np.asarray(jd_ut1, dtype=np.float64)
    tu = (jd - 2451545.0) / 36525.0
    sec = (
        67310.54841 + (876600.0 * 3600.0 + 8640184.812866) * tu + 0.093104 * tu**2 - 6.2e-6 * tu**3
    )
    return np.mod(np.mod(sec, 86400.0) * (2 * np.pi / 86400.0), 2 * np.pi)


def earth_rotation_angle(gmst0, t):
    """Earth rotation angle theta(t) = gmst0 + w_E t [rad] (JAX; t [s] from the epoch)."""
    return gmst0 + OMEGA_EARTH * t


def _rz(theta, x):
    """Coordinates of x in a frame rotated by +theta about z: (c x + s y, -s x + c y, z)."""
    c, s = jnp.cos(theta), jnp.sin(theta)
    return jnp.stack([c * x[..., 0] + s * x[..., 1], -s * x[..., 0] + c * x[..., 1], x[..., 2]], -1)


def teme_to_ecef(r, theta, v=None):
    """Rotate TEME position (and velocity) to Earth-fixed by the Earth rotation angle theta.

    r_ecef = Rz(theta) r; v_ecef = Rz(theta) v - w_E z x r_ecef. Polar motion ignored.
    Arrays [..., 3]; theta broadcastable to r[..., 0]. Returns r_ecef or (r_ecef, v_ecef).
    """
    r_e = _rz(theta, jnp.asarray(r))
    if v is None:
        return r_e
    v_e = _rz(theta, jnp.asarray(v))
    w_x_r = jnp.stack([-r_e[..., 1], r_e[..., 0], jnp.zeros_like(r_e[..., 0])], -1) * OMEGA_EARTH
    return r_e, v_e - w_x_r


def geodetic_to_ecef(lat, lon, h=0.0):
    """WGS84 geodetic latitude, longitude [rad] and height [m] -> ECEF [..., 3] [m].

    N = a / sqrt(1 - e^2 sin^2 lat); x = (N + h) cos lat cos lon, y = (N + h) cos lat sin lon,
    z = (N (1 - e^2) + h) sin lat.
    """
    lat, lon, h = jnp.asarray(lat), jnp.asarray(lon), jnp.asarray(h)
    sl = jnp.sin(lat)
    n = R_EARTH / jnp.sqrt(1.0 - WGS84_E2 * sl**2)
    return jnp.stack(
        [
            (n + h) * jnp.cos(lat) * jnp.cos(lon),
            (n + h) * jnp.cos(lat) * jnp.sin(lon),
            (n * (1.0 - WGS84_E2) + h) * sl,
        ],
        -1,
    )


def ecef_to_geodetic(r):
    """ECEF [..., 3] [m] -> WGS84 (lat [rad], lon [rad], h [m]) by 5 fixed-point iterations.

    Accurate to < 1 mm for heights below 1000 km (used for ground tracks and plots).
    """
    r = jnp.asarray(r)
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    p = jnp.hypot(x, y)
    lon = jnp.arctan2(y, x)
    lat = jnp.arctan2(z, p * (1.0 - WGS84_E2))
    for _ in range(5):
        n = R_EARTH / jnp.sqrt(1.0 - WGS84_E2 * jnp.sin(lat) ** 2)
        h = p / jnp.maximum(jnp.cos(lat), 1e-12) - n
        lat = jnp.arctan2(z, p * (1.0 - WGS84_E2 * n / (n + h)))
    n = R_EARTH / jnp.sqrt(1.0 - WGS84_E2 * jnp.sin(lat) ** 2)
    h = p * jnp.cos(lat) + z * jnp.sin(lat) - n * (1.0 - WGS84_E2 * jnp.sin(lat) ** 2)
    return lat, lon, h


def propagate_tle(line1: str, line2: str, jd, fr=0.0):
    """Propagate one TLE with SGP4 (vectorized ``SatrecArray.sgp4``) on numpy arrays.

    Args:
      line1, line2: the two TLE lines.
      jd, fr: Julian date split into integer-ish and fractional parts (arrays, UTC).
    Returns:
      (r [..., 3] [m], v [..., 3] [m/s], error [...] int) in TEME; error != 0 marks
      SGP4 failures (decayed orbit, etc.), as in the ``sgp4`` package.
    """
    from sgp4.api import Satrec, SatrecArray

    for k, line in ((1, line1), (2, line2)):
        if not isinstance(line, str) or len(line.rstrip()) < 64 or line[:2] != f"{k} ":
            raise ValueError(
                f"tle line {k} must be a 69-column TLE line starting '{k} ', got {line!r}"
            )
    try:
        sat = Satrec.twoline2rv(line1, line2)
    except Exception as exc:  # sgp4 raises ValueError / IndexError on malformed lines
        raise ValueError(f"tle lines could not be parsed: {exc}") from exc
    if sat.error != 0:
        raise ValueError(f"tle: SGP4 initialisation error code {sat.error}")
    jd = np.atleast_1d(np.asarray(jd, dtype=np.float64))
    fr = np.broadcast_to(np.asarray(fr, dtype=np.float64), jd.shape)
    shape = jd.shape
    e, r, v = SatrecArray([sat]).sgp4(jd.ravel(), np.ascontiguousarray(fr.ravel()))
    return r[0].reshape(*shape, 3) * 1e3, v[0].reshape(*shape, 3) * 1e3, e[0].reshape(shape)


def _gravity_j2(r):
    rn = np.linalg.norm(r, axis=-1, keepdims=True)
    z2 = (r[..., 2:3] / rn) ** 2
    k = 1.5 * J2_EARTH * (R_EARTH / rn) ** 2
    fac = np.concatenate([1 + k * (1 - 5 * z2), 1 + k * (1 - 5 * z2), 1 + k * (3 - 5 * z2)], -1)
    return -MU_EARTH * r / rn**3 * fac


def tle_orbit(line1: str, line2: str, epoch_jd: float, t_end: float, step: float = 20.0):
    """Tabulate a TLE with SGP4 on [-step, t_end + step] s from ``epoch_jd`` (HermiteOrbit).

    Knots every ``step`` seconds; knot accelerations from the two-body + J2 field,
    so the interpolant is a differentiable JAX function of t. Interpolation error
    against SGP4 is below 1 m for step <= 30 s at LEO.
    """
    check_positive("t_end", t_end)
    check_positive("step", step)
    m = int(np.ceil(t_end / step)) + 3
    t = -step + step * np.arange(m)
    jd = np.full(m, float(np.floor(epoch_jd)))
    fr = (epoch_jd - jd) + t / 86400.0
    r, v, err = propagate_tle(line1, line2, jd, fr)
    if np.any(err != 0):
        raise ValueError(f"tle: SGP4 error code {int(err[err != 0][0])} within the scenario span")
    return HermiteOrbit(*(jnp.asarray(x) for x in (t, r, v, _gravity_j2(r))))


def sun_direction(jd):
    """Unit vector to the Sun [..., 3] in the mean-equator-of-date frame (~0.01 deg).

    Astronomical Almanac low-precision formula: n = JD - 2451545, L = 280.460 +
    0.9856474 n, g = 357.528 + 0.9856003 n (deg), ecliptic longitude
    lambda = L + 1.915 sin g + 0.020 sin 2g, obliquity eps = 23.439 - 4e-7 n;
    s = (cos lambda, cos eps sin lambda, sin eps sin lambda). Valid 1950-2050.
    numpy float64 (a Julian date needs float64; not a JAX kernel).
    """
    n = np.asarray(jd, dtype=np.float64) - 2451545.0
    g = np.radians(np.mod(357.528 + 0.9856003 * n, 360.0))
    lam = np.radians(
        np.mod(280.460 + 0.9856474 * n, 360.0) + 1.915 * np.sin(g) + 0.020 * np.sin(2 * g)
    )
    eps = np.radians(23.439 - 4e-7 * n)
    return np.stack([np.cos(lam), np.cos(eps) * np.sin(lam), np.sin(eps) * np.sin(lam)], -1)
