"""Visibility windows: every pass of every satellite over every target, over the whole horizon.

A target's reference point (a point target, or a strip's midpoint) is *visible* from
satellite s at time t when it is above its local horizon and inside the off-nadir
cone: ``elevation_sine > horizon`` and ``off_nadir <= off_nadir_max[s] - margin``
(:func:`jaxspline.geometry.pointing.aim_geometry`). Windows are the maximal intervals of
visibility, clipped to the target's imaging window and the planning horizon, and only
for satellites whose sensor the target accepts.

Method (vectorized, no per-pair loop): the satellites' Earth-fixed positions at the
knots of the orbit table are compared with all targets in blocks. A coarse pass every
``coarse`` knots keeps the (target, instant) pairs whose Earth-central angle is within
the cone's ground radius widened by the ground track's motion over half a stride (so
no visible knot is dropped); only those are evaluated exactly at every knot. Runs of
consecutive visible knots give the windows at knot resolution (exact on a geometry
grid: the knots ARE the grid instants).

Units: metres, seconds, radians.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from jaxspline.base.elements import gmst
from jaxspline.geometry.frames import angle_between, earth_rotation_angle, rot_z
from jaxspline.geometry.orbit import tabulate_orbits
from jaxspline.geometry.pointing import Scene, off_nadir_flat
from jaxspline.kernels.validate import check_positive

__all__ = [
    "WindowWork",
    "Windows",
    "orbit_scene",
    "visibility_windows",
    "visibility_windows_all",
    "window_work",
]

_COARSE = 12  # knots per coarse step of the pre-screen
_SAFETY_ANGLE = math.radians(0.5)  # extra Earth-central angle of the pre-screen [rad]
_BLOCK = 512  # targets per pre-screen block
_HALF = _COARSE // 2 + 1  # fine knots each side of a near coarse knot
_SAMPLE = 64  # targets a satellite's work is estimated from (window_work)


class Windows(NamedTuple):
    """W visibility windows (numpy arrays [W]), sorted by (sat, target, lo).

    Attributes:
      sat, target: int indices into ``scenario.satellites`` / ``scenario.targets``.
      lo, hi: first and last visible knot [s] (the reference point is visible at
        every knot of [lo, hi]).
    """

    sat: np.ndarray
    target: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    def __len__(self) -> int:
        return int(self.sat.shape[0])


def _visible(offn, elev, limit, horizon):
    return (elev > horizon) & (offn <= limit)


def _exact_numpy(r_e, g):
    """(off_nadir, elevation_sine) of Earth-fixed points g seen from r_e (numpy, [..., 3])."""
    d = g - r_e
    dn = np.linalg.norm(d, axis=-1)
    offn = angle_between(d, -r_e)
    elev = np.sum(-d * g, axis=-1) / (dn * np.linalg.norm(g, axis=-1))
    return offn, elev


class _Knots(NamedTuple):
    """The orbit table's time grid."""

    t: np.ndarray  # [M] knot times [s]
    step: float  # knot spacing [s]
    in_horizon: np.ndarray  # bool [M], the knot lies in [0, duration]
    theta: np.ndarray  # [M] Earth rotation angle at the knots [rad]


class _Cone(NamedTuple):
    """One satellite's Earth-fixed knots and its coarse pre-screen."""

    r_e: np.ndarray  # [M, 3] Earth-fixed positions [m]
    good: np.ndarray  # bool [M], valid knots inside the horizon
    limit: float  # off-nadir limit [rad]
    coarse: np.ndarray  # [Mc] the coarse knots (every _COARSE-th)
    u_coarse: np.ndarray  # [Mc, 3] unit positions at the coarse knots
    cos_c: float  # cosine of the pre-screen's Earth-central angle


