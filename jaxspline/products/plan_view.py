"""What the plan page draws, as JSON: the ``"view"`` section of ``plan.json``.

:func:`view_data` turns a :class:`jaxspline.planner.result.PlanResult` into plain lists
(degrees, seconds from the epoch, rounded) so that the page (:mod:`jaxspline.products.plan_html`)
is rebuilt from ``plan.json`` alone, without the scenario or a re-plan
(``jaxspline view plan.json``):

* ``satellites``: name, maneuver model, colour (:data:`jaxspline.products.czml.SATELLITE_COLORS`)
  and swath of each satellite;
* ``tracks``: sub-satellite points every :data:`_TRACK_STEP_S` seconds
  (:func:`jaxspline.products.czml.satellite_tracks`), ``null`` where the orbit table is unusable;
* ``targets``: name, kind, position and priority of every target;
* ``strips``: the centreline of every strip target;
* ``observations``: per planned observation (the order of ``plan.json``'s
  ``observations``) the off-nadir angle of the line of sight at mid-imaging and the
  sensor footprint of a strip, its swept ground (:func:`jaxspline.geometry.ground.footprint_lonlat`,
  an area strip's the ring of its edge points, ``PlanResult.footprints``; ``null`` for a
  point, whose footprint is a disc as wide as the swath, :func:`disc`, as in the CZML
  export);
* ``areas``: the GeoJSON geometry, the priority and the samples (covered or not) of
  every area target;
* ``battery``: the planned battery level of every powered satellite;
* ``stereo`` (only when the scenario has stereo targets; absent otherwise): per stereo
  request its target's name and position, the product the plan collects
  (``report["stereo"]``: ``"pair"``, ``"tri"`` or ``null``, its candidates, quality,
  convergence and overlap) and the product's ``looks`` as indices of ``observations``
  in time order (the report names them by option ids, which the plan does not keep:
  :func:`_look_indices`).

The off-nadir angle is ``atan2(|d x n|, d . n)`` between the line of sight
``d = g - r`` (aim point ``g``, satellite ``r``, both Earth-fixed) and the geocentric
nadir ``n = -r``, the definition of :func:`jaxspline.geometry.pointing.off_nadir`;
the aim point at mid-imaging is the target itself, or a strip's midpoint (strips are
scanned at constant ground speed).
"""

from __future__ import annotations

import itertools
import math

import jax
import numpy as np

from jaxspline.base.elements import geodetic_to_ecef, gmst
from jaxspline.geometry.frames import (
    angle_between,
    earth_rotation_angle,
    ecef_to_geodetic,
    teme_to_ecef,
)
from jaxspline.geometry.ground import FOOTPRINT_STEP_M, footprint_lonlat, strip_centerline
from jaxspline.geometry.orbit import orbit_position, tabulate_orbits
from jaxspline.geometry.routes import KIND_NAMES, STRIP
from jaxspline.products.czml import SATELLITE_COLORS, satellite_tracks

__all__ = ["disc", "view_data"]

_VIEW_VERSION = 2  # bumped when the layout of the "view" section changes
_TRACK_STEP_S = 30.0  # ground-track sample step [s]
DISC_SIDES = 24  # polygon sides of a point target's footprint disc
DEG_DECIMALS = 4  # longitudes / latitudes rounded to ~10 m
TIME_DECIMALS = 3  # seconds rounded to milliseconds
VALUE_DECIMALS = 3  # battery levels [Wh], angles [deg]
_R_MEAN = 6371008.8  # mean Earth radius [m]: angular size of a footprint disc

# one XLA program per table shape (eager dispatch would compile every primitive)
_orbit_position = jax.jit(orbit_position)


def _round(x, decimals: int) -> list:
    """Rounded floats of an array as a list, non-finite values as None."""
    a = np.round(np.asarray(x, np.float64), decimals)
    return [float(v) if math.isfinite(v) else None for v in a.ravel()]


def _wrap_deg(lon_deg):
    """Longitudes [deg] wrapped into [-180, 180)."""
    return (np.asarray(lon_deg, np.float64) + 180.0) % 360.0 - 180.0


def _lonlat(r_ecef):
    """(lon, lat) [deg] of Earth-fixed points [..., 3], lon in [-180, 180)."""
    lat, lon, _ = ecef_to_geodetic(np.asarray(r_ecef, np.float64))
    return _wrap_deg(np.degrees(lon)), np.degrees(lat)


