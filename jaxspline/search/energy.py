"""Battery budgets as priced constraints of the Lagrangian bound (energy per orbit arc).

Without loads the battery of satellite k moves by ``base[k]`` per step (charge while
sunlit minus idle, :class:`jaxspline.search.BatteryModel`). Over any interval
``I = [a, b]`` of the horizon the level cannot exceed ``initial`` (a = 0) or
``capacity`` at ``a`` and must stay ``>= margin`` at ``b``, so the load energy spent
inside I obeys

    imaging energy of the observations inside I
      + slew energy of the near maneuvers inside I  <=  B_I
    B_I = (initial if a = 0 else capacity) - margin + sum of base over I.

Imaging counts ``imaging_w`` times the exact duration and a near maneuver ``slew_w``
times its required time less :data:`_SLEW_TOL` (always-feasible "far" transitions and
the first slew count zero), so every plan of the option model meets these
constraints: they relax its battery rule. Intervals start at 0 or a shadow entry and
end at a shadow exit or the horizon end. A constraint is dropped when no plan can
violate it: all options and near pairs inside fit in ``B_I``, or the interval is too
short (``|I| max(imaging_w, slew_w) <= B_I``: at most one load runs at a time).

Priced with ``nu_I >= 0`` in units of the constraint scaled by ``B_I``, option j
pays ``e_j sum_{I ∋ j} nu_I / B_I``, a near pair the same with its slew energy, and
the bound gains ``sum_I nu_I``. With A interval starts and E ends per satellite, "I
contains j" is ``a < ia_j`` and ``b >= ib_j`` on the index grid, so both the prices
of all options and the usage of a path are 2-D cumulative sums over an [A, E] grid.
"""

from __future__ import annotations

import numpy as np

from jaxspline.search.memory import trim_heap
from jaxspline.search.problem import Problem

__all__ = ["EnergyBudgets"]

_SLEW_TOL = 0.1  # [s] taken off each required slew time (covers the gap margin)
_CACHE_PAIRS = 1 << 25  # up to this many near pairs, each battery satellite's per-pair
# terms are kept between iterations (~28 bytes a pair); above, derived each time
_ARC_BLOCK = 1 << 18  # near pairs whose per-pair terms are derived at once (~18 MB)
_WH = 1.0 / 3600.0  # [Wh / J]


def _round_down32(x: np.ndarray) -> np.ndarray:
    """float32 copy never above x: a cheaper arc only raises the DP, so the bound stays valid."""
    x32 = x.astype(np.float32)
    high = x32.astype(np.float64) > x
    x32[high] = np.nextafter(x32[high], np.float32(-np.inf))
    return x32


