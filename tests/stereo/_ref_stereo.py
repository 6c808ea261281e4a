"""Shared data paths and reference helpers of the stereo_imaging tests."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from jaxspline.stereo.case import format_time
from jaxspline.stereo.check_geometry import Track, foot_point, steering_angles, target_ecef

ROOT = Path("/work/shared/data/stereo_imaging")
if not ROOT.is_dir():
    ROOT = Path(__file__).resolve().parents[3] / "shared/data/stereo_imaging"
DATA = ROOT / "train"
EXAMPLE = ROOT / "example_solution.json"
#: The example's first look: sat_cartosat_2e on rugged_060, 2026-04-21T03:52:18Z.
EXAMPLE_START_S = 82338.0


def aimed(case, sat_id: str, target_id: str, start_s: float, duration_s: float) -> dict:
    """An action whose boresight meets the target's foot point at its midpoint."""
    sat = next(s for s in case.satellites if s.id == sat_id)
    tgt = next(t for t in case.targets if t.id == target_id)
    pos, vel = Track(sat, case.start).ecef(np.array([start_s + duration_s / 2.0]))
    al, ac = steering_angles(pos[0], vel[0], foot_point(target_ecef(tgt)))
    return {
        "type": "observation",
        "satellite_id": sat_id,
        "target_id": target_id,
        "start_time": format_time(case.time_at(start_s)),
        "end_time": format_time(case.time_at(start_s + duration_s)),
        "off_nadir_along_deg": float(al),
        "off_nadir_across_deg": float(ac),
    }


def brute_force_hit(origin: np.ndarray, direction: np.ndarray, step_m: float = 200.0) -> float:
    """First crossing of the WGS84 ellipsoid along a ray, by marching and bisection."""
    a, b = 6378137.0, 6356752.314245179

    def f(s):
        p = origin + s * direction
        return (p[0] ** 2 + p[1] ** 2) / a**2 + p[2] ** 2 / b**2 - 1.0

    s = 0.0
    while f(s + step_m) > 0.0:
        s += step_m
        if s > 2e7:
            return math.nan
    lo, hi = s, s + step_m
    for _ in range(80):
        mid = (lo + hi) / 2.0
        lo, hi = (mid, hi) if f(mid) > 0.0 else (lo, mid)
    return (lo + hi) / 2.0


def noaa_solar_elevation_deg(lat_deg: float, lon_deg: float, unix_s: float) -> float:
    """Solar elevation from the NOAA / Spencer approximations (declination, equation of
    time, hour angle), geodetic horizon: an independent reference to ~0.2 deg."""
    day = unix_s / 86400.0 - 0.5  # days from 1970-01-01T12:00
    jc = (day + 2440588.0 - 2451545.0) / 36525.0
    l0 = math.radians((280.46646 + jc * (36000.76983 + jc * 0.0003032)) % 360.0)
    m = math.radians(357.52911 + jc * (35999.05029 - 0.0001537 * jc))
    e = 0.016708634 - jc * (0.000042037 + 0.0000001267 * jc)
    c = (
        math.sin(m) * (1.914602 - jc * (0.004817 + 0.000014 * jc))
        + math.sin(2 * m) * (0.019993 - 0.000101 * jc)
        + math.sin(3 * m) * 0.000289
    )
    lam = l0 + math.radians(c)
    eps = math.radians(23.439291 - 0.0130042 * jc)
    decl = math.asin(math.sin(eps) * math.sin(lam))
    y = math.tan(eps / 2) ** 2
    eot = 4 * math.degrees(
        y * math.sin(2 * l0)
        - 2 * e * math.sin(m)
        + 4 * e * y * math.sin(m) * math.cos(2 * l0)
        - 0.5 * y * y * math.sin(4 * l0)
        - 1.25 * e * e * math.sin(2 * m)
    )
    minutes = (unix_s % 86400.0) / 60.0
    ha = math.radians((minutes + eot + 4 * lon_deg) / 4.0 - 180.0)
    lat = math.radians(lat_deg)
    sin_el = math.sin(lat) * math.sin(decl) + math.cos(lat) * math.cos(decl) * math.cos(ha)
    return math.degrees(math.asin(sin_el))
