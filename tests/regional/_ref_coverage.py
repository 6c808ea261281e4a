"""numpy + scipy + shapely + sgp4 reference of strip coverage, pitch included.

Written apart from :mod:`jaxspline.screen.coverage` and its kernels:

* tracks: sgp4's own ``Satrec.sgp4_array`` (WGS84 constants) in TEME, turned Earth-fixed
  by sgp4's ``gstime`` (GMST 1982) about z, the velocity relative to the rotating Earth
  ``R v - w x (R r)``;
* a look direction is nadir turned by explicit rotations (``scipy.spatial.transform``):
  first by the pitch towards the track (about ``nadir x along``), then by the roll
  towards ``across`` (about the pitched boresight's ``down x across``);
* the ground point is the first root of the ray-ellipsoid quadratic (the textbook
  ``(-b - sqrt(b^2 - 4 a c)) / 2a``), its latitude by Bowring's fixed-point iteration;
* a sample is covered when shapely's ``intersects_xy`` puts it inside or on a quad
  ``(inner_a, outer_a, outer_b, inner_b)`` (longitudes unwrapped towards the strip).
"""

from __future__ import annotations

import math
from datetime import UTC, datetime, timedelta

import numpy as np
import shapely
from scipy.spatial.transform import Rotation

A = 6378137.0  # WGS84 equatorial radius [m]
F = 1.0 / 298.257223563
B = A * (1.0 - F)
E2 = F * (2.0 - F)
OMEGA = 7.292115146706979e-5  # Earth rotation rate [rad/s] (GMST per UT1 second)


def sgp4_tracks(tle1: str, tle2: str, start: datetime, t_s) -> tuple[np.ndarray, np.ndarray]:
    """Earth-fixed position [m] and velocity relative to the Earth [m/s] at ``start + t_s``."""
    from sgp4.api import WGS84, Satrec, jday
    from sgp4.propagation import gstime

    rec = Satrec.twoline2rv(tle1, tle2, WGS84)
    t_s = np.atleast_1d(np.asarray(t_s, np.float64))
    jd0, fr0 = jday(start.year, start.month, start.day, start.hour, start.minute, start.second)
    fr = fr0 + (start.microsecond * 1e-6 + t_s) / 86400.0
    jd = np.full(t_s.shape, jd0)
    err, r, v = rec.sgp4_array(jd, fr)
    assert not err.any()
    th = np.array([gstime(a + b) for a, b in zip(jd, fr, strict=True)])
    c, s = np.cos(th), np.sin(th)
    rot = np.zeros((t_s.size, 3, 3))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 1, 0], rot[:, 1, 1], rot[:, 2, 2] = c, s, -s, c, 1.0
    pos = np.einsum("tij,tj->ti", rot, r * 1e3)
    vel = np.einsum("tij,tj->ti", rot, v * 1e3) - np.cross([0.0, 0.0, OMEGA], pos)
    return pos, vel


def at(start: datetime, seconds: float) -> datetime:
    return (start + timedelta(seconds=float(seconds))).astimezone(UTC)


def frame(pos, vel):
    """(nadir, along, across) unit vectors of the track frame."""
    nadir = -pos / np.linalg.norm(pos, axis=-1, keepdims=True)
    along = vel - np.sum(vel * nadir, -1, keepdims=True) * nadir
    along /= np.linalg.norm(along, axis=-1, keepdims=True)
    return nadir, along, np.cross(along, nadir)


def look_directions(pos, vel, look_deg, pitch_deg=0.0) -> np.ndarray:
    """Unit look directions [n, 3]: nadir pitched by ``pitch_deg`` towards the track, then
    rolled by ``look_deg`` towards ``across`` (explicit rotations)."""
    nadir, along, across = frame(np.atleast_2d(pos), np.atleast_2d(vel))
    p, a = math.radians(pitch_deg), math.radians(look_deg)
    axis = np.cross(nadir, along)  # turns nadir towards along
    down = Rotation.from_rotvec(p * axis).apply(nadir)
    axis = np.cross(down, across)  # turns down towards across
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    return Rotation.from_rotvec(a * axis).apply(down)


def ground(pos, d):
    """(lon [deg], lat [deg], hit) of the first crossing of the rays with the ellipsoid."""
    w = np.array([1.0 / A, 1.0 / A, 1.0 / B])
    qa = np.sum((d * w) ** 2, -1)
    qb = 2.0 * np.sum(pos * d * w * w, -1)
    qc = np.sum((pos * w) ** 2, -1) - 1.0
    disc = qb * qb - 4.0 * qa * qc
    hit = (disc >= 0.0) & (qb < 0.0)
    s = (-qb - np.sqrt(np.where(hit, disc, 0.0))) / (2.0 * qa)
    g = pos + s[..., None] * d
    x, y, z = g[..., 0], g[..., 1], g[..., 2]
    rho = np.hypot(x, y)
    lat = np.arctan2(z, rho)
    for _ in range(8):  # Bowring: lat = atan2(z + e2 N sin(lat), rho)
        n = A / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
        lat = np.arctan2(z + E2 * n * np.sin(lat), rho)
    return np.degrees(np.arctan2(y, x)), np.degrees(lat), hit


def edges(pos, vel, roll_deg: float, fov_deg: float, pitch_deg: float = 0.0):
    """(inner [n, 2], outer [n, 2], hit [n]) edge points (lon, lat) [deg] of a strip."""
    sgn = -1.0 if roll_deg < 0 else 1.0
    out = []
    for look in (sgn * (abs(roll_deg) - fov_deg / 2), sgn * (abs(roll_deg) + fov_deg / 2)):
        lon, lat, hit = ground(np.atleast_2d(pos), look_directions(pos, vel, look, pitch_deg))
        out.append((np.stack([lon, lat], -1), hit))
    return out[0][0], out[1][0], out[0][1] & out[1][1]


def covered(inner, outer, lon, lat) -> np.ndarray:
    """Sorted indices of the samples inside or on a quad of the strip (shapely)."""

    def unwrap(x):
        return x + 360.0 * np.round((inner[0, 0] - x) / 360.0)

    ix, ox = unwrap(inner[:, 0]), unwrap(outer[:, 0])
    iy, oy = inner[:, 1], outer[:, 1]
    px, py = unwrap(np.asarray(lon, np.float64)), np.asarray(lat, np.float64)
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
    xs, ys = np.r_[ix, ox], np.r_[iy, oy]
    near = np.flatnonzero((px >= xs.min()) & (px <= xs.max()) & (py >= ys.min()) & (py <= ys.max()))
    if near.size == 0:
        return near.astype(np.int64)
    inside = shapely.intersects_xy(quads[:, None], px[near][None, :], py[near][None, :])
    return near[inside.any(0)].astype(np.int64)
