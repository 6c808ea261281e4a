"""The Lagrangian bound with its per-satellite subproblems sharded across processes.

Under task prices the bound splits into one longest-path DP per satellite
(:mod:`jaxspline.engine.search.lagrangian`). Here every process owns some satellites:
it screens and stores only their options and near pairs (its own
:class:`jaxspline.engine.search.Problem`, so memory is split too) and solves only their
DPs. Once per iteration the processes exchange one float64 vector through
``jax.distributed`` (:func:`jax.experimental.multihost_utils.process_allgather`):

    [DP value of every satellite (0 where not owned) | takers per task | stop flag]

Owned values are combined by satellite (adding exact zeros) and summed in satellite
order, takers are integers, so every process holds the same bound and subgradient as
a single process would and takes the same projected Polyak step: the prices, the bound
and the iteration count equal :func:`jaxspline.engine.search.upper_bound` (battery
relaxed) bit for bit. A process that reaches its deadline raises the stop flag; all
stop together at the end of that iteration (no process waits for a missing peer).

Satellite ``k`` belongs to process ``k % process_count``.
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.engine.search import clock
from jaxspline.engine.search.lagrangian import BoundResult, _Prices, dp_paths
from jaxspline.engine.search.problem import Problem

__all__ = ["jax_allgather", "owned_satellites", "sharded_upper_bound"]


def owned_satellites(n_sats: int, index: int, count: int) -> list[int]:
    """Satellites of process ``index`` among ``count``: ``k % count == index``.

    Args:
      n_sats: number of satellites of the scenario.
      index: this process (0-based).
      count: number of processes.
    Returns:
      sorted list of satellite indices (possibly empty).
    """
    if not (0 <= index < count):
        raise ValueError(f"process index {index!r} outside [0, {count})")
    return list(range(index, n_sats, count))


def jax_allgather(x: np.ndarray) -> np.ndarray:
    """[P, ...] stack of every process's ``x`` (jax.distributed must be initialized)."""
    from jax.experimental import multihost_utils

    return np.asarray(multihost_utils.process_allgather(np.asarray(x)), np.float64)


class _ShardPrices(_Prices):
    """:class:`_Prices` whose DP covers the owned satellites and whose totals are gathered."""

    def __init__(self, pb: Problem, sat_ids, n_sats: int, allgather):
        super().__init__(pb, energy=False)
        self.sat_ids = np.asarray(sat_ids, np.int64)
        self.n_sats = int(n_sats)
        self.allgather = allgather
        self.stop = False

    def solve_dp(self, want_stop: bool = False):
        self.it += 1
        n_t = self.W.size
        w = self.W[self.ctask] - self.lam[self.ctask]
        paths, vals = dp_paths(self.pb, self.d, w)
        local = np.zeros(self.n_sats + n_t + 1)
        local[self.sat_ids] = vals
        local[self.n_sats : -1] = self._takers(paths)
        local[-1] = float(want_stop)
        every = self.allgather(local)
        vals_all = every[:, : self.n_sats].sum(axis=0)  # one owner each: exact
        self.cnt = every[:, self.n_sats : -1].sum(axis=0)
        self.stop = bool(every[:, -1].max() > 0.0)
        self._record(vals_all.tolist(), paths)
        return paths

    def _subgradient(self) -> np.ndarray:
        return self.cnt - 1.0


def sharded_upper_bound(
    pb: Problem,
    sat_ids,
    n_sats: int,
    target: float,
    deadline: float,
    max_iters=None,
    allgather=jax_allgather,
) -> BoundResult:
    """The Lagrangian bound (battery relaxed) of a scenario whose satellites are sharded.

    Every process calls it with its own problem; all return the same result.

    Args:
      pb: this process's Problem (its satellites only, all the scenario's tasks).
      sat_ids: the scenario-wide index of each of ``pb``'s satellites.
      n_sats: satellites of the whole scenario.
      target: a plan value reached (sets the step size only; any value gives a bound);
        must be the same in every process.
      deadline: ``time.monotonic()`` value at which this process asks to stop [s].
      max_iters: cap on the iterations (None: the deadlines alone).
      allgather: callable ``x [L] -> [P, L]`` over the processes (default: through
        ``jax.distributed``); a single process passes ``lambda x: x[None]``.
    Returns:
      BoundResult (``best`` empty), status "converged" or "time".
    """
    if len(sat_ids) != pb.n_sats:
        raise ValueError(f"sat_ids has {len(sat_ids)} entries for {pb.n_sats} satellites")
    pr = _ShardPrices(pb, sat_ids, n_sats, allgather)
    status = "time"
    while max_iters is None or pr.it < max_iters:
        pr.solve_dp(want_stop=not clock.now() < deadline)
        if pr.stop:
            break
        if not pr.step(target):
            status = "converged"
            break
    ub = pr.ub if pr.it else math.inf
    return BoundResult([], ub, pr.it, status)
