"""Reference geometry of the regional_coverage checker: SGP4 states, strip rays, quads.

numpy + sgp4 only, independent of the solver's geometry (``jaxspline.geometry.orbit``,
``jaxspline.screen.coverage``); the frame and Sun models come from the other benchmark's
independent checker (:mod:`jaxspline.aeossp.check_frames`). Conventions follow the
official verifier (see :mod:`jaxspline.regional.check` for the sources):

* SGP4 with WGS84 constants -> TEME; Earth-fixed ``r = R3(GMST82) r_teme``,
  ``v = R3(GMST82) v_teme - ω × r`` (UT1 = UTC, zero polar motion).
* Local frame: nadir ``n = -p/|p|``; along = ``v`` minus its nadir component,
  normalised; across ``c = along × n``. A look angle ``a`` points along
  ``n + tan(a) c`` (normalised) and meets the WGS84 ellipsoid at the nearest positive root
  (> :data:`RAY_EPS` m) of the ray-ellipsoid quadratic.
* Ground points to geodetic longitude / latitude; quads are used as they come out in
  longitude / latitude, not unwrapped at ±180° (as the official verifier does).
"""

from __future__ import annotations

import math
from datetime import datetime

import numpy as np
from sgp4.api import WGS84, Satrec

from jaxspline.aeossp.check_frames import ecef_to_gcrf_matrix, gmst82
from jaxspline.regional.case import Satellite

#: Earth rotation rate used for the Earth-fixed velocity [rad/s] (brahe ``OMEGA_EARTH``).
OMEGA_EARTH = 7.292115146706979e-5
WGS84_A_M = 6378137.0
WGS84_B_M = 6356752.314245179
#: Smallest accepted ray length [m] (official ``_NUMERICAL_EPS``).
RAY_EPS = 1e-9
#: Relative tolerance of the on-border test of a point and a quad edge.
BORDER_REL_TOL = 1e-12
#: Fixed-point iterations of the geodetic latitude (converged to < 1e-15 rad near the surface).
GEODETIC_ITERATIONS = 6
_UNIX_EPOCH_JD = 2440587.5


