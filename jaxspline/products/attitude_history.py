"""Attitude history of a plan: scan laws, degree-7 joins and nadir hold, sampled per satellite.

:func:`attitude_history` turns a :class:`jaxspline.planner.result.PlanResult` into what a
flight-dynamics tool reads: per satellite, on a user-chosen step plus every junction
instant, the body -> TEME quaternion (scalar first), the body rates ω and the angular
acceleration ε (body axes, relative to TEME) and ε'. Frames, body axes and yaw
conventions: :mod:`jaxspline.planner.attitude_laws`; join timing, check and re-timing:
:mod:`jaxspline.planner.flown_joins` (the same joins :func:`jaxspline.plan` checked).

On ``[0, duration]`` each satellite follows, in time order: the nadir law, the join
from nadir to its first observation, each observation's scan law (extended into the
next join's interval when that join was re-timed), the join to the next observation
(or to nadir and back around long gaps), and after the last observation the join back
to nadir and the nadir law. The quaternion sign is chosen continuous along the samples.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import numpy as np

from jaxspline.geometry.pointing import Scene, roll_params
from jaxspline.geometry.routes import STRIP
from jaxspline.geometry.windows import orbit_scene
from jaxspline.kernels.joins import Maneuver, maneuver_eval
from jaxspline.planner.attitude_laws import NADIR_LAW, law_modes, law_states
from jaxspline.planner.flown_joins import NADIR, Joins, join_summary, plan_joins
from jaxspline.planner.opportunities import aim_laws

__all__ = ["PHASES", "AttitudeHistory", "PlanAttitude", "attitude_history", "plan_scene"]

PHASES = ("nadir", "observation", "hold", "join")  # phase codes 0..3 of the samples
_NADIR, _OBSERVATION, _HOLD, _JOIN = range(4)
_TIME_TOL = 1e-9  # [s] sample instants closer than this are one instant


class AttitudeHistory(NamedTuple):
    """The attitude of one satellite at N instants (numpy).

    Attributes:
      t: [N] seconds from the scenario epoch (the step grid on [0, duration] and every
        junction instant inside it), increasing.
      q: [N, 4] unit quaternion body -> TEME, scalar first ``[w, x, y, z]``, sign
        continuous.
      omega: [N, 3] body angular velocity relative to TEME, body axes [rad/s].
      accel: [N, 3] angular acceleration dω/dt, body axes [rad/s²].
      jerk: [N, 3] dε/dt, body axes [rad/s³].
      phase: [N] int: index into :data:`PHASES`.
      segment: [N] int: the observation index (observation, hold) or join index
        (join) into the :class:`PlanAttitude` tables; -1 for nadir.
    """

    t: np.ndarray
    q: np.ndarray
    omega: np.ndarray
    accel: np.ndarray
    jerk: np.ndarray
    phase: np.ndarray
    segment: np.ndarray


class PlanAttitude(NamedTuple):
    """What :func:`attitude_history` returns.

    Attributes:
      histories: ``{satellite name: AttitudeHistory}`` for every satellite.
      joins: :class:`jaxspline.planner.flown_joins.Joins` (``before`` / ``after`` index the
        plan's observations).
      summary: :func:`jaxspline.planner.flown_joins.join_summary` plus ``step_s``.
    """

    histories: dict
    joins: Joins
    summary: dict


def plan_scene(sc) -> Scene:
    """The planner's multi-satellite :class:`Scene` of a scenario (same knots as ``plan``).

    Args:
      sc: Scenario.
    Returns:
      Scene with a HermiteOrbit of all satellites.
    """
    return orbit_scene(sc)[1]


def observation_laws(sc, target, speed, roll=None, pitch=None) -> np.ndarray:
    """Aim laws [K, 8] of observations (targets [K], scan speeds [K] [m/s], 0 for points;
    ``roll``, ``pitch`` [K] [rad], the held offset of area strips, NaN for the others)."""
    laws = aim_laws(sc)
    speeds = np.array([lw[0] for lw in laws])
    target, speed = np.asarray(target, np.int64), np.asarray(speed, np.float64)
    strip = sc.targets.kind[target] == STRIP
    li = np.argmin(np.abs(speed[:, None] - speeds[None, :]), -1)
    if np.any(strip & ~np.isclose(speed, speeds[li], rtol=1e-12, atol=0.0)):
        raise ValueError(f"speed: a strip's scan speed is not a planner speed {speeds.tolist()}")
    out = np.stack([lw[1] for lw in laws])[np.where(strip, li, 0), target]
    if roll is not None:
        area = np.isfinite(np.asarray(roll, np.float64))
        if area.any():
            r, p = (np.asarray(x, np.float64)[area] for x in (roll, pitch))
            out[area] = np.asarray(roll_params(r, p))
    return out


def attitude_history(result, step: float = 1.0) -> PlanAttitude:
    """Attitude history of every satellite of a plan (module docstring), in float64.

    Args:
      result: a :class:`jaxspline.planner.result.PlanResult`.
      step: sample spacing [s] (> 0); junction instants are added to the grid.
    Returns:
      :class:`PlanAttitude`.
    """
    if not (isinstance(step, int | float) and math.isfinite(step) and step > 0):
        raise ValueError(f"step must be a number > 0 [s], got {step!r}")
    with jax.enable_x64(True):  # as plan(): float64 inside, the global setting untouched
        return _history(result, float(step))


def _history(result, step: float) -> PlanAttitude:
    sc = result.scenario
    obs = result.observations
    scene = plan_scene(sc)
    params = observation_laws(sc, obs.target, obs.speed, obs.roll, obs.pitch)
    joins = plan_joins(scene, sc.satellites, obs.sat, obs.start, obs.end, params)
    mode = law_modes(sc.satellites)
    grid = np.arange(0.0, sc.duration + _TIME_TOL, float(step))
    hist = {}
    for k, s in enumerate(sc.satellites):
        jk = np.flatnonzero(joins.sat == k)
        edges = np.stack([joins.t_start[jk], joins.t_end[jk]], -1).reshape(-1)
        mine = obs.sat == k
        t = np.concatenate([grid, edges, obs.start[mine], obs.end[mine]])
        t = np.unique(t[(t >= 0.0) & (t <= sc.duration + _TIME_TOL)])
        t = t[np.concatenate([[True], np.diff(t) > _TIME_TOL])]
        pos = np.searchsorted(edges, t, side="right")
        in_join = pos % 2 == 1
        region = pos // 2  # law region r: after join r-1 (r >= 1), before join 0 (r = 0)
        law_obs = np.where(
            region == 0,
            joins.before[jk][0] if jk.size else NADIR,
            joins.after[jk][np.maximum(region - 1, 0)] if jk.size else NADIR,
        )
        q = np.zeros((t.size, 4))
        w, e, d = (np.zeros((t.size, 3)) for _ in range(3))
        law_rows = np.flatnonzero(~in_join)
        lo = law_obs[law_rows]
        law = np.tile(NADIR_LAW, (lo.size, 1))
        is_obs = lo != NADIR
        law[is_obs, :8] = params[lo[is_obs]]
        law[is_obs, 8] = mode[k]
        t0 = np.where(is_obs, obs.start[np.maximum(lo, 0)], 0.0) if len(obs) else np.zeros(lo.size)
        st = law_states(scene, np.full(lo.size, k), law, t0, t[law_rows])
        for dst, src in zip((q, w, e, d), st, strict=True):
            dst[law_rows] = src
        j_rows = np.flatnonzero(in_join)
        if j_rows.size:
            ji = jk[(pos[j_rows] - 1) // 2]
            man = Maneuver(joins.q_ref[ji], joins.coeffs[ji], joins.t_end[ji] - joins.t_start[ji])
            tau = np.clip(t[j_rows] - joins.t_start[ji], 0.0, man.duration)
            for dst, src in zip((q, w, e, d), maneuver_eval(man, tau), strict=True):
                dst[j_rows] = np.asarray(src)
        phase = np.full(t.size, _JOIN)
        seg = np.where(in_join, 0, law_obs)
        if j_rows.size:
            seg[j_rows] = ji
        lt = t[law_rows]
        inside = (
            is_obs
            & (lt >= obs.start[np.maximum(lo, 0)] - _TIME_TOL)
            & (lt <= obs.end[np.maximum(lo, 0)] + _TIME_TOL)
            if len(obs)
            else np.zeros(lo.size, bool)
        )
        phase[law_rows] = np.where(is_obs, np.where(inside, _OBSERVATION, _HOLD), _NADIR)
        hist[s.name] = AttitudeHistory(t, _continuous(q), w, e, d, phase, seg)
    summary = {**join_summary(joins), "step_s": float(step)}
    return PlanAttitude(hist, joins, summary)


def _continuous(q: np.ndarray) -> np.ndarray:
    """Flip quaternion signs so that consecutive samples have a non-negative dot product."""
    if q.shape[0] < 2:
        return q
    flip = np.sum(q[1:] * q[:-1], -1) < 0.0
    sign = np.concatenate([[1.0], np.where(np.cumsum(flip) % 2 == 1, -1.0, 1.0)])
    return q * sign[:, None]
