"""Reference models of the aeossp checker: time scales, frames, Sun, shadow, ephemerides.

Independent of the rest of jaxspline on purpose (numpy + sgp4 only): the checker
shares no code with the planner it checks. Conventions follow the official
benchmark checker (see :mod:`jaxspline.aeossp.check`).
"""

from __future__ import annotations

import math
from datetime import UTC, datetime

import numpy as np
from sgp4.api import WGS72, WGS84, Satrec

from jaxspline.aeossp.case import Satellite

__all__ = [
    "EPS",
    "bang_coast_bang_time",
    "geodetic_to_ecef",
    "sun_position_gcrf",
    "Ephemeris",
    "angle_deg",
    "ecef_to_gcrf_matrix",
    "gmst82",
    "sunlit",
    "teme_to_ecef",
]

EPS = 1e-9  # official NUMERICAL_EPS (slew gap, battery, grid alignment)
R_EARTH_SHADOW_M = 6378136.3  # brahe R_EARTH (GGM05s), used by the official shadow test
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
TT_MINUS_UTC_S = 69.184  # 37 leap seconds + 32.184 s (valid since 2017)
_J2000_UNIX = 946728000.0  # 2000-01-01T12:00:00 UTC as Unix seconds
_AS2RAD = math.pi / 180.0 / 3600.0
_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)


