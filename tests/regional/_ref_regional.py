"""Test helpers for the regional checker: useful random actions and an independent geometry.

The reference geometry here shares nothing with ``jaxspline.regional.check_geometry``:
SGP4 through the pure-Python ``sgp4.model.Satrec`` path, the Earth angle from the IAU
2000 Earth rotation angle (GMST = ERA + precession polynomial, IERS 2010 eq. 5.32),
the Earth-fixed velocity by a 5-point finite difference of positions, the ellipsoid
crossing by bisection on the implicit surface, and Heikkinen's closed-form geodetic
latitude; coverage by shapely polygons.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from sgp4.earth_gravity import wgs84
from sgp4.io import twoline2rv
from sgp4.propagation import sgp4 as sgp4_py

from jaxspline.regional.case import Case, format_time
from jaxspline.regional.check_geometry import Track

A = 6378137.0
B = 6356752.314245179
STEP_FD = 1.0  # finite-difference step [s]
MAX_RANGE_M = 3.0e6  # a target farther than this is not in view


def useful_actions(case: Case, n: int, seed: int = 0, max_tries: int = 2000) -> list[dict]:
    """``n`` actions whose strips cross a region sample, each valid on its own rules.

    Each picks a random satellite and a random grid sample, finds an instant (10 s grid)
    where the sample is abeam within the sensor band, and centres a strip on it.
    Actions may conflict with one another (overlap, slew, duty).
    """
    rng = np.random.default_rng(seed)
    ts = np.arange(0.0, case.horizon_s, case.time_step_s)
    tracks = {}
    out = []
    g = case.grid
    for _ in range(max_tries):
        if len(out) >= n:
            break
        k = int(rng.integers(len(case.satellites)))
        sat = case.satellites[k]
        if k not in tracks:
            tr = Track(sat, case.start)
            tracks[k] = (tr, *tr.ecef(ts))
        tr, pos, vel = tracks[k]
        j = int(rng.integers(g.size))
        lat, lon = math.radians(g.lat_deg[j]), math.radians(g.lon_deg[j])
        e2 = 1 - (B / A) ** 2
        nn = A / math.sqrt(1 - e2 * math.sin(lat) ** 2)
        tgt = np.array(
            [nn * math.cos(lat) * math.cos(lon), nn * math.cos(lat) * math.sin(lon),
             nn * (1 - e2) * math.sin(lat)]
        )  # fmt: skip
        nadir = -pos / np.linalg.norm(pos, axis=1, keepdims=True)
        along = vel - np.sum(vel * nadir, 1, keepdims=True) * nadir
        along /= np.linalg.norm(along, axis=1, keepdims=True)
        across = np.cross(along, nadir)
        rel = tgt - pos
        a_al = np.sum(rel * along, 1)
        a_dn = np.sum(rel * nadir, 1)
        a_ac = np.degrees(np.arctan2(np.sum(rel * across, 1), a_dn))
        sen = sat.sensor
        lo, hi = sen.min_edge_deg + sen.fov_deg / 2, sen.max_edge_deg - sen.fov_deg / 2
        near = np.linalg.norm(rel, axis=1) < MAX_RANGE_M
        abeam = np.sign(a_al[:-1]) != np.sign(a_al[1:])
        band = (np.abs(a_ac) >= lo) & (np.abs(a_ac) <= hi)
        cand = np.flatnonzero(near[:-1] & abeam & band[:-1])
        if cand.size == 0:
            continue
        i = int(rng.choice(cand))
        steps = int(rng.integers(int(sen.min_duration_s // 10), int(sen.max_duration_s // 10) + 1))
        dur = steps * case.time_step_s
        start = ts[i] - (steps // 2) * case.time_step_s
        if start < 0 or start + dur > case.horizon_s:
            continue
        out.append(
            {
                "type": "strip_observation",
                "satellite_id": sat.id,
                "start_time": format_time(case.time_at(start)),
                "duration_s": int(dur),
                "roll_deg": round(float(a_ac[i]), 4),
            }
        )
    return out


def spaced(case: Case, actions: list[dict], gap_s: float = 60.0) -> list[dict]:
    """Keep actions in order while each satellite's kept actions stay ``gap_s`` apart."""
    from jaxspline.regional.case import parse_time

    kept: dict = {}
    out = []
    for a in actions:
        s = case.seconds(parse_time(a["start_time"]))
        e = s + a["duration_s"]
        mine = kept.setdefault(a["satellite_id"], [])
        if all(e + gap_s <= s2 or e2 + gap_s <= s for s2, e2 in mine):
            mine.append((s, e))
            out.append(a)
    return out


# ----------------------------------------------------------------------------- reference
TT_UTC_S = 69.184
AS2RAD = math.pi / 180.0 / 3600.0
BISECT_STEPS = 200
MARCH_M = 50e3
OMEGA_E = 7.292115146706979e-5