class EnergyBudgets:
    """Interval energy constraints of the battery satellites (module docstring).

    Attributes:
      m: number of constraints kept (length of the price vector).
      n_options, n_near: sizes of the per-option and per-near-pair price vectors.
    """

    def __init__(self, pb: Problem):
        bat = pb.battery
        s = np.asarray(pb.option_start, np.float64)
        e = np.asarray(pb.option_end, np.float64)
        far = np.asarray(pb.far, np.float64)
        pairs = pb.pairs
        self.n_options, self.n_near = pb.n_options, len(pairs)
        self.sats = []
        m = 0
        for k in range(pb.n_sats):
            lo, hi = pb.sat_lo[k], pb.sat_hi[k]
            if not bat.has(k) or hi <= lo:
                continue
            p = bat.powers[k]
            lit = bat.charging[k]
            edges = np.flatnonzero(np.diff(lit.astype(np.int8)))
            a_i = np.r_[0, edges[~lit[edges + 1]] + 1]  # 0 and shadow entries [steps]
            b_i = np.r_[edges[lit[edges + 1]] + 1, bat.n]  # shadow exits and the end
            a_t, b_t = a_i * bat.dt, b_i * bat.dt
            cum = np.r_[0.0, np.cumsum(bat.base[k])]
            level = np.where(a_i == 0, p.initial_wh, p.capacity_wh)
            budget = level[:, None] - bat.margin_wh + cum[b_i][None, :] - cum[a_i][:, None]
            span = (b_t[None, :] - a_t[:, None]) * max(p.imaging_w, p.slew_w) * _WH
            sk = {
                "lo": lo,
                "hi": hi,
                "shape": (a_i.size, b_i.size),
                "ia": np.searchsorted(a_t, s[lo:hi], side="right"),
                "ib": np.searchsorted(b_t, e[lo:hi], side="left"),
                "e": p.imaging_w * (e[lo:hi] - s[lo:hi]) * _WH,
                "slew_wh": p.slew_w * _WH,
                "far": far[k],
                "s": s[lo:hi],
                "e_t": e[lo:hi],
                "pairs": pairs,
            }
            if self.n_near <= _CACHE_PAIRS:
                sk["arcs"] = self._arc_terms(sk, lo, hi)
            inside = self._usage(sk, np.ones(hi - lo, bool))
            kept = (a_t[:, None] < b_t[None, :]) & (budget > 0.0)
            kept &= (inside > budget) & (span > budget)
            sk["kept"], sk["budget"], sk["off"] = kept, budget[kept], m
            m += int(kept.sum())
            self.sats.append(sk)
        self.m = m

    def restrict(self, keep: np.ndarray) -> None:
        """Keep only the constraints where ``keep`` (bool [m]) is True (any subset of
        the budgets is still a relaxation of the battery rule)."""
        m = 0
        for sk in self.sats:
            mine = keep[sk["off"] : sk["off"] + sk["budget"].size]
            kept = sk["kept"].copy()
            kept[kept] = mine
            sk["kept"], sk["budget"], sk["off"] = kept, sk["budget"][mine], m
            m += int(mine.sum())
        self.m = m

    @staticmethod
    def _arc_terms(sk, a: int, b: int, chosen=None):
        """(positions, ia, ib, energy [Wh]) of the near pairs into options ``a..b-1`` of
        the satellite (those where the bool [P] ``chosen`` holds, default all)."""
        pairs, lo = sk["pairs"], sk["lo"]
        idx, dst = pairs.gather(np.arange(a, b))
        if chosen is not None:
            m = chosen[idx]
            idx, dst = idx[m], dst[m]
        src = pairs.src[idx].astype(np.int64) - lo
        dst = dst - lo
        gap = sk["s"][dst] - sk["e_t"][src]
        need = pairs.need[idx].astype(np.float64)
        slew = np.where(gap < sk["far"], np.maximum(need - _SLEW_TOL, 0.0), 0.0)
        ia, ib = sk["ia"][src].astype(np.int32), sk["ib"][dst].astype(np.int32)
        return idx, ia, ib, sk["slew_wh"] * slew

    @classmethod
    def _arcs(cls, sk, chosen=None):
        """The satellite's :meth:`_arc_terms` (where ``chosen`` holds, default all):
        the kept ones, else derived from the pair table in blocks of about
        :data:`_ARC_BLOCK` pairs (an iterator of such tuples)."""
        if "arcs" in sk:
            idx, ia, ib, ea = sk["arcs"]
            if chosen is None:
                yield idx, ia, ib, ea
            else:
                m = chosen[idx]
                yield idx[m], ia[m], ib[m], ea[m]
            return
        pairs, lo, hi = sk["pairs"], sk["lo"], sk["hi"]
        r = pairs.row_of[lo:hi]
        upto = np.cumsum(pairs.ptr[r + 1] - pairs.ptr[r])  # pairs into options lo..j
        marks = np.arange(_ARC_BLOCK, int(upto[-1]) if upto.size else 0, _ARC_BLOCK)
        cuts = np.unique(np.r_[0, np.searchsorted(upto, marks, side="right"), hi - lo])
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            yield cls._arc_terms(sk, lo + int(a), lo + int(b), chosen)

    @classmethod
    def _usage(cls, sk, nodes, arcs=None):
        """[A, E] energy inside each interval of the chosen options / near pairs (masks;
        ``arcs`` None: every near pair)."""
        a_n, e_n = sk["shape"]
        h = np.zeros((a_n + 1, e_n + 1))
        np.add.at(h, (sk["ia"][nodes], sk["ib"][nodes]), sk["e"][nodes])
        for _, ia, ib, ea in cls._arcs(sk, arcs):  # in pair order, block by block
            np.add.at(h, (ia, ib), ea)
        r = np.cumsum(np.cumsum(h[::-1], axis=0)[::-1], axis=1)  # sum over x >= a, y <= b
        return r[1:, :e_n]

    def penalties(self, nu: np.ndarray):
        """Per option and per near pair (``pb.pairs`` order) price of their energy.

        Args:
          nu: float [B], multipliers of the B energy budgets (>= 0).
        Returns:
          (node float64 [N], arc float32 [P]) prices (arcs rounded down: a cheaper arc
          can only raise the DP's optimum, so the bound stays an upper bound).
        """
        trim_heap()  # the last iteration's freed blocks: not resident beside the new arcs
        node = np.zeros(self.n_options)
        arc = np.zeros(self.n_near, np.float32)  # 4 bytes a pair, rounded down below
        for sk in self.sats:
            a_n, e_n = sk["shape"]
            v = np.zeros((a_n, e_n))
            v[sk["kept"]] = nu[sk["off"] : sk["off"] + sk["budget"].size] / sk["budget"]
            sp = np.zeros((a_n + 1, e_n + 1))  # sum over a < x, b >= y
            sp[1:, :e_n] = np.cumsum(np.cumsum(v[:, ::-1], axis=1)[:, ::-1], axis=0)
            node[sk["lo"] : sk["hi"]] = sk["e"] * sp[sk["ia"], sk["ib"]]
            for idx, ia, ib, ea in self._arcs(sk):
                arc[idx] = _round_down32(ea * sp[ia, ib])
        return node, arc

    def usage(self, nodes: np.ndarray, arcs: np.ndarray) -> np.ndarray:
        """Scaled energy per constraint of the chosen options and near pairs.

        Args:
          nodes: bool [N], chosen options.
          arcs: bool [P], chosen near pairs.
        Returns:
          float [B], usage of each budget as a fraction of it.
        """
        out = np.zeros(self.m)
        for sk in self.sats:
            u = self._usage(sk, nodes[sk["lo"] : sk["hi"]], arcs)
            out[sk["off"] : sk["off"] + sk["budget"].size] = u[sk["kept"]] / sk["budget"]
        return out
