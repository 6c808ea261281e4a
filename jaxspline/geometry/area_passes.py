"""Where area strips can be: the passes of each satellite over each area, and their roll groups.

An area strip is a push-broom look at a pointing offset (roll, pitch) held fixed in the
track frame (:func:`jaxspline.geometry.pointing.roll_look_direction`,
:func:`jaxspline.geometry.pointing.roll_params`) over a whole number of action-grid slots:
at each instant its rays sweep the plane through ``down = cos(p) nadir + sin(p) along``
and ``across``, whose normal is ``n = cos(p) along - sin(p) nadir``. A roll-only satellite
has the pitch 0 alone; an agile one a grid of pitches, so that it can image several rows
of an area in one pass, looking ahead, then down, then back. This module finds, on the
satellites' Earth-fixed tracks (the planner's orbit table rotated to the Earth-fixed
frame), which (satellite, pitch, roll, slots) can cover any sample of an area:

1. **Passes.** Per pitch, the instants when the area's centre crosses the satellite's
   imaging plane (``(X - p) . n`` changes sign from + to -, the point in front of the
   Earth's horizon) with some sample inside the roll band (+- :data:`PASS_SLACK_DEG`)
   at that instant, and the Earth's central angle to the centre within reach.
2. **Sample crossings.** Per pass, every sample's own crossing instant ``t_j`` (linear
   interpolation of ``(X_j - p) . n`` on the mesh) and its look angle ``a_j =
   atan2((X_j - p) . across, (X_j - p) . down)`` there: a strip of roll ``r`` and field
   of view ``f`` covers sample ``j`` about when ``|a_j - r| <= f / 2`` and the strip
   spans ``t_j``.
3. **Groups.** Rolls on a grid of the satellite's step inside each side of its roll band
   (:func:`roll_grid`: values on a :data:`ROLL_DECIMALS` grid, strictly inside the band,
   the boresight within the off-nadir limit at that pitch); per (pass, roll) with any
   sample near it, the slots spanning those samples' crossings with one slot of slack
   on each side, at least the minimum strip length, clipped to the area's slots. Groups
   of one (satellite, pitch, roll) whose slots meet are merged (:func:`merge_groups`).

Which samples each slot of each group covers is the coverage engine's work
(:func:`jaxspline.screen.coverage.coverage_slices`, exact quadrilateral geometry).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from jaxspline.base.elements import R_EARTH
from jaxspline.geometry.pointing import roll_frame

__all__ = [
    "MIN_GROUND_SPEED",
    "PASS_SLACK_DEG",
    "ROLL_DECIMALS",
    "ROLL_SLACK_DEG",
    "AreaSamples",
    "Groups",
    "StripSensor",
    "find_groups",
    "merge_groups",
    "pass_crossings",
    "roll_grid",
    "sample_crossings",
]

#: Decimals of the roll values of a grid (a solution file writes them exactly).
ROLL_DECIMALS = 4
#: A pass is kept if some sample's look angle is within this of the roll band [deg].
PASS_SLACK_DEG = 1.0
#: Extra look-angle slack when deciding which samples a roll may cover [deg].
ROLL_SLACK_DEG = 0.3
#: Ground speed used to size a pass's search window (a lower bound) [m/s].
MIN_GROUND_SPEED = 6000.0
#: Mesh samples added on each side of a pass window.
WINDOW_PAD = 3
_WGS84_B = 6356752.314245  # m, polar radius (the smaller one: reach is over-estimated)


class StripSensor(NamedTuple):
    """What one satellite's area strips may be.

    Attributes:
      fov_deg: cross-track field of view [deg].
      roll_lo_deg, roll_hi_deg: the band of the strip's roll magnitude [deg], both sides
        of nadir (``0 <= lo <= hi``; the grid keeps 1e-4 deg inside it).
      roll_step_deg: roll grid step [deg].
      min_slots: fewest action-grid slots of a strip.
      pitches_deg: the pitches of its strips [deg] ((0,): roll only).
      off_nadir_deg: the boresight's off-nadir limit [deg]: at pitch p the roll keeps
        ``cos(r) cos(p) >= cos(limit)``.
    """

    fov_deg: float
    roll_lo_deg: float
    roll_hi_deg: float
    roll_step_deg: float
    min_slots: int
    pitches_deg: tuple = (0.0,)
    off_nadir_deg: float = 90.0


class AreaSamples(NamedTuple):
    """One area as the pass search sees it.

    Attributes:
      xyz: float [n, 3], Earth-fixed sample positions [m].
      slot_lo, slot_hi: the area's imaging window as action-grid slots ``[lo, hi)``.
      sats: bool [S], satellites allowed to image the area (sensor, pass rules).
    """

    xyz: np.ndarray
    slot_lo: int
    slot_hi: int
    sats: np.ndarray


class Groups(NamedTuple):
    """Roll groups: one satellite at one pointing offset over a contiguous range of slots.

    Attributes:
      sat: int64 [G]; roll_deg: float64 [G] [deg]; slot_lo, slot_hi: int64 [G], the
      group's slots ``[lo, hi)``; pitch_deg: float64 [G] [deg]; n_passes: passes found.
    """

    sat: np.ndarray
    roll_deg: np.ndarray
    slot_lo: np.ndarray
    slot_hi: np.ndarray
    pitch_deg: np.ndarray
    n_passes: int

    def __len__(self) -> int:
        return int(self.sat.shape[0])


def roll_grid(lo_deg: float, hi_deg: float, step_deg: float) -> np.ndarray:
    """Roll magnitudes [deg] on a grid inside a band, with 1e-4 deg to spare.

    Args:
      lo_deg: inner edge of the band of the roll magnitude [deg].
      hi_deg: outer edge of the band [deg].
      step_deg: grid step [deg] (> 0).
    Returns:
      float64 [M] increasing, on a ``10^-ROLL_DECIMALS`` grid (empty when the band is
      narrower than the spare).
    """
    q = 10.0**ROLL_DECIMALS
    lo = np.ceil(lo_deg * q + 1) / q
    hi = np.floor(hi_deg * q - 1) / q
    if hi < lo:
        return np.zeros(0)
    n = int(np.floor((hi - lo) / step_deg + 1e-9))
    vals = np.round(lo + step_deg * np.arange(n + 1), ROLL_DECIMALS)
    if hi - vals[-1] > 1e-9:
        vals = np.append(vals, hi)
    return vals[(vals >= lo) & (vals <= hi)]


def pass_crossings(frames, pos, point: np.ndarray) -> np.ndarray:
    """Mesh indices k where a ground point crosses the cross-track plane between k, k+1.

    Args:
      frames: (nadir, along, across) [K, 3] of one satellite; pos: float [K, 3] [m].
      point: float [3], Earth-fixed point [m].
    Returns:
      int64 indices (point in front of the horizon side: ``(X - p) . nadir > 0``).
    """
    nadir, along, _ = frames
    d = point[None, :] - pos
    u = np.sum(d * along, axis=1)
    front = np.sum(d * nadir, axis=1) > 0
    return np.nonzero((u[:-1] >= 0) & (u[1:] < 0) & front[:-1])[0]


def sample_crossings(frames, pos, xyz: np.ndarray, k_lo: int, k_hi: int, step_s: float):
    """Crossing instant and look angle of each point within mesh window [k_lo, k_hi].

    Args:
      frames: (nadir, along, across) [K, 3]; pos: [K, 3]; xyz: float [n, 3] points [m].
      k_lo, k_hi: mesh window (inclusive); step_s: mesh step [s].
    Returns:
      (t [n] seconds from the mesh start, a [n] look angle [deg]); NaN where the point
      does not cross inside the window.
    """
    nadir, along, across = (f[k_lo : k_hi + 1] for f in frames)
    d = xyz[:, None, :] - pos[None, k_lo : k_hi + 1]
    u = np.einsum("nkc,kc->nk", d, along)
    look = np.degrees(
        np.arctan2(np.einsum("nkc,kc->nk", d, across), np.einsum("nkc,kc->nk", d, nadir))
    )
    hit = (u[:, :-1] >= 0) & (u[:, 1:] < 0)
    has = hit.any(axis=1)
    k = np.argmax(hit, axis=1)
    rows = np.arange(xyz.shape[0])
    u0, u1 = u[rows, k], u[rows, k + 1]
    frac = np.where(has, u0 / np.where(has, u0 - u1, 1.0), np.nan)
    t = (k_lo + k + frac) * step_s
    a = look[rows, k] + frac * (look[rows, k + 1] - look[rows, k])
    return np.where(has, t, np.nan), np.where(has, a, np.nan)


def _ground_reach(pos: np.ndarray, look_deg: float) -> float:
    """Largest ground distance [m] a look angle reaches over a track (spherical Earth).

    Earth central angle ``asin(|p| / R sin(a)) - a`` (or the horizon's ``acos(R / |p|)``
    when the ray misses the sphere), ``R`` the WGS84 polar radius (the smaller one, so the
    distance is an over-estimate), times the equatorial radius.
    """
    rmax = float(np.max(np.linalg.norm(pos, axis=1)))
    a = np.radians(min(look_deg, 89.0))
    x = rmax / _WGS84_B * np.sin(a)
    lam = np.arccos(_WGS84_B / rmax) if x >= 1.0 else np.arcsin(x) - a
    return float(lam * R_EARTH)


def _pass_groups(sensor: StripSensor, grid, t, a, slot_s, slots):
    """(roll, slot_lo, slot_hi) of one pass from its samples' crossings (``slots``: the
    area's ``[lo, hi)``)."""
    ok = np.isfinite(t)
    t, a = t[ok], a[ok]
    out = []
    half = sensor.fov_deg / 2 + ROLL_SLACK_DEG
    need = sensor.min_slots
    for sign in (1.0, -1.0):
        rolls = sign * grid
        near = np.abs(a[None, :] - rolls[:, None]) <= half
        for i in np.nonzero(near.any(axis=1))[0]:
            tt = t[near[i]]
            lo = int(np.floor(tt.min() / slot_s)) - 1
            hi = int(np.floor(tt.max() / slot_s)) + 2
            if hi - lo < need:
                hi = lo + need
            lo, hi = max(lo, slots[0]), min(hi, slots[1])
            if hi - lo >= need:
                out.append((float(rolls[i]), lo, hi))
    return out


