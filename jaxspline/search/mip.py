"""A tighter, slower certificate: the option model as a 0/1 program solved by HiGHS.

The Lagrangian bound of :mod:`jaxspline.search.lagrangian` equals the linear
relaxation of the path model below (each satellite's subproblem is a longest path, an
integral polytope), so it cannot close a gap that comes from fractional "half plans".
A MIP solver's cuts and branching can: :func:`mip_bound` hands the model to HiGHS
(``scipy.optimize.milp``) and returns its dual bound (and its best plan value) after a
time limit. Use it offline to certify a plan; it takes minutes where the planner has
seconds.

The model, per satellite a unit flow in a DAG of its options (start order):

* ``y_j`` in {0, 1}: option j is imaged; ``y_j`` = inflow of j;
* near arcs ``i -> j``: the screened feasible pairs (gap < far + slack);
* far arcs through a waiting chain: option j feeds chain node ``r_j = end_j + far``,
  chain nodes flow forward in time, and option i is fed by the last chain node with
  ``r <= start_i``; so every always-feasible pair is a path, with O(options) arcs;
* source arcs into options allowed first (one unit per satellite); outflow <= inflow
  everywhere (a path may end anywhere);
* ``z_t <= 1`` and ``z_t <= sum_{j of t} y_j``; maximize ``sum_t w_t z_t``.

Repeats of a target are allowed and count once (as in the rules), and the battery is
dropped: the optimum of this model bounds every plan of the option model. Only the
``y`` are integer: with at most one unit of flow per satellite, every node with
``y_j = 1`` carries the whole unit, so the chosen options lie on one path.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from jaxspline.search.problem import Problem
from jaxspline.search.status import BoundStatus

__all__ = ["MipBound", "mip_bound"]


@dataclass(frozen=True)
class MipBound:
    """Outcome of :func:`mip_bound`.

    Attributes:
      bound: HiGHS's dual bound (an upper bound of every plan of the model).
      value: value of HiGHS's best plan (``nan`` if it found none).
      status: :class:`BoundStatus`, ``OPTIMAL`` (bound met) or ``TIME`` (stopped by
        the time limit).
      seconds: solver wall time [s].
    """

    bound: float
    value: float
    status: BoundStatus
    seconds: float


def _chain(start, end, sat, far, n_sats):
    """Chain position of every option (sorted by sat, then ``end + far``) and the
    chain node feeding each option (-1: none)."""
    r = end + far[sat]
    order = np.lexsort((r, sat))
    pos = np.empty(len(r), np.int64)
    pos[order] = np.arange(len(r))
    feed = np.full(len(r), -1, np.int64)
    for k in range(n_sats):
        nodes = order[sat[order] == k]
        opts = np.flatnonzero(sat == k)
        q = np.searchsorted(r[nodes], start[opts], side="right") - 1
        feed[opts] = np.where(q >= 0, pos[nodes[np.maximum(q, 0)]], -1)
    link = np.flatnonzero(sat[order[:-1]] == sat[order[1:]])
    return pos, feed, link


def mip_bound(pb: Problem, time_limit: float, rel_gap: float = 1e-4) -> MipBound:
    """Dual bound of the option model's 0/1 program (module docstring) via HiGHS.

    Args:
      pb: the search problem (e.g. ``build_problem(scenario).problem``).
      time_limit: HiGHS wall-clock limit [s].
      rel_gap: stop when (bound - value) / bound falls below this.

    Raises:
      ImportError: scipy (>= 1.11, HiGHS inside) is not installed.
    """
    try:
        import scipy.sparse as sps
        from scipy.optimize import Bounds, LinearConstraint, milp
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("mip_bound needs scipy >= 1.11: pip install scipy") from exc

    n, n_tg, n_s = pb.n_options, pb.n_targets, pb.n_sats
    start = np.asarray(pb.option_start, np.float64)
    sat = np.asarray(pb.option_sat, np.int64)
    target = np.asarray(pb.option_target, np.int64)
    pos, feed, link = _chain(
        start, np.asarray(pb.option_end, np.float64), sat, np.asarray(pb.far), n_s
    )
    src, dst = np.asarray(pb.near_src, np.int64), np.asarray(pb.near_dst, np.int64)
    fed = np.flatnonzero(feed >= 0)
    first = np.flatnonzero(np.asarray(pb.option_first) <= start)
    # variable blocks: y, z, near arcs, option -> chain, chain -> option, chain links, source
    sizes = [n, n_tg, len(src), n, len(fed), len(link), len(first)]
    oy, oz, ox, of, og, oh, os_ = np.cumsum([0, *sizes[:-1]])
    nv = sum(sizes)
    # row blocks: inflow (= 0), outflow (<= 0), chain (>= 0), targets (<= 0), sources (<= 1)
    ri, ro, rc, rt, rs = 0, n, 2 * n, 3 * n, 3 * n + n_tg
    ar = np.arange
    entries = [
        (ri + ar(n), oy + ar(n), -1.0),
        (ro + ar(n), oy + ar(n), -1.0),
        (ri + dst, ox + ar(len(src)), 1.0),
        (ro + src, ox + ar(len(src)), 1.0),
        (ro + ar(n), of + ar(n), 1.0),
        (rc + pos, of + ar(n), 1.0),
        (ri + fed, og + ar(len(fed)), 1.0),
        (rc + feed[fed], og + ar(len(fed)), -1.0),
        (rc + link, oh + ar(len(link)), -1.0),
        (rc + link + 1, oh + ar(len(link)), 1.0),
        (ri + first, os_ + ar(len(first)), 1.0),
        (rs + sat[first], os_ + ar(len(first)), 1.0),
        (rt + ar(n_tg), oz + ar(n_tg), 1.0),
        (rt + target, oy + ar(n), -1.0),
    ]
    rows = np.concatenate([e[0] for e in entries])
    cols = np.concatenate([e[1] for e in entries])
    vals = np.concatenate([np.full(len(e[0]), e[2]) for e in entries])
    m = rs + n_s
    a_mat = sps.csr_array((vals, (rows, cols)), shape=(m, nv))
    lo = np.r_[np.zeros(n), np.full(n, -np.inf), np.zeros(n), np.full(n_tg + n_s, -np.inf)]
    hi = np.r_[np.zeros(2 * n), np.full(n, np.inf), np.zeros(n_tg), np.ones(n_s)]
    cost = np.zeros(nv)
    cost[oz : oz + n_tg] = -np.asarray(pb.target_value, np.float64)
    integ = np.zeros(nv)
    integ[:n] = 1.0
    t0 = time.monotonic()
    res = milp(
        cost,
        constraints=LinearConstraint(a_mat, lo, hi),
        integrality=integ,
        bounds=Bounds(0.0, 1.0),
        options={"time_limit": float(time_limit), "mip_rel_gap": float(rel_gap)},
    )
    bound = getattr(res, "mip_dual_bound", None)
    value = -float(res.fun) if res.x is not None else float("nan")
    if bound is None or not np.isfinite(bound):
        bound = value if res.status == 0 else float(np.sum(pb.target_value))
    else:
        bound = -float(bound)
    status = BoundStatus.OPTIMAL if res.status == 0 else BoundStatus.TIME
    return MipBound(bound, value, status, time.monotonic() - t0)
