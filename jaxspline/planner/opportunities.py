"""Imaging options: every (target, satellite, start on the action grid) that can be imaged.

From the visibility windows of every target's reference point (a point target, or
a strip's midpoint; :func:`jaxspline.geometry.windows.visibility_windows_all`), each window
gives the starts ``k * time_step`` whose observation fits it. An option is kept when,
at every *sample* of the observation (its start, every geometry knot inside it, its
end), the aim point is above its horizon and inside the off-nadir cone (limit minus
margin), the target's imaging window and the horizon [0, duration] hold, the Sun is
high enough at the start (``sun_elevation_min``), the imaging midpoint lies in the
target's ``[mid_lo, mid_hi]`` (a desired time with its tolerance), the imaging time
reaches the target's ``min_duration`` (for strips: per scan speed), and, for ``per_channel``
satellites, every channel's rate and acceleration stay within the limits (the scan
itself must be flyable). Point options whose start and end are knots of the window
are exact already (the window was computed on every knot) and skip the resampling.

Strips are scanned from their start point along their azimuth at each of the
planner's scan speeds (one option per speed).

Per option the engine keeps what the maneuver models need: attitude angles and rates
at start and end (per_channel), the unit lines of sight at start and end and the
nadir at the start (rest-to-rest models), in the :class:`RouteOptions` contract.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from jaxspline.base.elements import geodetic_to_ecef
from jaxspline.geometry.frames import earth_rotation_angle, rot_z, sun_direction, sun_elevation
from jaxspline.geometry.orbit import HermiteOrbit, padded_orbit
from jaxspline.geometry.pointing import Scene, aim_geometry, aim_params, aim_point, aim_state
from jaxspline.geometry.routes import strip_direction
from jaxspline.geometry.windows import Windows
from jaxspline.kernels.batch import map_chunked, ragged_positions
from jaxspline.kernels.validate import to_device
from jaxspline.readers.mission import STRIP, Scenario
from jaxspline.screen.options import RouteOptions

__all__ = [
    "Opportunities",
    "build_opportunities",
    "evaluate",
    "nadir_rate",
    "observation_samples",
    "option_counts",
    "reference_points",
]

_CHUNK = 1 << 13  # candidates per compiled evaluation (padded)
_TICK_CHUNKS = 16  # chunks between two clock checks (evaluate's tick)
_SAMPLES_SHARE = 0.6  # share of the options stage the sample checks take (for the clock)
_GRID_TOL = 1e-6  # [s] a time within this of a knot is on the knot
_KNOT_TOL = 1e-6  # [steps] knots this close to a start / end are left to that sample
_DURATION_TOL = 1e-9  # [s] an imaging time this much short of min_duration still counts
_LIMIT_TOL = 1e-9  # relative tolerance of the scan's rate / acceleration test
_NADIR_RATE_SAFETY = 1e-6  # relative excess of the nadir turn rate over the knots' maximum


class Opportunities(NamedTuple):
    """N imaging options (numpy), sorted by (satellite, start, target).

    Attributes:
      options: :class:`RouteOptions` (``route`` = target index, ``sat`` set, LOS and
        nadir set; angles and rates are zero for rest-to-rest satellites).
      speed: [N] scan speed [m/s] (0 for points).
      params: [N, 8] aim laws (:func:`jaxspline.geometry.pointing.aim_params`).
    """

    options: RouteOptions
    speed: np.ndarray
    params: np.ndarray

    def __len__(self) -> int:
        return int(self.speed.shape[0])


def _geometry(scene, sat, p, t0, t):
    return aim_geometry(scene, p, t0, t, sat)


def _state(scene, sat, p, t0, t):
    ang, rate, acc, _ = aim_state(scene, p, t0, t, sat)
    return ang, rate, acc


geometry_batched = jax.jit(jax.vmap(_geometry, in_axes=(None, 0, 0, 0, 0)))
"""``aim_geometry`` batched over (sat, law, t0, t) for :func:`evaluate`."""
state_batched = jax.jit(jax.vmap(_state, in_axes=(None, 0, 0, 0, 0)))
"""``aim_state`` (angles, rates, accelerations) batched like :data:`geometry_batched`."""
# one program a table size (run eagerly, each of their operations compiles on its own)
_aim_params = jax.jit(aim_params)
_aim_points = jax.jit(jax.vmap(aim_point))


_BUCKETED: list = []  # [(scene, its padded copy)] of the last call (one entry)


def _bucketed(scene: Scene) -> Scene:
    """The scene with its orbit table padded to power-of-two sizes (:func:`padded_orbit`):
    the compiled kernels then serve every scenario of similar size. Kept for the next
    call with the same scene."""
    orb = scene.orbit
    if not isinstance(orb, HermiteOrbit) or orb.n is not None or np.ndim(orb.r) != 3:
        return scene
    if _BUCKETED and _BUCKETED[0][0] is scene:
        return _BUCKETED[0][1]
    out = scene._replace(orbit=padded_orbit(orb))
    _BUCKETED[:] = [(scene, out)]
    return out


def evaluate(fn, scene: Scene, sat, p, t0, t, tick=None):
    """Apply a vmapped kernel ``fn(scene, sat, p, t0, t)`` in padded chunks (numpy out).

    Every chunk is padded to :data:`_CHUNK` rows by repeating the last row, so one
    compiled shape serves every call (compilation, not evaluation, dominates small
    batches).

    Args:
      fn: vmapped kernel over the leading axis of sat, p, t0 and t.
      scene: Scene.
      sat: int [M], satellite indices.
      p: float [M, 8], aim laws.
      t0: float [M], aim-law start times [s from the epoch].
      t: float [M], evaluation times [s from the epoch].
      tick: optional ``tick(share done)`` called after every block of
        :data:`_TICK_CHUNKS` chunks (the results are the same with or without it).
    Returns:
      list of numpy arrays [M, ...] (one per kernel output), or None when M = 0.
    """
    m = int(np.shape(sat)[0])
    if m == 0:
        return None
    args = [np.asarray(x) for x in (sat, p, t0, t)]
    scene = _bucketed(scene)

    def run(*a):
        return fn(scene, *(to_device(x) for x in a))

    if tick is None:
        return map_chunked(run, args, _CHUNK)
    block, parts = _TICK_CHUNKS * _CHUNK, []
    for a in range(0, m, block):  # whole chunks: the same padding as one call
        parts.append(map_chunked(run, [x[a : a + block] for x in args], _CHUNK))
        tick(min(m, a + block) / m)
    return [np.concatenate(col) for col in zip(*parts, strict=True)]


def aim_laws(sc: Scenario):
    """Per scan speed: (speed [m/s], aim laws [R, 8], durations [R] [s])."""
    tg = sc.targets
    g0 = np.asarray(geodetic_to_ecef(tg.lat, tg.lon, tg.alt))
    d = strip_direction(tg.lat, tg.lon, tg.azimuth)
    is_strip = tg.kind == STRIP
    p_point = np.asarray(_aim_params(g0))
    laws = []
    for speed in sc.planner.scan_speeds:
        p = np.where(is_strip[:, None], np.asarray(_aim_params(g0, d, speed)), p_point)
        laws.append((float(speed), p, np.where(is_strip, tg.length / speed, tg.duration)))
    return laws


def reference_points(sc: Scenario) -> np.ndarray:
    """The Earth-fixed point whose visibility windows a target's options come from.

    A point target itself; a strip's midpoint, on the same great circle as its scan
    (:func:`jaxspline.geometry.pointing.aim_params`, half the strip's length along it).

    Args:
      sc: Scenario with R targets.
    Returns:
      numpy float [R, 3], Earth-fixed points [m].
    """
    tg = sc.targets
    _, p, _ = aim_laws(sc)[0]
    half = (tg.length / 2.0) / np.linalg.norm(p[:, :3], axis=-1)
    mid = np.asarray(_aim_points(to_device(p), to_device(half))[0])
    return np.where((tg.kind == STRIP)[:, None], mid, p[:, :3])


def observation_samples(t0, t1, step: float, tol: float = _KNOT_TOL):
    """Sample instants of observations [t0, t1]: start, every knot ``k step`` inside, end.

    Knots within ``tol`` steps of the start or end are left to the start / end sample.

    Args:
      t0: float [K], observation starts [s from the epoch].
      t1: float [K], observation ends [s from the epoch].
      step: float, knot spacing [s].
      tol: float, fraction of a step.
    Returns:
      (owner int [M], t float [M]): the observation index and the time [s] of every sample.
    """
    t0, t1 = np.asarray(t0, np.float64), np.asarray(t1, np.float64)
    k0 = np.floor(t0 / step + tol).astype(np.int64) + 1
    k1 = np.ceil(t1 / step - tol).astype(np.int64) - 1
    cnt = np.maximum(k1 - k0 + 1, 0) + 2
    owner, pos = ragged_positions(cnt)
    t = np.where(
        pos == 0,
        t0[owner],
        np.where(pos == cnt[owner] - 1, t1[owner], (k0[owner] + pos - 1) * step),
    )
    return owner, t


def _limit_table(sats, name: str) -> np.ndarray:
    """[S, 3] per-channel limit ``name`` of per-channel satellites (inf for the others)."""
    return np.stack(
        [
            np.broadcast_to(getattr(s.limits, name), (3,))
            if not s.maneuver.rest_to_rest
            else np.full(3, np.inf)
            for s in sats
        ]
    )


def build_opportunities(
    sc: Scenario, scene: Scene, table_ok, windows: Windows, tick=None
) -> Opportunities:
    """All valid options of the windows (see module docstring).

    Args:
      sc: the scenario.
      scene: multi-satellite :class:`Scene` (orbit tables [S, M, 3]).
      table_ok: callable ``(sat [N], t [N]) -> bool [N]``, ephemeris usable.
      windows: visibility windows of the targets' reference points.
      tick: optional ``tick(share of the stage done)``, called while the samples are
        checked (the clock of :class:`jaxspline.planner.deadline.StageDeadline`).
    """
    per_ch = np.array([not s.maneuver.rest_to_rest for s in sc.satellites])
    cand = _grid_candidates(sc, aim_laws(sc), windows)
    ok = _samples_ok(sc, scene, table_ok, cand, per_ch, tick)
    if sc.planner.sun_elevation_min is not None and cand.sat.size:
        ok &= _sun_ok(sc, scene, cand)
    sel = np.flatnonzero(ok)
    c = _Candidates(*(x[sel] for x in cand))
    order = np.lexsort((c.tgt, c.t0, c.sat))
    sat, tgt, t0, t1, speed, params = (x[order] for x in c)
    return Opportunities(option_states(sc, scene, sat, tgt, t0, t1, params, per_ch), speed, params)


def option_counts(sc: Scenario, windows: Windows) -> tuple[int, int]:
    """Upper bounds on what :func:`build_opportunities` will hold, without building it.

    The candidates are counted window by window as :func:`_grid_candidates` makes them
    (before duplicates are removed); every candidate is counted with the samples of a
    checked one (start, end and every geometry knot inside), whether it needs them or not.

    Args:
      sc: the scenario.
      windows: its visibility windows.
    Returns:
      (candidates, samples): int, int.
    """
    gstep = sc.planner.geometry_step
    strip = sc.targets.kind[windows.target] == STRIP
    cands = samples = 0
    for li, (_, _, dur_all) in enumerate(aim_laws(sc)):
        keep = strip if li > 0 else np.ones(len(windows), bool)
        dur = dur_all[windows.target[keep]]
        k_lo, k_hi = _start_range(sc, windows, keep, strip[keep], dur)
        n = np.maximum(k_hi - k_lo + 1, 0).astype(np.float64)
        cands += int(n.sum())
        samples += int((n * (np.ceil(dur / gstep) + 2.0)).sum())
    return cands, samples


class _Candidates(NamedTuple):
    """Candidate options, one row each: satellite ``sat``, target ``tgt``, start ``t0``
    and end ``t1`` [s], scan ``speed`` [m/s] (0 for points) and aim law ``params``
    [N, 8]."""

    sat: np.ndarray
    tgt: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    speed: np.ndarray
    params: np.ndarray


def _grid_candidates(sc: Scenario, laws, windows: Windows) -> _Candidates:
    """Every (satellite, target, start on the action grid, scan speed) whose observation
    fits its visibility window, the target's imaging window, the horizon and the
    midpoint window, for scan speeds long enough for ``min_duration`` (points: the first
    law only, one option per start), without duplicates, in (satellite, target, grid
    start, law) order, with their ends and aim laws from ``laws`` (:func:`aim_laws`)."""
    step = sc.planner.time_step
    cols = {k: [] for k in ("sat", "target", "t0", "speed", "law")}
    strip = sc.targets.kind[windows.target] == STRIP
    for li, (speed, _, dur_all) in enumerate(laws):
        # points have one option per start, whatever the speed
        keep = strip if li > 0 else np.ones(len(windows), bool)
        w_sat, w_tgt = windows.sat[keep], windows.target[keep]
        k_lo, k_hi = _start_range(sc, windows, keep, strip[keep], dur_all[w_tgt])
        wi, off = ragged_positions(np.maximum(k_hi - k_lo + 1, 0))
        cols["sat"].append(w_sat[wi])
        cols["target"].append(w_tgt[wi])
        cols["t0"].append((k_lo[wi] + off) * step)
        cols["speed"].append(np.where(strip[keep][wi], speed, 0.0))
        cols["law"].append(np.full(wi.size, li))
    sat, tgt, t0, speed, law = (np.concatenate(cols[k]) for k in cols)
    # dedupe (overlapping windows of the same target cannot occur, but be safe)
    key = np.unique(
        np.stack([sat, tgt, np.round(t0 / step).astype(np.int64), law]), axis=1, return_index=True
    )[1]
    sat, tgt, t0, speed, law = sat[key], tgt[key], t0[key], speed[key], law[key]
    params = np.stack([lw[1] for lw in laws])[law, tgt]
    t1 = t0 + np.stack([lw[2] for lw in laws])[law, tgt]
    return _Candidates(sat, tgt, t0, t1, speed, params)


def _start_range(sc: Scenario, windows: Windows, keep, strip, dur):
    """The first and last action-grid indices ``k`` (int [W], empty when k_lo > k_hi) of
    the starts ``k * time_step`` of the windows ``keep`` (``strip``: their targets are
    strips; ``dur``: imaging times [s]) whose observation fits: the visibility window
    (a strip's widened by half its scan, its midpoint being the reference point), the
    target's imaging window, the horizon [0, duration] and the midpoint window; none
    when ``dur`` is short of the target's ``min_duration``."""
    tg = sc.targets
    step = sc.planner.time_step
    w_tgt = windows.target[keep]
    half = np.where(strip, dur / 2.0, 0.0)
    lo = np.maximum(windows.lo[keep] - half, tg.t_lo[w_tgt])
    hi = np.minimum(windows.hi[keep] + half, tg.t_hi[w_tgt])
    hi = np.minimum(hi, sc.duration) - dur
    # the imaging midpoint start + dur / 2 within [mid_lo, mid_hi]; long enough
    lo = np.maximum(lo, tg.mid_lo[w_tgt] - dur / 2.0)
    hi = np.minimum(hi, tg.mid_hi[w_tgt] - dur / 2.0)
    hi = np.where(dur >= tg.min_duration[w_tgt] - _DURATION_TOL, hi, -step)
    k_lo = np.ceil(np.maximum(lo, 0.0) / step - 1e-9).astype(np.int64)
    k_hi = np.floor(hi / step + 1e-9).astype(np.int64)
    return k_lo, k_hi


def _samples_ok(
    sc: Scenario, scene: Scene, table_ok, cand: _Candidates, per_ch, tick=None
) -> np.ndarray:
    """bool [N]: the candidate holds at every sample (start, every geometry knot inside,
    end): the off-nadir limit minus margin, the horizon margin, the usable ephemeris and,
    on ``per_ch`` satellites, a flyable scan (:func:`_scan_flyable`). Point candidates of
    rest-to-rest satellites starting and ending on knots pass unsampled (their window
    was computed on every knot). ``tick(share)``: the clock, while the geometry is
    evaluated."""
    pc = sc.planner
    gstep = pc.geometry_step
    limit = np.array([s.off_nadir_max for s in sc.satellites]) - pc.margins.off_nadir
    sat, t0, t1, params = cand.sat, cand.t0, cand.t1, cand.params
    ok = np.ones(sat.size, bool)
    # samples: start, every knot inside, end (points on knots: window already exact)
    on_knots = (np.abs(t0 / gstep - np.round(t0 / gstep)) < _GRID_TOL / gstep) & (
        np.abs(t1 / gstep - np.round(t1 / gstep)) < _GRID_TOL / gstep
    )
    need = (sc.targets.kind[cand.tgt] == STRIP) | ~on_knots | per_ch[sat]
    idx = np.flatnonzero(need)
    if idx.size:
        owner, ts = observation_samples(t0[idx], t1[idx], gstep)
        o = idx[owner]
        share = None if tick is None else (lambda x: tick(_SAMPLES_SHARE * x))
        offn, elev, _, _ = evaluate(geometry_batched, scene, sat[o], params[o], t0[o], ts, share)
        good = (offn <= limit[sat[o]]) & (elev > pc.margins.horizon) & table_ok(sat[o], ts)
        if per_ch.any():
            pcm = per_ch[sat[o]]
            fly = _scan_flyable(
                sc.satellites, scene, sat[o][pcm], params[o][pcm], t0[o][pcm], ts[pcm]
            )
            if fly is not None:
                good[pcm] &= fly
        bad = np.zeros(idx.size, bool)
        np.logical_or.at(bad, owner, ~good)
        ok[idx] = ~bad
    return ok


def _scan_flyable(sats, scene: Scene, sat, params, t0, ts):
    """bool [M] (None when M = 0): at the samples ``ts`` [s] of the laws ``params``
    started at ``t0`` on the per-channel satellites ``sat``, every channel's rate and
    acceleration are finite and within the satellite's limits (to ``_LIMIT_TOL``)."""
    res = evaluate(state_batched, scene, sat, params, t0, ts)
    if res is None:
        return None
    _, rate, acc = res
    rl, al = _limit_table(sats, "rate"), _limit_table(sats, "accel")
    fly = np.all(np.abs(rate) <= rl[sat] * (1 + _LIMIT_TOL), -1) & np.all(
        np.abs(acc) <= al[sat] * (1 + _LIMIT_TOL), -1
    )
    return fly & np.isfinite(rate).all(-1)


def _sun_ok(sc: Scenario, scene: Scene, cand: _Candidates) -> np.ndarray:
    """bool [N]: the Sun is at least ``sun_elevation_min`` above the target's horizon at
    the candidate's start."""
    tg = sc.targets
    t0 = cand.t0
    jd = sc.epoch_jd + t0 / 86400.0
    sun_e = rot_z(earth_rotation_angle(float(scene.gmst0), t0), sun_direction(jd))
    el = sun_elevation(tg.lat[cand.tgt], tg.lon[cand.tgt], sun_e)
    return el >= sc.planner.sun_elevation_min


def option_states(sc, scene, sat, tgt, t0, t1, params, per_ch) -> RouteOptions:
    """The option table of given options: boundary lines of sight and nadirs, and (with
    ``per_ch``) the boundary attitude states per channel."""
    n = sat.size
    zeros = np.zeros((n, 3))
    st = evaluate(geometry_batched, scene, sat, params, t0, t0)
    en = evaluate(geometry_batched, scene, sat, params, t0, t1)
    los0, nad0 = (st[2], st[3]) if n else (zeros, zeros)
    los1 = en[2] if n else zeros
    a0, r0, a1, r1 = zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy()
    m = per_ch[sat] if n else np.zeros(0, bool)
    if m.any():
        s0 = evaluate(state_batched, scene, sat[m], params[m], t0[m], t0[m])
        s1 = evaluate(state_batched, scene, sat[m], params[m], t0[m], t1[m])
        a0[m], r0[m], a1[m], r1[m] = s0[0], s0[1], s1[0], s1[1]
    return RouteOptions(
        route=tgt,
        t_start=t0,
        t_end=t1,
        start_angle=a0,
        start_rate=r0,
        end_angle=a1,
        end_rate=r1,
        value=np.asarray(sc.targets.value)[tgt],
        scan_ok=np.ones(n, bool),
        sat=sat,
        start_los=los0,
        end_los=los1,
        start_nadir=nad0,
    )


def nadir_rate(scene: Scene) -> np.ndarray:
    """Per satellite: the largest inertial turn rate of the nadir direction (with a safety factor).

    Args:
      scene: Scene with a HermiteOrbit of S satellites ([S, M, 3] tables).
    Returns:
      numpy float [S], rate [rad/s].
    """
    r = np.asarray(scene.orbit.r)
    v = np.asarray(scene.orbit.v)
    rate = np.linalg.norm(np.cross(r, v), axis=-1) / np.sum(r * r, axis=-1)
    return rate.max(axis=1) * (1.0 + _NADIR_RATE_SAFETY)
