"""The Earth and time in the base layer: constants, time scales, circular orbit elements.

Every layer reads these (the readers to check a scenario, the geometry to propagate it):

* constants: WGS84 (``R_EARTH``, ``WGS84_F``, ``WGS84_E2``, ``MU_EARTH``), ``J2``, the
  Earth's spin ``OMEGA_EARTH`` (Earth-fixed velocities) and the rate ``GMST_RATE`` of
  its rotation angle (GMST per UT1 second), seconds per day;
* WGS84 geodetic coordinates to Earth-fixed positions (:func:`geodetic_to_ecef`);
* time scales: :func:`julian_date` of a date-time, :func:`jd_split` (the two-part form
  SGP4 and GMST take), :func:`gmst` (IAU 1982, UT1 = UTC);
* TLEs: :func:`parse_tle`, the ``sgp4`` record of two lines (WGS84 or WGS72 constants);
* circular orbits: :class:`CircularOrbit` (a pytree of scalars with secular J2 nodal
  regression), :func:`sso_inclination`, :func:`circular_orbit`, :func:`circular_orbit_over`.

All numpy float64. Units: metres, seconds, radians.
"""

from __future__ import annotations

import datetime as _dt
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.validate import check_finite, check_positive

__all__ = [
    "J2_EARTH",
    "MU_EARTH",
    "GMST_RATE",
    "OMEGA_EARTH",
    "R_EARTH",
    "SECONDS_PER_DAY",
    "WGS84_E2",
    "WGS84_F",
    "CircularOrbit",
    "circular_orbit",
    "circular_orbit_over",
    "geodetic_to_ecef",
    "unit_vectors",
    "gmst",
    "jd_split",
    "julian_date",
    "parse_tle",
    "sso_inclination",
]

R_EARTH = 6378137.0  # m, WGS84 equatorial radius
WGS84_F = 1.0 / 298.257223563
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
OMEGA_EARTH = 7.292115146706979e-5  # rad/s, the Earth's inertial spin (Earth-fixed velocities)
_GMST_S_PER_CENTURY = 876600.0 * 3600.0 + 8640184.812866  # linear term of GMST (IAU 1982)
#: rad/s, GMST (IAU 1982) advance per UT1 second, the rate of the Earth rotation angle
#: that turns inertial positions Earth-fixed (1.00273790935 sidereal turns a solar day).
GMST_RATE = _GMST_S_PER_CENTURY / (36525.0 * 86400.0) * (2.0 * math.pi / 86400.0)
SECONDS_PER_DAY = 86400.0
MU_EARTH = 3.986004418e14  # m^3/s^2 (WGS84)
J2_EARTH = 1.08262668e-3
_TROPICAL_YEAR = 365.2421897 * SECONDS_PER_DAY  # s
_JD_UNIX0 = 2440587.5  # Julian date of 1970-01-01T00:00:00 UTC
_JD_J2000 = 2451545.0
_DAYS_PER_CENTURY = 36525.0


def julian_date(when) -> float:
    """Julian date (UTC) of a datetime or ISO-8601 string (naive = UTC).

    Args:
      when: datetime or ISO-8601 string.
    Returns:
      float, Julian date [days].
    Raises:
      ValueError: naming the value if it is not a date-time.
    """
    if isinstance(when, str):
        text = when.strip()
        if text.endswith(("Z", "z")):
            text = text[:-1] + "+00:00"
        try:
            when = _dt.datetime.fromisoformat(text)
        except ValueError as exc:
            raise ValueError(f"epoch must be an ISO-8601 date-time, got {when!r}") from exc
    if not isinstance(when, _dt.datetime):
        raise ValueError(f"epoch must be a datetime or ISO string, got {when!r}")
    if when.tzinfo is None:
        when = when.replace(tzinfo=_dt.UTC)
    return _JD_UNIX0 + when.timestamp() / SECONDS_PER_DAY