def merge_groups(groups) -> list:
    """Merge (sat, pitch, roll, lo, hi) entries of one (sat, pitch, roll) whose slot
    ranges meet.

    Args:
      groups: iterable of (sat, pitch, roll, lo, hi).
    Returns:
      list of [sat, pitch, roll, lo, hi], sorted.
    """
    out = []
    for s, p, r, lo, hi in sorted(groups):
        if out and out[-1][:3] == [s, p, r] and lo <= out[-1][4]:
            out[-1][4] = max(out[-1][4], hi)
        else:
            out.append([s, p, r, lo, hi])
    return out


def tilted_frames(frames, pitch_deg: float):
    """The imaging plane's frame at a pitch: ``(down, n, across)`` [K, 3] (module docstring),
    from the track frames ``(nadir, along, across)``; pitch 0 gives them back."""
    nadir, along, across = frames
    if pitch_deg == 0.0:
        return frames
    p = np.radians(pitch_deg)
    return np.cos(p) * nadir + np.sin(p) * along, np.cos(p) * along - np.sin(p) * nadir, across


def find_groups(pos, vel, step_s: float, sensors, areas, slot_s: float) -> Groups:
    """All roll groups of the satellites over the areas (module docstring).

    Args:
      pos: float [S, K, 3], Earth-fixed positions [m] on the mesh ``k * step_s``.
      vel: float [S, K, 3], velocities relative to the rotating Earth [m/s].
      step_s: mesh step [s].
      sensors: per satellite a :class:`StripSensor`, or None (no area strips).
      areas: list of :class:`AreaSamples`.
      slot_s: action-grid step [s] (a multiple of ``step_s``).
    Returns:
      :class:`Groups`.
    """
    out, n_passes = [], 0
    for s, sensor in enumerate(sensors):
        if sensor is None:
            continue
        track = roll_frame(pos[s], vel[s])
        for pitch in sensor.pitches_deg:
            grid = roll_grid(*_roll_band(sensor, pitch), sensor.roll_step_deg)
            if grid.size == 0:
                continue
            frames = tilted_frames(track, pitch)
            for area in areas:
                if not area.sats[s] or area.xyz.shape[0] == 0:
                    continue
                found, n = _area_passes(pos[s], frames, step_s, sensor, grid, area, slot_s, pitch)
                out += [(s, float(pitch), *g) for g in found]
                n_passes += n
    merged = np.array(merge_groups(out), np.float64).reshape(-1, 5)
    return Groups(
        merged[:, 0].astype(np.int64),
        merged[:, 2],
        merged[:, 3].astype(np.int64),
        merged[:, 4].astype(np.int64),
        merged[:, 1],
        n_passes,
    )


