"""An upper bound on the coverage any plan built from a problem's groups can reach.

Relaxation (every plan of strips from the groups is feasible for it): a satellite images
at most one group per slot; two strips of one satellite leave at least one idle slot
between them (the gap needs settling > 0 and strips sit on the slot grid); a pass (the
satellite's groups whose slots chain, :func:`jaxspline.search.coverage_problem.group_passes`)
holds at most ``floor((T + 1) / (min_slots + 1))`` strips; the whole plan at most
``max_actions``; a strip spans at least ``min_slots`` slots. Dropped: the maximum
duration, slews beyond one slot, duty, battery, the separation between passes. A bound on
plans over the screened candidates (the roll grid and slot rows), not on every roll.

Lagrangian: multipliers ``0 <= lam_j <= w_j`` on ``y_j <= sum_{rows covering j} x_row``.
For fixed ``lam`` the relaxed problem splits into ``sum_j max(0, w_j - lam_j)`` plus, per
pass, a dynamic programme over its slots (state: idle, or imaging group g with the run
length so far capped at ``min_slots``; runs used), row values ``sum_{j in row} lam_j``,
and a knapsack over passes on the number of runs. Every ``lam`` gives a valid bound
(weak duality); deflected subgradient steps (Polyak, with a known plan value as target)
lower it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from jaxspline.search.coverage_problem import CoverProblem, group_passes

__all__ = [
    "BoundResult",
    "PassLayout",
    "bound_main",
    "lagrangian_bound",
    "lagrangian_value",
    "pass_layout",
]

#: Padded DP cells per block of passes (memory / speed trade-off).
BLOCK_CELLS = 6_000_000
#: Subgradient deflection (share of the new subgradient in the step direction).
DEFLECT = 0.3
#: Iterations without a better bound before the step factor halves.
PATIENCE = 10
#: Start multipliers as a share of the sample weights.
LAM0_SHARE = 0.2


@dataclass(frozen=True)
class PassLayout:
    """Where each CSR row sits in the per-pass DP arrays.

    Attributes:
      n_pass: number of passes.
      row_pass, row_lg, row_lt: int64 [rows], pass, local group and local slot of each row.
      n_groups, n_slots, max_runs, min_len: int64 [n_pass], per pass (min_len: fewest
        slots of a strip).
      blocks: list of int arrays of pass indices processed together.
    """

    n_pass: int
    row_pass: np.ndarray
    row_lg: np.ndarray
    row_lt: np.ndarray
    n_groups: np.ndarray
    n_slots: np.ndarray
    max_runs: np.ndarray
    min_len: np.ndarray
    blocks: list


def pass_layout(prob: CoverProblem) -> PassLayout:
    """Group the rows of a problem by pass for the dynamic programme.

    Args:
      prob: CoverProblem.
    Returns:
      PassLayout.
    """
    gp = group_passes(prob)
    n_pass = int(gp.max()) + 1 if gp.size else 0
    first = np.full(n_pass, np.iinfo(np.int64).max)
    last = np.zeros(n_pass, dtype=np.int64)
    np.minimum.at(first, gp, prob.group_slot0)
    np.maximum.at(last, gp, prob.group_slot0 + prob.group_nslots)
    order = np.lexsort((np.arange(gp.size), gp))
    lg = np.empty(gp.size, dtype=np.int64)
    counts = np.bincount(gp, minlength=n_pass)
    lg[order] = np.arange(gp.size) - np.repeat(np.cumsum(counts) - counts, counts)
    nrow = prob.group_nslots
    row_group = np.repeat(np.arange(gp.size), nrow)
    within = np.arange(prob.n_rows) - np.repeat(prob.group_row0, nrow)
    row_lt = prob.group_slot0[row_group] - first[gp[row_group]] + within
    n_slots = last - first
    sat_of_pass = np.zeros(n_pass, dtype=np.int64)
    sat_of_pass[gp] = prob.group_sat
    need = np.array([prob.min_slots(int(s)) for s in sat_of_pass], dtype=np.int64)
    max_runs = np.minimum((n_slots + 1) // (need + 1), prob.max_actions)
    max_runs = np.maximum(max_runs, 1)
    by_size = np.lexsort((n_slots * counts, need))
    blocks, cur, peak = [], [], (0, 0, 0)
    for p in by_size:
        new_peak = (max(peak[0], counts[p]), max(peak[1], n_slots[p]), max(peak[2], max_runs[p]))
        cells = (len(cur) + 1) * new_peak[0] * new_peak[1] * (new_peak[2] + 1) * need[p]
        if cur and (cells > BLOCK_CELLS or need[p] != need[cur[0]]):
            blocks.append(np.array(cur))
            cur, new_peak = [], (counts[p], n_slots[p], max_runs[p])
        cur.append(int(p))
        peak = new_peak
    if cur:
        blocks.append(np.array(cur))
    return PassLayout(
        n_pass, gp[row_group], lg[row_group], row_lt, counts, n_slots, max_runs, need, blocks
    )


def _block_dp(vals: np.ndarray, runs: np.ndarray, lmin: int):
    """Per-pass DP on padded values [P, G, T] with runs of >= ``lmin`` slots.

    State per slot: idle (runs used r) or imaging group g with run length k (capped at
    ``lmin``). Returns V [P, R+1] (best value with exactly r runs) and the choices.
    """
    p_n, g_n, t_n = vals.shape
    r_n = int(runs.max()) + 1
    big = max(int(lmin), 1)
    neg = -np.inf
    act = np.full((p_n, g_n, big, r_n), neg)
    idle = np.full((p_n, r_n), neg)
    idle[:, 0] = 0.0
    cont = np.zeros((t_n, p_n, g_n, r_n), dtype=bool)
    src = np.zeros((t_n, p_n, r_n), dtype=np.int64)  # -1: idle before, else the group ended
    for t in range(t_n):
        start = np.concatenate([np.full((p_n, 1), neg), idle[:, :-1]], axis=1)[:, None, :]
        v = vals[:, :, t, None]
        new = np.empty_like(act)
        if big == 1:
            c = act[:, :, 0] >= start
            new[:, :, 0] = v + np.where(c, act[:, :, 0], start)
        else:
            new[:, :, 0] = v + start
            new[:, :, 1 : big - 1] = v[:, :, None] + act[:, :, : big - 2]
            c = act[:, :, big - 1] >= act[:, :, big - 2]
            new[:, :, big - 1] = v + np.where(c, act[:, :, big - 1], act[:, :, big - 2])
        cont[t] = c
        done = act[:, :, big - 1]
        best_g = np.argmax(done, axis=1)
        best_a = np.take_along_axis(done, best_g[:, None, :], axis=1)[:, 0, :]
        stay = idle >= best_a
        src[t] = np.where(stay, -1, best_g)
        idle = np.where(stay, idle, best_a)
        act = new
    done = act[:, :, big - 1]
    best_g = np.argmax(done, axis=1)
    best_a = np.take_along_axis(done, best_g[:, None, :], axis=1)[:, 0, :]
    end_idle = idle >= best_a
    value = np.where(end_idle, idle, best_a)
    value[np.arange(r_n)[None, :] > runs[:, None]] = neg
    return value, (cont, src, end_idle, best_g, big)


def _backtrack(choice, p: int, r: int, t_n: int) -> list[tuple[int, int]]:
    """Imaged (local group, local slot) of pass ``p`` (block row) with ``r`` runs."""
    cont, src, end_idle, best_g, big = choice
    out = []
    g, k = (-1, 0) if end_idle[p, r] else (int(best_g[p, r]), big - 1)
    for t in range(t_n - 1, -1, -1):
        if g == -1:
            s = int(src[t, p, r])
            g, k = (-1, 0) if s == -1 else (s, big - 1)
            continue
        out.append((g, t))
        if big == 1:
            if not cont[t, p, g, r]:
                g, r = -1, r - 1
        elif k == 0:
            g, r = -1, r - 1
        elif k < big - 1:
            k -= 1
        elif not cont[t, p, g, r]:
            k = big - 2
    return out


def _knapsack(values: list, cap: int):
    """Best total over passes with at most ``cap`` runs; returns (total, runs per pass).

    ``values[p][r]`` is pass p's best value with exactly r runs (-inf: impossible); the
    returned runs per pass are the ones whose value was used.
    """
    f = np.full(cap + 1, -np.inf)
    f[0] = 0.0
    picks, argbest = [], []
    for v in values:
        r_n = min(len(v), cap + 1)
        v = v[:r_n]
        at = np.zeros(r_n, dtype=np.int64)
        for r in range(1, r_n):
            at[r] = r if v[r] > v[at[r - 1]] else at[r - 1]
        vm = v[at]
        cand = np.full((cap + 1, r_n), -np.inf)
        for r in range(r_n):
            cand[r:, r] = f[: cap + 1 - r] + vm[r]
        pick = np.argmax(cand, axis=1)
        f = cand[np.arange(cap + 1), pick]
        picks.append(pick)
        argbest.append(at)
    k = int(np.argmax(f))
    total = float(f[k])
    runs = []
    for pick, at in zip(reversed(picks), reversed(argbest), strict=True):
        r = int(pick[k])
        runs.append(int(at[r]))
        k -= r
    return total, runs[::-1]


def lagrangian_value(prob: CoverProblem, lay: PassLayout, lam: np.ndarray, with_grad=True):
    """The Lagrangian bound at multipliers ``lam`` and (optionally) a subgradient.

    Args:
      prob: CoverProblem; lay: its PassLayout; lam: float64 [N], ``0 <= lam <= weight``.
      with_grad: also return the subgradient ``d = z - y`` (z: selected rows covering j).
    Returns:
      (L, d or None): L >= the coverage of every plan of the problem's groups.
    """
    w = prob.weight
    cum = np.concatenate([[0.0], np.cumsum(lam[prob.indices])])
    row_val = cum[prob.indptr[1:]] - cum[prob.indptr[:-1]]
    values = [None] * lay.n_pass
    choices = {}
    for blk in lay.blocks:
        pos = np.full(lay.n_pass, -1)
        pos[blk] = np.arange(blk.size)
        sel = np.nonzero(pos[lay.row_pass] >= 0)[0]
        shape = (blk.size, int(lay.n_groups[blk].max()), int(lay.n_slots[blk].max()))
        vals = np.zeros(shape)
        rowmap = np.full(shape, -1, dtype=np.int64)
        where = (pos[lay.row_pass[sel]], lay.row_lg[sel], lay.row_lt[sel])
        vals[where] = row_val[sel]
        rowmap[where] = sel
        v, ch = _block_dp(vals, lay.max_runs[blk], int(lay.min_len[blk[0]]))
        for i, p in enumerate(blk):
            values[p] = v[i, : int(lay.max_runs[p]) + 1]
            choices[int(p)] = (ch, i, rowmap)
    total, runs = _knapsack(values, prob.max_actions)
    bound = float(np.sum(np.clip(w - lam, 0.0, None))) + total
    if not with_grad:
        return bound, None
    chosen = np.zeros(prob.n_rows, dtype=bool)
    for p, r in enumerate(runs):
        if r:
            ch, i, rowmap = choices[p]
            for lgi, lt in _backtrack(ch, i, r, rowmap.shape[2]):
                row = rowmap[i, lgi, lt]
                if row >= 0:
                    chosen[row] = True
    counts = np.repeat(chosen, np.diff(prob.indptr))
    z = np.bincount(prob.indices[counts], minlength=prob.n_samples).astype(np.float64)
    y = (lam < w).astype(np.float64)
    return bound, z - y


@dataclass(frozen=True)
class BoundResult:
    """Outcome of :func:`lagrangian_bound`.

    Attributes:
      bound: the best (lowest) valid bound found.
      iterations: subgradient iterations run.
      lam: float64 [N], multipliers of the best bound.
      history: list of bound values per iteration.
    """

    bound: float
    iterations: int
    lam: np.ndarray
    history: list


def lagrangian_bound(
    prob: CoverProblem,
    target: float,
    deadline: float,
    max_iter: int = 5000,
    lam0: np.ndarray | None = None,
    deflect: float = DEFLECT,
    patience: int = PATIENCE,
) -> BoundResult:
    """Deflected subgradient descent on the Lagrangian bound (Polyak steps to ``target``).

    Direction ``D = deflect * d + (1 - deflect) * D_prev`` (d the subgradient), step
    ``theta (L - target) / |D|^2``, ``theta`` halved after ``patience`` iterations without
    a better bound; multipliers projected on ``[0, w]``.

    Args:
      prob: CoverProblem.
      target: a known plan value (lower bound) the steps aim at.
      deadline: ``time.perf_counter()`` instant to stop at (one evaluation always runs).
      max_iter: most iterations.
      lam0: optional start multipliers (default ``LAM0_SHARE * weight``).
      deflect: weight of the new subgradient in the direction (1 = plain subgradient).
      patience: iterations without improvement before ``theta`` halves.
    Returns:
      BoundResult.
    """
    lay = pass_layout(prob)
    w = prob.weight
    lam = np.clip(LAM0_SHARE * w if lam0 is None else lam0, 0.0, w)
    best, best_lam, hist = np.inf, lam.copy(), []
    theta, stall, direction = 1.0, 0, None
    it = 0
    for it in range(max_iter):  # noqa: B007 (reported after the loop)
        val, d = lagrangian_value(prob, lay, lam)
        hist.append(val)
        if val < best - 1e-9:
            best, best_lam, stall = val, lam.copy(), 0
        else:
            stall += 1
            if stall >= patience:
                theta, stall = theta * 0.5, 0
        direction = d if direction is None else deflect * d + (1.0 - deflect) * direction
        norm = float(direction @ direction)
        if norm == 0.0 or time.perf_counter() > deadline or theta < 1e-6:
            break
        step = theta * max(val - target, 1e-6) / norm
        lam = np.clip(lam - step * direction, 0.0, w)
    return BoundResult(float(best), it + 1, best_lam, hist)


def bound_main(argv=None) -> int:
    """Entry point of ``python -m jaxspline.search.coverage_bound PROBLEM.pkl SECONDS``.

    Reads the pickled ``(CoverProblem, target)``, runs :func:`lagrangian_bound` for
    SECONDS and prints ``bound iterations`` on stdout (so the search can run meanwhile in
    the parent process).

    Args:
      argv: command-line arguments (default ``sys.argv[1:]``).
    Returns:
      exit code 0.
    """
    import pickle
    import sys

    args = sys.argv[1:] if argv is None else argv
    t0 = time.perf_counter()
    with open(args[0], "rb") as fh:
        prob, target = pickle.load(fh)
    res = lagrangian_bound(prob, target, t0 + float(args[1]))
    print(f"{res.bound!r} {res.iterations}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(bound_main())
