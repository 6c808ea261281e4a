"""Reference frames and Earth/Sun models: the one home of GMST, TEME <-> Earth-fixed, WGS84, Sun.

Every part of jaxspline that needs a frame uses this module: the orbit models, the
pointing kernels, the visibility and option geometry, the battery's shadow model and
the aeossp adapter. (The aeossp *checker* keeps its own chain on purpose: it must not
share code with what it checks.)

Frames. ``ECI`` is the true-equator, mean-equinox frame of SGP4 (TEME). Earth-fixed
coordinates come from one rotation about z by the Greenwich mean sidereal time
(IAU 1982) with UT1 = UTC and no polar motion, i.e. TEME -> pseudo-Earth-fixed
(Vallado, *Fundamentals of Astrodynamics*, 4th ed., alg. 24 and eq. 3-45). Measured
against the GCRF/ITRF chain of the aeossp checker (zero EOP): 1.5e-7 deg in off-nadir
angle and 3.6e-7 deg in slew angle (docs/aeossp.md).

Array namespaces. Functions marked *generic* accept numpy arrays (and return numpy,
float64 for bulk host geometry) or JAX arrays / tracers (and return JAX arrays, for
kernels under ``jit``/``vmap``/``grad``); the same formula serves both.

Units: metres, seconds, radians.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.base.elements import (
    GMST_RATE,
    OMEGA_EARTH,
    R_EARTH,
    WGS84_E2,
)

_JD_J2000 = 2451545.0  # Julian date of J2000.0
_DAYS_PER_CENTURY = 36525.0

__all__ = [
    "earth_rotation_angle",
    "rot_z",
    "teme_to_ecef",
    "ecef_to_teme",
    "ecef_to_geodetic",
    "sun_direction",
    "angle_between",
    "in_shadow",
    "sun_elevation",
]


def _xp(*xs):
    """jax.numpy if any argument is a JAX array or tracer, else numpy."""
    return jnp if any(isinstance(x, jax.Array) for x in xs) else np


def earth_rotation_angle(gmst0, t):
    """Earth rotation angle ``theta(t) = gmst0 + GMST_RATE t`` (generic: numpy or JAX).

    Linear in t: the dropped T^2 term of GMST changes theta by < 1e-12 rad over a day.

    Args:
      gmst0: float [...], GMST at the epoch [rad].
      t: float [...], seconds from the epoch.
    Returns:
      float [...], theta [rad] (not wrapped).
    """
    return gmst0 + GMST_RATE * t


def rot_z(theta, x):
    """Coordinates of x in a frame rotated by +theta about z (generic: numpy or JAX).

    ``(c x + s y, -s x + c y, z)``.

    Args:
      theta: float [...], rotation angle [rad], broadcastable to ``x[..., 0]``.
      x: float [..., 3], vectors (any unit).
    Returns:
      float [..., 3], the rotated coordinates (unit of x).
    """
    xp = _xp(theta, x)
    c, s = xp.cos(theta), xp.sin(theta)
    return xp.stack([c * x[..., 0] + s * x[..., 1], -s * x[..., 0] + c * x[..., 1], x[..., 2]], -1)


def teme_to_ecef(r, theta, v=None):
    """TEME position (and velocity) to Earth-fixed by the rotation angle (generic: numpy or JAX).

    ``r_ecef = Rz(theta) r``; ``v_ecef = Rz(theta) v - w_E z x r_ecef``. Polar motion ignored.

    Args:
      r: float [..., 3], TEME position [m].
      theta: float [...], Earth rotation angle [rad].
      v: float [..., 3], TEME velocity [m/s], optional.
    Returns:
      r_ecef float [..., 3] [m], or (r_ecef, v_ecef [m/s]) when v is given.
    """
    xp = _xp(r, theta, v)
    r_e = rot_z(theta, xp.asarray(r))
    if v is None:
        return r_e
    v_e = rot_z(theta, xp.asarray(v))
    w_x_r = xp.stack([-r_e[..., 1], r_e[..., 0], xp.zeros_like(r_e[..., 0])], -1) * OMEGA_EARTH
    return r_e, v_e - w_x_r


def ecef_to_teme(r, theta):
    """Earth-fixed vectors to TEME: ``Rz(-theta) r`` (generic: numpy or JAX; directions too).

    Args:
      r: float [..., 3], Earth-fixed vectors (any unit).
      theta: float [...], Earth rotation angle [rad].
    Returns:
      float [..., 3], TEME vectors (unit of r).
    """
    return rot_z(-theta, r)


def ecef_to_geodetic(r):
    """Earth-fixed position to WGS84 geodetic coordinates (generic: numpy or JAX).

    Five fixed-point iterations on the latitude: < 1 mm for heights below 1000 km.

    Args:
      r: float [..., 3], Earth-fixed position [m].
    Returns:
      (lat [rad], lon [rad], h [m]), float [...] each.
    """
    xp = _xp(r)
    r = xp.asarray(r)
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    p = xp.hypot(x, y)
    lon = xp.arctan2(y, x)
    lat = xp.arctan2(z, p * (1.0 - WGS84_E2))
    for _ in range(5):
        n = R_EARTH / xp.sqrt(1.0 - WGS84_E2 * xp.sin(lat) ** 2)
        h = p / xp.maximum(xp.cos(lat), 1e-12) - n
        lat = xp.arctan2(z, p * (1.0 - WGS84_E2 * n / (n + h)))
    n = R_EARTH / xp.sqrt(1.0 - WGS84_E2 * xp.sin(lat) ** 2)
    h = p * xp.cos(lat) + z * xp.sin(lat) - n * (1.0 - WGS84_E2 * xp.sin(lat) ** 2)
    return lat, lon, h


def sun_direction(jd, fr=0.0):
    """Unit vector to the Sun, mean equator and equinox of date (~TEME), ~0.01 deg.

    Astronomical Almanac low-precision formula: mean longitude
    ``L = 280.460 + 36000.771 T``, mean anomaly ``M = 357.5291092 + 35999.05034 T``,
    ecliptic longitude ``L + 1.914666471 sin M + 0.019994643 sin 2M``, obliquity
    ``23.439291 - 0.0130042 T`` [deg], T Julian centuries from J2000 (UTC ~ TT).
    Reference: Vallado (4th ed.) algorithm 29. numpy float64.

    Args:
      jd: float [...], Julian date (whole part) [days].
      fr: float [...], day fraction [days].
    Returns:
      float64 [..., 3], unit Sun direction.
    """
    t = ((np.asarray(jd, np.float64) - _JD_J2000) + np.asarray(fr, np.float64)) / _DAYS_PER_CENTURY
    mean_lon = np.radians(280.460 + 36000.771 * t)
    m = np.radians(357.5291092 + 35999.05034 * t)
    lam = mean_lon + np.radians(1.914666471 * np.sin(m) + 0.019994643 * np.sin(2.0 * m))
    eps = np.radians(23.439291 - 0.0130042 * t)
    return np.stack([np.cos(lam), np.cos(eps) * np.sin(lam), np.sin(eps) * np.sin(lam)], axis=-1)


def angle_between(u, v):
    """Angle between vectors: ``atan2(|u x v|, u . v)`` (generic: numpy or JAX).

    Accurate near 0 and pi, unlike ``arccos`` of the normalized dot product.

    Args:
      u: float [..., 3], vectors (any unit, not necessarily unit length).
      v: float [..., 3], vectors, broadcast against u.
    Returns:
      float [...], angle [rad] in [0, pi].
    """
    xp = _xp(u, v)
    return xp.arctan2(xp.linalg.norm(xp.cross(u, v), axis=-1), xp.sum(u * v, axis=-1))


def in_shadow(r_sat, sun_hat, radius=R_EARTH):
    """True where a satellite is in the cylindrical Earth shadow (generic: numpy or JAX).

    In shadow iff ``r . s < 0`` (behind the Earth relative to the Sun) and the
    distance to the Earth-Sun line ``|r - (r . s) s| < radius``.
    Reference: aeossp_standard RULES.md rule 8.

    Args:
      r_sat: float [..., 3], satellite position [m], inertial frame.
      sun_hat: float [..., 3], unit Sun direction in the same frame (broadcastable).
      radius: float, shadow cylinder radius [m] (default the Earth's equatorial radius).
    Returns:
      bool [...].
    """
    xp = _xp(r_sat, sun_hat)
    proj = xp.sum(r_sat * sun_hat, axis=-1)
    perp = r_sat - proj[..., None] * sun_hat
    return (proj < 0.0) & (xp.sum(perp * perp, axis=-1) < radius * radius)


def sun_elevation(lat, lon, sun_ecef):
    """Elevation of the Sun over the geodetic horizon at (lat, lon) (generic: numpy or JAX).

    ``asin(up . s)`` with ``up`` the geodetic vertical and ``s`` the unit Sun direction
    in Earth-fixed coordinates (``teme_to_ecef(sun_direction(...), theta)``).

    Args:
      lat: float [...], geodetic latitude [rad].
      lon: float [...], longitude [rad].
      sun_ecef: float [..., 3], unit Sun direction, Earth-fixed.
    Returns:
      float [...], elevation [rad] in [-pi/2, pi/2].
    """
    xp = _xp(lat, lon, sun_ecef)
    up = xp.stack([xp.cos(lat) * xp.cos(lon), xp.cos(lat) * xp.sin(lon), xp.sin(lat)], -1)
    return xp.arcsin(xp.clip(xp.sum(up * sun_ecef, axis=-1), -1.0, 1.0))
