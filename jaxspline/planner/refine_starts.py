"""Start-time refinement of per-channel satellites' sequences (optax, through the reach margins).

The search picks starts on the action grid. For a ``per_channel`` satellite the
transition margins are differentiable in the start times, so each such satellite's
sequence is refined by :func:`jaxspline.sequences.refine_plan` (Adam on the soft minimum of the
reach margins, starts projected into their windows) inside a window of half an action
step to each side of every chosen start where the neighbouring grid start of the same
target, satellite and scan speed is an option too (then every start in between keeps
the observation inside its visibility pass), clipped to the target's imaging window
and the horizon. The boundary states as functions of the start shift ``delta`` are the
quadratic through the exact states at ``delta = -h, 0, +h`` (h = half a step): cheap
to compile, exact at the grid start. The refined starts replace the grid ones only if
the whole plan, with states recomputed exactly, passes the independent re-check
(:func:`jaxspline.planner.plan_check.check_plan`) - the caller's job - and the smallest
transition margin of the satellite did not shrink.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.planner.context import PlanContext
from jaxspline.planner.opportunities import Opportunities, option_states
from jaxspline.readers.mission import HELD_KINDS
from jaxspline.screen.options import take_options
from jaxspline.sequences.refine import refine_plan
from jaxspline.sequences.sequencer import Plan

__all__ = ["refine_starts"]

_LEARNING_RATE = 0.05  # Adam step in fractions of each start window
_SAMPLES = 201  # validation samples per maneuver inside refine_plan
_MIN_BUCKET = 64  # sequences are padded to a power of two >= this (shared compilations)
_PAD_GAP = 1e4  # [s] spacing of the padding observations after the last real one


class _QuadraticStarts(NamedTuple):
    """RouteModel: states of observation k at start ``t_ref[k] + delta``, quadratic in delta."""

    t_ref: jnp.ndarray  # [K]
    dur: jnp.ndarray  # [K]
    coef: jnp.ndarray  # [3, K, 4, C]: (c0, c1, c2) of start angle, start rate, end angle, end rate
    lo: jnp.ndarray
    hi: jnp.ndarray
    value: jnp.ndarray

    def states(self, route, t0):
        d = (t0 - self.t_ref[route])[:, None, None]
        c = self.coef[:, route]
        s = c[0] + c[1] * d + c[2] * d * d
        return t0 + self.dur[route], s[:, 0], s[:, 1], s[:, 2], s[:, 3]

    def window(self, route):
        return self.lo[route], self.hi[route]

    def value_of(self, route):
        return self.value[route]


def _exact(ctx: PlanContext, ids, t0, per_ch):
    """Exact boundary states of the search's options ``ids`` started at ``t0`` [s]."""
    opp = ctx.opportunities
    o = opp.options
    dur = np.asarray(o.t_end)[ids] - np.asarray(o.t_start)[ids]
    return option_states(
        ctx.scenario,
        ctx.scene,
        np.asarray(o.sat)[ids],
        np.asarray(o.route)[ids],
        t0,
        t0 + dur,
        opp.params[ids],
        per_ch,
    )


def refine_starts(ctx: PlanContext, chosen, steps: int):
    """Refined copy of the search's option table for the ``chosen`` option ids (those
    rows replaced).

    Args:
      ctx: PlanContext (its scenario, scene and option table ``opportunities``).
      chosen: int [K], option ids of the plan.
      steps: int, refinement iterations.
    Returns:
      ``(opp2, stats)``: ``stats`` maps each refined satellite's name to the smallest
      transition margin [rad] before and after (model states) and whether the refined
      plan validates; ``opp2 is ctx.opportunities`` when nothing moved.
    """
    sc, opp = ctx.scenario, ctx.opportunities
    o = opp.options
    chosen = np.asarray(chosen, np.int64)
    per_ch = np.array([not s.maneuver.rest_to_rest for s in sc.satellites])
    grid = _grid_of(opp, sc.planner.time_step)
    t_new = np.array(o.t_start, np.float64)
    stats = {}
    for k, s in enumerate(sc.satellites):
        if s.maneuver.rest_to_rest:
            continue
        ids = chosen[np.asarray(o.sat)[chosen] == k]
        ids = ids[np.argsort(np.asarray(o.t_start)[ids])]
        if ids.size < 2:
            continue
        t_refined, stats[s.name] = _refine_satellite(ctx, grid, ids, s, steps, per_ch)
        if t_refined is not None:
            t_new[ids] = t_refined
    moved = np.flatnonzero(t_new != np.asarray(o.t_start))
    if moved.size == 0:
        return opp, stats
    return _moved(ctx, moved, t_new[moved], per_ch), stats


class _Grid(NamedTuple):
    """The options on the action grid: each option's grid index ``key`` (start / step,
    rounded) and the set ``known`` of every option's (satellite, target, scan speed,
    grid index)."""

    key: np.ndarray
    known: set

    def has(self, opp: Opportunities, ids, shift: int) -> np.ndarray:
        """bool [len(ids)]: the grid start ``shift`` steps from option ``ids[i]``'s, same
        satellite, target and scan speed, is an option too."""
        o = opp.options
        return np.array(
            [
                (int(o.sat[i]), int(o.route[i]), float(opp.speed[i]), int(self.key[i]) + shift)
                in self.known
                for i in ids
            ]
        )