def _satellite_cone(knots: _Knots, r_teme, good, limit: float, r_min_t: float) -> _Cone:
    """The pre-screen of one satellite: the cone's ground radius (Earth-central angle of
    the off-nadir limit seen from the highest knot over the lowest target) widened by the
    ground track's motion over half a coarse stride and a safety angle."""
    r_e = rot_z(knots.theta, r_teme)
    rn = np.linalg.norm(r_e, axis=-1)
    u = r_e / rn[:, None]
    lam = math.asin(min(1.0, rn.max() / r_min_t * math.sin(limit))) - limit
    track = np.arccos(np.clip(np.sum(u[1:] * u[:-1], axis=-1), -1.0, 1.0)).max()
    widen = track * (_COARSE / 2 + 1) + _SAFETY_ANGLE
    kc = np.arange(0, knots.t.size, _COARSE)
    return _Cone(r_e, good, limit, kc, u[kc], math.cos(min(math.pi, lam + widen)))


def _near_knots(knots: _Knots, cone: _Cone, g_hat, tb, lo_t, hi_t):
    """(target, knot) pairs of the block ``tb`` that may be visible: every knot within
    half a coarse stride (plus one) of a coarse knot inside the widened cone, valid,
    and inside the target's imaging window. Returns (ti, ks) int [P] each."""
    m, tc = knots.t.size, knots.t[cone.coarse]
    near = (g_hat[tb] @ cone.u_coarse.T) > cone.cos_c
    near &= (tc[None, :] >= lo_t[tb, None] - _COARSE * knots.step) & (
        tc[None, :] <= hi_t[tb, None] + _COARSE * knots.step
    )
    ii, ci = np.nonzero(near)
    half = np.arange(-_HALF, _HALF + 1)
    ks = np.clip((cone.coarse[ci][:, None] + half[None, :]).ravel(), 0, m - 1)
    key = np.unique(np.repeat(ii, half.size) * m + ks)
    ii, ks = key // m, key % m
    ti = tb[ii]
    tk = knots.t
    keep = cone.good[ks] & (tk[ks] >= lo_t[ti] - 1e-9) & (tk[ks] <= hi_t[ti] + 1e-9)
    return ti[keep], ks[keep]


def _runs(ti, ks):
    """First and last positions of the runs of consecutive knots of one target."""
    brk = np.ones(ti.size, bool)
    brk[1:] = (ti[1:] != ti[:-1]) | (ks[1:] != ks[:-1] + 1)
    first = np.flatnonzero(brk)
    return first, np.append(first[1:], ti.size) - 1


def _sorted_windows(out: dict) -> Windows:
    """The collected windows as one :class:`Windows` sorted by (sat, target, lo)."""
    if not out["sat"]:
        z = np.zeros(0)
        return Windows(z.astype(np.int64), z.astype(np.int64), z, z)
    w = Windows(*(np.concatenate(out[k]) for k in ("sat", "target", "lo", "hi")))
    w = Windows(w.sat.astype(np.int64), w.target.astype(np.int64), w.lo, w.hi)
    order = np.lexsort((w.lo, w.target, w.sat))
    return Windows(*(x[order] for x in w))


class _Grid(NamedTuple):
    """The knots, the satellites' positions and the targets of one windows call."""

    knots: _Knots
    r: np.ndarray  # [S, M, 3] TEME positions at the knots [m]
    g: np.ndarray  # [R, 3] Earth-fixed reference points [m]
    g_hat: np.ndarray  # [R, 3] their unit vectors
    r_min_t: float  # the lowest target's geocentric radius [m]
    lo_t: np.ndarray  # [R] the targets' windows clipped to the horizon [s]
    hi_t: np.ndarray

    @classmethod
    def of(cls, scene: Scene, points_ecef, t_lo, t_hi, duration: float) -> _Grid:
        """The grid of :func:`visibility_windows_all`'s arguments."""
        tk = np.asarray(scene.orbit.t)
        in_h = (tk >= -1e-9) & (tk <= duration + 1e-9)
        knots = _Knots(tk, tk[1] - tk[0], in_h, earth_rotation_angle(float(scene.gmst0), tk))
        g = np.asarray(points_ecef, np.float64)
        g_hat = g / np.linalg.norm(g, axis=-1, keepdims=True)
        r_min_t = float(np.min(np.linalg.norm(g, axis=-1))) if len(g) else 1.0
        lo_t = np.maximum(np.asarray(t_lo, np.float64), 0.0)
        hi_t = np.minimum(np.asarray(t_hi, np.float64), duration)
        return cls(knots, np.asarray(scene.orbit.r), g, g_hat, r_min_t, lo_t, hi_t)

    def satellite(self, s: int, ok_knots, allowed, off_nadir_limit):
        """(tasks, cone) of satellite ``s``: its targets' indices and its pre-screen
        (None when it has no target or no valid knot)."""
        tasks = np.flatnonzero(allowed[s] & (self.lo_t <= self.hi_t))
        good_k = ok_knots[s] & self.knots.in_horizon
        if tasks.size == 0 or not good_k.any():
            return tasks, None
        limit = float(off_nadir_limit[s])
        return tasks, _satellite_cone(self.knots, self.r[s], good_k, limit, self.r_min_t)


