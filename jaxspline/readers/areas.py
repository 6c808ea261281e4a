"""Area targets: GeoJSON polygons cut into strips along the ground tracks, and their coverage.

An ``[[areas]]`` table of a scenario file (schema: :mod:`jaxspline.readers.scenario`, read by
:mod:`jaxspline.readers.area_files`) names a polygon; :func:`cut_areas` turns it into ordinary
strip targets, so the planner, the
checker and every output handle them unchanged, and :func:`area_coverage` reports after
planning which fraction of each polygon the planned strips cover.

An area's ``objective`` picks how its strips are chosen: ``"coverage"`` (the default)
by unique coverage of a sample grid over the cuttings' directions
(:mod:`jaxspline.readers.coverage_strips`, each strip worth its marginal covered share),
``"strips"`` by the cutting below. Both share steps 1 and 2.

Cutting (numpy + shapely, at load time):

1. **Passes.** The satellites whose sensor the area accepts are tabulated as the planner
   does (:func:`jaxspline.readers.mission.orbit_scene`); every visibility window of the
   polygon's centre and vertices (:func:`jaxspline.geometry.windows.visibility_windows_all`,
   off-nadir limit minus margin, within the area's window) is merged per satellite into
   passes. A pass counts only if the Sun is high enough at the centre at closest approach
   when the planner has ``sun_elevation_min``.
2. **Cuttings.** At the knot of closest approach the ground track's direction of travel
   (:func:`jaxspline.geometry.ground.ground_track`) is moved to the area's centre
   (projected on its tangent plane); passes whose track axes (mod 180 deg) lie within
   :data:`MERGE_DEG` of each other share one cutting along their mean axis.
3. **Strips.** In the gnomonic plane about the centre (great circles are straight lines,
   so a strip of the planner is a segment, and ground distances map to plane distances
   at least as long) the polygon is cut into bands ``swath`` wide across the cutting
   direction, centred on the polygon's cross-track extent; each connected along-track
   run of a band becomes one strip (split into equal pieces no longer than
   ``max_length_km``, and at least :data:`MIN_STRIP_M` long), from its first to its last
   point along the band's centre line. The strip's imaged footprint (``swath`` wide)
   then contains the band's part of the polygon. Each strip is a ``kind = strip``
   target (:func:`jaxspline.geometry.ground.strip_between` inverts the planner's strip
   model exactly) whose value is the area's priority times its share of the polygon's
   area (in the plane), so the strips of one cutting are worth the priority together.
   Cuttings of different directions overlap on the ground; each is worth the whole
   priority, so a plan may collect more than an area's priority when it images the same
   ground along two directions (the coverage report counts the union).

Coverage (:func:`area_coverage`): the footprint of every planned strip of an area is its
centre line (:func:`jaxspline.geometry.ground.strip_centerline`) widened by the imaging
satellite's swath (:func:`jaxspline.geometry.ground.strip_footprint`, a polygon every
:data:`FOOTPRINT_STEP_M` along the strip); the union of the footprints intersected with
the polygon, over the polygon's area, both in the Lambert azimuthal equal-area
projection about the centre (:func:`jaxspline.geometry.ground.equal_area`, areas exact on
the sphere), is the covered fraction. GeoJSON edges are straight in longitude /
latitude (RFC 7946 section 3.1.1): polygons are densified every :data:`DENSIFY_DEG`
before they are projected.
"""

from __future__ import annotations

import dataclasses
import json
import math

import jax
import numpy as np
import shapely
from shapely.geometry import Polygon, box, mapping, shape

from jaxspline.geometry.frames import (
    earth_rotation_angle,
    ecef_to_geodetic,
    geodetic_to_ecef,
    jd_split,
    rot_z,
    sun_direction,
    sun_elevation,
    teme_to_ecef,
)
from jaxspline.geometry.ground import (
    equal_area,
    gnomonic,
    gnomonic_inverse,
    ground_track,
    local_axes,
    strip_between,
    strip_footprint,
    surface_point,
    unit_vectors,
)
from jaxspline.geometry.windows import visibility_windows_all
from jaxspline.readers.area_files import DENSIFY_DEG, MIN_STRIP_M, AreaSpec, polygon_center
from jaxspline.readers.coverage_strips import area_grid, covered_samples, select_strips
from jaxspline.readers.mission import STRIP, Area, Scenario, Targets, make_targets, orbit_scene

__all__ = [
    "FOOTPRINT_STEP_M",
    "MERGE_DEG",
    "area_coverage",
    "coverage_line",
    "cut_areas",
    "footprint_lonlat",
    "sample_cover",
]