def disc(lon_deg: float, lat_deg: float, radius_m: float):
    """A point target's footprint: the ring at ``radius_m`` around it.

    Spherical destination formula on a sphere of the mean Earth radius, ``b = radius / R``:
    ``lat2 = asin(sin(lat) cos(b) + cos(lat) sin(b) cos(th))``,
    ``lon2 = lon + atan2(sin(th) sin(b) cos(lat), cos(b) - sin(lat) sin(lat2))``.

    Args:
      lon_deg, lat_deg: centre [deg].
      radius_m: ring radius [m] (half the swath).
    Returns:
      (lon [deg], lat [deg]), float [DISC_SIDES + 1] each, the ring closed.
    """
    b = radius_m / _R_MEAN
    th = np.linspace(0.0, 2.0 * math.pi, DISC_SIDES + 1)
    la, lo = math.radians(lat_deg), math.radians(lon_deg)
    lat2 = np.arcsin(np.sin(la) * np.cos(b) + np.cos(la) * np.sin(b) * np.cos(th))
    lon2 = lo + np.arctan2(
        np.sin(th) * np.sin(b) * np.cos(la), np.cos(b) - np.sin(la) * np.sin(lat2)
    )
    return np.degrees(lon2), np.degrees(lat2)


def _aim_points(tg, r):
    """Earth-fixed aim points [K, 3] [m] at mid-imaging of targets r [K] (strips: midpoint)."""
    g = geodetic_to_ecef(tg.lat[r], tg.lon[r], tg.alt[r])
    strip = tg.kind[r] == STRIP
    if strip.any():
        s = r[strip]
        u, _, rad = strip_centerline(
            tg.lat[s], tg.lon[s], tg.azimuth[s], tg.length[s], 3, tg.alt[s]
        )
        g[strip] = u[:, 1] * rad[:, None]
    return g


def _mid_positions(sc, obs) -> np.ndarray:
    """Earth-fixed satellite positions [K, 3] [m] of every observation at mid-imaging."""
    if len(obs) == 0:
        return np.zeros((0, 3))
    mid = 0.5 * (np.asarray(obs.start, np.float64) + np.asarray(obs.end, np.float64))
    sat = np.asarray(obs.sat, np.int64)
    with jax.enable_x64(True):  # metre-level positions need float64 (global config untouched)
        table = tabulate_orbits(
            [s.orbit for s in sc.satellites], sc.epoch_jd, sc.duration, sc.planner.geometry_step
        )
        r_teme = np.asarray(_orbit_position(table.orbit, mid, sat=sat), np.float64)
    return teme_to_ecef(r_teme, earth_rotation_angle(float(gmst(sc.epoch_jd)), mid))


def _off_nadir_deg(sc, obs, r) -> np.ndarray:
    """Off-nadir angle [deg] of every observation at mid-imaging (module docstring), the
    satellites at ``r`` [K, 3] (:func:`_mid_positions`)."""
    if len(obs) == 0:
        return np.zeros(0)
    g = _aim_points(sc.targets, np.asarray(obs.target, np.int64))
    off = np.degrees(angle_between(g - r, -r))
    held = np.isfinite(obs.roll)  # an area strip or a look: the angle of its held offset
    roll, pitch = (np.where(held, x, 0.0) for x in (obs.roll, obs.pitch))
    return np.where(held, np.degrees(np.arccos(np.cos(roll) * np.cos(pitch))), off)


def _tracks(sc) -> dict:
    t, r, ok = satellite_tracks(sc, _TRACK_STEP_S)
    lon, lat = _lonlat(r)
    return {
        "step_s": _TRACK_STEP_S,
        "t_s": _round(t, TIME_DECIMALS),
        "lon_deg": [_round(np.where(ok[k], lon[k], np.nan), DEG_DECIMALS) for k in range(len(r))],
        "lat_deg": [_round(np.where(ok[k], lat[k], np.nan), DEG_DECIMALS) for k in range(len(r))],
    }


def _strips(tg) -> list[dict]:
    out = []
    for r in np.flatnonzero(tg.kind == STRIP):
        n = max(2, math.ceil(float(tg.length[r]) / FOOTPRINT_STEP_M) + 1)
        u, _, rad = strip_centerline(
            tg.lat[r], tg.lon[r], tg.azimuth[r], tg.length[r], n, tg.alt[r]
        )
        lon, lat = _lonlat(u * rad)
        out.append(
            {
                "target": int(r),
                "lon_deg": _round(lon, DEG_DECIMALS),
                "lat_deg": _round(lat, DEG_DECIMALS),
            }
        )
    return out


def _footprints(result) -> list[dict | None]:
    sc, obs = result.scenario, result.observations
    tg = sc.targets
    out = []
    for i in range(len(obs)):
        k, j = int(obs.sat[i]), int(obs.target[i])
        swath = float(sc.satellites[k].swath)
        if result.footprints and result.footprints[i] is not None:  # an area strip
            lon, lat = result.footprints[i]
        elif int(tg.kind[j]) == STRIP:
            lon, lat = footprint_lonlat(tg.lat[j], tg.lon[j], tg.azimuth[j], tg.length[j],
                                        swath, tg.alt[j])  # fmt: skip
        else:
            out.append(None)
            continue
        lon = _wrap_deg(lon)
        out.append({"lon_deg": _round(lon, DEG_DECIMALS), "lat_deg": _round(lat, DEG_DECIMALS)})
    return out


