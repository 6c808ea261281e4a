"""Reference geometry of the stereo_imaging checker: states, steering, rays, Sun, strips.

numpy + sgp4 only, independent of the planner's geometry; the Earth-rotation, Sun and
geodetic models come from the aeossp checker (:mod:`jaxspline.aeossp.check_frames`).
Conventions follow RULES.md and the official verifier (see :mod:`jaxspline.stereo.check`):

* Satellite states: SGP4 with the WGS72 constants (the official verifier propagates with
  skyfield's ``EarthSatellite``, which uses them) -> TEME; Earth-fixed ``r = R3(GMST82)
  r_teme`` and ``v = R3(GMST82) v_teme - ω × r`` with UT1 = UTC + ``ut1_minus_utc_s``.
* Local frame: nadir ``n = -p/|p|``; along ``a`` = ``v`` minus its ``n`` component,
  normalised; across ``c = a × n``. Steering angles (al, ac) point along
  ``n + tan(al) a + tan(ac) c`` (normalised) for the whole look.
* Ground point of a ray: nearest root > :data:`RAY_EPS` m of the WGS84 ray-ellipsoid
  quadratic (height 0).
* Sun: the low-precision series of :func:`~jaxspline.aeossp.check_frames.sun_position_gcrf`
  turned Earth-fixed; elevation against the geocentric up at the target, seen from the
  target toward ``AU_M`` times the Sun's unit vector.
* Strip footprint: boresight ground points at the start, every :data:`STRIP_STEP_S`
  after it and at the end (a point whose ray misses is dropped), in the target's
  geocentric east / north plane; a strip is the set of points within ``h`` of that
  polyline (a capsule chain).
* Overlap: the share of a fixed sunflower (Vogel) lattice of :data:`OVERLAP_POINTS`
  points, uniform over the AOI disk, inside every strip: a deterministic quadrature of the
  area fraction that the official checker estimates with 100 seeded random points.
"""

from __future__ import annotations

import math
from datetime import datetime

import numpy as np
from sgp4.api import WGS72, Satrec

from jaxspline.aeossp.check_frames import (
    angle_deg,
    ecef_to_gcrf_matrix,
    geodetic_to_ecef,
    gmst82,
    sun_position_gcrf,
)
from jaxspline.stereo.case import Satellite, Target

__all__ = [
    "AU_M",
    "OVERLAP_POINTS",
    "STRIP_STEP_S",
    "UT1_MINUS_UTC_S",
    "Track",
    "ANGLE_TOL_DEG",
    "access_mask",
    "access_terms",
    "boresight",
    "combined_off_nadir_deg",
    "disk_lattice",
    "enu_basis",
    "foot_point",
    "ground_point",
    "inside_strip",
    "line_of_sight_clear",
    "local_frame",
    "off_nadir_to_deg",
    "polyline_distance",
    "ray_ellipsoid",
    "solar_elevation_deg",
    "steering_angles",
    "strip_polyline",
    "target_ecef",
    "window_samples",
]

#: UT1 - UTC of the official verifier's states [s]: skyfield's bundled IERS prediction,
#: 0.0373 s +- 0.0005 s over 18-26 April 2026, the benchmark's horizons.
UT1_MINUS_UTC_S = 0.0373
#: Earth rotation rate for the Earth-fixed velocity [rad/s].
OMEGA_EARTH = 7.292115146706979e-5
WGS84_A_M = 6378137.0
WGS84_B_M = 6356752.314245179
#: Smallest accepted ray length [m] (the official ``_NUMERICAL_EPS``).
RAY_EPS = 1e-9
#: Distance at which the Sun is placed along its unit vector [m] (the official ``au``).
AU_M = 1.496e11
#: Sample step of the strip polyline [s].
STRIP_STEP_S = 8.0
#: Lattice points of the overlap quadrature over one AOI disk.
OVERLAP_POINTS = 4096
#: Line-of-sight slack when the target is on or above the ellipsoid [m] (official).
LOS_SLACK_ABOVE_M = 1.0
#: Line-of-sight slack added to the target's depth when it is below the ellipsoid [m].
LOS_SLACK_BELOW_M = 10.0
#: Height above the target from which :func:`foot_point` casts its ray [m].
FOOT_SEARCH_M = 2e4
#: Off-nadir, solar elevation tolerances of the access test [deg] (official).
ANGLE_TOL_DEG = 1e-6
_UNIX_EPOCH_JD = 2440587.5
_GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