def jd_split(epoch_jd: float, t):
    """Two-part Julian dates ``(jd, fr)`` of ``epoch_jd + t / 86400`` (numpy).

    ``jd`` is the epoch's preceding midnight (x.5) and ``fr`` the day fraction from it,
    so ``fr`` keeps float64 resolution of ~1e-11 s over days (SGP4 and GMST take the
    split form; a single float64 Julian date resolves only ~40 microseconds).

    Args:
      epoch_jd: float, Julian date of the epoch [days].
      t: float [...], seconds from the epoch.
    Returns:
      (jd, fr), float64 [...] each [days].
    """
    t = np.asarray(t, np.float64)
    jd0 = math.floor(epoch_jd - 0.5) + 0.5
    fr0 = epoch_jd - jd0
    return np.full(t.shape, jd0), fr0 + t / SECONDS_PER_DAY


def gmst(jd, fr=0.0):
    """Greenwich mean sidereal time (IAU 1982) at Julian date jd + fr.

    ``GMST = 67310.54841 + (876600 h + 8640184.812866) T + 0.093104 T^2 - 6.2e-6 T^3``
    seconds of time, ``T`` Julian centuries of UT1 (UTC used) from J2000 (Vallado 4th
    ed. eq. 3-45; identical to ``sgp4.propagation.gstime``). numpy float64.

    Args:
      jd: float [...], Julian date (whole part) [days].
      fr: float [...], day fraction [days].
    Returns:
      float64 [...], GMST [rad] in [0, 2 pi).
    """
    t = ((np.asarray(jd, np.float64) - _JD_J2000) + np.asarray(fr, np.float64)) / _DAYS_PER_CENTURY
    sec = -6.2e-6 * t**3 + 0.093104 * t**2 + _GMST_S_PER_CENTURY * t + 67310.54841
    return np.mod(np.mod(sec, SECONDS_PER_DAY) * (2.0 * np.pi / SECONDS_PER_DAY), 2.0 * np.pi)


def unit_vectors(x):
    """``x / |x|`` along the last axis.

    Args:
      x: float [..., 3].
    Returns:
      float [..., 3], unit vectors.
    """
    x = np.asarray(x, np.float64)
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def _xp(*xs):
    """jax.numpy if any argument is a JAX array or tracer, else numpy."""
    return jnp if any(isinstance(x, jax.Array) for x in xs) else np


def geodetic_to_ecef(lat, lon, h=0.0):
    """WGS84 geodetic coordinates to Earth-fixed position (generic: numpy or JAX).

    ``N = a / sqrt(1 - e^2 sin^2 lat)``; ``x = (N + h) cos lat cos lon``,
    ``y = (N + h) cos lat sin lon``, ``z = (N (1 - e^2) + h) sin lat`` (Vallado eq. 3-7).

    Args:
      lat: float [...], geodetic latitude [rad].
      lon: float [...], longitude [rad].
      h: float [...], height above the ellipsoid [m].
    Returns:
      float [..., 3], Earth-fixed position [m].
    """
    xp = _xp(lat, lon, h)
    lat, lon, h = xp.asarray(lat), xp.asarray(lon), xp.asarray(h)
    sl = xp.sin(lat)
    n = R_EARTH / xp.sqrt(1.0 - WGS84_E2 * sl**2)
    return xp.stack(
        [
            (n + h) * xp.cos(lat) * xp.cos(lon),
            (n + h) * xp.cos(lat) * xp.sin(lon),
            (n * (1.0 - WGS84_E2) + h) * sl,
        ],
        -1,
    )


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


