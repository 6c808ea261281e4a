"""Ground geometry of strips and areas: local projections, strips between points, footprints.

Points on the ground are handled as Earth-fixed unit vectors ``u`` (directions from the
Earth's centre); :func:`surface_point` puts them on the WGS84 ellipsoid. Two local
projections about a centre ``c`` (unit vector), both on the unit sphere, with axes
``e`` (east) and ``n`` (north) of the geocentric tangent plane at ``c``
(:func:`local_axes`):

* :func:`gnomonic` - central projection ``(u . e, u . n) / (u . c)``: every great
  circle, so every strip of the planner, is a straight line; distances are stretched
  by ``1 / cos^2`` (radially) and ``1 / cos`` (across) of the central angle, never
  shrunk (1.0002 at 1 deg, 100 km, from the centre);
* :func:`equal_area` - Lambert azimuthal equal-area, ``sqrt(2 / (1 + u . c)) (u . e,
  u . n)``: areas on the sphere are kept exactly (Snyder, *Map Projections - A Working
  Manual*, USGS PP 1395, eq. 24-2 to 24-4, in vector form).

Strips follow the planner's model (:func:`jaxspline.geometry.pointing.aim_params`): from
the start point ``g0`` (geodetic, on the ellipsoid) the aim point runs along the great
circle of radius ``|g0|`` whose start direction is ``strip_direction(lat, lon, az)``
made orthogonal to ``g0``; ``length / |g0|`` is the arc [rad]. :func:`strip_between`
inverts that model exactly and :func:`strip_centerline` samples it (numpy).

All functions are numpy, float64. Units: metres, radians.
"""

from __future__ import annotations

import numpy as np

from jaxspline.base.elements import R_EARTH, WGS84_E2, geodetic_to_ecef, unit_vectors
from jaxspline.geometry.frames import ecef_to_geodetic

__all__ = [
    "equal_area",
    "gnomonic",
    "gnomonic_inverse",
    "ground_track",
    "local_axes",
    "strip_between",
    "strip_centerline",
    "FOOTPRINT_STEP_M",
    "footprint_lonlat",
    "strip_footprint",
    "surface_point",
]

_B2 = R_EARTH**2 * (1.0 - WGS84_E2)  # squared polar radius [m^2]
FOOTPRINT_STEP_M = 2000.0  # footprint rings get a point on each side every this [m]


def surface_point(u):
    """The WGS84 ellipsoid point in direction ``u`` from the Earth's centre.

    ``s u`` with ``s = 1 / sqrt((u_x^2 + u_y^2) / a^2 + u_z^2 / b^2)``.

    Args:
      u: float [..., 3], unit vectors, Earth-fixed.
    Returns:
      float [..., 3], Earth-fixed points [m].
    """
    u = np.asarray(u, np.float64)
    s = 1.0 / np.sqrt((u[..., 0] ** 2 + u[..., 1] ** 2) / R_EARTH**2 + u[..., 2] ** 2 / _B2)
    return s[..., None] * u


def local_axes(center):
    """Geocentric east and north unit vectors of the tangent plane at ``center``.

    ``e = z x c / |z x c|`` (``x`` at a pole), ``n = c x e``.

    Args:
      center: float [3], unit vector.
    Returns:
      (e float [3], n float [3]).
    """
    c = unit_vectors(center)
    e = np.cross([0.0, 0.0, 1.0], c)
    e = unit_vectors(e) if np.linalg.norm(e) > 1e-12 else np.array([1.0, 0.0, 0.0])
    return e, np.cross(c, e)


def gnomonic(u, center):
    """Gnomonic (central) projection about ``center``: great circles map to straight lines.

    ``(x, y) = (u . e, u . n) / (u . c)``, dimensionless (tangents of the central angle;
    multiply by a radius for metres). Defined for ``u . c > 0``.

    Args:
      u: float [..., 3], unit vectors, Earth-fixed.
      center: float [3], unit vector.
    Returns:
      float [..., 2].
    """
    c = unit_vectors(center)
    e, n = local_axes(c)
    u = np.asarray(u, np.float64)
    return np.stack([u @ e, u @ n], -1) / (u @ c)[..., None]