class Track:
    """SGP4 (WGS72) states of one satellite at offsets (seconds) from the horizon start.

    Args:
      sat: the case's Satellite.
      start: horizon start (aware UTC datetime), offset 0.
      ut1_minus_utc_s: UT1 - UTC used for the Earth rotation [s] (default: the official
        verifier's, :data:`UT1_MINUS_UTC_S`; 0: zero EOP).

    Attributes:
      satellite_id: the satellite.
      t0_unix: Unix seconds of ``start``.
    """

    def __init__(self, sat: Satellite, start: datetime, ut1_minus_utc_s: float = UT1_MINUS_UTC_S):
        self.satellite_id = sat.id
        self._rec = Satrec.twoline2rv(sat.tle1, sat.tle2, WGS72)
        self.t0_unix = start.timestamp()
        self._dut1 = float(ut1_minus_utc_s)

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
        """Earth-fixed position and velocity: ``R3(GMST82(UT1))`` of TEME, ``v - ω × r``.

        Args:
          seconds: float [...], offsets [s].
        Returns:
          (r, v): float [..., 3] [m], [m/s].
        """
        r, v = self.teme(seconds)
        g = gmst82(self.unix(seconds) + self._dut1)
        c, s = np.cos(g), np.sin(g)
        rx = c * r[..., 0] + s * r[..., 1]
        ry = -s * r[..., 0] + c * r[..., 1]
        vx = c * v[..., 0] + s * v[..., 1] + OMEGA_EARTH * ry
        vy = -s * v[..., 0] + c * v[..., 1] - OMEGA_EARTH * rx
        return np.stack([rx, ry, r[..., 2]], -1), np.stack([vx, vy, v[..., 2]], -1)


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


def boresight(pos: np.ndarray, vel: np.ndarray, along_deg, across_deg) -> np.ndarray:
    """Unit boresight of steering angles: ``normalise(n + tan(al) a + tan(ac) c)``.

    Args:
      pos: float [..., 3] [m].
      vel: float [..., 3] [m/s].
      along_deg: float [...], along-track steering angle [deg] (positive: forward).
      across_deg: float [...], across-track steering angle [deg] (positive: left).
    Returns:
      float [..., 3].
    """
    nadir, along, across = local_frame(pos, vel)
    ta = np.tan(np.radians(np.asarray(along_deg, dtype=float)))[..., None]
    tc = np.tan(np.radians(np.asarray(across_deg, dtype=float)))[..., None]
    return _unit(nadir + ta * along + tc * across)


def combined_off_nadir_deg(along_deg, across_deg) -> np.ndarray:
    """Angle between the boresight and nadir, ``atan(sqrt(tan²(al) + tan²(ac)))`` [deg].

    Args:
      along_deg: float [...] [deg].
      across_deg: float [...] [deg].
    Returns:
      float [...] [deg].
    """
    ta = np.tan(np.radians(np.asarray(along_deg, dtype=float)))
    tc = np.tan(np.radians(np.asarray(across_deg, dtype=float)))
    return np.degrees(np.arctan(np.hypot(ta, tc)))


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


def ground_point(pos: np.ndarray, vel: np.ndarray, along_deg, across_deg) -> np.ndarray:
    """Boresight ground point on the ellipsoid (height 0).

    Args:
      pos: float [..., 3] [m].
      vel: float [..., 3] [m/s].
      along_deg: float [...] [deg].
      across_deg: float [...] [deg].
    Returns:
      float [..., 3] [m]; NaN where the ray misses.
    """
    d = boresight(pos, vel, along_deg, across_deg)
    return pos + ray_ellipsoid(pos, d)[..., None] * d


def steering_angles(pos: np.ndarray, vel: np.ndarray, point: np.ndarray) -> tuple:
    """Steering angles that point the boresight from ``pos`` at ``point`` (the inverse of
    :func:`boresight`): ``atan(d·a / d·n)`` and ``atan(d·c / d·n)`` for ``d = point - pos``.

    Args:
      pos: float [..., 3], Earth-fixed position [m].
      vel: float [..., 3], Earth-fixed velocity [m/s].
      point: float [3] or [..., 3], the aim point [m].
    Returns:
      (along_deg, across_deg): float [...] each [deg].
    """
    nadir, along, across = local_frame(pos, vel)
    d = point - pos
    dn = np.sum(d * nadir, axis=-1)
    al = np.degrees(np.arctan(np.sum(d * along, axis=-1) / dn))
    return al, np.degrees(np.arctan(np.sum(d * across, axis=-1) / dn))


