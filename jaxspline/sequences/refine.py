"""Gradient refinement of a plan's continuous start times with optax (SPEC section 4).

The discrete search picks each route's start time t0 from a grid of options.
Refinement keeps the chosen routes and their order and moves every t0
continuously inside its window [t0_min, t0_max] to improve a differentiable
cost built from the exact-T reach kernels (SPEC section 1):

* ``"softmin_margin"`` — maximize a soft minimum over all transitions and
  channels of the signed reach margin m (``reach.reach_margin_kernel``, rad;
  m >= 0 iff the transfer in exactly T is feasible):
  loss = tau * log(sum exp(-m / tau)) (>= -min m, equal as tau -> 0);
* ``"effort"`` — minimize the summed required peak acceleration
  sum_k max_c d*_kc / accel_c (``reach_durations.min_peak_accel_kernel``; seed
  retarget-scan eq. 13), for plans that are already feasible.

Start times are the parameters u = (t0 - t0_min)/(t0_max - t0_min) in [0, 1],
updated by Adam and projected back onto [0, 1] after every step (projected
gradient), so the windows always hold; the boundary states follow from the
differentiable :class:`jaxspline.screen.options.RouteModel`. The best iterate
(feasible first, then best objective) is re-validated with
:func:`jaxspline.sequences.steps_check.check_steps`.

The geometry layer provides the real RouteModel
(:class:`jaxspline.geometry.routes.RouteSet`); the tests use a linear toy
(tests/sequences/_ref_refine.py).
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.limits import AxisLimits, validate_limits
from jaxspline.screen.options import RouteOptions, validate_options
from jaxspline.sequences.sequencer import Plan
from jaxspline.sequences.steps_check import StepsReport, check_steps

__all__ = ["refine_plan", "try_insert", "plan_costs"]

_OBJECTIVES = ("softmin_margin", "effort")


class RefineResult(NamedTuple):
    """Outcome of :func:`refine_plan`.

    Attributes:
      t0: [K] refined start times [s] (best iterate).
      steps: RouteOptions [K] of the refined plan (states from the RouteModel).
      margin_before, margin_after: [K-1] reach margin [rad] of each transition
        (min over channels) at the initial and the refined start times.
      effort_before, effort_after: [K-1] max over channels of d*/accel.
      history: [steps] objective value per optimizer step.
      report: StepsReport of the refined plan (independent checker).
      ok: ``report.ok``.
    """

    t0: np.ndarray
    steps: RouteOptions
    margin_before: np.ndarray
    margin_after: np.ndarray
    effort_before: np.ndarray
    effort_after: np.ndarray
    history: np.ndarray
    report: StepsReport
    ok: bool


def _kernels():
    from jaxspline.kernels import reach, reach_durations

    return (
        jnp.vectorize(reach.reach_margin_kernel),
        jnp.vectorize(reach_durations.min_peak_accel_kernel),
    )


def plan_costs(model, route, t0, rate, accel):
    """Per-transition, per-channel margins m and efforts e of a plan.

    m = ``reach.reach_margin_kernel`` at T_k = t0[k+1] - t_end[k]; for
    T_k <= eps the margin is continued linearly, m(eps) - (eps - T_k) rate (a
    negative, differentiable penalty for overlapping steps). e = d*/accel
    (``reach_durations.min_peak_accel_kernel``), +inf where impossible for any d.
    Differentiable in t0 (jit-able; ``model`` must be jit-able).

    Args:
      model: RouteModel.
      route: int [K], routes of the plan in time order.
      t0: float [K], start times [s from the epoch].
      rate: float [C], rate bounds [rad/s].
      accel: float [C], acceleration bounds [rad/s^2].
    Returns:
      (m float [K-1, C] [rad], e float [K-1, C] [dimensionless]).
    """
    margin_k, peak_k = _kernels()
    t_end, sa, sr, ea, er = model.states(route, t0)
    T = (t0[1:] - t_end[:-1])[:, None]
    eps = jnp.asarray(1e-3, T.dtype)
    ok = T > eps
    Ts = jnp.where(ok, T, eps)
    m = margin_k(ea[:-1], er[:-1], sa[1:], sr[1:], Ts, rate, accel)
    m = jnp.where(ok, m, m - (eps - T) * rate)
    e = peak_k(ea[:-1], er[:-1], sa[1:], sr[1:], Ts, rate) / accel
    e = jnp.where(ok, e, jnp.inf)
    return m, e


class _Opaque:
    """Static stand-in for a model that is not a pytree of arrays (hashed by identity)."""

    def __init__(self, model):
        self.model = model


def _split_model(model):
    """(leaves, static): array leaves are traced, anything else is a static argument."""
    leaves, treedef = jax.tree_util.tree_flatten(model)
    if leaves and all(isinstance(x, np.ndarray | jax.Array | float | int) for x in leaves):
        return leaves, treedef
    return [], _Opaque(model)


def _join_model(static, leaves):
    if isinstance(static, _Opaque):
        return static.model
    return jax.tree_util.tree_unflatten(static, leaves)


@functools.partial(jax.jit, static_argnames=("model_static",))
def _costs_jit(model_leaves, model_static, route, t0, rate, accel):
    return plan_costs(_join_model(model_static, model_leaves), route, t0, rate, accel)


@functools.partial(jax.jit, static_argnames=("model_static", "objective", "steps"))
def _optimize(
    u0, lo, hi, route, rate, accel, tau, lr, model_leaves, model_static, objective, steps
):
    import optax  # here, not at import: optax (and jax.scipy) cost ~0.3 s of every start

    model = _join_model(model_static, model_leaves)
    opt = optax.adam(lr)

    def costs(u):
        return plan_costs(model, route, lo + (hi - lo) * u, rate, accel)

    def loss(u):
        m, e = costs(u)
        if objective == "softmin_margin":
            return tau * jax.nn.logsumexp(-m.reshape(-1) / tau)
        e_safe = jnp.where(jnp.isfinite(e), e, 10.0)
        return jnp.sum(jnp.max(e_safe, axis=1))

    def step(carry, _):
        u, state = carry
        val, g = jax.value_and_grad(loss)(u)
        g = jnp.where(jnp.isfinite(g), g, 0.0)
        upd, state = opt.update(g, state, u)
        u_new = jnp.clip(optax.apply_updates(u, upd), 0.0, 1.0)
        m, e = costs(u)
        return (u_new, state), (u, val, jnp.min(m), jnp.sum(jnp.max(e, axis=1)))

    (u_last, _), (us, vals, mins, efforts) = jax.lax.scan(
        step, (u0, opt.init(u0)), None, length=steps
    )
    m, e = costs(u_last)
    us = jnp.concatenate([us, u_last[None]])
    mins = jnp.concatenate([mins, jnp.min(m)[None]])
    efforts = jnp.concatenate([efforts, jnp.sum(jnp.max(e, axis=1))[None]])
    return us, vals, mins, efforts


def _steps_table(model, route, t0, scan_ok, dtype) -> RouteOptions:
    te, sa, sr, ea, er = (np.asarray(x, dtype) for x in model.states(jnp.asarray(route), t0))
    return RouteOptions(
        route=np.asarray(route),
        t_start=np.asarray(t0, dtype),
        t_end=te,
        start_angle=sa,
        start_rate=sr,
        end_angle=ea,
        end_rate=er,
        value=np.asarray(model.value_of(jnp.asarray(route)), dtype),
        scan_ok=np.asarray(scan_ok, bool),
    )


def refine_plan(
    plan: Plan,
    options: RouteOptions,
    model,
    limits: AxisLimits,
    *,
    steps: int = 200,
    learning_rate: float = 0.02,
    objective: str = "softmin_margin",
    temperature: float | None = None,
    samples: int = 2001,
) -> RefineResult:
    """Refine the start times of ``plan`` inside their windows (Adam + projection).

    Args:
      plan: Plan (option indices in time order) chosen on ``options``.
      options: the RouteOptions the plan indexes (gives routes and initial t0).
      model: a RouteModel (``states``, ``window``, ``value_of``), jit-able and
        differentiable in t0. A pytree of arrays (e.g. a NamedTuple) is traced,
        so one compilation serves every call; any other object is a static
        argument (hashed by identity: recompiles per model object).
      limits: AxisLimits, rate [rad/s] and accel [rad/s^2] scalars or [C].
      steps: optimizer steps (>= 1).
      learning_rate: Adam step size in window fractions (u = (t0 - t0_min) /
        (t0_max - t0_min)).
      objective: ``"softmin_margin"`` (loss tau logsumexp(-m / tau)) or
        ``"effort"`` (loss sum_k max_c d*/accel); see module docstring.
      temperature: tau [rad] of the soft minimum; default 5 % of the largest
        |margin| at the start (at least 1e-9).
      samples: samples per maneuver for the final validation.

    Returns:
      RefineResult, a NamedTuple: ``t0`` [K] refined starts [s], ``steps`` (their
      RouteOptions), ``margin_before`` / ``margin_after`` [K-1] [rad] and
      ``effort_before`` / ``effort_after`` [K-1], the objective ``history``, and the
      independent validation of the refined plan (``report``, ``ok``). Steps keep
      the ``scan_ok`` flag of their original option.
    """
    limits, idx = _validated(plan, options, limits, objective, steps, learning_rate)
    st = _start(options, model, limits, idx)
    if idx.size < 2:
        return _unrefined(model, st, limits, samples)
    leaves, static = _split_model(model)
    m0, e0 = _costs_jit(leaves, static, st.route, st.t_init, st.rate, st.accel)
    if temperature is None:
        temperature = _default_temperature(m0)
    run = _Run(float(learning_rate), objective, int(steps), jnp.asarray(temperature, st.dtype))
    t_best, history = _best_starts(st, run, leaves, static)
    m1, e1 = _costs_jit(leaves, static, st.route, t_best, st.rate, st.accel)
    steps_tab = _steps_table(model, st.route, t_best, st.scan_ok, st.dtype)
    rep = check_steps(steps_tab, limits, windows=(st.lo_np, st.hi_np), samples=samples)
    return RefineResult(
        t0=np.asarray(t_best),
        steps=steps_tab,
        margin_before=np.asarray(jnp.min(m0, axis=1)),
        margin_after=np.asarray(jnp.min(m1, axis=1)),
        effort_before=np.asarray(jnp.max(e0, axis=1)),
        effort_after=np.asarray(jnp.max(e1, axis=1)),
        history=np.asarray(history),
        report=rep,
        ok=rep.ok,
    )


class _Start(NamedTuple):
    """Where the refinement starts: the plan's ``route`` [K] and start times ``t_init``
    [K] [s], their windows ``lo``, ``hi`` [K] (jax, and as numpy ``lo_np``, ``hi_np``
    for the final check), the window fractions ``u0`` [K] of ``t_init``, the steps'
    ``scan_ok`` [K], the bounds ``rate``, ``accel`` [C] and the float ``dtype``."""

    route: jax.Array
    t_init: jax.Array
    lo: jax.Array
    hi: jax.Array
    lo_np: np.ndarray
    hi_np: np.ndarray
    u0: jax.Array
    scan_ok: np.ndarray
    rate: jax.Array
    accel: jax.Array
    dtype: np.dtype


class _Run(NamedTuple):
    """The optimizer's settings: Adam's ``learning_rate`` (window fractions), the
    ``objective`` name, the number of ``steps`` and the soft-minimum ``temperature``
    [rad] (a jax scalar of the plan's dtype)."""

    learning_rate: float
    objective: str
    steps: int
    temperature: jax.Array


def _validated(plan: Plan, options: RouteOptions, limits, objective, steps, learning_rate):
    """Check the arguments of :func:`refine_plan` (ValueError naming the first bad one)
    and return ``(limits, idx)``: the validated AxisLimits and the plan's option
    indices as int64 [K], every one an index of ``options``."""
    validate_options(options)
    limits = validate_limits(limits)
    if objective not in _OBJECTIVES:
        raise ValueError(f"objective must be one of {_OBJECTIVES}, got {objective!r}")
    if int(steps) < 1:
        raise ValueError(f"steps must be >= 1, got {steps!r}")
    if not learning_rate > 0:
        raise ValueError(f"learning_rate must be > 0, got {learning_rate!r}")
    idx = np.asarray(plan.chosen, np.int64)
    n = np.shape(options.t_start)[0]
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ValueError(f"plan.chosen must index the {n} options, got {idx.tolist()}")
    return limits, idx


def _start(options: RouteOptions, model, limits: AxisLimits, idx: np.ndarray) -> _Start:
    """The starting point of the refinement of the options ``idx``: routes, start times
    and windows from ``model.window`` (ValueError when a start time lies outside its
    window by more than 1e-9 relative), the window fractions u0 (0 for an empty
    window), and the bounds in the options' float dtype (jax's default float when the
    options' states are not floats)."""
    dtype = np.asarray(options.start_angle).dtype
    if not np.issubdtype(dtype, np.floating):
        dtype = np.dtype(jnp.result_type(float))
    c = np.shape(options.start_angle)[1]
    rate = jnp.asarray(np.broadcast_to(np.asarray(limits.rate, float), (c,)), dtype)
    accel = jnp.asarray(np.broadcast_to(np.asarray(limits.accel, float), (c,)), dtype)
    route = jnp.asarray(np.asarray(options.route)[idx])
    t_init = jnp.asarray(np.asarray(options.t_start)[idx], dtype)
    lo, hi = (jnp.asarray(x, dtype) for x in model.window(route))
    lo_np, hi_np = np.asarray(lo), np.asarray(hi)
    t_np = np.asarray(t_init)
    if np.any(t_np < lo_np - 1e-9 * (1 + np.abs(lo_np))) or np.any(
        t_np > hi_np + 1e-9 * (1 + np.abs(hi_np))
    ):
        raise ValueError("plan start times must lie inside model.window of their routes")
    scan_ok = np.asarray(options.scan_ok, bool)[idx]
    width = jnp.where(hi > lo, hi - lo, 1.0)
    u0 = jnp.clip((t_init - lo) / width, 0.0, 1.0)
    u0 = jnp.where(hi > lo, u0, 0.0)
    return _Start(route, t_init, lo, hi, lo_np, hi_np, u0, scan_ok, rate, accel, dtype)


def _unrefined(model, st: _Start, limits: AxisLimits, samples: int) -> RefineResult:
    """The result for a plan of fewer than two steps (no transition, nothing to
    optimize): its steps at their own start times, checked, with empty margins,
    efforts and history."""
    steps_tab = _steps_table(model, st.route, st.t_init, st.scan_ok, st.dtype)
    rep = check_steps(steps_tab, limits, windows=(st.lo_np, st.hi_np), samples=samples)
    z = np.zeros(0, st.dtype)
    return RefineResult(np.asarray(st.t_init), steps_tab, z, z, z, z, np.zeros(0), rep, rep.ok)


def _default_temperature(m0) -> float:
    """The default soft-minimum temperature: 5 % of the largest finite |margin| [rad]
    of the starting plan ``m0`` [K-1, C], at least 1e-9."""
    finite = jnp.where(jnp.isfinite(m0), jnp.abs(m0), 0.0)
    return max(0.05 * float(jnp.max(finite)), 1e-9)


def _best_starts(st: _Start, run: _Run, leaves, static):
    """Run the projected Adam iteration from ``st`` and pick its best iterate: the one
    of largest minimum margin for ``"softmin_margin"`` (or when no iterate is
    feasible), else the feasible one of least effort. Returns (its start times [K]
    [s], the objective history [steps])."""
    us, vals, mins, efforts = _optimize(
        st.u0,
        st.lo,
        jnp.where(st.hi > st.lo, st.hi, st.lo),
        st.route,
        st.rate,
        st.accel,
        run.temperature,
        run.learning_rate,
        leaves,
        static,
        run.objective,
        run.steps,
    )
    mins, efforts = np.asarray(mins), np.asarray(efforts)
    feasible = mins >= 0
    if run.objective == "softmin_margin" or not feasible.any():
        best = int(np.argmax(mins))
    else:
        best = int(np.flatnonzero(feasible)[np.argmin(efforts[feasible])])
    return st.lo + (st.hi - st.lo) * us[best], vals


def try_insert(
    plan: Plan, options: RouteOptions, model, limits: AxisLimits, route: int, **kwargs
) -> tuple[Plan, RefineResult] | None:
    """Insert one more route into ``plan`` by continuous refinement of start times.

    Every option of ``route`` (none already in the plan) is placed at its
    time-ordered position in the plan, and the combined plan is refined with
    :func:`refine_plan` (``objective="softmin_margin"``).

    Args:
      plan: Plan indexing ``options``.
      options: RouteOptions.
      model: RouteModel.
      limits: AxisLimits per channel.
      route: int, the route to insert.
      **kwargs: passed on to :func:`refine_plan`.
    Returns:
      ``(new plan, result)`` of the refined plan that validates with the largest
      minimum margin, or None when none validates. The returned Plan indexes
      ``options`` (start times as in the options table; the refined ones are
      ``result.t0``).
    """
    validate_options(options)
    idx = np.asarray(plan.chosen, np.int64)
    routes = np.asarray(options.route)
    if np.any(routes[idx] == route):
        raise ValueError(f"route {route} is already in the plan")
    cand = np.flatnonzero((routes == route) & np.asarray(options.scan_ok, bool))
    ts = np.asarray(options.t_start)
    best = None
    for j in cand:
        pos = int(np.searchsorted(ts[idx], ts[j]))
        new_idx = np.insert(idx, pos, j)
        res = refine_plan(Plan(new_idx, 0.0), options, model, limits, **kwargs)
        if res.ok and (best is None or res.margin_after.min() > best[1].margin_after.min()):
            value = float(np.asarray(model.value_of(jnp.asarray(routes[new_idx]))).sum())
            best = (Plan(new_idx, value), res)
    return best
