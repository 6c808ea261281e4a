"""The options of area targets: samples, passes, roll groups, covered rows, every strip window.

An area (:class:`jaxspline.readers.mission.Area`) is planned as its weighted samples; its
options are strips at a held roll (:func:`jaxspline.geometry.pointing.roll_params`) over
whole slots of the action grid, on every satellite whose sensor the area accepts,
whatever its maneuver model. This stage builds them in five steps:

1. **Samples**: the scenario's own, or a grid of the area's spacing over its polygon
   (:func:`jaxspline.geometry.area_grid.area_grid`); a sample's value is the area's
   priority times its weight.
2. **Tracks**: the planner's orbit table (SGP4 for TLEs) at its knots, rotated to the
   Earth-fixed frame (velocity relative to the rotating Earth).
3. **Groups** (:func:`jaxspline.geometry.area_passes.find_groups`): per satellite and
   area, the passes and, per pass, the rolls on the satellite's grid that can cover a
   sample, with the slots that span them; with a daylight rule only groups whose area
   centre sees the Sun high enough at the group's middle.
4. **Rows** (:func:`jaxspline.screen.coverage.coverage_slices`): per slot of each group
   the samples its quadrilaterals cover (groups whose rays miss the Earth are dropped).
5. **Options**: every window of every group, each length from the satellite's shortest
   to its longest strip, whose rows cover a sample and whose ephemeris is usable; their
   boundary states through the same aim-law kernels as every option
   (:func:`jaxspline.planner.opportunities.option_states`).

The satellite's field of view is its ``fov`` or, without one, its swath seen from its
mean altitude at nadir; its rolls lie inside its edge band (``edge_band``, the strip's
edges) and within its off-nadir limit (the boresight), less the planner's margin.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from shapely.geometry import shape

from jaxspline.base.elements import R_EARTH, geodetic_to_ecef
from jaxspline.geometry.area_grid import AreaGrid, area_grid
from jaxspline.geometry.area_passes import AreaSamples, Groups, StripSensor, find_groups
from jaxspline.geometry.frames import (
    earth_rotation_angle,
    rot_z,
    sun_direction,
    sun_elevation,
    teme_to_ecef,
)
from jaxspline.geometry.pointing import roll_params
from jaxspline.planner.opportunities import Opportunities, option_states
from jaxspline.readers.mission import Scenario
from jaxspline.screen.coverage import Candidates, coverage_slices
from jaxspline.screen.options import RouteOptions
from jaxspline.search.cover import CoverTable

__all__ = [
    "AreaOptions",
    "area_options",
    "cover_table",
    "earth_fixed_tracks",
    "merge_options",
    "strip_sensor",
]

_GRID_TOL = 1e-6  # [s] slack of times on the slot grid


class AreaOptions(NamedTuple):
    """What the area stage built (module docstring).

    Attributes:
      grids: per area its :class:`jaxspline.geometry.area_grid.AreaGrid`.
      groups: :class:`jaxspline.geometry.area_passes.Groups` (rows found for each).
      group_area: int64 [G], the area each group was found for.
      indptr, indices: CSR of the groups' slot rows (samples numbered area by area).
      opp: :class:`Opportunities` of the area options (unsorted).
      window: int64 [K, 3], per option its (group, first slot, end slot).
      fov_deg: float [S], each satellite's field of view of area strips [deg] (0: none).
    """

    grids: list
    groups: Groups
    group_area: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    opp: Opportunities
    window: np.ndarray
    fov_deg: np.ndarray

    def __len__(self) -> int:
        return int(self.window.shape[0])


def earth_fixed_tracks(sc: Scenario, table, scene):
    """The satellites' Earth-fixed states on the mesh ``k * geometry_step``, k = 0..K.

    Args:
      sc: Scenario; table: its OrbitTable (knots ``k step`` from k = -1); scene: its Scene.
    Returns:
      (pos [S, K+1, 3] [m], vel [S, K+1, 3] [m/s] relative to the rotating Earth, t [K+1] [s]).
    """
    step = sc.planner.geometry_step
    t = np.asarray(table.orbit.t)
    first = int(np.argmin(np.abs(t)))
    n = int(math.ceil(sc.duration / step - 1e-9)) + 1
    sl = slice(first, first + n)
    theta = earth_rotation_angle(float(scene.gmst0), t[sl])
    r = np.asarray(table.orbit.r)[:, sl]
    v = np.asarray(table.orbit.v)[:, sl]
    pos, vel = teme_to_ecef(r, theta[None, :], v)
    return pos, vel, t[sl]


def strip_sensor(sat, sc: Scenario, altitude: float, speed: float) -> StripSensor | None:
    """What a satellite's area strips may be (module docstring), None when none fits.

    Args:
      sat: Satellite; sc: Scenario (the planner's settings); altitude: mean altitude [m];
      speed: mean speed of its ground track [m/s] (the automatic pitch step).
    Returns:
      :class:`StripSensor` or None (no roll in the band, or no strip fits the slots).
    """
    pc = sc.planner
    fov = sat.fov if sat.fov is not None else 2.0 * math.atan(sat.swath / 2.0 / altitude)
    lo, hi = 0.0, float(sat.off_nadir_max) - pc.margins.off_nadir
    if sat.edge_band is not None:
        lo = max(lo, float(sat.edge_band[0]) + fov / 2.0)
        hi = min(hi, float(sat.edge_band[1]) - fov / 2.0)
    shortest, longest = (float(x) for x in sat.strip_duration)
    need = max(1, int(math.ceil(shortest / pc.time_step - 1e-9)))
    if hi < lo or int(math.floor(longest / pc.time_step + 1e-9)) < need:
        return None
    deg = math.degrees
    off = float(sat.off_nadir_max) - pc.margins.off_nadir
    pitches = (0.0,)
    if sat.maneuver.tracks_points:  # an agile satellite may also look ahead or back
        step = pc.area_pitch_step
        if step is None:  # the pitch that moves the imaged ground by one time step
            step = math.atan(speed * pc.time_step / altitude)
        n = int(math.floor(off / step + 1e-9))
        pitches = tuple(round(deg(k * step), 6) for k in range(-n, n + 1))
    return StripSensor(deg(fov), deg(lo), deg(hi), deg(pc.area_roll_step), need, pitches, deg(off))


def _grids(sc: Scenario) -> list:
    """Per area its samples: the scenario's, or a grid over its polygon."""
    out = []
    for a in sc.areas:
        if a.samples.shape[0]:
            smp = a.samples
            out.append(AreaGrid(smp[:, 0].copy(), smp[:, 1].copy(), smp[:, 2].copy(), 0.0))
        else:
            out.append(area_grid(shape(a.geometry), float(a.spacing)))
    return out


def _sun_ok(sc: Scenario, scene, grids, groups: Groups, group_area) -> np.ndarray:
    """bool [G]: the Sun stands at least ``sun_elevation_min`` over the area's centre at
    the middle of the group's slots (all True without a daylight rule)."""
    pc = sc.planner
    if pc.sun_elevation_min is None or len(groups) == 0:
        return np.ones(len(groups), bool)
    lat = np.array([np.radians(np.average(g.lat_deg, weights=g.weight)) for g in grids])
    lon = np.array([np.radians(np.average(g.lon_deg, weights=g.weight)) for g in grids])
    t = 0.5 * (groups.slot_lo + groups.slot_hi) * pc.time_step
    sun = rot_z(
        earth_rotation_angle(float(scene.gmst0), t), sun_direction(sc.epoch_jd + t / 86400.0)
    )
    return sun_elevation(lat[group_area], lon[group_area], sun) >= pc.sun_elevation_min


def _rows(pos, vel, sensors, groups: Groups, per: int, lon, lat, region):
    """Covered-sample rows of every (group, slot); returns (indptr, indices, bad [G])."""
    n = groups.slot_hi - groups.slot_lo
    gi = np.repeat(np.arange(len(groups)), n)
    slot = np.repeat(groups.slot_lo, n) + (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n))
    fov = np.array([0.0 if s is None else s.fov_deg for s in sensors])
    cands = Candidates(
        sat=groups.sat[gi].astype(np.int32),
        k0=(slot * per).astype(np.int32),
        n=np.full(slot.size, per + 1, np.int32),
        roll_deg=groups.roll_deg[gi],
        pitch_deg=groups.pitch_deg[gi],
    )
    res = coverage_slices(pos, vel, fov, cands, lon, lat, region)
    table = res.csr()
    bad = np.bincount(gi[~res.valid], minlength=len(groups)) > 0
    return table.indptr, table.indices, bad


