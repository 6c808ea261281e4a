"""Where a stereo target can be imaged: access intervals and candidate looks (numpy).

A stereo target (kind ``STEREO`` with its :class:`~jaxspline.readers.stereo_request.Stereo`
request) is a disk of ``radius`` metres about its centre, imaged by push-broom *looks*:
steering angles (along, across) held fixed in the satellite's Earth-fixed track frame
(:func:`jaxspline.geometry.pointing.roll_frame`: nadir ``n``, along ``a``, across ``c``)
over whole slots of the action grid, the boresight pointing along ``n + tan(al) a +
tan(ac) c`` (the stereo_imaging benchmark's law; the planner's roll law
:func:`~jaxspline.geometry.pointing.roll_params` with pitch ``al`` and roll
``atan(tan(ac) cos(al))`` is the same direction, :func:`roll_pitch`). This module builds:

1. **Access intervals** (:func:`stereo_access`): per (satellite, stereo target) the
   maximal runs of instants on the access grid (:data:`ACCESS_STEP`) where the *access
   test* holds at the target centre: the centre above its horizon (elevation sine >
   the planner's horizon margin: with the off-nadir limits of imaging satellites the
   line of sight then clears the ellipsoid), its off-nadir angle seen from the
   satellite within the satellite's limit less the planner's off-nadir margin, the Sun
   at least ``sun_elevation_min`` plus :data:`SUN_MARGIN` over the centre's geocentric
   horizon, inside the target's window, the horizon and usable ephemeris. Passes come
   from the planner's visibility windows on the orbit knots
   (:func:`~jaxspline.geometry.windows.visibility_windows_all`), widened by one knot and
   resampled on the access grid.
2. **Looks** (:func:`stereo_looks`): in each interval, one look per midpoint on a grid
   of ``mid_step`` seconds. Its duration is the shortest whole number of action-grid
   slots within the satellite's ``strip_duration`` whose strip (half-width ``h = slant
   tan(fov / 2)``) covers the disk along the track: ground length ``2 sqrt(R^2 - h^2) +
   2 END_MARGIN R`` at the boresight's ground speed (``h >= R``: the shortest); its
   start is on the action grid, and its steering puts the boresight at the midpoint on
   the target's *foot point* (the ellipsoid point under the centre along the geocentric
   vertical: where a strip's ground track is laid flat in the target's east / north
   plane, so the strip is centred on the disk whatever the terrain height). A look is
   kept when its whole span lies in its interval (the access test at its start, every
   access step and its end) and the combined off-nadir of its steering is within the
   limit less the margin.

Per look: the satellite state at its midpoint, its slant range there (satellite to the
boresight's ground point on the ellipsoid), pixel scale (slant times ``ifov``), strip
half-width, its ground track (boresight ground points at its start, every
:data:`TRACK_STEP` after it and at its end, Earth-fixed) and its boresight at start and
end (what a rest-to-rest slew is measured between).

Satellite states are the planner's orbit table (:func:`satellite_states`: quintic Hermite
interpolation of the SGP4 knots, rotated to the Earth-fixed frame with the velocity
relative to the rotating Earth). Units: metres, seconds, radians.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import numpy as np

from jaxspline.base.elements import R_EARTH, WGS84_F, geodetic_to_ecef
from jaxspline.geometry.frames import earth_rotation_angle, rot_z, sun_direction, teme_to_ecef
from jaxspline.geometry.ground import surface_point
from jaxspline.geometry.orbit import orbit_state
from jaxspline.geometry.pointing import roll_frame
from jaxspline.geometry.windows import visibility_windows_all
from jaxspline.kernels.batch import map_chunked, ragged_positions

__all__ = [
    "ACCESS_STEP",
    "END_MARGIN",
    "MID_STEP",
    "SUN_MARGIN",
    "TRACK_STEP",
    "StereoAccess",
    "StereoLooks",
    "access_step",
    "ellipsoid_distance",
    "look_direction",
    "roll_pitch",
    "satellite_states",
    "steering_to",
    "stereo_access",
    "stereo_looks",
]

#: Step of the access test [s] (stereo_imaging RULES.md 7: every 1 s of a look).
ACCESS_STEP = 1.0
#: Spacing of the candidate look midpoints [s] (measured: docs of :func:`stereo_looks`).
MID_STEP = 5.0
#: Step of a strip's ground-track polyline [s] (RULES.md "Overlap").
TRACK_STEP = 8.0
#: Along-track margin of a look's covering length, a share of the disk radius.
END_MARGIN = 0.1
#: Extra Sun elevation the access test keeps [rad]: the planner's Sun series and the
#: stereo_imaging benchmark's differ by up to 0.082 deg in elevation (measured over 48 h).
SUN_MARGIN = math.radians(0.1)
#: Half the time span over which a look's ground speed is measured [s].
SPEED_PROBE = 1.0
_CHUNK = 1 << 15  # satellite states per compiled evaluation
_TIME_TOL = 1e-6  # [s] slack of times on the grids
_WGS84_B = R_EARTH * (1.0 - WGS84_F)  # polar semi-axis [m]


class StereoAccess(NamedTuple):
    """I access intervals (numpy [I]), sorted by (satellite, target, start).

    Attributes:
      sat: int64, satellite index.
      target: int64, row of the stereo target in ``scenario.targets``.
      lo, hi: first and last instant of the access grid where the access test holds [s].
    """

    sat: np.ndarray
    target: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    def __len__(self) -> int:
        return int(self.sat.shape[0])


class StereoLooks(NamedTuple):
    """L candidate looks (numpy, leading axis L), sorted by (target, satellite, start).

    Attributes:
      sat, target: int64, satellite index and target row.
      access: int64, index of its interval in :class:`StereoAccess` (the same-pass label).
      t_start, t_end: float, start and end [s] (on the action grid).
      along, across: float, steering angles [rad] (boresight ``n + tan(al) a + tan(ac) c``).
      roll, pitch: float, the same direction as the planner's roll law [rad].
      off_nadir: float, combined off-nadir angle of the steering [rad].
      slant: float, satellite to the boresight's ground point at the midpoint [m].
      scale: float, pixel scale ``slant * ifov`` [m] (NaN without ``ifov``).
      half_width: float, strip half-width ``slant * tan(fov / 2)`` [m].
      sat_mid: float [L, 3], Earth-fixed satellite position at the midpoint [m].
      track: float [L, K, 3], Earth-fixed ground points of the boresight at the start,
        every :data:`TRACK_STEP` and at the end, the last repeated to fill K [m].
      los_start, los_end: float [L, 3], unit Earth-fixed boresight at start and end.
    """

    sat: np.ndarray
    target: np.ndarray
    access: np.ndarray
    t_start: np.ndarray
    t_end: np.ndarray
    along: np.ndarray
    across: np.ndarray
    roll: np.ndarray
    pitch: np.ndarray
    off_nadir: np.ndarray
    slant: np.ndarray
    scale: np.ndarray
    half_width: np.ndarray
    sat_mid: np.ndarray
    track: np.ndarray
    los_start: np.ndarray
    los_end: np.ndarray

    def __len__(self) -> int:
        return int(self.sat.shape[0])

    def take(self, idx) -> StereoLooks:
        """The looks ``idx`` (int or bool index along L), in that order."""
        return StereoLooks(*(np.asarray(x)[idx] for x in self))


@jax.jit
def _teme_states(orbit, sat, t):
    return orbit_state(orbit, t, sat)


def satellite_states(scene, sat, t) -> tuple[np.ndarray, np.ndarray]:
    """Earth-fixed states of satellites at times (the planner's orbit table).

    ``r = Rz(theta) r_teme``, ``v = Rz(theta) v_teme - w_E z x r`` (velocity relative to
    the rotating Earth), ``theta`` the Earth rotation angle
    (:func:`~jaxspline.geometry.frames.teme_to_ecef`).

    Args:
      scene: Scene whose orbit is a multi-satellite HermiteOrbit.
      sat: int [N], satellite indices.
      t: float [N], times [s from the epoch].
    Returns:
      (pos float [N, 3] [m], vel float [N, 3] [m/s]).
    """
    sat = np.asarray(sat, np.int32).ravel()
    t = np.asarray(t, np.float64).ravel()
    if t.size == 0:
        return np.zeros((0, 3)), np.zeros((0, 3))
    r, v = map_chunked(lambda s, x: _teme_states(scene.orbit, s, x), [sat, t], _CHUNK)
    theta = earth_rotation_angle(float(scene.gmst0), t)
    return teme_to_ecef(np.asarray(r, np.float64), theta, np.asarray(v, np.float64))


def ellipsoid_distance(origin, direction) -> np.ndarray:
    """Distance along unit rays to their first crossing of the WGS84 ellipsoid (height 0).

    Scaled by the semi-axes (``P = o / (a, a, b)``, ``D = d / (a, a, b)``) the ray meets
    the unit sphere where ``|P + s D|^2 = 1``; the first root is ``s = C / (-B +
    sqrt(B^2 - A C))`` with ``A = D.D``, ``B = P.D``, ``C = P.P - 1`` (cancellation-free).

    Args:
      origin: float [..., 3], ray origins outside the ellipsoid [m].
      direction: float [..., 3], unit directions.
    Returns:
      float [...], distance [m]; NaN where the ray misses.
    """
    scale = np.array([1.0 / R_EARTH, 1.0 / R_EARTH, 1.0 / _WGS84_B])
    p, d = np.asarray(origin) * scale, np.asarray(direction) * scale
    a = np.sum(d * d, axis=-1)
    b = np.sum(p * d, axis=-1)
    c = np.sum(p * p, axis=-1) - 1.0
    disc = b * b - a * c
    hit = (disc >= 0.0) & (b < 0.0) & (c > 0.0)
    root = np.sqrt(np.where(hit, disc, 0.0))
    return np.where(hit, c / np.where(hit, root - b, 1.0), np.nan)


def look_direction(pos, vel, along, across) -> np.ndarray:
    """Unit boresight ``normalize(n + tan(al) a + tan(ac) c)`` in the track frame.

    Args:
      pos: float [..., 3], Earth-fixed position [m].
      vel: float [..., 3], Earth-fixed velocity relative to the rotating Earth [m/s].
      along, across: float [...], steering angles [rad] (positive forward / left).
    Returns:
      float [..., 3], unit Earth-fixed direction.
    """
    n, a, c = roll_frame(np.asarray(pos), np.asarray(vel))
    d = n + np.tan(along)[..., None] * a + np.tan(across)[..., None] * c
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def steering_to(pos, vel, point) -> tuple[np.ndarray, np.ndarray]:
    """Steering angles that put the boresight on ``point`` (inverse of :func:`look_direction`).

    ``al = atan(d.a / d.n)``, ``ac = atan(d.c / d.n)`` for ``d = point - pos``.

    Args:
      pos: float [..., 3], Earth-fixed position [m].
      vel: float [..., 3], Earth-fixed velocity relative to the rotating Earth [m/s].
      point: float [..., 3], the aim point [m].
    Returns:
      (along [...], across [...]) [rad].
    """
    n, a, c = roll_frame(np.asarray(pos), np.asarray(vel))
    d = np.asarray(point) - pos
    dn = np.sum(d * n, axis=-1)
    return np.arctan(np.sum(d * a, axis=-1) / dn), np.arctan(np.sum(d * c, axis=-1) / dn)


def roll_pitch(along, across) -> tuple[np.ndarray, np.ndarray]:
    """The planner's roll law (:func:`~jaxspline.geometry.pointing.roll_params`) of steering
    angles: ``cos(p) n + sin(p) a + tan(r) c`` is ``cos(al) (n + tan(al) a + tan(ac) c)``
    for ``p = al`` and ``r = atan(tan(ac) cos(al))``.

    Args:
      along, across: float [...], steering angles [rad].
    Returns:
      (roll [...], pitch [...]) [rad].
    """
    along = np.asarray(along, np.float64)
    return np.arctan(np.tan(across) * np.cos(along)), along


def _sun_up(sc, scene, t, up) -> np.ndarray:
    """Sine of the Sun's elevation over the geocentric horizons ``up`` [N, 3] at times t."""
    sun = rot_z(
        earth_rotation_angle(float(scene.gmst0), t), sun_direction(sc.epoch_jd + t / 86400.0)
    )
    return np.sum(up * sun, axis=-1)


def _targets(sc):
    """(rows int64 [T], centres [T, 3] [m], allowed bool [S, T], lo [T], hi [T] [s])."""
    tg = sc.targets
    rows = np.array([int(s.target) for s in sc.stereo], np.int64)
    centre = np.asarray(geodetic_to_ecef(tg.lat[rows], tg.lon[rows], tg.alt[rows]))
    allowed = np.array([[tg.sensor[r] in ("", s.sensor) for r in rows] for s in sc.satellites])
    lo = np.maximum(np.asarray(tg.t_lo[rows], np.float64), 0.0)
    hi = np.minimum(np.asarray(tg.t_hi[rows], np.float64), float(sc.duration))
    return rows, centre, allowed.reshape(len(sc.satellites), rows.size), lo, hi


def access_step(time_step: float) -> float:
    """The access grid [s]: :data:`ACCESS_STEP`, or the largest step below it that
    divides the action grid ``time_step`` (so looks start and end on it)."""
    return time_step / math.ceil(time_step / ACCESS_STEP - 1e-9)


def _samples(sc, table, scene, wins, centre, lo_t, hi_t, f):
    """Access-test samples of the widened windows: (owner window, t, ok)."""
    g = sc.planner.geometry_step
    lo = np.maximum(wins.lo - g, lo_t[wins.target])
    hi = np.minimum(wins.hi + g, hi_t[wins.target])
    k0 = np.ceil(lo / f - _TIME_TOL).astype(np.int64)
    k1 = np.floor(hi / f + _TIME_TOL).astype(np.int64)
    owner, off = ragged_positions(np.maximum(k1 - k0 + 1, 0))
    t = (k0[owner] + off) * f
    sat, tgt = wins.sat[owner], wins.target[owner]
    pos, _ = satellite_states(scene, sat, t)
    c = centre[tgt]
    d = c - pos
    dn = np.linalg.norm(d, axis=-1)
    off_n = np.arctan2(np.linalg.norm(np.cross(d, -pos), axis=-1), np.sum(d * -pos, axis=-1))
    up = c / np.linalg.norm(c, axis=-1, keepdims=True)
    elev = np.sum(-d * up, axis=-1) / dn
    pc = sc.planner
    limit = np.array([s.off_nadir_max for s in sc.satellites]) - pc.margins.off_nadir
    ok = (off_n <= limit[sat]) & (elev > pc.margins.horizon) & table.usable(sat, t)
    if pc.sun_elevation_min is not None:
        ok &= _sun_up(sc, scene, t, up) >= math.sin(pc.sun_elevation_min + SUN_MARGIN)
    return owner, t, ok


def stereo_access(sc, table, scene) -> StereoAccess:
    """The access intervals of every (satellite, stereo target) (module docstring, step 1).

    Args:
      sc: Scenario (its ``stereo`` requests, satellites and planner settings).
      table: its OrbitTable; scene: its Scene (:func:`jaxspline.geometry.windows.orbit_scene`).
    Returns:
      :class:`StereoAccess` (``target`` holds rows of ``sc.targets``).
    """
    rows, centre, allowed, lo_t, hi_t = _targets(sc)
    empty = StereoAccess(*(np.zeros(0, d) for d in (np.int64, np.int64, float, float)))
    if rows.size == 0:
        return empty
    pc = sc.planner
    limit = np.array([s.off_nadir_max for s in sc.satellites]) - pc.margins.off_nadir
    wins = visibility_windows_all(
        scene, table.ok, centre, allowed, limit, pc.margins.horizon, lo_t, hi_t, sc.duration
    )
    if len(wins) == 0:
        return empty
    f = access_step(pc.time_step)
    owner, t, ok = _samples(sc, table, scene, wins, centre, lo_t, hi_t, f)
    # runs of passing samples inside one window (a failing sample or a new window ends one)
    prev = np.concatenate([[False], ok[:-1] & (owner[1:] == owner[:-1])])
    nxt = np.concatenate([ok[1:] & (owner[1:] == owner[:-1]), [False]])
    first, last = np.flatnonzero(ok & ~prev), np.flatnonzero(ok & ~nxt)
    w = owner[first]
    out = StereoAccess(wins.sat[w].astype(np.int64), rows[wins.target[w]], t[first], t[last])
    order = np.lexsort((out.lo, out.target, out.sat))
    return StereoAccess(*(x[order] for x in out))


def _sensor(sc):
    """Per satellite: (fov [rad] or NaN, ifov [rad] or NaN, slots (shortest, longest))."""
    pc = sc.planner
    fov = np.array([np.nan if s.fov is None else float(s.fov) for s in sc.satellites])
    ifov = np.array([np.nan if s.ifov is None else float(s.ifov) for s in sc.satellites])
    lo = [max(1, math.ceil(s.strip_duration[0] / pc.time_step - 1e-9)) for s in sc.satellites]
    hi = [math.floor(s.strip_duration[1] / pc.time_step + 1e-9) for s in sc.satellites]
    return fov, ifov, np.array(lo, np.int64), np.array(hi, np.int64)


def _half_width(sc, fov, sat, pos, slant) -> np.ndarray:
    """Strip half-width [m]: ``slant tan(fov / 2)``; without a field of view, half the
    satellite's swath scaled from its altitude to the slant range."""
    swath = np.array([float(s.swath) for s in sc.satellites])[sat]
    alt = np.linalg.norm(pos, axis=-1) - R_EARTH
    f = fov[sat]
    return np.where(np.isfinite(f), slant * np.tan(f / 2.0), swath / 2.0 * slant / alt)


def _hit(pos, vel, al, ac) -> np.ndarray:
    """Ground points [N, 3] of the boresights of steering (al, ac) from states (NaN where
    a ray misses)."""
    d = look_direction(pos, vel, al, ac)
    return pos + ellipsoid_distance(pos, d)[..., None] * d


def _aim(scene, sat, t, foot):
    """State at t, steering at ``foot`` and the boresight's ground point: (pos, vel, al,
    ac, ground)."""
    pos, vel = satellite_states(scene, sat, t)
    al, ac = steering_to(pos, vel, foot)
    return pos, vel, al, ac, _hit(pos, vel, al, ac)


def _ground(scene, sat, t, al, ac) -> np.ndarray:
    """Boresight ground points of steering (al, ac) at times t (NaN where a ray misses)."""
    return _hit(*satellite_states(scene, sat, t), al, ac)


def _durations(sc, scene, cand_sat, t_mid, foot, radius):
    """Per candidate midpoint: its duration [s] (module docstring, step 2)."""
    fov, _, lo, hi = _sensor(sc)
    pos, _, al, ac, g = _aim(scene, cand_sat, t_mid, foot)
    slant = np.linalg.norm(g - pos, axis=-1)
    h = _half_width(sc, fov, cand_sat, pos, slant)
    g0 = _ground(scene, cand_sat, t_mid - SPEED_PROBE, al, ac)
    g1 = _ground(scene, cand_sat, t_mid + SPEED_PROBE, al, ac)
    speed = np.linalg.norm(g1 - g0, axis=-1) / (2.0 * SPEED_PROBE)
    length = 2.0 * np.sqrt(np.maximum(radius**2 - h**2, 0.0)) + 2.0 * END_MARGIN * radius
    step = sc.planner.time_step
    slots = np.ceil(length / np.where(speed > 0, speed, np.inf) / step - 1e-9)
    slots = np.clip(np.nan_to_num(slots, nan=0.0).astype(np.int64), lo[cand_sat], hi[cand_sat])
    return slots * step


def _candidates(sc, scene, access: StereoAccess, mid_step: float):
    """Candidate looks: (interval id, start, end) on the action grid inside the interval."""
    k0 = np.ceil(access.lo / mid_step - _TIME_TOL).astype(np.int64)
    k1 = np.floor(access.hi / mid_step + _TIME_TOL).astype(np.int64)
    owner, off = ragged_positions(np.maximum(k1 - k0 + 1, 0))
    mid = (k0[owner] + off) * mid_step
    rows = np.asarray(access.target)[owner]
    centre = _centres(sc, rows)
    radius = _radii(sc, rows)
    dur = _durations(sc, scene, access.sat[owner], mid, _feet(centre), radius)
    step = sc.planner.time_step
    t0 = np.round((mid - dur / 2.0) / step) * step
    t1 = t0 + dur
    inside = (t0 >= access.lo[owner] - _TIME_TOL) & (t1 <= access.hi[owner] + _TIME_TOL)
    owner, t0, t1 = owner[inside], t0[inside], t1[inside]
    key = np.unique(np.stack([owner, np.round(t0 / step), np.round(t1 / step)], -1), axis=0)
    return key[:, 0].astype(np.int64), key[:, 1] * step, key[:, 2] * step


def _centres(sc, rows) -> np.ndarray:
    """Earth-fixed centres [N, 3] of target rows (geodetic, at their height) [m]."""
    tg = sc.targets
    return np.asarray(geodetic_to_ecef(tg.lat[rows], tg.lon[rows], tg.alt[rows])).reshape(-1, 3)


def _feet(centre) -> np.ndarray:
    """The foot points of centres [N, 3]: the ellipsoid under them along the geocentric
    vertical (:func:`~jaxspline.geometry.ground.surface_point`)."""
    return surface_point(centre / np.linalg.norm(centre, axis=-1, keepdims=True))


def _radii(sc, rows) -> np.ndarray:
    """Disk radii [N] of stereo target rows [m]."""
    radius = {int(s.target): float(s.radius) for s in sc.stereo}
    return np.array([radius[int(r)] for r in rows], np.float64)


def _tracks(scene, sat, t0, t1, al, ac) -> np.ndarray:
    """Ground tracks [L, K, 3]: boresight ground points at ``min(t0 + k TRACK_STEP, t1)``."""
    if sat.size == 0:
        return np.zeros((0, 2, 3))
    k = int(np.floor(np.max(t1 - t0) / TRACK_STEP + 1e-9)) + 2
    t = np.minimum(t0[:, None] + TRACK_STEP * np.arange(k)[None, :], t1[:, None])
    rep = np.repeat
    g = _ground(scene, rep(sat, k), t.ravel(), rep(al, k), rep(ac, k))
    return g.reshape(sat.size, k, 3)


def stereo_looks(sc, table, scene, access: StereoAccess | None = None, mid_step=MID_STEP):
    """The candidate looks of every stereo target (module docstring, step 2).

    Args:
      sc: Scenario with stereo requests; table: its OrbitTable; scene: its Scene.
      access: :func:`stereo_access` of the same arguments (computed when None).
      mid_step: spacing of the candidate midpoints [s] (> 0).
    Returns:
      (:class:`StereoAccess`, :class:`StereoLooks`).
    Raises:
      ValueError: ``mid_step`` is not > 0.
    """
    if not mid_step > 0:
        raise ValueError(f"mid_step must be > 0, got {mid_step!r}")
    access = stereo_access(sc, table, scene) if access is None else access
    owner, t0, t1 = _candidates(sc, scene, access, float(mid_step))
    sat, rows = access.sat[owner], access.target[owner]
    foot = _feet(_centres(sc, rows))
    pos, vel, al, ac, g = _aim(scene, sat, (t0 + t1) / 2.0, foot)
    off = np.arctan(np.hypot(np.tan(al), np.tan(ac)))
    limit = np.array([s.off_nadir_max for s in sc.satellites]) - sc.planner.margins.off_nadir
    keep = (off <= limit[sat]) & np.isfinite(g).all(axis=-1)
    keep &= table.usable(sat, t0) & table.usable(sat, t1)
    order = np.flatnonzero(keep)[np.lexsort((t0[keep], sat[keep], rows[keep]))]
    sat, rows, t0, t1, al, ac = (x[order] for x in (sat, rows, t0, t1, al, ac))
    pos, g, off = pos[order], g[order], off[order]
    slant = np.linalg.norm(g - pos, axis=-1)
    fov, ifov, _, _ = _sensor(sc)
    p0, v0 = satellite_states(scene, sat, t0)
    p1, v1 = satellite_states(scene, sat, t1)
    roll, pitch = roll_pitch(al, ac)
    looks = StereoLooks(
        sat=sat.astype(np.int64),
        target=rows.astype(np.int64),
        access=owner[order].astype(np.int64),
        t_start=t0,
        t_end=t1,
        along=al,
        across=ac,
        roll=roll,
        pitch=pitch,
        off_nadir=off,
        slant=slant,
        scale=slant * ifov[sat],
        half_width=_half_width(sc, fov, sat, pos, slant),
        sat_mid=pos,
        track=_tracks(scene, sat, t0, t1, al, ac),
        los_start=look_direction(p0, v0, al, ac),
        los_end=look_direction(p1, v1, al, ac),
    )
    return access, looks