def view_data(result) -> dict:
    """The ``"view"`` section of ``plan.json`` (module docstring), JSON-ready.

    Args:
      result: :class:`jaxspline.planner.result.PlanResult`.
    Returns:
      dict of lists, strings and numbers.
    """
    sc = result.scenario
    obs = result.observations
    tg = sc.targets
    lon = _wrap_deg(np.degrees(tg.lon))
    r = _mid_positions(sc, obs)
    view = {
        "version": _VIEW_VERSION,
        "epoch_utc": sc.epoch.strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
        "duration_s": float(sc.duration),
        "satellites": [
            {
                "name": s.name,
                "model": s.model,
                "color": SATELLITE_COLORS[k % len(SATELLITE_COLORS)],
                "swath_m": float(s.swath),
            }
            for k, s in enumerate(sc.satellites)
        ],
        "tracks": _tracks(sc),
        "targets": {
            "name": [str(n) for n in tg.name],
            "kind": [KIND_NAMES[int(k)] for k in tg.kind],
            "lon_deg": _round(lon, DEG_DECIMALS),
            "lat_deg": _round(np.degrees(tg.lat), DEG_DECIMALS),
            "value": [float(v) for v in tg.value],
        },
        "strips": _strips(tg),
        "observations": {
            "off_nadir_deg": _round(_off_nadir_deg(sc, obs, r), VALUE_DECIMALS),
            "footprint": _footprints(result),
        },
        "areas": [_area_view(result, i, a) for i, a in enumerate(sc.areas)],
        "battery": {
            name: {"t_s": _round(t, TIME_DECIMALS), "level_wh": _round(level, VALUE_DECIMALS)}
            for name, (t, level) in (result.battery or {}).items()
        },
    }
    if sc.stereo:  # only then: the view of other plans stays as it was
        view["stereo"] = _stereo_view(result, r)
    return view


def _area_view(result, i: int, a) -> dict:
    """An area of the view: name, priority, polygon (None when the scenario gave only
    samples) and its samples (``lon_deg``, ``lat_deg``, ``covered`` 0/1 by the plan)."""
    value = float(result.scenario.targets.value[a.target])
    out = {"name": a.name, "value": value, "geometry": a.geometry}
    if result.areas:
        smp = result.areas[i]
        out["samples"] = {
            "lon_deg": _round(smp["lon_deg"], DEG_DECIMALS),
            "lat_deg": _round(smp["lat_deg"], DEG_DECIMALS),
            "covered": [int(c) for c in smp["covered"]],
        }
    return out


def _stereo_view(result, r) -> list[dict]:
    """Per stereo request (``sc.stereo`` order) its target, position and product
    (``report["stereo"]``), the product's looks as observation indices (module docstring).

    Args:
      result: PlanResult; r: float [K, 3], the satellites at mid-imaging (:func:`_mid_positions`).
    """
    sc, obs = result.scenario, result.observations
    tg = sc.targets
    report = result.report.get("stereo") or []
    out = []
    for k, req in enumerate(sc.stereo):
        t = int(req.target)
        rep = report[k] if k < len(report) else {}
        g = geodetic_to_ecef(tg.lat[t], tg.lon[t], tg.alt[t])
        conv = rep.get("convergence_deg")
        looks = _look_indices(obs, r, t, len(rep.get("looks") or []), g, conv)
        out.append(
            {
                "target": str(tg.name[t]),
                "lon_deg": _round(_wrap_deg(math.degrees(float(tg.lon[t]))), DEG_DECIMALS)[0],
                "lat_deg": _round(math.degrees(float(tg.lat[t])), DEG_DECIMALS)[0],
                "product": rep.get("product"),
                "candidates": rep.get("candidates"),
                "quality": rep.get("quality"),
                "convergence_deg": conv,
                "overlap": rep.get("overlap"),
                "looks": looks,
            }
        )
    return out


def _look_indices(obs, r, t: int, n: int, g, conv_deg) -> list[int]:
    """Observation indices (time order) of the ``n`` looks of target ``t``'s product.

    The report names a product's looks by option ids, which the plan does not keep; its
    looks are observations of the target with a held roll and pitch. When the plan holds
    more such looks than ``n``, the ``n`` whose best pair's convergence (the angle at the
    target ``g`` between the satellites ``r`` at mid-imaging,
    :mod:`jaxspline.screen.stereo_products`) is nearest the report's ``conv_deg`` are
    taken, the shortest span of time first on a tie."""
    mine = np.flatnonzero((np.asarray(obs.target) == t) & np.isfinite(obs.roll))
    mine = mine[np.argsort(np.asarray(obs.start)[mine], kind="stable")]
    if n == 0 or len(mine) <= n:
        return [int(i) for i in mine] if n else []

    def miss(sub):
        pairs = itertools.combinations(sub, 2)
        conv = [math.degrees(float(angle_between(r[i] - g, r[j] - g))) for i, j in pairs]
        err = min(abs(c - conv_deg) for c in conv) if conv_deg is not None else 0.0
        return (round(err, 3), float(obs.end[sub[-1]] - obs.start[sub[0]]))

    best = min(itertools.combinations(mine.tolist(), n), key=miss)
    return [int(i) for i in best]