# --------------------------------------------------------------------------- frames
def _rot3(angle: np.ndarray) -> np.ndarray:
    """Passive rotation about z by ``angle`` (rad): stacked (..., 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack(
        [np.stack([c, s, z], -1), np.stack([-s, c, z], -1), np.stack([z, z, o], -1)], -2
    )


def _rot2(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack(
        [np.stack([c, z, -s], -1), np.stack([z, o, z], -1), np.stack([s, z, c], -1)], -2
    )


def _rot1(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack(
        [np.stack([o, z, z], -1), np.stack([z, c, s], -1), np.stack([z, -s, c], -1)], -2
    )


def _days_since_j2000(unix_s: np.ndarray) -> np.ndarray:
    return (np.asarray(unix_s, dtype=float) - _J2000_UNIX) / 86400.0


def gmst82(unix_s) -> np.ndarray:
    """Greenwich mean sidereal time, IAU 1982, UT1 = UTC.

    ``GMST = 67310.54841 + (876600·3600 + 8640184.812866) T + 0.093104 T² − 6.2e-6 T³``
    seconds of time, T in Julian centuries UT1 since J2000 (Vallado et al. 2006, AIAA
    2006-6753, eq. for TEME -> PEF).

    Args:
      unix_s: float [...], UTC as Unix seconds.
    Returns:
      float [...], GMST [rad] in [0, 2π).
    """
    t = _days_since_j2000(unix_s) / 36525.0
    sec = 67310.54841 + (876600.0 * 3600.0 + 8640184.812866) * t + 0.093104 * t**2 - 6.2e-6 * t**3
    return np.mod(sec * (math.pi / 180.0) / 240.0, 2.0 * math.pi)


def teme_to_ecef(r_teme: np.ndarray, unix_s) -> np.ndarray:
    """TEME -> Earth-fixed position (zero polar motion): ``R3(GMST82) r``.

    Args:
      r_teme: float [..., 3], TEME position (any unit).
      unix_s: float [...], UTC as Unix seconds.
    Returns:
      float [..., 3], Earth-fixed position (unit of r_teme).
    """
    return np.einsum("...ij,...j->...i", _rot3(gmst82(unix_s)), r_teme)


def _nutation(t_tt: np.ndarray):
    """Mean obliquity ε0, Δψ, Δε (rad): IAU 1980, 4 largest terms (Meeus 1998, ch. 22)."""
    om = np.radians(125.04452 - 1934.136261 * t_tt)
    ls = np.radians(280.4665 + 36000.7698 * t_tt)
    lm = np.radians(218.3165 + 481267.8813 * t_tt)
    dpsi = (
        -17.20 * np.sin(om) - 1.32 * np.sin(2 * ls) - 0.23 * np.sin(2 * lm) + 0.21 * np.sin(2 * om)
    ) * _AS2RAD
    deps = (
        9.20 * np.cos(om) + 0.57 * np.cos(2 * ls) + 0.10 * np.cos(2 * lm) - 0.09 * np.cos(2 * om)
    ) * _AS2RAD
    eps0 = (84381.448 - 46.8150 * t_tt - 0.00059 * t_tt**2 + 0.001813 * t_tt**3) * _AS2RAD
    return eps0, dpsi, deps


def ecef_to_gcrf_matrix(unix_s) -> np.ndarray:
    """Rotation Earth-fixed -> inertial (J2000 ≈ GCRF).

    ``M = P^T N^T R3(−GAST)`` with IAU 1976 precession P (ζ, θ, z polynomials, Lieske
    1977), IAU 1980 nutation N truncated to 4 terms, GAST = GMST82 + Δψ cos ε; zero
    EOP (UT1 = UTC, no polar motion), TT = UTC + 69.184 s.

    Args:
      unix_s: float [...], UTC as Unix seconds.
    Returns:
      float [..., 3, 3], M.
    """
    unix_s = np.asarray(unix_s, dtype=float)
    t = _days_since_j2000(unix_s + TT_MINUS_UTC_S) / 36525.0
    zeta = (2306.2181 * t + 0.30188 * t**2 + 0.017998 * t**3) * _AS2RAD
    theta = (2004.3109 * t - 0.42665 * t**2 - 0.041833 * t**3) * _AS2RAD
    zz = (2306.2181 * t + 1.09468 * t**2 + 0.018203 * t**3) * _AS2RAD
    prec = _rot3(-zz) @ _rot2(theta) @ _rot3(-zeta)  # J2000 -> mean of date
    eps0, dpsi, deps = _nutation(t)
    nut = _rot1(-(eps0 + deps)) @ _rot3(-dpsi) @ _rot1(eps0)  # mean -> true of date
    gast = gmst82(unix_s) + dpsi * np.cos(eps0 + deps)
    tod_from_ecef = _rot3(-gast)
    return np.swapaxes(prec, -1, -2) @ np.swapaxes(nut, -1, -2) @ tod_from_ecef


def sun_position_gcrf(unix_s) -> np.ndarray:
    """Sun position, J2000 equatorial, low precision (Montenbruck & Gill 2012, p. 70).

    ``M = 2π frac(0.9931267 + 99.9973583 T)``, ``L = 2π frac(0.7859444 + M/2π +
    (6892 sin M + 72 sin 2M)/1296e3)``, ``r = 149.619e9 − 2.499e9 cos M − 0.021e9 cos 2M``,
    rotated from the ecliptic by ε = 23.43929111°; T in centuries TT since J2000.

    Args:
      unix_s: float [...], UTC as Unix seconds.
    Returns:
      float [..., 3], position [m].
    """
    t = _days_since_j2000(np.asarray(unix_s, dtype=float) + TT_MINUS_UTC_S) / 36525.0
    m = 2 * math.pi * np.mod(0.9931267 + 99.9973583 * t, 1.0)
    lon = (
        2
        * math.pi
        * np.mod(
            0.7859444 + m / (2 * math.pi) + (6892.0 * np.sin(m) + 72.0 * np.sin(2 * m)) / 1296.0e3,
            1.0,
        )
    )
    r = 149.619e9 - 2.499e9 * np.cos(m) - 0.021e9 * np.cos(2 * m)
    eps = math.radians(23.43929111)
    x, y = r * np.cos(lon), r * np.sin(lon)
    return np.stack([x, y * math.cos(eps), y * math.sin(eps)], -1)


def sunlit(r_gcrf: np.ndarray, unix_s) -> np.ndarray:
    """Cylindrical shadow: sunlit unless behind the Earth (r·ŝ < 0) and |r − (r·ŝ)ŝ| < R.

    Args:
      r_gcrf: float [..., 3], satellite position, GCRF [m].
      unix_s: float [...], UTC as Unix seconds.
    Returns:
      bool [...].
    """
    sun = sun_position_gcrf(unix_s)
    shat = sun / np.linalg.norm(sun, axis=-1, keepdims=True)
    proj = np.sum(r_gcrf * shat, axis=-1)
    perp = np.linalg.norm(r_gcrf - proj[..., None] * shat, axis=-1)
    return ~((proj < 0.0) & (perp < R_EARTH_SHADOW_M))


def geodetic_to_ecef(lat_deg, lon_deg, alt_m) -> np.ndarray:
    """WGS84 geodetic coordinates -> Earth-fixed Cartesian position.

    Args:
      lat_deg: float [...], geodetic latitude [deg].
      lon_deg: float [...], longitude [deg].
      alt_m: float [...], height above the ellipsoid [m].
    Returns:
      float [..., 3], position [m].
    """
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    e2 = WGS84_F * (2.0 - WGS84_F)
    n = WGS84_A / np.sqrt(1.0 - e2 * np.sin(lat) ** 2)
    alt = np.asarray(alt_m, dtype=float)
    return np.stack(
        [
            (n + alt) * np.cos(lat) * np.cos(lon),
            (n + alt) * np.cos(lat) * np.sin(lon),
            (n * (1.0 - e2) + alt) * np.sin(lat),
        ],
        -1,
    )


def angle_deg(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Angle between vectors, ``atan2(|u×v|, u·v)`` (accurate at small angles).

    Args:
      u: float [..., 3].
      v: float [..., 3].
    Returns:
      float [...], angle [deg].
    """
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(u, v), axis=-1), np.sum(u * v, axis=-1)))