class WindowWork(NamedTuple):
    """Upper-ish size of a :func:`visibility_windows_all` call (:func:`window_work`).

    Attributes:
      cells: (target, coarse knot) cells of its largest block of targets.
      pairs: (target, knot) pairs its largest block evaluates (before duplicates go).
      windows: windows of all satellites.
      knots: knots of the orbit table.
    """

    cells: int
    pairs: int
    windows: int
    knots: int


def window_work(
    scene: Scene,
    ok_knots: np.ndarray,
    points_ecef: np.ndarray,
    allowed: np.ndarray,
    off_nadir_limit: np.ndarray,
    horizon: float,
    t_lo: np.ndarray,
    t_hi: np.ndarray,
    duration: float,
) -> WindowWork:
    """The work of :func:`visibility_windows_all` on the same arguments, before it runs.

    Every satellite's pre-screen is run on an evenly spread sample of at most
    ``_SAMPLE`` (64) of its targets; the target of the sample nearest the most coarse
    knots, and the one with the most runs of them, stand for every target of the
    satellite (an upper-ish estimate: targets sorted by place give blocks of like
    targets). Costs the pre-screen of 64 targets a satellite.

    Args:
      scene, ok_knots, points_ecef, allowed, off_nadir_limit, horizon, t_lo, t_hi,
        duration: as :func:`visibility_windows_all` (``horizon`` unused: the estimate
        counts every near knot as visible).
    Returns:
      :class:`WindowWork`.
    """
    grid = _Grid.of(scene, points_ecef, t_lo, t_hi, duration)
    cells = pairs = windows = 0
    for s in range(grid.r.shape[0]):
        tasks, cone = grid.satellite(s, ok_knots, allowed, off_nadir_limit)
        if cone is None:
            continue
        pick = tasks[np.unique(np.linspace(0, tasks.size - 1, _SAMPLE).astype(int))]
        near = (grid.g_hat[pick] @ cone.u_coarse.T) > cone.cos_c
        runs = near[:, 0].astype(int) + (near[:, 1:] & ~near[:, :-1]).sum(axis=1)
        block = min(_BLOCK, tasks.size)
        cells = max(cells, block * cone.coarse.size)
        pairs = max(pairs, block * int(near.sum(axis=1).max()) * (2 * _HALF + 1))
        windows += tasks.size * int(runs.max())
    return WindowWork(cells, pairs, windows, grid.knots.t.size)