def _keep_groups(groups: Groups, group_area, indptr, indices, keep):
    """The groups (and their rows) where ``keep`` holds."""
    n = groups.slot_hi - groups.slot_lo
    row0 = np.concatenate([[0], np.cumsum(n)[:-1]]).astype(np.int64)
    if keep.all():
        return groups, group_area, indptr, indices
    rows = np.concatenate(
        [np.arange(r, r + m) for r, m in zip(row0[keep], n[keep], strict=True)] or [[]]
    ).astype(np.int64)
    counts = np.diff(indptr)[rows]
    starts = np.repeat(indptr[rows] - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    indices = indices[starts + np.arange(int(counts.sum()))]
    indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    kept = Groups(*(x[keep] for x in groups[:5]), groups.n_passes)
    return kept, group_area[keep], indptr, indices


def _windows(sc: Scenario, groups: Groups, indptr, table) -> np.ndarray:
    """(group, a, b) of every strip window whose rows cover a sample (module docstring)."""
    pc = sc.planner
    counts = np.diff(indptr)
    n = groups.slot_hi - groups.slot_lo
    row0 = np.concatenate([[0], np.cumsum(n)[:-1]])
    cum = np.concatenate([[0], np.cumsum(counts)])
    out = []
    for g in range(len(groups)):
        sat = sc.satellites[int(groups.sat[g])]
        shortest, longest = sat.strip_duration
        need = max(1, int(math.ceil(shortest / pc.time_step - 1e-9)))
        most = int(math.floor(longest / pc.time_step + 1e-9))
        s0, m, r0 = int(groups.slot_lo[g]), int(n[g]), int(row0[g])
        for length in range(need, min(most, m) + 1):
            a = np.arange(0, m - length + 1)
            full = cum[r0 + a + length] - cum[r0 + a] > 0
            a = a[full]
            out.append(np.stack([np.full(a.size, g), s0 + a, s0 + a + length], -1))
    win = np.concatenate(out) if out else np.zeros((0, 3), np.int64)
    t0 = win[:, 1] * pc.time_step
    t1 = win[:, 2] * pc.time_step
    sat = groups.sat[win[:, 0]]
    ok = (t1 <= sc.duration + _GRID_TOL) & table.usable(sat, t0) & table.usable(sat, t1)
    return win[ok].astype(np.int64)


def _option_table(sc: Scenario, scene, groups: Groups, group_area, win) -> Opportunities:
    """The Opportunities rows of the windows: roll laws, boundary states (lines of sight
    in each model's frame)."""
    pc = sc.planner
    sats = sc.satellites
    g = win[:, 0]
    sat = groups.sat[g].astype(np.int64)
    tgt = np.array([sc.areas[int(a)].target for a in group_area], np.int64)[g]
    t0 = win[:, 1] * pc.time_step
    t1 = win[:, 2] * pc.time_step
    params = np.asarray(
        roll_params(np.radians(groups.roll_deg[g]), np.radians(groups.pitch_deg[g]))
    )
    per_ch = np.array([not s.maneuver.rest_to_rest for s in sats])
    o = option_states(sc, scene, sat, tgt, t0, t1, params, per_ch)
    earth = np.array([s.maneuver.los_frame == "earth_fixed" for s in sats])[sat]
    if earth.any():  # the model compares Earth-fixed lines of sight
        th0 = earth_rotation_angle(float(scene.gmst0), t0)
        th1 = earth_rotation_angle(float(scene.gmst0), t1)
        o = o._replace(
            start_los=np.where(earth[:, None], rot_z(th0, o.start_los), o.start_los),
            end_los=np.where(earth[:, None], rot_z(th1, o.end_los), o.end_los),
            start_nadir=np.where(earth[:, None], rot_z(th0, o.start_nadir), o.start_nadir),
        )
    return Opportunities(o, np.zeros(sat.size), params)


def area_options(sc: Scenario, table, scene) -> AreaOptions | None:
    """The area stage (module docstring).

    Args:
      sc: Scenario with areas; table: its OrbitTable; scene: its Scene.
    Returns:
      :class:`AreaOptions`, or None when the scenario has no areas.
    """
    if not sc.areas:
        return None
    pc = sc.planner
    grids = _grids(sc)
    pos, vel, _ = earth_fixed_tracks(sc, table, scene)
    rad = np.linalg.norm(pos, axis=-1)
    alt = rad.mean(axis=1) - R_EARTH
    ground = (np.linalg.norm(vel, axis=-1) * R_EARTH / rad).mean(axis=1)
    sensors = [
        strip_sensor(s, sc, float(h), float(v))
        for s, h, v in zip(sc.satellites, alt, ground, strict=True)
    ]
    tg = sc.targets
    areas = []
    for a, grid in zip(sc.areas, grids, strict=True):
        xyz = geodetic_to_ecef(np.radians(grid.lat_deg), np.radians(grid.lon_deg), 0.0)
        t_lo, t_hi = max(float(tg.t_lo[a.target]), 0.0), min(float(tg.t_hi[a.target]), sc.duration)
        sats = np.array([tg.sensor[a.target] in ("", s.sensor) for s in sc.satellites])
        lo = int(math.ceil(t_lo / pc.time_step - 1e-9))
        hi = int(math.floor(t_hi / pc.time_step + 1e-9))
        areas.append(AreaSamples(np.asarray(xyz), lo, hi, sats))
    groups, group_area = _find(pos, vel, pc, sensors, areas)
    groups, group_area = _daylight(sc, scene, grids, groups, group_area)
    lon = np.concatenate([g.lon_deg for g in grids])
    lat = np.concatenate([g.lat_deg for g in grids])
    region = np.repeat(np.arange(len(grids)), [len(g) for g in grids]).astype(np.int32)
    per = int(round(pc.time_step / pc.geometry_step))
    indptr, indices, bad = _rows(pos, vel, sensors, groups, per, lon, lat, region)
    groups, group_area, indptr, indices = _keep_groups(groups, group_area, indptr, indices, ~bad)
    win = _windows(sc, groups, indptr, table)
    opp = _option_table(sc, scene, groups, group_area, win)
    fov = np.array([0.0 if x is None else x.fov_deg for x in sensors])
    return AreaOptions(grids, groups, group_area, indptr, indices, opp, win, fov)


def _find(pos, vel, pc, sensors, areas):
    """:func:`find_groups` area by area (so each group knows its area)."""
    parts, owner, n_passes = [], [], 0
    for i, area in enumerate(areas):
        g = find_groups(pos, vel, pc.geometry_step, sensors, [area], pc.time_step)
        parts.append(g)
        owner.append(np.full(len(g), i, np.int64))
        n_passes += g.n_passes
    cat = [np.concatenate([getattr(p, f) for p in parts]) for f in Groups._fields[:5]]
    groups = Groups(
        cat[0].astype(np.int64),
        cat[1],
        cat[2].astype(np.int64),
        cat[3].astype(np.int64),
        cat[4],
        n_passes,
    )
    return groups, np.concatenate(owner)


def _daylight(sc, scene, grids, groups: Groups, group_area):
    """The groups that keep the daylight rule (:func:`_sun_ok`)."""
    keep = _sun_ok(sc, scene, grids, groups, group_area)
    if keep.all():
        return groups, group_area
    return Groups(*(x[keep] for x in groups[:5]), groups.n_passes), group_area[keep]


def merge_options(opp: Opportunities, area: AreaOptions):
    """The point and strip options with the area options, sorted by (satellite, start,
    target) as :class:`Opportunities` are.

    Args:
      opp: the point and strip targets' Opportunities; area: :class:`AreaOptions`.
    Returns:
      (Opportunities, window int64 [N, 3]: each option's (group, a, b), -1 rows for the
      options of point and strip targets).
    """
    a = area.opp
    fields = [
        np.concatenate([np.asarray(x), np.asarray(y)])
        for x, y in zip(opp.options, a.options, strict=True)
    ]
    o = RouteOptions(*fields)
    speed = np.concatenate([opp.speed, a.speed])
    params = np.concatenate([opp.params, a.params])
    window = np.concatenate([np.full((len(opp), 3), -1, np.int64), area.window])
    order = np.lexsort((o.route, o.t_start, o.sat))
    sorted_opt = RouteOptions(*(x[order] for x in o))
    return Opportunities(sorted_opt, speed[order], params[order]), window[order]


def cover_table(sc: Scenario, area: AreaOptions, window: np.ndarray) -> CoverTable:
    """The search's :class:`CoverTable` of the area stage's result.

    Args:
      sc: Scenario; area: :class:`AreaOptions`; window: int64 [N, 3], per option of the
        problem its (group, a, b), -1 rows for the others (:func:`merge_options`).
    Returns:
      CoverTable.
    """
    pc = sc.planner
    tg = sc.targets
    prio = np.array([float(tg.value[a.target]) for a in sc.areas])
    share = np.concatenate([g.weight for g in area.grids])
    which = np.repeat(np.arange(len(area.grids)), [len(g) for g in area.grids])
    g = area.groups
    need = [
        max(1, int(math.ceil(s.strip_duration[0] / pc.time_step - 1e-9))) for s in sc.satellites
    ]
    most = [int(math.floor(s.strip_duration[1] / pc.time_step + 1e-9)) for s in sc.satellites]
    return CoverTable(
        indptr=np.asarray(area.indptr, np.int64),
        indices=np.asarray(area.indices, np.int32),
        group_sat=g.sat,
        group_roll=g.roll_deg,
        group_pitch=g.pitch_deg,
        group_slot0=g.slot_lo,
        group_nslots=g.slot_hi - g.slot_lo,
        group_area=area.group_area,
        weight=prio[which] * share,
        area=which.astype(np.int64),
        share=share,
        area_target=np.array([a.target for a in sc.areas], np.int64),
        area_min=np.array([a.min_share for a in sc.areas], np.float64),
        slot_s=float(pc.time_step),
        n_slots=int(math.floor(sc.duration / pc.time_step + 1e-9)),
        min_slots=np.array(need, np.int64),
        max_slots=np.array(most, np.int64),
        option_group=window[:, 0].copy(),
        option_a=window[:, 1].copy(),
        option_b=window[:, 2].copy(),
    )
