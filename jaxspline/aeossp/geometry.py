"""Orbit, target and Sun geometry on the time grid of an aeossp_standard case.

Everything is computed once per case, vectorized with numpy:

* satellites: SGP4 through the ``sgp4`` package's vectorized ``SatrecArray``
  (C++ core; ``jd``/``fr`` arrays), giving positions in TEME [km];
* TEME -> Earth-fixed (pseudo Earth-fixed, PEF) by a rotation about z by the
  IAU-82 Greenwich mean sidereal time with UT1 = UTC, no polar motion
  (Vallado, "Fundamentals of Astrodynamics", 4th ed., alg. 15 and eq. 3-45).
  The official checker uses GCRF / ITRF with zero Earth-orientation
  parameters; both frame chains agree to tens of metres on the Earth-fixed
  satellite position, i.e. ~1e-3 deg of off-nadir angle (the solver keeps a
  0.05 deg margin, see ``solve.py``);
* targets: WGS84 geodetic -> ECEF (Vallado eq. 3-7);
* Sun: the Astronomical Almanac low-precision solar position (~0.01 deg,
  Vallado alg. 29), mean equator/equinox of date (~TEME to arcminutes);
* shadow: cylindrical Earth shadow, radius 6378.137 km (RULES.md rule 8).

Units: kilometres, seconds, radians unless a name says otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from sgp4.api import WGS84, Satrec, SatrecArray, jday

__all__ = [
    "EARTH_RADIUS_KM",
    "GridGeometry",
    "cylindrical_shadow",
    "ecef_to_teme",
    "gmst82",
    "propagate_grid",
    "sun_direction",
    "target_ecef",
    "teme_to_ecef",
]

EARTH_RADIUS_KM = 6378.137  # WGS84 equatorial radius
_WGS84_F = 1.0 / 298.257223563
_WGS84_E2 = _WGS84_F * (2.0 - _WGS84_F)


def gmst82(jd, fr):
    """Greenwich mean sidereal time (IAU-82) [rad] at Julian date ``jd + fr`` (UT1 = UTC).

    ``theta = 67310.54841 + (876600*3600 + 8640184.812866) T + 0.093104 T^2
    - 6.2e-6 T^3`` seconds of time, ``T`` Julian centuries of UT1 from J2000.
    Reference: Vallado (4th ed.) eq. 3-45; identical to ``sgp4.propagation.gstime``.
    """
    t = ((np.asarray(jd, float) - 2451545.0) + np.asarray(fr, float)) / 36525.0
    sec = -6.2e-6 * t**3 + 0.093104 * t**2 + (876600.0 * 3600.0 + 8640184.812866) * t + 67310.54841
    return np.mod(sec * (math.pi / 180.0) / 240.0, 2.0 * math.pi)


def teme_to_ecef(r, gmst):
    """Rotate TEME vectors ``r`` [..., 3] into the Earth-fixed frame: ``R3(gmst) r``."""
    c, s = np.cos(gmst)[..., None], np.sin(gmst)[..., None]
    x, y, z = r[..., 0:1], r[..., 1:2], r[..., 2:3]
    return np.concatenate([c * x + s * y, -s * x + c * y, z], axis=-1)


def ecef_to_teme(r, gmst):
    """Rotate Earth-fixed vectors ``r`` [..., 3] into TEME: ``R3(-gmst) r``."""
    return teme_to_ecef(r, -np.asarray(gmst))


def target_ecef(lat_deg, lon_deg, alt_m):
    """WGS84 geodetic latitude/longitude [deg] and height [m] -> ECEF [km], shape [..., 3].

    ``N = a / sqrt(1 - e^2 sin^2 phi)``; ``x = (N + h) cos phi cos lam``,
    ``y = (N + h) cos phi sin lam``, ``z = (N (1 - e^2) + h) sin phi``.
    Reference: Vallado (4th ed.) eq. 3-7.
    """
    phi = np.radians(np.asarray(lat_deg, float))
    lam = np.radians(np.asarray(lon_deg, float))
    h = np.asarray(alt_m, float) / 1000.0
    n = EARTH_RADIUS_KM / np.sqrt(1.0 - _WGS84_E2 * np.sin(phi) ** 2)
    return np.stack(
        [
            (n + h) * np.cos(phi) * np.cos(lam),
            (n + h) * np.cos(phi) * np.sin(lam),
            (n * (1.0 - _WGS84_E2) + h) * np.sin(phi),
        ],
        axis=-1,
    )


def sun_direction(jd, fr):
    """Unit vector to the Sun, mean equator and equinox of date, at ``jd + fr`` (UTC ~ TT).

    Astronomical Almanac low-precision formula: mean longitude
    ``L = 280.460 + 36000.771 T``, mean anomaly ``M = 357.5291092 + 35999.05034 T``,
    ecliptic longitude ``L + 1.914666471 sin M + 0.019994643 sin 2M``,
    obliquity ``23.439291 - 0.0130042 T`` [deg]. Accuracy ~0.01 deg.
    Reference: Vallado (4th ed.) algorithm 29.
    """
    t = ((np.asarray(jd, float) - 2451545.0) + np.asarray(fr, float)) / 36525.0
    mean_lon = np.radians(280.460 + 36000.771 * t)
    m = np.radians(357.5291092 + 35999.05034 * t)
    lam = mean_lon + np.radians(1.914666471 * np.sin(m) + 0.019994643 * np.sin(2.0 * m))
    eps = np.radians(23.439291 - 0.0130042 * t)
    return np.stack([np.cos(lam), np.cos(eps) * np.sin(lam), np.sin(eps) * np.sin(lam)], axis=-1)


def cylindrical_shadow(r_sat, sun_hat, radius=EARTH_RADIUS_KM):
    """True where the satellite is in the cylindrical Earth shadow.

    In shadow iff ``r . s < 0`` (behind the Earth relative to the Sun) and the
    distance to the Earth-Sun line ``|r - (r . s) s| < radius``.

    Args:
      r_sat: satellite positions [..., 3] [km] (any inertial frame, same as ``sun_hat``).
      sun_hat: unit Sun directions broadcastable to ``r_sat``.
      radius: shadow cylinder radius [km].
    Reference: RULES.md rule 8.
    """
    proj = np.sum(r_sat * sun_hat, axis=-1)
    perp = r_sat - proj[..., None] * sun_hat
    return (proj < 0.0) & (np.sum(perp * perp, axis=-1) < radius * radius)


@dataclass(frozen=True)
class GridGeometry:
    """Satellite geometry sampled on ``times_s = k * step_s``, k = 0..n (from horizon start).

    Attributes:
      step_s: grid step [s].
      times_s: [n+1] seconds from horizon start.
      gmst: [n+1] Greenwich mean sidereal time [rad].
      sat_teme: [S, n+1, 3] positions in TEME [km] (NaN where SGP4 failed).
      sat_ecef: [S, n+1, 3] Earth-fixed positions [km].
      sunlit: [S, n+1] bool, not in the cylindrical shadow (False where SGP4 failed).
      sgp4_ok: [S, n+1] bool, SGP4 returned without error.
    """

    step_s: float
    times_s: np.ndarray
    gmst: np.ndarray
    sat_teme: np.ndarray
    sat_ecef: np.ndarray
    sunlit: np.ndarray
    sgp4_ok: np.ndarray


def propagate_grid(case, step_s: float | None = None) -> GridGeometry:
    """Propagate every satellite of ``case`` on a uniform grid over the horizon.

    Args:
      case: an :class:`jaxspline.aeossp.case.Case`.
      step_s: grid step [s]; default: the gcd of the action and geometry steps
        (so every instant the checker samples is a grid instant).
    Returns:
      :class:`GridGeometry`.
    """
    if step_s is None:
        a, g = case.action_step_s, case.geometry_step_s
        if float(a).is_integer() and float(g).is_integer():
            step_s = float(math.gcd(int(a), int(g)))
        else:
            step_s = float(min(a, g))
    if not step_s > 0:
        raise ValueError(f"step_s: must be > 0, got {step_s!r}")
    n = int(math.floor(case.duration_s / step_s + 1e-9))
    times = np.arange(n + 1, dtype=float) * step_s
    h0 = case.horizon_start
    jd0, fr0 = jday(
        h0.year, h0.month, h0.day, h0.hour, h0.minute, h0.second + h0.microsecond * 1e-6
    )
    jd = np.full(n + 1, jd0)
    fr = fr0 + times / 86400.0
    sats = [Satrec.twoline2rv(s.tle_line1, s.tle_line2, WGS84) for s in case.satellites]
    err, r, _ = SatrecArray(sats).sgp4(jd, fr)
    ok = (err == 0) & np.all(np.isfinite(r), axis=-1)
    r = np.where(ok[..., None], r, np.nan)
    gmst = gmst82(jd, fr)
    ecef = teme_to_ecef(r, gmst[None, :])
    sun = sun_direction(jd, fr)[None, :, :]
    sunlit = ok & ~cylindrical_shadow(np.where(ok[..., None], r, 0.0), sun)
    return GridGeometry(step_s, times, gmst, r, ecef, sunlit, ok)