def _grid_of(opp: Opportunities, step: float) -> _Grid:
    """The grid indices of the options of ``opp`` (action grid ``step`` [s]) and the set
    of their (satellite, target, scan speed, grid index)."""
    o = opp.options
    key = np.round(np.asarray(o.t_start) / step).astype(np.int64)
    known = set(
        zip(
            np.asarray(o.sat).tolist(),
            np.asarray(o.route).tolist(),
            opp.speed.tolist(),
            key.tolist(),
            strict=True,
        )
    )
    return _Grid(key, known)


def _refine_satellite(ctx: PlanContext, grid: _Grid, ids, s, steps: int, per_ch):
    """Refine the starts of one per-channel satellite ``s``'s options ``ids`` (in start
    order, at least two) through their quadratic model, padded to a shared bucket size.
    Returns (the refined starts [K] [s], or None when the refined plan does not validate
    or its smallest transition margin shrank; the satellite's stats entry)."""
    sc = ctx.scenario
    o = ctx.opportunities.options
    n = ids.size
    t0 = np.asarray(o.t_start)[ids]
    dur = np.asarray(o.t_end)[ids] - t0
    h = 0.5 * sc.planner.time_step
    coef = _quadratic_coef(ctx, ids, t0, h, per_ch)
    lo, hi = _start_windows(sc, ctx.opportunities, grid, ids, t0, dur, h)
    model, local = _padded_model(o, ids, t0, dur, coef, lo, hi)
    size = local.route.size
    res = refine_plan(
        Plan(np.arange(size), float(np.sum(np.asarray(o.value)[ids]))),
        local,
        model,
        s.limits,
        steps=steps,
        learning_rate=_LEARNING_RATE,
        samples=_SAMPLES,
    )
    before = float(np.min(res.margin_before[: n - 1]))
    after = float(np.min(res.margin_after[: n - 1]))
    stat = {"margin_before_rad": before, "margin_after_rad": after, "valid": res.ok}
    return (res.t0[:n] if res.ok and after >= before else None), stat


def _quadratic_coef(ctx: PlanContext, ids, t0, h: float, per_ch) -> np.ndarray:
    """[3, K, 4, C] coefficients (c0, c1, c2) in the start shift of the quadratic through
    the exact boundary states (start angle, start rate, end angle, end rate) of the
    options ``ids`` started at ``t0 - h``, ``t0`` and ``t0 + h``."""
    samples = []
    for shift in (-h, 0.0, h):
        st = _exact(ctx, ids, t0 + shift, per_ch)
        samples.append(np.stack([st.start_angle, st.start_rate, st.end_angle, st.end_rate], 1))
    m, z, p = samples
    return np.stack([z, (p - m) / (2 * h), (p - 2 * z + m) / (2 * h * h)])


def _start_windows(sc, opp: Opportunities, grid: _Grid, ids, t0, dur, h: float):
    """The start windows (lo, hi) [K] [s] of the options ``ids`` (starts ``t0``, imaging
    times ``dur``): half a step ``h`` to each side where the neighbouring grid start is
    an option too, clipped to the target's imaging window and the horizon (an area
    strip's is its start alone)."""
    tg = sc.targets
    r = np.asarray(opp.options.route)[ids]
    lo = np.maximum.reduce([t0 - h * grid.has(opp, ids, -1), tg.t_lo[r], np.zeros_like(t0)])
    hi = np.minimum.reduce([t0 + h * grid.has(opp, ids, 1), tg.t_hi[r] - dur, sc.duration - dur])
    area = np.isin(tg.kind[r], HELD_KINDS)  # a strip or look stays on its slots
    return np.where(area, t0, lo), np.where(area, t0, hi)


def _padded_model(o, ids, t0, dur, coef, lo, hi):
    """The :class:`_QuadraticStarts` model of the options ``ids`` and their local option
    table (route = step index), padded to a power of two >= ``_MIN_BUCKET`` steps with
    fixed copies of the last observation, ``_PAD_GAP`` apart after it (their transitions
    are long, so their margins never set the soft minimum). Windows are widened to hold
    their start. Returns (model, local options)."""
    n = ids.size
    size = max(_MIN_BUCKET, 1 << (n - 1).bit_length())
    pad = size - n
    t_pad = t0[-1] + dur[-1] + _PAD_GAP * np.arange(1, pad + 1)
    still = coef[:, -1:].copy()
    still[1:] = 0.0
    tt = np.concatenate([t0, t_pad])
    model = _QuadraticStarts(
        jnp.asarray(tt),
        jnp.asarray(np.concatenate([dur, np.full(pad, dur[-1])])),
        jnp.asarray(np.concatenate([coef, np.repeat(still, pad, 1)], 1)),
        jnp.asarray(np.concatenate([np.minimum(lo, t0), t_pad])),
        jnp.asarray(np.concatenate([np.maximum(hi, t0), t_pad])),
        jnp.asarray(np.concatenate([np.asarray(o.value)[ids], np.zeros(pad)])),
    )
    rows = np.concatenate([ids, np.full(pad, ids[-1])])
    local = take_options(o, rows)._replace(
        route=np.arange(size), t_start=tt, t_end=tt + np.asarray(model.dur)
    )
    return model, local


def _moved(ctx: PlanContext, moved, t_moved, per_ch) -> Opportunities:
    """A copy of the search's option table whose options ``moved`` start at ``t_moved``
    [s], every field of theirs recomputed exactly (the others unchanged)."""
    opp = ctx.opportunities
    o = opp.options
    new = _exact(ctx, moved, t_moved, per_ch)
    fields = {f: np.array(getattr(o, f)) for f in o._fields if getattr(o, f) is not None}
    for f in fields:
        fields[f][moved] = np.asarray(getattr(new, f))
    return Opportunities(type(o)(**fields), opp.speed, opp.params)