def sso_inclination(altitude: float) -> float:
    """Inclination of a circular Sun-synchronous orbit.

    cos i = -W'_sun / (1.5 n J2 (R/a)^2), with W'_sun = 2 pi / tropical year,
    n = sqrt(mu / a^3), a = R + h (Vallado eq. 9-41). 600 km -> 97.79 deg.

    Args:
      altitude: float, height above the equatorial radius [m].
    Returns:
      float, inclination [rad].
    Raises:
      ValueError: the altitude admits no Sun-synchronous orbit.
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
    """Build a :class:`CircularOrbit` from elements.

    Args:
      altitude: float, height above the equatorial radius [m].
      inclination: float [rad] in [0, pi]; None gives the Sun-synchronous inclination
        (:func:`sso_inclination`).
      raan: float, right ascension of the ascending node at t = 0 [rad].
      arg_lat: float, argument of latitude at t = 0 [rad].
      j2_drift: add the secular nodal regression W' = -1.5 n J2 (R/a)^2 cos i.
    Returns:
      CircularOrbit.
    Raises:
      ValueError: inclination outside [0, pi] or no Sun-synchronous orbit at altitude.
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
    # numpy float64 scalars: jnp arrays made here would be float32 whenever the caller has
    # not switched JAX to float64 (a scenario read before plan() enters its float64 context)
    return CircularOrbit(*(np.float64(x) for x in (a, inclination, raan, arg_lat, n, rate)))


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
    """A circular orbit whose sub-satellite point is at geocentric (lat, lon) at time t.

    sin(lat) = sin i sin u gives u (ascending or descending branch); the node follows
    from lon + theta(t) = W + atan2(cos i sin u, cos u), theta(t) = gmst0 + w_E t.

    Args:
      lat: float, geocentric latitude [rad].
      lon: float, longitude [rad].
      t: float, seconds from the epoch.
      gmst0: float, GMST at the epoch [rad].
      altitude: float [m].
      inclination: float [rad]; None gives the Sun-synchronous inclination.
      descending: pass over the point on the descending branch.
      j2_drift: as in :func:`circular_orbit`.
    Returns:
      CircularOrbit.
    Raises:
      ValueError: |lat| is not reachable with the inclination.
    """
    base = circular_orbit(altitude, inclination, 0.0, 0.0, j2_drift)
    inc = float(base.inclination)
    s = np.sin(lat) / np.sin(inc)
    if abs(s) > 1.0:
        raise ValueError(f"lat={np.degrees(lat)!r} deg is not reachable with inclination {inc!r}")
    u = np.arcsin(s)
    if descending:
        u = np.pi - u
    raan_t = lon + gmst0 + GMST_RATE * t - np.arctan2(np.cos(inc) * np.sin(u), np.cos(u))
    u0 = u - float(base.mean_motion) * t
    raan0 = raan_t - float(base.raan_rate) * t
    return base._replace(
        raan=np.float64(np.mod(raan0, 2 * np.pi)), arg_lat=np.float64(np.mod(u0, 2 * np.pi))
    )


_GRAVITY_MODELS = ("wgs72", "wgs84")


def parse_tle(line1: str, line2: str, who: str = "tle", gravity: str = "wgs84"):
    """``Satrec`` (the ``sgp4`` package) of two TLE lines; ValueError naming ``who`` if
    malformed (the one place TLE lines become an SGP4 record).

    ``gravity`` picks SGP4's geopotential constants: "wgs84" (default, as the aeossp
    benchmark's propagator) or "wgs72" (the constants of Vallado's verification set).
    """
    from sgp4.api import WGS72, WGS84, Satrec

    if gravity not in _GRAVITY_MODELS:
        raise ValueError(f"gravity must be one of {_GRAVITY_MODELS}, got {gravity!r}")

    for k, line in ((1, line1), (2, line2)):
        if not isinstance(line, str) or len(line.rstrip()) < 64 or line[:2] != f"{k} ":
            raise ValueError(
                f"{who} line {k} must be a 69-column TLE line starting '{k} ', got {line!r}"
            )
    try:
        sat = Satrec.twoline2rv(line1, line2, WGS84 if gravity == "wgs84" else WGS72)
    except Exception as exc:  # sgp4 raises ValueError / IndexError on malformed lines
        raise ValueError(f"{who} lines could not be parsed: {exc}") from exc
    if sat.error != 0:
        raise ValueError(f"{who}: SGP4 initialisation error code {sat.error}")
    return sat