class RefTrack:
    """Earth-fixed states by pure-Python SGP4 and an ERA-based sidereal angle."""

    def __init__(self, sat, start):
        self.rec = twoline2rv(sat.tle1, sat.tle2, wgs84)
        self.t0 = start.timestamp()

    def _gmst(self, unix: float) -> float:
        du = (unix / 86400.0 + 2440587.5) - 2451545.0
        era = 2 * math.pi * ((0.7790572732640 + 1.00273781191135448 * du) % 1.0)
        t = (du + TT_UTC_S / 86400.0) / 36525.0
        poly = 0.014506 + 4612.156534 * t + 1.3915817 * t**2 - 0.00000044 * t**3
        return (era + poly * AS2RAD) % (2 * math.pi)

    def position(self, seconds: float) -> np.ndarray:
        unix = self.t0 + seconds
        jd = unix / 86400.0 + 2440587.5
        r, _ = sgp4_py(self.rec, (jd - self.rec.jdsatepoch) * 1440.0)
        g = self._gmst(unix)
        c, s_ = math.cos(g), math.sin(g)
        x, y, z = (1e3 * v for v in r)
        return np.array([c * x + s_ * y, -s_ * x + c * y, z])

    def state(self, seconds: float):
        h = STEP_FD
        p = [self.position(seconds + k * h) for k in (-2, -1, 0, 1, 2)]
        v = (p[0] - 8 * p[1] + 8 * p[3] - p[4]) / (12 * h)
        return p[2], v


def ref_direction(pos, vel, angle_deg):
    nadir = -pos / np.linalg.norm(pos)
    along = vel - np.dot(vel, nadir) * nadir
    along /= np.linalg.norm(along)
    across = np.cross(along, nadir)
    across /= np.linalg.norm(across)
    d = nadir + math.tan(math.radians(angle_deg)) * across
    return d / np.linalg.norm(d)


def _implicit(p):
    return (p[0] ** 2 + p[1] ** 2) / A**2 + p[2] ** 2 / B**2 - 1.0


def ref_hit(o, d):
    """First crossing of the ray with the ellipsoid by marching then bisection (None: miss)."""
    lo = 0.0
    hi = MARCH_M
    while _implicit(o + hi * d) > 0:
        lo, hi = hi, hi + MARCH_M
        if hi > 2 * np.linalg.norm(o):
            return None
    for _ in range(BISECT_STEPS):
        mid = 0.5 * (lo + hi)
        if _implicit(o + mid * d) > 0:
            lo = mid
        else:
            hi = mid
    return o + 0.5 * (lo + hi) * d


def heikkinen(p):
    """Geodetic (lon, lat) [deg], Heikkinen's closed form."""
    x, y, z = p
    e2 = 1 - (B / A) ** 2
    ep2 = (A**2 - B**2) / B**2
    rho = math.hypot(x, y)
    f = 54 * B**2 * z**2
    g = rho**2 + (1 - e2) * z**2 - e2 * (A**2 - B**2)
    c = e2**2 * f * rho**2 / g**3
    s = (1 + c + math.sqrt(c * c + 2 * c)) ** (1 / 3)
    k = s + 1 + 1 / s
    pp = f / (3 * k**2 * g**2)
    q = math.sqrt(1 + 2 * e2**2 * pp)
    r0 = -pp * e2 * rho / (1 + q) + math.sqrt(
        A**2 / 2 * (1 + 1 / q) - pp * (1 - e2) * z**2 / (q * (1 + q)) - pp * rho**2 / 2
    )
    v = math.sqrt((rho - e2 * r0) ** 2 + (1 - e2) * z**2)
    z0 = B**2 * z / (A * v)
    return math.degrees(math.atan2(y, x)), math.degrees(math.atan((z + ep2 * z0) / rho))


def ref_quads(case: Case, action: dict):
    """Shapely quads of one action by the reference geometry (None if a ray misses)."""
    from jaxspline.regional.case import parse_time

    sat = next(s for s in case.satellites if s.id == action["satellite_id"])
    tr = RefTrack(sat, case.start)
    t0 = case.seconds(parse_time(action["start_time"]))
    dur, roll, f = action["duration_s"], action["roll_deg"], sat.sensor.fov_deg
    inner = math.copysign(abs(roll) - f / 2, roll)
    outer = math.copysign(abs(roll) + f / 2, roll)
    times = list(np.arange(0.0, dur, case.sample_step_s)) + [float(dur)]
    edges = []
    for t in times:
        pos, vel = tr.state(t0 + t)
        pair = [ref_hit(pos, ref_direction(pos, vel, a)) for a in (inner, outer)]
        if any(h is None for h in pair):
            return None
        edges.append([heikkinen(h) for h in pair])
    return [
        shapely.Polygon([edges[i][0], edges[i][1], edges[i + 1][1], edges[i + 1][0]])
        for i in range(len(edges) - 1)
    ]


def ref_covered(case: Case, actions: list[dict]) -> tuple[np.ndarray, list]:
    """Covered sample mask by shapely ``covers`` over the reference quads, and the quads."""
    g = case.grid
    pts = shapely.points(g.lon_deg, g.lat_deg)
    covered = np.zeros(g.size, dtype=bool)
    polys = []
    for a in actions:
        quads = ref_quads(case, a)
        for q in quads or []:
            polys.append(q)
            x0, y0, x1, y1 = q.bounds
            idx = np.flatnonzero(
                (g.lon_deg >= x0) & (g.lon_deg <= x1) & (g.lat_deg >= y0) & (g.lat_deg <= y1)
            )
            covered[idx] |= shapely.covers(q, pts[idx])
    return covered, polys