class Ephemeris:
    """SGP4 positions of one satellite at times given as seconds from ``horizon_start``.

    Positions in metres; TEME, Earth-fixed and GCRF.

    Args:
      sat: Satellite of the case (TLE).
      horizon_start: datetime of offset 0 (UTC).
      gravity: ``"wgs84"`` (official) or ``"wgs72"`` (sgp4's classic default, for the
        frame-difference study).

    Attributes:
      satellite_id: the satellite.
      rec: the sgp4 ``Satrec``.
      t0_unix: Unix seconds of ``horizon_start``.
    """

    def __init__(self, sat: Satellite, horizon_start: datetime, gravity: str = "wgs84"):
        grav = {"wgs84": WGS84, "wgs72": WGS72}[gravity]
        self.satellite_id = sat.satellite_id
        self.rec = Satrec.twoline2rv(sat.tle_line1, sat.tle_line2, grav)
        self.t0_unix = (horizon_start - _EPOCH).total_seconds()

    def unix(self, seconds) -> np.ndarray:
        """Unix seconds (UTC) of offsets from ``horizon_start``.

        Args:
          seconds: float [...], offsets [s].
        Returns:
          float [...], Unix seconds.
        """
        return self.t0_unix + np.asarray(seconds, dtype=float)

    def teme(self, seconds) -> np.ndarray:
        """TEME position by SGP4.

        Args:
          seconds: float [...], offsets from ``horizon_start`` [s].
        Returns:
          float [..., 3], position [m].
        Raises:
          ValueError: SGP4 reports an error (naming the satellite and the code).
        """
        s = np.atleast_1d(np.asarray(seconds, dtype=float))
        days = (self.t0_unix + s) / 86400.0
        jd = np.floor(days) + 2440587.5
        fr = days - np.floor(days)
        err, r, _ = self.rec.sgp4_array(jd.ravel(), fr.ravel())
        if np.any(err):
            raise ValueError(f"satellite {self.satellite_id}: SGP4 error code {int(err.max())}")
        return (r * 1000.0).reshape(np.shape(seconds) + (3,))

    def ecef(self, seconds) -> np.ndarray:
        """Earth-fixed position: ``R3(GMST82) r_teme``.

        Args:
          seconds: float [...], offsets from ``horizon_start`` [s].
        Returns:
          float [..., 3], position [m].
        """
        return teme_to_ecef(self.teme(seconds), self.unix(seconds))

    def gcrf(self, seconds) -> np.ndarray:
        """Inertial (GCRF) position via the Earth-fixed frame (official route).

        Args:
          seconds: float [...], offsets from ``horizon_start`` [s].
        Returns:
          float [..., 3], position [m].
        """
        m = ecef_to_gcrf_matrix(self.unix(seconds))
        return np.einsum("...ij,...j->...i", m, self.ecef(seconds))


def bang_coast_bang_time(theta_deg: float, rate: float, accel: float) -> float:
    """Rest-to-rest time for angle θ, max rate v, max accel a (RULES.md 7).

    ``2 sqrt(θ/a)`` if θ <= v²/a else ``2v/a + (θ − v²/a)/v``; 0 for θ <= 1e-9.

    Args:
      theta_deg: angle θ [deg].
      rate: max rate v [deg/s].
      accel: max acceleration a [deg/s²].
    Returns:
      float, time [s].
    """
    theta = max(0.0, float(theta_deg))
    if theta <= EPS:
        return 0.0
    if theta <= rate * rate / accel:
        return 2.0 * math.sqrt(theta / accel)
    return 2.0 * rate / accel + (theta - rate * rate / accel) / rate
