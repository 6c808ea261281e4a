"""Best strips inside one pass: a dynamic programme over (slot, group, strips used).

Within one pass of one satellite a sample is swept at one instant, so the rows of
different slots are (up to their shared borders) disjoint and the value of a set of
strips is close to the sum of its rows' open weights. :func:`best_runs` finds the set of
runs (strips) maximizing ``sum of row values - price * runs`` exactly, with:

* each run one group over consecutive allowed slots, ``lmin <= length <= lmax``;
* consecutive runs ``(g', ends at t')`` -> ``(g, starts at s)`` separated by
  ``s - t' >= gaps[g', g]`` slots (the maneuver between them,
  :func:`jaxspline.search.area_fill.pass_gaps`);
* at most ``rmax`` runs.

``F_r[t, g]`` = best value of ``r`` runs, the last of group ``g`` ending at slot ``t``;
``F_r[t, g] = max_L C[g, t] - C[g, t - L] - price + B_{r-1}[t - L, g]`` with
``B_{r-1}[s, g] = max_{g'} max_{t' <= s - gaps[g', g]} F_{r-1}[t', g']`` (``B_0 = 0``).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["best_runs", "run_layers", "runs_of"]

NEG = -np.inf


def _layer(c, blk, b_prev, lmin, lmax, price):
    """One DP layer: F [T+1, G] and the chosen run length per cell."""
    g_n, t1 = c.shape
    f = np.full((t1, g_n), NEG)
    larg = np.zeros((t1, g_n), dtype=np.int64)
    for length in range(lmin, min(lmax, t1 - 1) + 1):
        t = np.arange(length, t1)
        s = t - length
        val = (c[:, t] - c[:, s]).T - price + b_prev[s]
        val = np.where((blk[:, t] - blk[:, s]).T == 0, val, NEG)
        upd = val > f[t]
        f[t] = np.where(upd, val, f[t])
        larg[t] = np.where(upd, length, larg[t])
    return f, larg


def _next_start(f, gaps):
    """B[s, g] = max over g', t' <= s - gaps[g', g] of F[t', g'], with the argmax (t', g')."""
    t1, g_n = f.shape
    pf = np.maximum.accumulate(f, axis=0)
    pos = np.where(f == pf, np.arange(t1)[:, None], 0)
    parg = np.maximum.accumulate(pos, axis=0)
    idx = np.arange(t1)[:, None, None] - gaps[None, :, :]
    cols = np.arange(g_n)[None, :, None]
    gathered = np.where(idx >= 0, pf[np.clip(idx, 0, None), cols], NEG)
    gp = np.argmax(gathered, axis=1)
    b = np.take_along_axis(gathered, gp[:, None, :], axis=1)[:, 0, :]
    tp = parg[np.clip(np.take_along_axis(idx, gp[:, None, :], axis=1)[:, 0, :], 0, None), gp]
    return b, gp, tp


def run_layers(vals, allowed, gaps, lmin: int, lmax: int, rmax: int, price: float = 0.0):
    """The DP layers of one pass: per number of runs, the best value and how to get it.

    Args:
      vals, allowed, gaps, lmin, lmax, rmax, price: as :func:`best_runs`.
    Returns:
      (tops, layers): tops float [rmax + 1], best value with exactly r runs (-inf when
      impossible, tops[0] = 0); layers for :func:`runs_of`.
    """
    vals = np.asarray(vals, dtype=np.float64)
    g_n, t_n = vals.shape
    tops = np.full(rmax + 1, NEG)
    tops[0] = 0.0
    layers = []
    if g_n == 0 or t_n < lmin:
        return tops, layers
    c = np.concatenate([np.zeros((g_n, 1)), np.cumsum(np.where(allowed, vals, 0.0), axis=1)], 1)
    blk = np.concatenate([np.zeros((g_n, 1)), np.cumsum(~allowed, axis=1)], axis=1)
    b_prev = np.zeros((t_n + 1, g_n))
    for r in range(rmax):
        f, larg = _layer(c, blk, b_prev, lmin, lmax, price)
        top = float(np.max(f))
        tops[r + 1] = top
        if not math.isfinite(top):
            break
        b_prev, gp, tp = _next_start(f, gaps)
        layers.append((f, larg, gp, tp))
    return tops, layers


def runs_of(layers, r: int) -> list:
    """The runs (g, s, t) of the best ``r``-run solution of :func:`run_layers` (r >= 1)."""
    f = layers[r - 1][0]
    t, g = np.unravel_index(int(np.argmax(f)), f.shape)
    t, g, r = int(t), int(g), r - 1
    runs = []
    while True:
        larg = layers[r][1]
        s = t - int(larg[t, g])
        runs.append((g, s, t))
        if r == 0:
            break
        _, _, gp, tp = layers[r - 1]
        g, t = int(gp[s, g]), int(tp[s, g])
        r -= 1
    return runs[::-1]


def best_runs(vals, allowed, gaps, lmin: int, lmax: int, rmax: int, price: float = 0.0):
    """The best set of runs of one pass (see the module docstring).

    Args:
      vals: float [G, T], value of each (group, slot) row.
      allowed: bool [G, T], where a group may image.
      gaps: int [G, G], slots between runs (>= 1).
      lmin, lmax: run length limits [slots].
      rmax: most runs.
      price: subtracted per run.
    Returns:
      (value, runs): the best total and a list of (g, s, t) runs, slots ``[s, t)``
      relative to the pass's first slot, in time order (value 0 and [] when no run pays).
    """
    if rmax < 1:
        return 0.0, []
    tops, layers = run_layers(vals, allowed, gaps, lmin, lmax, rmax, price)
    r = int(np.argmax(tops))
    if r == 0 or tops[r] <= 1e-15:
        return 0.0, []
    return float(tops[r]), runs_of(layers, r)