def _roll_band(sensor: StripSensor, pitch: float) -> tuple[float, float]:
    """The roll band at a pitch: the sensor's, its top lowered so the boresight keeps
    ``cos(r) cos(p) >= cos(off-nadir limit)``."""
    c = np.cos(np.radians(sensor.off_nadir_deg)) / np.cos(np.radians(pitch))
    top = float(np.degrees(np.arccos(min(c, 1.0))))
    return sensor.roll_lo_deg, min(sensor.roll_hi_deg, top)


def _area_passes(pos, frames, step_s, sensor: StripSensor, grid, area: AreaSamples, slot_s,
                 pitch: float):  # fmt: skip
    """The groups ``(roll, lo, hi)`` of one satellite at one pitch over one area (``frames``
    the imaging plane's, :func:`tilted_frames`), and its passes."""
    xyz = area.xyz
    centre = xyz.mean(axis=0)
    reach = float(np.max(np.linalg.norm(xyz - centre, axis=1)))
    w = int(np.ceil(reach / MIN_GROUND_SPEED / step_s)) + WINDOW_PAD
    look = sensor.roll_hi_deg + sensor.fov_deg / 2 + abs(pitch) + PASS_SLACK_DEG
    far = _ground_reach(pos, look) + reach
    lo_b = max(sensor.roll_lo_deg - sensor.fov_deg / 2 - PASS_SLACK_DEG, 0.0)
    hi_b = sensor.roll_hi_deg + sensor.fov_deg / 2 + PASS_SLACK_DEG
    slots = (area.slot_lo, area.slot_hi)
    out, n = [], 0
    for k in pass_crossings(frames, pos, centre):
        p = pos[k]
        ang = np.arctan2(np.linalg.norm(np.cross(p, centre)), p @ centre)
        if ang * np.linalg.norm(centre) > far:
            continue
        k_lo, k_hi = max(0, k - w), min(pos.shape[0] - 1, k + 1 + w)
        if (k_hi + 1) * step_s <= slots[0] * slot_s or k_lo * step_s >= slots[1] * slot_s:
            continue
        t, a = sample_crossings(frames, pos, xyz, k_lo, k_hi, step_s)
        aa = np.abs(a[np.isfinite(a)])
        if not np.any((aa >= lo_b) & (aa <= hi_b)):
            continue
        n += 1
        out += _pass_groups(sensor, grid, t, a, slot_s, slots)
    return out, n
