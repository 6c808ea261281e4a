"""How low a bound of the path relaxation can go: a fractional plan's value (Frank-Wolfe).

The strengthened relaxation of :mod:`jaxspline.search.lagrangian` bounds every plan by
``UB(lam) = sum_k DP_k(lam) + sum_t lam_t`` for any prices ``0 <= lam <= w``. Its best
price vector gives the value ``LP*`` of the linear program over convex combinations of
each satellite's paths (Dantzig-Wolfe master)::

    max  sum_t w_t min(1, cov_t(alpha)),   cov_t = sum_k sum_p alpha_kp runs_t(p),
    alpha_k a sub-probability vector over satellite k's paths,

where ``runs_t(p)`` counts the runs of target t on path p (a run of consecutive options
of one target is credited once, as the DP credits it or less). So every iterate alpha
gives ``LP* >= f(alpha)``: no price vector, however well iterated, gives a bound below
that *floor*. Where a plan stays far below the floor, the gap cannot be closed by the
prices (the subgradient rule or its convergence), only by a better plan or a relaxation
beyond the linear one (cuts that need more DP state, branching).

:func:`relaxation_floor` iterates the bound (:func:`upper_bound`), starts alpha at the
average of the last :data:`_ERGODIC` iterations' DP paths (primal recovery) or at a given
plan's paths when those are worth more, then runs Frank-Wolfe steps: the linear oracle
is the DP itself at option values ``w_t [cov_t < 1]`` (the supergradient of f), the step
is the best of a grid of :data:`_GRID` lengths (f is concave and piecewise linear, so
the iterate never loses value). The oracle's prices ``w_t [cov_t >= 1]`` are in
``[0, w]``, so each oracle call also gives a valid bound. The battery is dropped, as in
:func:`upper_bound` and the bound worker: a bound that prices the battery's budgets (the
search's own Lagrangian phase, :mod:`jaxspline.search.energy`) relaxes less and may go
below this floor.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from jaxspline.search.dp import dp_paths, dp_prepare
from jaxspline.search.lagrangian import BOUND_MU_MIN, run_targets, upper_bound
from jaxspline.search.problem import Problem

__all__ = ["RelaxationFloor", "relaxation_floor"]

_ERGODIC = 30  # last iterations of the bound whose DP paths start the fractional plan
_GRID = np.r_[0.0, np.geomspace(1e-5, 1.0, 96)]  # Frank-Wolfe step lengths tried
_COVERED = 1.0 - 1e-9  # coverage at which a target is worth nothing more


@dataclass(frozen=True)
class RelaxationFloor:
    """Outcome of :func:`relaxation_floor`.

    Attributes:
      floor: value of the best fractional plan found: the relaxation's optimum, and so
        every bound of it, is at least this.
      bound: the smallest bound ``UB(lam)`` seen (subgradient and oracle prices).
      iterations: subgradient iterations of the bound.
      fw_iterations: Frank-Wolfe steps.
      seconds: wall time [s].
    """

    floor: float
    bound: float
    iterations: int
    fw_iterations: int
    seconds: float


def _runs(target: np.ndarray, path, n_targets: int) -> np.ndarray:
    """Per target the number of runs of its options on ``path`` (float [T]); ``target``:
    the options' targets (the DP layout's)."""
    t = run_targets(target[np.asarray(path, np.int64)])
    return np.bincount(t, minlength=n_targets).astype(np.float64)


def _coverage(target: np.ndarray, n_sats: int, paths_list, n_targets: int) -> np.ndarray:
    """Per satellite the mean run counts of its paths over ``paths_list`` (float [K, T])."""
    cov = np.zeros((n_sats, n_targets))
    for paths in paths_list:
        for k, p in enumerate(paths):
            cov[k] += _runs(target, p, n_targets)
    return cov / max(len(paths_list), 1)


def relaxation_floor(
    pb: Problem,
    plan_value: float,
    deadline: float = math.inf,
    max_iters=None,
    fw_iters: int = 200,
    plan_paths=None,
    dp=None,
) -> RelaxationFloor:
    """A fractional plan of the strengthened path relaxation and the bound (module doc).

    Args:
      pb: Problem.
      plan_value: float, a value some plan reaches (step size of the bound only).
      deadline: ``time.monotonic()`` value at which the bound's iteration stops [s]
        (the Frank-Wolfe steps run after it).
      max_iters: cap on the bound's iterations (None: until converged or the deadline).
      fw_iters: Frank-Wolfe steps.
      plan_paths: optional per satellite the option ids of a plan's sequence (time
        order): alpha starts there when it is worth more than the average of the
        bound's paths, so the floor is at least that plan's value.
      dp: the problem's :func:`dp_prepare` (None: prepared here).
    Returns:
      RelaxationFloor.
    """
    t0 = time.monotonic()
    w = np.asarray(pb.target_value, np.float64)
    if pb.n_options == 0:
        return RelaxationFloor(0.0, 0.0, 0, 0, 0.0)
    d = dp_prepare(pb) if dp is None else dp
    last = []

    def keep(_it, paths, _improved):
        last.append([np.asarray(p, np.int64).copy() for p in paths])
        del last[:-_ERGODIC]

    res = upper_bound(pb, plan_value, deadline, max_iters, dp=d, on_paths=keep, mu_min=BOUND_MU_MIN)
    bound = res.bound

    def value(cov):
        return float(w @ np.minimum(cov, 1.0))

    tg, n_t = d.target, w.size
    covs = _coverage(tg, pb.n_sats, last, n_t)
    if plan_paths is not None:
        mine = _coverage(tg, pb.n_sats, [plan_paths], n_t)
        if value(mine.sum(0)) > value(covs.sum(0)):
            covs = mine
    cov = covs.sum(0)
    for _ in range(fw_iters):
        open_w = np.where(cov < _COVERED, w, 0.0)
        paths, vals = dp_paths(pb, d, open_w[tg], merge_repeats=True)
        bound = min(bound, float(sum(vals) + (w - open_w).sum()))
        new = np.stack([_runs(tg, p, n_t) for p in paths])
        step = new.sum(0) - cov
        gain = [value(cov + g * step) for g in _GRID]
        g = float(_GRID[int(np.argmax(gain))])
        covs = (1.0 - g) * covs + g * new
        cov = covs.sum(0)
    return RelaxationFloor(value(cov), bound, res.iterations, int(fw_iters), time.monotonic() - t0)
