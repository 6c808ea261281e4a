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

from jaxspline.geometry.frames import angle_between, earth_rotation_angle, rot_z
from jaxspline.geometry.pointing import Scene

__all__ = ["Windows", "visibility_windows_all"]

_COARSE = 12  # knots per coarse step of the pre-screen
_SAFETY_ANGLE = math.radians(0.5)  # extra Earth-central angle of the pre-screen [rad]
_BLOCK = 512  # targets per pre-screen block


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
    orbit = scene.orbit
    tk = np.asarray(orbit.t)
    rk = np.asarray(orbit.r)
    s_count, m = rk.shape[0], tk.size
    step = tk[1] - tk[0]
    in_h = (tk >= -1e-9) & (tk <= duration + 1e-9)
    theta = earth_rotation_angle(float(scene.gmst0), tk)
    g = np.asarray(points_ecef, np.float64)
    g_hat = g / np.linalg.norm(g, axis=-1, keepdims=True)
    r_min_t = float(np.min(np.linalg.norm(g, axis=-1))) if len(g) else 1.0
    lo_t = np.maximum(np.asarray(t_lo, np.float64), 0.0)
    hi_t = np.minimum(np.asarray(t_hi, np.float64), duration)
    out = {"sat": [], "target": [], "lo": [], "hi": []}
    for s in range(s_count):
        tasks = np.flatnonzero(allowed[s] & (lo_t <= hi_t))
        good_k = ok_knots[s] & in_h
        if tasks.size == 0 or not good_k.any():
            continue
        r_e = rot_z(theta, rk[s])
        rn = np.linalg.norm(r_e, axis=-1)
        u = r_e / rn[:, None]
        eta = float(off_nadir_limit[s])
        cos_c = _coarse_cos(u, rn, r_min_t, eta)
        kc = np.arange(0, m, _COARSE)
        uc = u[kc]
        half = np.arange(-(_COARSE // 2) - 1, _COARSE // 2 + 2)
        for b0 in range(0, tasks.size, _BLOCK):
            if tick is not None:
                tick((s + b0 / tasks.size) / s_count)
            tb = tasks[b0 : b0 + _BLOCK]
            near = _coarse_near(g_hat[tb], uc, tk[kc], lo_t[tb], hi_t[tb], _COARSE * step, cos_c)
            ii, ci = np.nonzero(near)
            if ii.size == 0:
                continue
            ks = np.clip((kc[ci][:, None] + half[None, :]).ravel(), 0, m - 1)
            key = np.unique(np.repeat(ii, half.size) * m + ks)
            ii, ks = key // m, key % m
            ti = tb[ii]
            keep = good_k[ks] & (tk[ks] >= lo_t[ti] - 1e-9) & (tk[ks] <= hi_t[ti] + 1e-9)
            ti, ks = ti[keep], ks[keep]
            offn, elev = _exact_numpy(r_e[ks], g[ti])
            vis = _visible(offn, elev, eta, horizon)
            ti, ks = ti[vis], ks[vis]
            if ti.size == 0:
                continue
            first, last = _runs(ti, ks)
            out["sat"].append(np.full(first.size, s))
            out["target"].append(ti[first])
            out["lo"].append(tk[ks[first]])
            out["hi"].append(tk[ks[last]])
    return _collect(out)


def _coarse_cos(u, rn, r_min_t: float, eta: float) -> float:
    """Cosine of the pre-screen's Earth-central angle for one satellite (unit positions
    ``u`` [M, 3], radii ``rn`` [M] [m], nearest target radius ``r_min_t`` [m], off-nadir
    limit ``eta`` [rad]): the cone's ground radius widened by the track over half a
    coarse stride and a safety angle (module docstring)."""
    lam = math.asin(min(1.0, rn.max() / r_min_t * math.sin(eta))) - eta
    track = np.arccos(np.clip(np.sum(u[1:] * u[:-1], axis=-1), -1.0, 1.0)).max()
    widen = track * (_COARSE / 2 + 1) + _SAFETY_ANGLE
    return math.cos(min(math.pi, lam + widen))


def _coarse_near(g_hat, uc, tc, lo, hi, pad: float, cos_c: float):
    """bool [B, C]: targets (unit vectors ``g_hat`` [B, 3], windows [lo, hi] [s]) within
    the pre-screen angle of the coarse knots (unit positions ``uc`` [C, 3] at ``tc`` [s])
    inside their window widened by ``pad`` [s]."""
    near = (g_hat @ uc.T) > cos_c
    return near & (tc[None, :] >= lo[:, None] - pad) & (tc[None, :] <= hi[:, None] + pad)


def _runs(ti, ks):
    """First and last index of every run of consecutive knots ``ks`` of one target ``ti``
    (both sorted by target, then knot)."""
    brk = np.ones(ti.size, bool)
    brk[1:] = (ti[1:] != ti[:-1]) | (ks[1:] != ks[:-1] + 1)
    first = np.flatnonzero(brk)
    return first, np.append(first[1:], ti.size) - 1


def _collect(out: dict) -> Windows:
    """The windows of the lists ``out`` (sat, target, lo, hi), sorted by (sat, target, lo)."""
    if not out["sat"]:
        z = np.zeros(0)
        return Windows(z.astype(np.int64), z.astype(np.int64), z, z)
    w = Windows(*(np.concatenate(out[k]) for k in ("sat", "target", "lo", "hi")))
    w = Windows(w.sat.astype(np.int64), w.target.astype(np.int64), w.lo, w.hi)
    order = np.lexsort((w.lo, w.target, w.sat))
    return Windows(*(x[order] for x in w))
