"""The areas' part of the bound: an exact dynamic programme per pass, a knapsack over passes.

Area options are strips of roll groups over slots (:mod:`jaxspline.search.cover`); their
transitions are never screened pair by pair. The bound relaxes them as follows (every
plan of the problem's area options is a plan of the relaxation): a satellite images at
most one group per slot; two strips of different groups leave at least one idle slot
between them (their maneuver takes time: the look directions differ); strips of one
group back to back are one longer strip (the longest strip is dropped); a strip spans at
least the satellite's shortest strip; a pass (a satellite's groups whose slots chain,
:func:`jaxspline.search.cover.group_passes`) holds at most ``floor((T + 1) / (min + 1))``
strips; the plan at most ``max_actions`` (all passes together). Dropped: slews longer
than a slot, the duty, the battery, the separation between passes and the point and
strip targets' observations on the same satellite (their own DP, summed: valid).

For row credits ``c_row`` (the Lagrangian's ``sum (w_s - lam_s)`` of the row's samples,
:mod:`jaxspline.search.lagrangian`) :func:`area_dp` finds the best value of every pass
with ``r`` runs by one forward pass over its slots (state: idle, or imaging group g with
the run length so far capped at the shortest strip; runs used), then the best runs per
pass under the cap by a knapsack, and the rows the chosen runs take.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BLOCK_CELLS", "PassLayout", "area_dp", "pass_layout", "run_options"]

#: Padded DP cells per block of passes (memory / speed trade-off).
BLOCK_CELLS = 6_000_000


@dataclass(frozen=True)
class PassLayout:
    """Where each row sits in the per-pass DP arrays.

    Attributes:
      n_pass: number of passes.
      row_pass, row_lg, row_lt: int64 [rows], pass, local group and local slot of each row.
      n_groups, n_slots, max_runs, min_len: int64 [n_pass], per pass (min_len: fewest
        slots of a strip).
      blocks: list of int arrays of pass indices processed together.
      cap: most runs of a plan (the action cap, or the sum of the passes' most).
      pass_ptr, pass_samples: CSR of the samples each pass's rows cover (each once).
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
    cap: int
    pass_ptr: np.ndarray
    pass_samples: np.ndarray


def pass_layout(cv, max_actions: int | None) -> PassLayout:
    """Group the rows of a :class:`jaxspline.search.cover.CoverTable` by pass.

    Args:
      cv: CoverTable; max_actions: the plan's action cap (None: none).
    Returns:
      PassLayout.
    """
    gp = cv.group_pass
    n_pass = int(gp.max()) + 1 if gp.size else 0
    first = np.full(n_pass, np.iinfo(np.int64).max)
    last = np.zeros(n_pass, dtype=np.int64)
    np.minimum.at(first, gp, cv.group_slot0)
    np.maximum.at(last, gp, cv.group_slot0 + cv.group_nslots)
    order = np.lexsort((np.arange(gp.size), gp))
    lg = np.empty(gp.size, dtype=np.int64)
    counts = np.bincount(gp, minlength=n_pass)
    lg[order] = np.arange(gp.size) - np.repeat(np.cumsum(counts) - counts, counts)
    nrow = cv.group_nslots
    row_group = np.repeat(np.arange(gp.size), nrow)
    within = np.arange(cv.n_rows) - np.repeat(cv.group_row0, nrow)
    row_lt = cv.group_slot0[row_group] - first[gp[row_group]] + within
    n_slots = last - first
    sat_of_pass = np.zeros(n_pass, dtype=np.int64)
    sat_of_pass[gp] = cv.group_sat
    need = np.asarray(cv.min_slots, np.int64)[sat_of_pass]
    max_runs = np.maximum((n_slots + 1) // (need + 1), 1)
    cap = int(max_runs.sum()) if max_actions is None else int(max_actions)
    max_runs = np.minimum(max_runs, max(cap, 1))
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
    row_pass = gp[row_group]
    per_row = np.diff(cv.indptr)
    key = np.unique(np.repeat(row_pass, per_row) * cv.n_samples + cv.indices)
    pass_ptr = np.searchsorted(key // max(cv.n_samples, 1), np.arange(n_pass + 1))
    return PassLayout(n_pass, row_pass, lg[row_group], row_lt, counts, n_slots, max_runs, need,
                      blocks, cap, pass_ptr, key % max(cv.n_samples, 1))  # fmt: skip


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


def area_dp(
    cv,
    lay: PassLayout,
    row_credit: np.ndarray,
    sample_credit=None,
    capped=None,
    action_price: float = 0.0,
    runs_out=None,
):
    """The areas' part of the relaxation at row credits (module docstring).

    With ``sample_credit`` each pass's value is also capped by the credits of the samples
    it can cover, each once (the rows of a pass may cover a sample at several slots when
    the satellite pitches; the relaxation of :mod:`jaxspline.search.lagrangian` counts a
    sample once per pass).

    Args:
      cv: CoverTable; lay: its :func:`pass_layout`; row_credit: float64 [R], each row's
        credit; sample_credit: optional float64 [N samples], each sample's credit (the sum
        over its rows' samples gives ``row_credit``); capped: optional list, gets the
        passes whose cap is below their runs' value; action_price: each run's charge
        (the Lagrangian price of the action cap); runs_out: optional list, gets the runs
        of each pass in the chosen plan.
    Returns:
      (value, rows): the best total (>= what any plan's area options are credited) and
      int64 the rows the chosen runs take.
    """
    if lay.n_pass == 0:
        return 0.0, np.zeros(0, np.int64)
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
        vals[where] = row_credit[sel]
        rowmap[where] = sel
        v, ch = _block_dp(vals, lay.max_runs[blk], int(lay.min_len[blk[0]]))
        for i, p in enumerate(blk):
            values[p] = v[i, : int(lay.max_runs[p]) + 1]
            choices[int(p)] = (ch, i, rowmap)
    over = set()
    if sample_credit is not None:
        pos = np.maximum(sample_credit, 0.0)[lay.pass_samples]
        most = np.add.reduceat(np.r_[pos, 0.0], lay.pass_ptr[:-1]) * (np.diff(lay.pass_ptr) > 0)
        for p in range(lay.n_pass):
            over.update([p] if values[p][1:].max(initial=-np.inf) > most[p] else [])
            values[p] = np.minimum(values[p], most[p])
    if action_price:
        values = [v - action_price * np.arange(v.size) for v in values]
    total, runs = _knapsack(values, lay.cap)
    if runs_out is not None:
        runs_out.extend(runs)
    if capped is not None:
        capped.extend(p for p, r in enumerate(runs) if r and p in over)
    rows = []
    for p, r in enumerate(runs):
        if r:
            ch, i, rowmap = choices[p]
            for lgi, lt in _backtrack(ch, i, r, rowmap.shape[2]):
                row = rowmap[i, lgi, lt]
                if row >= 0:
                    rows.append(int(row))
    return total, np.asarray(sorted(rows), np.int64)


def run_options(cv, rows: np.ndarray) -> list:
    """The area options of the runs that rows of :func:`area_dp` make: per group its rows'
    consecutive slots, cut into strips no longer than the satellite's longest (each the
    problem's option of that window, or of the longest window inside it that is one).

    Args:
      cv: CoverTable; rows: int [K], rows (group slots).
    Returns:
      list of option ids.
    """
    if rows.size == 0:
        return []
    group = np.searchsorted(cv.group_row0, rows, side="right") - 1
    slot = cv.group_slot0[group] + rows - cv.group_row0[group]
    out = []
    cut = np.flatnonzero((np.diff(group) != 0) | (np.diff(slot) != 1)) + 1
    for run_g, run_s in zip(np.split(group, cut), np.split(slot, cut), strict=True):
        g = int(run_g[0])
        a, b = int(run_s[0]), int(run_s[-1]) + 1
        most = int(cv.max_slots[cv.group_sat[g]])
        need = int(cv.min_slots[cv.group_sat[g]])
        for s in range(a, b, most):
            c = _window_option(cv, g, s, min(b, s + most), need)
            if c >= 0:
                out.append(c)
    return out


def _window_option(cv, g: int, a: int, b: int, need: int) -> int:
    """The option of group g over ``[a, b)``, else the longest (earliest) one inside it."""
    for length in range(b - a, need - 1, -1):
        for s in range(a, b - length + 1):
            c = cv.option_of(g, s, s + length)
            if c >= 0:
                return c
    return -1