def gnomonic_inverse(xy, center):
    """Unit vectors of gnomonic coordinates: ``unit_vectors(c + x e + y n)``.

    Args:
      xy: float [..., 2], as returned by :func:`gnomonic`.
      center: float [3], unit vector.
    Returns:
      float [..., 3], unit vectors, Earth-fixed.
    """
    c = unit_vectors(center)
    e, n = local_axes(c)
    xy = np.asarray(xy, np.float64)
    return unit_vectors(c + xy[..., :1] * e + xy[..., 1:2] * n)


def equal_area(u, center):
    """Lambert azimuthal equal-area projection about ``center`` on the unit sphere.

    ``(x, y) = sqrt(2 / (1 + u . c)) (u . e, u . n)``; areas are those on the unit sphere
    (multiply by ``R^2`` for m^2 on a sphere of radius R). Defined for ``u != -c``.

    Args:
      u: float [..., 3], unit vectors, Earth-fixed.
      center: float [3], unit vector.
    Returns:
      float [..., 2].
    """
    c = unit_vectors(center)
    e, n = local_axes(c)
    u = np.asarray(u, np.float64)
    k = np.sqrt(2.0 / np.maximum(1.0 + u @ c, 1e-300))
    return k[..., None] * np.stack([u @ e, u @ n], -1)


def _geodetic_axes(lat, lon):
    """Geodetic north and east unit vectors [..., 3] at (lat, lon)."""
    north = np.stack([-np.sin(lat) * np.cos(lon), -np.sin(lat) * np.sin(lon), np.cos(lat)], -1)
    east = np.stack([-np.sin(lon), np.cos(lon), np.zeros_like(lon)], -1)
    return north, east


def strip_between(u_a, u_b):
    """The planner's strip from direction ``u_a`` to ``u_b`` (exact inverse of its model).

    Start point: the ellipsoid point along ``u_a`` (height 0); length ``|g0|`` times the
    arc ``atan2(|u_a x u_b|, u_a . u_b)``; azimuth such that the planner's start
    direction, ``strip_direction`` made orthogonal to ``u_a``, is the great-circle
    tangent ``t`` towards ``u_b``: with ``N'`` the geodetic north made orthogonal to
    ``u_a``, ``az = atan2((t . E) (N . N'), t . N')``.

    Args:
      u_a: float [..., 3], unit start directions, Earth-fixed.
      u_b: float [..., 3], unit end directions (not equal or opposite to ``u_a``).
    Returns:
      (lat [rad], lon [rad], azimuth [rad] clockwise from north, length [m]), float [...].
    """
    u_a, u_b = unit_vectors(u_a), unit_vectors(u_b)
    g0 = surface_point(u_a)
    lat, lon, _ = ecef_to_geodetic(g0)
    arc = np.arctan2(np.linalg.norm(np.cross(u_a, u_b), axis=-1), np.sum(u_a * u_b, -1))
    t = unit_vectors(u_b - np.sum(u_a * u_b, -1)[..., None] * u_a)
    north, east = _geodetic_axes(lat, lon)
    n_perp = north - np.sum(north * u_a, -1)[..., None] * u_a
    n_len = np.linalg.norm(n_perp, axis=-1)
    az = np.arctan2(np.sum(t * east, -1) * n_len, np.sum(t * n_perp, -1) / n_len)
    length = np.linalg.norm(geodetic_to_ecef(lat, lon, 0.0), axis=-1) * arc
    return lat, lon, np.mod(az, 2.0 * np.pi), length


def strip_centerline(lat, lon, azimuth, length, samples: int, alt=0.0):
    """Directions along the planner's strips at ``samples`` equally spaced arc lengths.

    ``u(s) = u0 cos(s / |g0|) + d sin(s / |g0|)``, ``s = 0 .. length``, with
    ``g0 = geodetic_to_ecef(lat, lon, alt)``, ``u0 = g0 / |g0|`` and ``d`` the
    geodetic direction of ``azimuth`` made orthogonal to ``u0``.

    Args:
      lat: float [...], geodetic latitude of the start [rad].
      lon: float [...], longitude of the start [rad].
      azimuth: float [...], direction at the start, clockwise from north [rad].
      length: float [...], strip length [m].
      samples: int >= 2, points per strip.
      alt: float [...], height of the start above the ellipsoid [m].
    Returns:
      (u float [..., samples, 3] unit directions, tangent float [..., samples, 3] unit
      ground directions of travel, radius float [...] = |g0| [m]).
    """
    if samples < 2:
        raise ValueError(f"samples must be >= 2, got {samples!r}")
    lat, lon, azimuth, length, alt = np.broadcast_arrays(
        *(np.asarray(x, np.float64) for x in (lat, lon, azimuth, length, alt))
    )
    g0 = geodetic_to_ecef(lat, lon, alt)
    rad = np.linalg.norm(g0, axis=-1)
    u0 = g0 / rad[..., None]
    north, east = _geodetic_axes(lat, lon)
    d = np.cos(azimuth)[..., None] * north + np.sin(azimuth)[..., None] * east
    d = unit_vectors(d - np.sum(d * u0, -1)[..., None] * u0)
    ang = (length / rad)[..., None] * np.linspace(0.0, 1.0, samples)
    c, s = np.cos(ang)[..., None], np.sin(ang)[..., None]
    u0, d = u0[..., None, :], d[..., None, :]
    return u0 * c + d * s, d * c - u0 * s, rad


