"""numpy + shapely reference of the strip coverage (the baseline of the ``coverage`` bench
section and the reference of ``tests/regional/test_coverage_kernel.py``).

Written apart from :mod:`jaxspline.screen.coverage` on purpose: its own edge-point
formula (the textbook quadratic root, the iterative geodetic latitude of
``jaxspline.geometry.frames``) and shapely's own point-in-polygon predicate
(``shapely.intersects_xy``: inside or on the border). Per candidate: edge points of
every sample (numpy, vectorized over the samples), one shapely polygon per quad
(inner_a, outer_a, outer_b, inner_b) in (lon, lat) with longitudes unwrapped towards
the strip's first inner point, the grid samples inside the strip's bounding box,
``intersects_xy`` of every quad against them.
"""

from __future__ import annotations

import numpy as np
import shapely

from jaxspline.base.elements import R_EARTH, WGS84_F
from jaxspline.geometry.frames import ecef_to_geodetic

__all__ = ["look_points_np", "edges_np", "covered_baseline"]

_B = R_EARTH * (1.0 - WGS84_F)


def look_points_np(pos, vel, look_deg):
    """Ground points of one look angle at n samples (numpy).

    Args:
      pos: float [n, 3], Earth-fixed positions [m].
      vel: float [n, 3], Earth-fixed velocities [m/s].
      look_deg: float, look angle [deg].
    Returns:
      (lon [n], lat [n] [deg], hit bool [n]).
    """
    up = pos / np.linalg.norm(pos, axis=-1, keepdims=True)
    nadir = -up
    along = vel - np.sum(vel * nadir, -1, keepdims=True) * nadir
    along /= np.linalg.norm(along, axis=-1, keepdims=True)
    across = np.cross(along, nadir)
    d = nadir + np.tan(np.radians(look_deg)) * across
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    w = np.array([1.0 / R_EARTH, 1.0 / R_EARTH, 1.0 / _B])
    a = np.sum((d * w) ** 2, -1)
    b = 2.0 * np.sum(pos * d * w * w, -1)
    c = np.sum((pos * w) ** 2, -1) - 1.0
    disc = b * b - 4.0 * a * c
    hit = (disc >= 0.0) & (b < 0.0)
    t = (-b - np.sqrt(np.where(hit, disc, 0.0))) / (2.0 * a)
    g = pos + t[:, None] * d
    lat, lon, _ = ecef_to_geodetic(g)
    return np.degrees(lon), np.degrees(lat), hit


def edges_np(pos, vel, roll_deg, fov_deg):
    """Inner and outer edge points of a strip (numpy).

    Args:
      pos: float [n, 3] [m]; vel: float [n, 3] [m/s].
      roll_deg: roll [deg]; fov_deg: field of view [deg].
    Returns:
      (inner [n, 2], outer [n, 2], hit [n]), (lon, lat) [deg].
    """
    sgn = -1.0 if roll_deg < 0 else 1.0
    li, ai, hi = look_points_np(pos, vel, sgn * (abs(roll_deg) - 0.5 * fov_deg))
    lo, ao, ho = look_points_np(pos, vel, sgn * (abs(roll_deg) + 0.5 * fov_deg))
    return np.stack([li, ai], -1), np.stack([lo, ao], -1), hi & ho


def _unwrap(lon, ref):
    return lon + 360.0 * np.round((ref - lon) / 360.0)


def covered_baseline(inner, outer, lon, lat) -> np.ndarray:
    """Grid samples inside or on the border of any quad of one strip (shapely).

    Args:
      inner: float [n, 2], inner-edge (lon, lat) [deg].
      outer: float [n, 2], outer-edge (lon, lat) [deg].
      lon: float [N], grid longitudes [deg].
      lat: float [N], grid latitudes [deg].
    Returns:
      int64 [m], sorted covered sample indices.
    """
    ref = inner[0, 0]
    ix, ox = _unwrap(inner[:, 0], ref), _unwrap(outer[:, 0], ref)
    iy, oy = inner[:, 1], outer[:, 1]
    px = _unwrap(np.asarray(lon, np.float64), ref)
    py = np.asarray(lat, np.float64)
    xs = np.concatenate([ix, ox])
    ys = np.concatenate([iy, oy])
    near = np.flatnonzero((px >= xs.min()) & (px <= xs.max()) & (py >= ys.min()) & (py <= ys.max()))
    if near.size == 0:
        return near.astype(np.int64)
    ring = np.stack(
        [
            np.stack([ix[:-1], iy[:-1]], -1),
            np.stack([ox[:-1], oy[:-1]], -1),
            np.stack([ox[1:], oy[1:]], -1),
            np.stack([ix[1:], iy[1:]], -1),
            np.stack([ix[:-1], iy[:-1]], -1),
        ],
        1,
    )
    quads = shapely.polygons(ring)
    shapely.prepare(quads)
    inside = shapely.intersects_xy(quads[:, None], px[near][None, :], py[near][None, :])
    return near[inside.any(0)].astype(np.int64)