MERGE_DEG = 5.0  # passes whose track axes differ by at most this share a cutting [deg]
FOOTPRINT_STEP_M = 2000.0  # footprint polygons get a point on each side every this [m]
_MAX_REFERENCE_POINTS = 64  # polygon vertices whose visibility windows give the passes
_AREA_TOL = 1e-9  # band pieces below this share of the polygon's area are dropped


# --- cutting ---


def _passes(sc: Scenario, spec: AreaSpec, table, scene, center) -> list[tuple[int, int]]:
    """(satellite, knot of closest approach) of every pass over the area (see module doc)."""
    sats = sc.satellites
    pc = sc.planner
    allowed_sat = np.array([spec.sensor in ("", s.sensor) for s in sats])
    xy = np.asarray(shapely.get_coordinates(spec.polygon))
    step = max(1, -(-len(xy) // _MAX_REFERENCE_POINTS))
    pts = np.vstack(
        [
            surface_point(center),
            geodetic_to_ecef(np.radians(xy[::step, 1]), np.radians(xy[::step, 0]), 0.0),
        ]
    )
    n = len(pts)
    limit = np.array([s.off_nadir_max for s in sats]) - pc.margins.off_nadir
    w = visibility_windows_all(
        scene,
        table.ok,
        pts,
        np.repeat(allowed_sat[:, None], n, 1),
        limit,
        pc.margins.horizon,
        np.full(n, spec.t_lo),
        np.full(n, spec.t_hi),
        sc.duration,
    )
    tk = np.asarray(table.orbit.t)
    r = np.asarray(table.orbit.r)
    out = []
    for s in np.unique(w.sat):
        m = w.sat == s
        lo, hi = w.lo[m], w.hi[m]
        order = np.argsort(lo)
        lo, hi = lo[order], hi[order]
        runs, cur = [], [lo[0], hi[0]]
        for a, b in zip(lo[1:], hi[1:], strict=True):
            if a <= cur[1] + 2.0 * pc.geometry_step:
                cur[1] = max(cur[1], b)
            else:
                runs.append(cur)
                cur = [a, b]
        runs.append(cur)
        for a, b in runs:
            ks = np.flatnonzero((tk >= a - 1e-9) & (tk <= b + 1e-9))
            theta = earth_rotation_angle(float(scene.gmst0), tk[ks])
            u = unit_vectors(rot_z(theta, r[s, ks]))
            k = int(ks[np.argmax(u @ center)])
            if pc.sun_elevation_min is not None:
                sun = rot_z(
                    earth_rotation_angle(float(scene.gmst0), tk[k]),
                    sun_direction(*jd_split(sc.epoch_jd, tk[k])),
                )
                la, lo_, _ = ecef_to_geodetic(surface_point(center))
                if sun_elevation(la, lo_, sun) < pc.sun_elevation_min:
                    continue
            out.append((int(s), k))
    return out


def _cuttings(axes: np.ndarray) -> list[tuple[float, int]]:
    """Group track axes [rad, mod pi] within MERGE_DEG: (mean axis in [0, pi), count)."""
    if axes.size == 0:
        return []
    tol = math.radians(MERGE_DEG)
    a = np.sort(np.mod(axes, math.pi))
    groups, cur = [], [a[0]]
    for x in a[1:]:
        if x - cur[0] <= tol:
            cur.append(x)
        else:
            groups.append(cur)
            cur = [x]
    groups.append(cur)
    if len(groups) > 1 and groups[0][-1] + math.pi - groups[-1][0] <= tol:  # wrap at pi
        groups[0] = [x - math.pi for x in groups[-1]] + groups[0]
        groups.pop()
    out = []
    for g in groups:
        g = np.asarray(g)
        mean = 0.5 * math.atan2(np.mean(np.sin(2 * g)), np.mean(np.cos(2 * g)))
        out.append((float(np.mod(mean, math.pi)), int(g.size)))
    return out


def _to_plane(geom, center, radius, azimuth):
    """The polygon in (along, cross) metres of the gnomonic plane, along = ``azimuth``."""
    e_ax, n_ax = math.sin(azimuth), math.cos(azimuth)

    def f(xy):
        u = unit_vectors(geodetic_to_ecef(np.radians(xy[:, 1]), np.radians(xy[:, 0]), 0.0))
        p = radius * gnomonic(u, center)
        return np.stack([p[:, 0] * e_ax + p[:, 1] * n_ax, p[:, 0] * n_ax - p[:, 1] * e_ax], -1)

    return shapely.transform(shapely.segmentize(geom, DENSIFY_DEG), f)


def _bands(plane, swath: float, max_length: float) -> list[tuple[float, float, float, float]]:
    """(along0, along1, cross, share) of every strip of a polygon in the cutting plane."""
    x0, y0, x1, y1 = plane.bounds
    total = plane.area
    n = max(1, math.ceil((y1 - y0) / swath - 1e-9))
    out = []
    for k in range(n):
        c = 0.5 * (y0 + y1) + (k - 0.5 * (n - 1)) * swath
        band = box(x0 - 1.0, c - swath / 2, x1 + 1.0, c + swath / 2)
        piece = plane.intersection(band)
        parts = sorted(
            (g.bounds[0], g.bounds[2])
            for g in getattr(piece, "geoms", [piece])
            if g.area > _AREA_TOL * total
        )
        runs = []
        for a, b in parts:
            if runs and a <= runs[-1][1]:
                runs[-1][1] = max(runs[-1][1], b)
            else:
                runs.append([a, b])
        for a, b in runs:
            m = max(1, math.ceil((b - a) / max_length - 1e-9)) if math.isfinite(max_length) else 1
            for j in range(m):
                s0, s1 = a + j * (b - a) / m, a + (j + 1) * (b - a) / m
                share = piece.intersection(box(s0, c - swath / 2, s1, c + swath / 2)).area / total
                if share <= _AREA_TOL:
                    continue
                if s1 - s0 < MIN_STRIP_M:
                    mid = 0.5 * (s0 + s1)
                    s0, s1 = mid - MIN_STRIP_M / 2, mid + MIN_STRIP_M / 2
                out.append((s0, s1, c, share))
    return out


def _cut(spec: AreaSpec, center, azimuth: float):
    """Strips (lat, lon, azimuth, length [rad, m], share) of one cutting of an area."""
    radius = float(np.linalg.norm(surface_point(center)))
    strips = _bands(_to_plane(spec.polygon, center, radius, azimuth), spec.swath, spec.max_length)
    if not strips:
        return np.zeros((0, 5))
    s = np.asarray(strips)
    e_ax, n_ax = math.sin(azimuth), math.cos(azimuth)

    def plane_to_unit(along, cross):
        x = along * e_ax + cross * n_ax
        y = along * n_ax - cross * e_ax
        return gnomonic_inverse(np.stack([x, y], -1) / radius, center)

    lat, lon, az, length = strip_between(
        plane_to_unit(s[:, 0], s[:, 2]), plane_to_unit(s[:, 1], s[:, 2])
    )
    return np.stack([lat, lon, az, length, s[:, 3]], -1)


def _area_strips(spec: AreaSpec, center, cuts):
    """Strips of one area: (rows [K, 5] = lat, lon, azimuth [rad], length [m], share;
    cutting [K]; names [K]; extra :class:`Area` fields), by its objective."""
    if spec.objective == "coverage":
        grid = area_grid(spec.polygon, center, spec.grid)
        chosen = select_strips(grid, center, [a for a, _ in cuts], spec.swath, spec.max_length)
        rows = np.column_stack([chosen.strips, chosen.gain]).reshape(-1, 5)
        names = [f"{spec.name}/d{c}/c{k}" for k, c in enumerate(chosen.cutting)]
        extra = {
            "objective": "coverage",
            "sample_lonlat": np.column_stack([grid.lon_deg, grid.lat_deg]),
            "sample_weight": grid.weight,
            "candidates": chosen.candidates,
            "union": chosen.union,
        }
        return rows, chosen.cutting, names, extra
    parts = [(c, _cut(spec, center, az)) for c, (az, _) in enumerate(cuts)]
    rows = np.concatenate([st for _, st in parts] + [np.zeros((0, 5))], 0)
    cutting = np.concatenate([np.full(len(st), c, np.int64) for c, st in parts] + [[]])
    names = [f"{spec.name}/d{c}/s{k}" for c, st in parts for k in range(len(st))]
    return rows, cutting.astype(np.int64), names, {}


def cut_areas(sc: Scenario, specs) -> Scenario:
    """The scenario with every area cut into strip targets (appended) and its :class:`Area`.

    See the module docstring for the method. An area no satellite passes over gets no
    strips (its coverage is 0).

    Args:
      sc: Scenario without these areas.
      specs: list of :class:`AreaSpec`.
    Returns:
      Scenario whose ``targets`` end with the areas' strips (names ``<area>/d<c>/s<k>``:
      cutting c, strip k) and whose ``areas`` are the new :class:`Area` records.
    """
    if not specs:
        return sc
    with jax.enable_x64(True):  # metre-level orbits (the global setting is left alone)
        table, scene = orbit_scene(sc)
    tk = np.asarray(table.orbit.t)
    theta = earth_rotation_angle(float(scene.gmst0), tk)[None, :]
    r_e, v_e = teme_to_ecef(np.asarray(table.orbit.r), theta, np.asarray(table.orbit.v))
    _, u_dot = ground_track(r_e, v_e)
    targets, areas, n0 = sc.targets, list(sc.areas), len(sc.targets)
    for spec in specs:
        center = polygon_center(spec.polygon)
        e_ax, n_ax = local_axes(center)
        axes = []
        for s, k in _passes(sc, spec, table, scene, center):
            t_c = u_dot[s, k] - (u_dot[s, k] @ center) * center
            axes.append(math.atan2(float(t_c @ e_ax), float(t_c @ n_ax)))
        cuts = _cuttings(np.asarray(axes))
        st, cutting, names, extra = _area_strips(spec, center, cuts)
        lat, lon, az, length, share = (st[:, i] for i in range(5))
        k = len(lat)
        if k:
            new = make_targets(
                np.full(k, STRIP),
                lat,
                lon,
                length=length,
                azimuth=az,
                value=spec.value * np.asarray(share),
                t_lo=spec.t_lo,
                t_hi=spec.t_hi,
                sensor=spec.sensor,
                name=np.asarray(names, str),
            )
            targets = new if len(targets) == 0 else targets.concat(new)
        geometry = json.loads(json.dumps(mapping(spec.polygon)))
        areas.append(
            Area(
                name=spec.name,
                geometry=geometry,
                value=spec.value,
                swath=spec.swath,
                targets=np.arange(n0, n0 + k, dtype=np.int64),
                share=np.asarray(share, np.float64),
                cutting=np.asarray(cutting, np.int64),
                azimuth=np.asarray([a for a, _ in cuts], np.float64),
                passes=np.asarray([p for _, p in cuts], np.int64),
                **extra,
            )
        )
        n0 += k
    return dataclasses.replace(sc, targets=targets, areas=tuple(areas))


# --- coverage ---


def _footprint_units(tg: Targets, r: int, swath: float, upto: float = 1.0):
    """Footprint ring (unit vectors [n, 3]) of the first ``upto`` of strip ``r``, ``swath`` wide."""
    length = float(tg.length[r]) * upto
    samples = max(2, math.ceil(length / FOOTPRINT_STEP_M) + 1)
    return strip_footprint(
        tg.lat[r], tg.lon[r], tg.azimuth[r], length, swath, samples, alt=tg.alt[r]
    )


def footprint_lonlat(tg: Targets, r: int, swath: float, upto: float = 1.0):
    """Ground footprint of strip target ``r`` imaged ``swath`` metres wide, as a lon/lat ring.

    Args:
      tg: Targets.
      r: index of a strip target.
      swath: imaged width [m].
      upto: fraction of the strip from its start (0 < upto <= 1).
    Returns:
      (lon [deg], lat [deg]), float [n] each, the ring closed (first point repeated).
    """
    u = _footprint_units(tg, r, swath, upto)
    lat, lon, _ = ecef_to_geodetic(surface_point(u))
    lon, lat = np.degrees(lon), np.degrees(lat)
    return np.append(lon, lon[0]), np.append(lat, lat[0])


def area_coverage(result) -> list[dict]:
    """Covered fraction of every area of a plan (method: module docstring).

    Args:
      result: :class:`jaxspline.planner.result.PlanResult` of a scenario with areas.
    Returns:
      list of dict (JSON-ready), one per area: ``area``, ``priority``, ``swath_km``,
      ``area_km2``, ``covered_km2``, ``covered_fraction`` (0..1), ``strips`` and
      ``strips_planned``, ``value_planned`` (sum of the planned strips' values) and
      ``cuttings`` (per cutting: ``azimuth_deg``, ``passes``, ``strips``,
      ``strips_planned``).
    """
    sc = result.scenario
    tg = sc.targets
    obs = result.observations
    sat_of = {int(t): int(s) for t, s in zip(obs.target, obs.sat, strict=True)}
    out = []
    for a in sc.areas:
        geom = shape(a.geometry)
        center = polygon_center(geom)
        radius = float(np.linalg.norm(surface_point(center)))

        def project(xy, center=center, radius=radius):
            u = unit_vectors(geodetic_to_ecef(np.radians(xy[:, 1]), np.radians(xy[:, 0]), 0.0))
            return radius * equal_area(u, center)

        poly = shapely.transform(shapely.segmentize(geom, DENSIFY_DEG), project)
        idx = np.asarray(a.targets, np.int64)
        planned = np.array([int(r) in sat_of for r in idx], bool)
        feet = [
            Polygon(
                radius
                * equal_area(
                    _footprint_units(tg, int(r), sc.satellites[sat_of[int(r)]].swath), center
                )
            )
            for r in idx[planned]
        ]
        covered = shapely.union_all(feet).intersection(poly).area if feet else 0.0
        cut = np.asarray(a.cutting, np.int64)
        out.append(
            {
                "area": a.name,
                "objective": a.objective,
                "priority": float(a.value),
                "swath_km": a.swath / 1e3,
                "area_km2": poly.area / 1e6,
                "covered_km2": covered / 1e6,
                "covered_fraction": covered / poly.area,
                **_sample_coverage(result, a, covered / poly.area),
                "strips": int(idx.size),
                "strips_planned": int(planned.sum()),
                "value_planned": float(np.sum(tg.value[idx[planned]])),
                "cuttings": [
                    {
                        "azimuth_deg": math.degrees(float(az)),
                        "passes": int(p),
                        "strips": int(np.sum(cut == c)),
                        "strips_planned": int(np.sum(planned & (cut == c))),
                    }
                    for c, (az, p) in enumerate(zip(a.azimuth, a.passes, strict=True))
                ],
            }
        )
    return out


def sample_cover(result, a) -> np.ndarray:
    """Which coverage samples of area ``a`` the plan covers.

    Args:
      result: :class:`jaxspline.planner.result.PlanResult`.
      a: one of ``result.scenario.areas`` (``objective = "coverage"``).
    Returns:
      bool [N], per sample of ``a.sample_lonlat``
      (:func:`jaxspline.readers.coverage_strips.covered_samples` on the area's planned
      strips, each with its imaging satellite's swath).
    """
    sc, obs = result.scenario, result.observations
    sat_of = {int(t): int(s) for t, s in zip(obs.target, obs.sat, strict=True)}
    planned = np.array([int(r) for r in a.targets if int(r) in sat_of], np.int64)
    tg = sc.targets
    strips = np.stack([getattr(tg, f)[planned] for f in ("lat", "lon", "azimuth", "length")], -1)
    swaths = np.array([sc.satellites[sat_of[int(r)]].swath for r in planned], np.float64)
    lonlat = np.radians(np.asarray(a.sample_lonlat, np.float64))
    unit = unit_vectors(geodetic_to_ecef(lonlat[:, 1], lonlat[:, 0], 0.0))
    return covered_samples(unit, strips.reshape(-1, 4), swaths)


def _sample_coverage(result, a, polygon_fraction) -> dict:
    """The coverage report of an ``objective = "coverage"`` area ({} for cut strips):
    ``samples``, ``samples_covered``, ``covered_fraction`` (weighted share of the grid
    covered, :func:`sample_cover`; it replaces the polygon fraction),
    ``polygon_fraction`` (the polygon method's), ``bound`` (share covered by all
    candidates together) and ``candidates``."""
    if a.objective != "coverage":
        return {}
    hit = sample_cover(result, a)
    return {
        "samples": int(hit.size),
        "samples_covered": int(hit.sum()),
        "covered_fraction": float(np.sum(np.asarray(a.sample_weight)[hit])),
        "polygon_fraction": polygon_fraction,
        "bound": float(a.union),
        "candidates": int(a.candidates),
    }


def coverage_line(areas: list[dict], limit: int = 6) -> str:
    """One summary line of :func:`area_coverage` (the first ``limit`` areas, scenario order).

    Args:
      areas: list of dict from :func:`area_coverage`.
      limit: how many areas to name.
    Returns:
      str, e.g. ``2 areas covered: karst 63.2 % (5/9 strips), vipava 100.0 % (4/4)``.
    """
    parts = [
        f"{a['area']} {100 * a['covered_fraction']:.1f} % "
        f"({a['strips_planned']}/{a['strips']} strips)"
        for a in areas[:limit]
    ]
    more = f", ... ({len(areas) - limit} more)" if len(areas) > limit else ""
    return f"{len(areas)} area{'s' * (len(areas) != 1)} covered: " + ", ".join(parts) + more