def strip_footprint(lat, lon, azimuth, length, swath, samples: int, alt=0.0):
    """Ground footprint of strips imaged ``swath`` metres wide: a closed ring of directions.

    Each centreline point :func:`strip_centerline` moves ``swath / 2`` along the
    ground perpendicular to the left and to the right (great circles through it,
    ``cos(b) u +- sin(b) (u x tangent)``, ``b = swath / (2 |g0|)``); the ring is the
    left side forward, then the right side back (ends cut square).

    Args:
      lat: float [...], geodetic latitude of the strip's start [rad].
      lon: float [...], longitude of the start [rad].
      azimuth: float [...], direction at the start, clockwise from north [rad].
      length: float [...], strip length [m].
      swath: float [...], imaged width [m] (> 0).
      samples: int >= 2, centreline points per strip.
      alt: float [...], start heights [m].
    Returns:
      float [..., 2 samples, 3], unit directions, Earth-fixed (not repeated at the end).
    """
    u, tan, rad = strip_centerline(lat, lon, azimuth, length, samples, alt)
    b = (np.asarray(swath, np.float64) / (2.0 * rad))[..., None, None]
    side = np.cross(u, tan)
    left = np.cos(b) * u + np.sin(b) * side
    right = np.cos(b) * u - np.sin(b) * side
    return np.concatenate([left, right[..., ::-1, :]], axis=-2)


def footprint_lonlat(lat, lon, azimuth, length, swath, alt=0.0, upto: float = 1.0):
    """Ground footprint of one strip imaged ``swath`` metres wide, as a closed lon/lat ring.

    :func:`strip_footprint` of the first ``upto`` of the strip, a point on each side
    every :data:`FOOTPRINT_STEP_M`, put on the ellipsoid.

    Args:
      lat: geodetic latitude of the start point [rad].
      lon: longitude of the start point [rad].
      azimuth: direction at the start [rad].
      length: strip length [m].
      swath: imaged width [m].
      alt: start height [m].
      upto: fraction of the strip from its start (0 < upto <= 1).
    Returns:
      (lon [deg], lat [deg]), float [n] each, the ring closed (first point repeated).
    """
    part = float(length) * upto
    samples = max(2, int(np.ceil(part / FOOTPRINT_STEP_M)) + 1)
    u = strip_footprint(lat, lon, azimuth, part, swath, samples, alt=alt)
    la, lo, _ = ecef_to_geodetic(surface_point(u))
    lo, la = np.degrees(lo), np.degrees(la)
    return np.append(lo, lo[0]), np.append(la, la[0])


def ground_track(r_ecef, v_ecef):
    """Sub-satellite directions and their rate of change (the ground track), Earth-fixed.

    ``u = r / |r|``; ``u' = (v - (v . u) u) / |r|`` with ``v`` the Earth-fixed velocity
    (:func:`jaxspline.geometry.frames.teme_to_ecef`).

    Args:
      r_ecef: float [..., 3], satellite positions, Earth-fixed [m].
      v_ecef: float [..., 3], Earth-fixed velocities [m/s].
    Returns:
      (u float [..., 3] unit, u_dot float [..., 3] [rad/s], tangent to the sphere).
    """
    r = np.asarray(r_ecef, np.float64)
    v = np.asarray(v_ecef, np.float64)
    rn = np.linalg.norm(r, axis=-1, keepdims=True)
    u = r / rn
    return u, (v - np.sum(v * u, -1, keepdims=True) * u) / rn