def foot_point(center: np.ndarray) -> np.ndarray:
    """Where the geocentric vertical through ``center`` meets the ellipsoid: the point whose
    east / north offset from the target is zero (a strip's ground track is laid there).

    Args:
      center: float [3], Earth-fixed point [m].
    Returns:
      float [3] [m].
    """
    down = -center / np.linalg.norm(center)
    top = center - FOOT_SEARCH_M * down  # above any terrain: the ray starts outside
    return top + ray_ellipsoid(top, down) * down


def target_ecef(target: Target) -> np.ndarray:
    """Earth-fixed position of the target centre (geodetic, ``elevation_ref_m`` above WGS84).

    Args:
      target: Target.
    Returns:
      float [3] [m].
    """
    return geodetic_to_ecef(target.lat_deg, target.lon_deg, target.elevation_m)


def enu_basis(center: np.ndarray) -> np.ndarray:
    """Rows east, north, up of the geocentric local frame at ``center``.

    Args:
      center: float [3], Earth-fixed point [m].
    Returns:
      float [3, 3]; ``basis @ (p - center)`` is (east, north, up) [m].
    """
    lon = math.atan2(center[1], center[0])
    lat = math.atan2(center[2], math.hypot(center[0], center[1]))
    so, co, sa, ca = math.sin(lon), math.cos(lon), math.sin(lat), math.cos(lat)
    return np.array([[-so, co, 0.0], [-sa * co, -sa * so, ca], [ca * co, ca * so, sa]])