def visibility_windows_all(
    scene: Scene,
    ok_knots: np.ndarray,
    points_ecef: np.ndarray,
    allowed: np.ndarray,
    off_nadir_limit: np.ndarray,
    horizon: float,
    t_lo: np.ndarray,
    t_hi: np.ndarray,
    duration: float,
    tick=None,
) -> Windows:
    """All visibility windows of R points from S satellites of a tabulated ``scene``.

    Args:
      scene: :class:`Scene` whose orbit is a multi-satellite HermiteOrbit [S, M, 3].
      ok_knots: bool [S, M], knots where the orbit is valid (SGP4 succeeded).
      points_ecef: [R, 3] Earth-fixed reference points [m].
      allowed: bool [S, R], satellite s may image target r (sensor type).
      off_nadir_limit: [S] off-nadir limit minus margin [rad].
      horizon: the elevation sine must exceed this.
      t_lo: [R] start of each target's window [s] (-inf: free).
      t_hi: [R] end of each target's window [s] (+inf: free).
      duration: horizon end [s] (windows lie in [0, duration]).
      tick: optional ``tick(share done)`` called before every block of targets (a
        clock that may stop the call by raising; the windows do not depend on it).
    Returns:
      :class:`Windows`.
    """
    grid = _Grid.of(scene, points_ecef, t_lo, t_hi, duration)
    knots, g, lo_t, hi_t = grid.knots, grid.g, grid.lo_t, grid.hi_t
    tk = knots.t
    out = {"sat": [], "target": [], "lo": [], "hi": []}
    s_count = grid.r.shape[0]
    for s in range(s_count):
        tasks, cone = grid.satellite(s, ok_knots, allowed, off_nadir_limit)
        if cone is None:
            continue
        for b0 in range(0, tasks.size, _BLOCK):
            if tick is not None:
                tick((s + b0 / tasks.size) / s_count)
            ti, ks = _near_knots(knots, cone, grid.g_hat, tasks[b0 : b0 + _BLOCK], lo_t, hi_t)
            offn, elev = _exact_numpy(cone.r_e[ks], g[ti])
            vis = _visible(offn, elev, cone.limit, horizon)
            ti, ks = ti[vis], ks[vis]
            if ti.size == 0:
                continue
            first, last = _runs(ti, ks)
            out["sat"].append(np.full(first.size, s))
            out["target"].append(ti[first])
            out["lo"].append(tk[ks[first]])
            out["hi"].append(tk[ks[last]])
    return _sorted_windows(out)


def visibility_windows(scene: Scene, targets_ecef, t_begin, t_end, max_off_nadir, step=10.0):
    """Intervals where each ground point is within ``max_off_nadir`` of nadir.

    The off-nadir angle is sampled every ``step`` seconds on [t_begin, t_end]; each
    sign change of ``off_nadir - max_off_nadir`` is refined by 50 bisection steps
    (vectorized over all crossings). A window narrower than ``step`` can be missed.

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      targets_ecef: float [K, 3], ground points, Earth-fixed [m].
      t_begin: float, start of the search [s from the epoch].
      t_end: float, end of the search [s from the epoch].
      max_off_nadir: float, off-nadir limit [rad].
      step: float, sampling step [s].
    Returns:
      list of K float64 arrays [W, 2] of (start, end) [s from the epoch].
    """
    check_positive("max_off_nadir", max_off_nadir)
    check_positive("step", step)
    if not t_end > t_begin:
        raise ValueError(f"t_end must be > t_begin, got t_begin={t_begin!r}, t_end={t_end!r}")
    targets = np.asarray(targets_ecef, dtype=np.float64).reshape(-1, 3)
    m = int(np.ceil((t_end - t_begin) / step)) + 1
    grid = np.linspace(t_begin, t_end, m)
    nt = targets.shape[0]
    g = off_nadir_flat(scene, np.repeat(targets, m, 0), np.tile(grid, nt)).reshape(nt, m)
    g = g - max_off_nadir
    inside = g <= 0
    ti, ki = np.nonzero(inside[:, 1:] != inside[:, :-1])
    lo, hi = grid[ki].copy(), grid[ki + 1].copy()
    if ti.size:
        lo_in = inside[ti, ki]
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            gm = off_nadir_flat(scene, targets[ti], mid) - max_off_nadir
            same = (gm <= 0) == lo_in
            lo = np.where(same, mid, lo)
            hi = np.where(same, hi, mid)
    cross = 0.5 * (lo + hi)
    out = []
    for i in range(targets.shape[0]):
        sel = ti == i
        edges = list(cross[sel])
        if inside[i, 0]:
            edges.insert(0, grid[0])
        if inside[i, -1]:
            edges.append(grid[-1])
        out.append(np.asarray(edges, dtype=np.float64).reshape(-1, 2))
    return out


def orbit_scene(sc):
    """Orbit table and :class:`Scene` of a scenario's satellites, as the planner builds them.

    Args:
      sc: :class:`jaxspline.readers.mission.Scenario`.
    Returns:
      (OrbitTable on the common geometry-step knots, Scene of all satellites).
    """
    table = tabulate_orbits(
        [s.orbit for s in sc.satellites], sc.epoch_jd, sc.duration, sc.planner.geometry_step
    )
    return table, Scene(table.orbit, np.float64(gmst(sc.epoch_jd)))