class Track:
    """SGP4 states of one satellite at offsets (seconds) from the horizon start.

    Args:
      sat: the case's Satellite.
      start: horizon start (aware UTC datetime), offset 0.

    Attributes:
      satellite_id: the satellite.
      t0_unix: Unix seconds of ``start``.
    """

    def __init__(self, sat: Satellite, start: datetime):
        self.satellite_id = sat.id
        self._rec = Satrec.twoline2rv(sat.tle1, sat.tle2, WGS84)
        self.t0_unix = start.timestamp()

    def unix(self, seconds) -> np.ndarray:
        """Unix seconds (UTC) of offsets.

        Args:
          seconds: float [...], offsets from the horizon start [s].
        Returns:
          float [...].
        """
        return self.t0_unix + np.asarray(seconds, dtype=float)

    def teme(self, seconds) -> tuple[np.ndarray, np.ndarray]:
        """TEME position and velocity by SGP4.

        Args:
          seconds: float [...], offsets [s].
        Returns:
          (r, v): float [..., 3] [m], [m/s].
        Raises:
          ValueError: SGP4 reports an error (naming the satellite and the code).
        """
        shape = np.shape(seconds)
        days = np.atleast_1d(self.unix(seconds)).ravel() / 86400.0
        whole = np.floor(days)
        err, r, v = self._rec.sgp4_array(whole + _UNIX_EPOCH_JD, days - whole)
        if np.any(err):
            raise ValueError(f"satellite {self.satellite_id}: SGP4 error {int(err.max())}")
        return (r * 1e3).reshape(shape + (3,)), (v * 1e3).reshape(shape + (3,))

    def ecef(self, seconds) -> tuple[np.ndarray, np.ndarray]:
        """Earth-fixed position and velocity: ``R3(GMST82)`` of TEME, ``v - ω × r``.

        Args:
          seconds: float [...], offsets [s].
        Returns:
          (r, v): float [..., 3] [m], [m/s].
        """
        r, v = self.teme(seconds)
        g = gmst82(self.unix(seconds))
        c, s = np.cos(g)[..., None], np.sin(g)[..., None]

        def rot(x):
            return np.stack(
                [c[..., 0] * x[..., 0] + s[..., 0] * x[..., 1],
                 -s[..., 0] * x[..., 0] + c[..., 0] * x[..., 1],
                 x[..., 2]], -1
            )  # fmt: skip

        re = rot(r)
        ve = rot(v) + OMEGA_EARTH * np.stack(
            [re[..., 1], -re[..., 0], np.zeros_like(c[..., 0])], -1
        )
        return re, ve

    def gcrf_position(self, seconds) -> np.ndarray:
        """Inertial (GCRF) position through the Earth-fixed frame (the official route).

        Args:
          seconds: float [...], offsets [s].
        Returns:
          float [..., 3] [m].
        """
        re, _ = self.ecef(seconds)
        return np.einsum("...ij,...j->...i", ecef_to_gcrf_matrix(self.unix(seconds)), re)


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def local_frame(pos: np.ndarray, vel: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nadir, along-track and across-track unit vectors (RULES.md "Geometry").

    Args:
      pos: float [..., 3], Earth-fixed position [m].
      vel: float [..., 3], Earth-fixed velocity [m/s].
    Returns:
      (nadir, along, across): float [..., 3] each; ``across = along × nadir``.
    """
    nadir = -_unit(pos)
    along = _unit(vel - np.sum(vel * nadir, axis=-1, keepdims=True) * nadir)
    return nadir, along, _unit(np.cross(along, nadir))


def look_direction(pos: np.ndarray, vel: np.ndarray, angle_deg) -> np.ndarray:
    """Unit direction of look angle ``a``: ``normalise(nadir + tan(a) across)``.

    Args:
      pos: float [..., 3] [m].
      vel: float [..., 3] [m/s].
      angle_deg: float [...], signed look angle [deg].
    Returns:
      float [..., 3].
    """
    nadir, _, across = local_frame(pos, vel)
    t = np.tan(np.radians(np.asarray(angle_deg, dtype=float)))[..., None]
    return _unit(nadir + t * across)


def ray_ellipsoid(origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Distance to the first WGS84 ellipsoid crossing of the ray ``origin + s d``, s > 0.

    Solves ``A s² + B s + C = 0`` on the scaled coordinates (x/a, y/a, z/b).

    Args:
      origin: float [..., 3] [m].
      direction: float [..., 3], unit.
    Returns:
      float [...], distance [m]; NaN where the ray misses (or only roots <= RAY_EPS).
    """
    scale = np.array([1.0 / WGS84_A_M, 1.0 / WGS84_A_M, 1.0 / WGS84_B_M])
    o, d = origin * scale, direction * scale
    qa = np.sum(d * d, axis=-1)
    qb = 2.0 * np.sum(o * d, axis=-1)
    qc = np.sum(o * o, axis=-1) - 1.0
    disc = qb * qb - 4.0 * qa * qc
    root = np.sqrt(np.where(disc >= 0.0, disc, 0.0))
    s1 = (-qb - root) / (2.0 * qa)
    s2 = (-qb + root) / (2.0 * qa)
    near = np.where(s1 > RAY_EPS, s1, np.where(s2 > RAY_EPS, s2, np.nan))
    return np.where(disc >= 0.0, near, np.nan)


def ecef_to_lonlat(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """WGS84 geodetic longitude and latitude of Earth-fixed points.

    Latitude by fixed-point iteration ``φ = atan2(z + e² N(φ) sin φ, ρ)``.

    Args:
      p: float [..., 3] [m].
    Returns:
      (lon_deg, lat_deg): float [...] each, longitude in (-180, 180].
    """
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    e2 = 1.0 - (WGS84_B_M / WGS84_A_M) ** 2
    rho = np.hypot(x, y)
    lat = np.arctan2(z, rho * (1.0 - e2))
    for _ in range(GEODETIC_ITERATIONS):
        n = WGS84_A_M / np.sqrt(1.0 - e2 * np.sin(lat) ** 2)
        lat = np.arctan2(z + e2 * n * np.sin(lat), rho)
    return np.degrees(np.arctan2(y, x)), np.degrees(lat)


def sample_offsets(duration_s: float, step_s: float) -> np.ndarray:
    """Sample offsets of a strip: 0, step, ... while < duration, then the end.

    Args:
      duration_s: strip duration [s] (> 0).
      step_s: sample step [s].
    Returns:
      float [K], K >= 2.
    """
    n = max(0, math.ceil(duration_s / step_s - 1e-9) - 1)
    return np.append(np.arange(n + 1, dtype=float) * step_s, float(duration_s))


def strip_ground(track: Track, start_s: float, offsets: np.ndarray, angles_deg) -> np.ndarray:
    """Ground points of several look angles at each sample time.

    Args:
      track: Track.
      start_s: strip start [s from horizon start].
      offsets: float [K] sample offsets [s].
      angles_deg: float [L] signed look angles [deg].
    Returns:
      float [K, L, 3], Earth-fixed ground points [m] (NaN where a ray misses).
    """
    pos, vel = track.ecef(start_s + offsets)
    pos, vel = pos[:, None, :], vel[:, None, :]
    ang = np.asarray(angles_deg, dtype=float)[None, :]
    d = look_direction(np.broadcast_to(pos, (len(offsets), ang.shape[1], 3)), vel, ang)
    return pos + ray_ellipsoid(np.broadcast_to(pos, d.shape), d)[..., None] * d


def strip_quads(inner_lonlat: np.ndarray, outer_lonlat: np.ndarray) -> np.ndarray:
    """Quads (inner_a, outer_a, outer_b, inner_b) between consecutive samples.

    Args:
      inner_lonlat: float [K, 2] inner edge (lon, lat) [deg].
      outer_lonlat: float [K, 2] outer edge (lon, lat) [deg].
    Returns:
      float [K-1, 4, 2].
    """
    return np.stack([inner_lonlat[:-1], outer_lonlat[:-1], outer_lonlat[1:], inner_lonlat[1:]], 1)


def quad_area(quads: np.ndarray) -> np.ndarray:
    """Absolute shoelace area of quads in the lon/lat plane [deg²].

    Args:
      quads: float [Q, 4, 2].
    Returns:
      float [Q].
    """
    x, y = quads[..., 0], quads[..., 1]
    return 0.5 * np.abs(np.sum(x * np.roll(y, -1, -1) - np.roll(x, -1, -1) * y, -1))


def points_in_quad(quad: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Points inside or on the border of one quad (even-odd rule, planar lon/lat).

    A point within ``BORDER_REL_TOL`` (relative to the edge length times the coordinate
    scale) of an edge segment counts as on the border.

    Args:
      quad: float [4, 2] vertices (lon, lat) [deg].
      x: float [N] longitudes [deg].
      y: float [N] latitudes [deg].
    Returns:
      bool [N].
    """
    inside = np.zeros(x.shape, dtype=bool)
    border = np.zeros(x.shape, dtype=bool)
    for k in range(4):
        (x1, y1), (x2, y2) = quad[k], quad[(k + 1) % 4]
        dx, dy = x2 - x1, y2 - y1
        cross = dx * (y - y1) - dy * (x - x1)
        seg2 = dx * dx + dy * dy
        scale = max(1.0, abs(x1), abs(y1), abs(x2), abs(y2))
        if seg2 == 0.0:  # repeated vertex: only the point itself
            border |= (x == x1) & (y == y1)
        else:
            on_line = np.abs(cross) <= BORDER_REL_TOL * scale * math.sqrt(seg2)
            dot = (x - x1) * dx + (y - y1) * dy
            border |= on_line & (dot >= 0.0) & (dot <= seg2)
        crosses = (y1 > y) != (y2 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_at = x1 + (y - y1) * dx / (dy if dy != 0.0 else 1.0)
        inside ^= crosses & (x < x_at)
    return inside | border


def covered_by_quads(quads: np.ndarray, lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
    """Samples inside or on any quad (bounding-box prefilter, then the exact test).

    Args:
      quads: float [Q, 4, 2].
      lon: float [N] [deg].
      lat: float [N] [deg].
    Returns:
      bool [N].
    """
    out = np.zeros(lon.shape, dtype=bool)
    if len(quads) == 0:
        return out
    lo, hi = quads.min(axis=1), quads.max(axis=1)
    box = (
        (lon[None, :] >= lo[:, None, 0])
        & (lon[None, :] <= hi[:, None, 0])
        & (lat[None, :] >= lo[:, None, 1])
        & (lat[None, :] <= hi[:, None, 1])
    )
    for q in np.flatnonzero(box.any(axis=1)):
        idx = np.flatnonzero(box[q] & ~out)
        if idx.size:
            out[idx] = points_in_quad(quads[q], lon[idx], lat[idx])
    return out