def off_nadir_to_deg(sat_pos: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Angle between nadir and the direction from the satellite to ``point`` [deg].

    Args:
      sat_pos: float [..., 3] [m].
      point: float [3] or [..., 3] [m].
    Returns:
      float [...] [deg].
    """
    return angle_deg(-sat_pos, point - sat_pos)


def line_of_sight_clear(sat_pos: np.ndarray, point: np.ndarray) -> np.ndarray:
    """The segment satellite -> point meets the ellipsoid no earlier than the point.

    A point on or above the ellipsoid is clear when the ray's first crossing is at most
    :data:`LOS_SLACK_ABOVE_M` before it; one below when the crossing is within its depth
    plus :data:`LOS_SLACK_BELOW_M` (the official slacks). A ray that never meets the
    ellipsoid counts as blocked, as in the official verifier.

    Args:
      sat_pos: float [..., 3] [m].
      point: float [3] [m].
    Returns:
      bool [...].
    """
    los = point - sat_pos
    dist = np.linalg.norm(los, axis=-1)
    hit = ray_ellipsoid(sat_pos, los / dist[..., None])
    q = (point[0] ** 2 + point[1] ** 2) / WGS84_A_M**2 + point[2] ** 2 / WGS84_B_M**2
    if q >= 1.0 - RAY_EPS:
        slack = LOS_SLACK_ABOVE_M
    else:
        slack = float(np.linalg.norm(point)) * (1.0 / math.sqrt(q) - 1.0) + LOS_SLACK_BELOW_M
    return np.isfinite(hit) & (hit + slack >= dist)


def solar_elevation_deg(point: np.ndarray, unix_s) -> np.ndarray:
    """Sun elevation above the geocentric horizon of ``point`` [deg].

    Args:
      point: float [3], Earth-fixed [m].
      unix_s: float [...], UTC as Unix seconds.
    Returns:
      float [...] [deg].
    """
    sun = sun_position_gcrf(unix_s)
    m = ecef_to_gcrf_matrix(unix_s)  # ecef -> gcrf; its transpose turns gcrf to ecef
    sun_ecef = _unit(np.einsum("...ji,...j->...i", m, _unit(sun)))
    up = point / np.linalg.norm(point)
    view = _unit(AU_M * sun_ecef - point)
    return np.degrees(np.arcsin(np.clip(view @ up, -1.0, 1.0)))


def access_terms(track: Track, point: np.ndarray, seconds) -> tuple:
    """The three quantities of the access test at each instant.

    Args:
      track: Track.
      point: float [3], the target centre [m].
      seconds: float [T], offsets from the horizon start [s].
    Returns:
      (clear bool [T], off-nadir of the target float [T] [deg], solar elevation float
      [T] [deg]).
    """
    seconds = np.atleast_1d(np.asarray(seconds, dtype=float))
    pos, _ = track.ecef(seconds)
    return (
        line_of_sight_clear(pos, point),
        off_nadir_to_deg(pos, point),
        solar_elevation_deg(point, track.unix(seconds)),
    )


def access_mask(
    track: Track, point: np.ndarray, max_off_nadir_deg: float, min_sun_deg: float, seconds
) -> np.ndarray:
    """The access test at each instant (RULES.md 7): line of sight clear, the target within
    ``max_off_nadir_deg`` of nadir and the Sun at least ``min_sun_deg`` above its horizon
    (tolerances :data:`ANGLE_TOL_DEG`).

    Args:
      track: Track.
      point: float [3], the target centre [m].
      max_off_nadir_deg: the satellite's limit [deg].
      min_sun_deg: the mission's minimum solar elevation [deg].
      seconds: float [T], offsets from the horizon start [s].
    Returns:
      bool [T].
    """
    clear, off, sun = access_terms(track, point, seconds)
    return clear & (off <= max_off_nadir_deg + ANGLE_TOL_DEG) & (sun >= min_sun_deg - ANGLE_TOL_DEG)


def window_samples(start_s: float, end_s: float, step_s: float) -> np.ndarray:
    """Instants of a sampled test over [start, end]: start, every step while before end, end.

    Args:
      start_s: start [s].
      end_s: end [s] (an end before the start gives no instant).
      step_s: step [s] (> 0).
    Returns:
      float [K].
    """
    if end_s < start_s:
        return np.zeros(0)
    if end_s == start_s:
        return np.array([start_s])
    n = max(0, math.ceil((end_s - start_s) / step_s - 1e-9) - 1)
    return np.append(start_s + step_s * np.arange(n + 1, dtype=float), end_s)


def strip_polyline(
    track: Track,
    basis: np.ndarray,
    center: np.ndarray,
    start_s: float,
    end_s: float,
    along_deg: float,
    across_deg: float,
) -> np.ndarray:
    """Boresight ground track of a look in the target's east / north plane.

    Samples at the start, every :data:`STRIP_STEP_S` while not after the end, and the end
    when the last sample falls before it; points whose ray misses are dropped.

    Args:
      track: Track.
      basis: float [3, 3], :func:`enu_basis` of the target.
      center: float [3], the target centre [m].
      start_s: start [s].
      end_s: end [s].
      along_deg: along-track steering [deg].
      across_deg: across-track steering [deg].
    Returns:
      float [K, 2], (east, north) [m]; K = 0 when the end is not after the start.
    """
    if not end_s > start_s:
        return np.zeros((0, 2))
    n = math.floor((end_s - start_s) / STRIP_STEP_S + 1e-9)
    t = start_s + STRIP_STEP_S * np.arange(n + 1, dtype=float)
    if t[-1] < end_s - 1e-9:
        t = np.append(t, end_s)
    pos, vel = track.ecef(t)
    g = ground_point(pos, vel, along_deg, across_deg)
    g = g[np.isfinite(g).all(axis=-1)]
    return ((g - center) @ basis.T)[:, :2]


def polyline_distance(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Distance from points to a polyline (a single vertex: to that point).

    Args:
      points: float [N, 2] [m].
      poly: float [K, 2] [m] (K = 0: infinite distance).
    Returns:
      float [N] [m].
    """
    if len(poly) == 0:
        return np.full(len(points), np.inf)
    if len(poly) == 1:
        return np.linalg.norm(points - poly[0], axis=-1)
    a, b = poly[:-1], poly[1:]
    ab = b - a
    len2 = np.sum(ab * ab, axis=-1)
    rel = points[:, None, :] - a[None, :, :]
    u = np.sum(rel * ab[None], axis=-1) / np.where(len2 > 0.0, len2, 1.0)
    u = np.clip(np.where(len2 > 0.0, u, 0.0), 0.0, 1.0)
    d = rel - u[..., None] * ab[None]
    return np.min(np.linalg.norm(d, axis=-1), axis=1)


def inside_strip(points: np.ndarray, poly: np.ndarray, half_width_m: float) -> np.ndarray:
    """Points within ``half_width_m`` of the polyline (border included).

    Args:
      points: float [N, 2] [m].
      poly: float [K, 2] [m].
      half_width_m: strip half-width [m].
    Returns:
      bool [N].
    """
    return polyline_distance(points, poly) <= half_width_m + RAY_EPS


def disk_lattice(radius_m: float, n: int = OVERLAP_POINTS) -> np.ndarray:
    """Sunflower (Vogel) lattice: ``n`` points of equal area share over a disk.

    Point k sits at radius ``R sqrt((k + 1/2) / n)`` and angle ``k π (3 - √5)``, so each
    holds ``1/n`` of the area; the share of points inside a region with a smooth border
    converges to its area share much faster than random points.

    Args:
      radius_m: disk radius [m].
      n: number of points.
    Returns:
      float [n, 2] (east, north) [m].
    """
    k = np.arange(n, dtype=float)
    r = radius_m * np.sqrt((k + 0.5) / n)
    th = k * _GOLDEN_ANGLE
    return np.stack([r * np.cos(th), r * np.sin(th)], -1)
