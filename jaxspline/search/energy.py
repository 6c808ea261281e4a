"""Battery budgets as priced constraints of the Lagrangian bound (energy from the start).

Without loads the battery of satellite k moves by ``base[k]`` per step (charge while
sunlit minus idle, :class:`jaxspline.search.BatteryModel`). Its level never exceeds
the unclamped sum, so at any step ``b`` the loads before it obey

    imaging energy of the observations ending by b
      + slew energy of the near maneuvers into them  <=  B_b
    B_b = initial - margin + sum of base over [0, b)

(``margin``: the level the model keeps, :attr:`BatteryModel.margin_wh`). The steps b
are the satellite's shadow exits and the horizon end: between two of them the budget
only falls (no charge in shadow), so these are the constraints that can bind first.
Imaging counts ``imaging_w`` times the exact duration, a near maneuver ``slew_w``
times its required time less :data:`_SLEW_TOL`, and maneuvers through the always-feasible
"far" transitions and the first slew count zero: every plan of the option model meets
these constraints (a subset of its loads, each at most what the model charges), so
pricing them relaxes its battery rule. Budgets from a later start (from a full battery)
relax it too, but with a 1.3 kWh battery they never bound on the scale instances: left
out, each would cost a cumulative pass per iteration.

Priced with ``nu_b >= 0`` in units of value per :attr:`EnergyBudgets.unit` Wh (the
energy of :data:`_UNIT_OBS` typical observations and their maneuvers on that satellite,
so a unit of the subgradient is a few observations too many, near the target prices'
scale), option j
pays ``rate_j e_j`` and a near pair into j ``rate_j`` times its slew energy, with
``rate_j = sum_{b: j ends by b} nu_b / unit`` (value per Wh), and the bound gains
``sum_b nu_b B_b / unit``. The pair costs are derived block by block inside the DP
(:class:`jaxspline.search.dp.NeedPrice`): no array the size of the pair table.
"""

from __future__ import annotations

import numpy as np

from jaxspline.search.dp import NeedPrice
from jaxspline.search.problem import Problem

__all__ = ["EnergyBudgets"]

_SLEW_TOL = 0.1  # [s] taken off each required slew time (covers the gap margin)
_WH = 1.0 / 3600.0  # [Wh / J]
#: observations' energy a unit of an energy price stands for: at one, the budgets' rows
#: (tens of observations over at first) took most of every step's length and the
#: target prices moved slowly (unseen 12 x 12 h instance: 45,746 converged, 45,659 at
#: three; the plain bound 45,827)
_UNIT_OBS = 3.0


class EnergyBudgets:
    """Energy budgets from the horizon start of the battery satellites (module docstring).

    Attributes:
      m: number of constraints kept (length of the price vector).
      budget: float [m], ``B_b`` of each kept constraint [Wh].
      unit: float [m], the energy a unit of its price and subgradient stands for [Wh].
    """

    def __init__(self, pb: Problem):
        bat = pb.battery
        s = np.asarray(pb.option_start, np.float64)
        e = np.asarray(pb.option_end, np.float64)
        self.n_options = pb.n_options
        self.need, self.ptr, self.rows = pb.pairs.need, pb.pairs.ptr, pb.pairs.rows
        self.sats = []
        budgets, units = [], []
        for k in range(pb.n_sats):
            lo, hi = pb.sat_lo[k], pb.sat_hi[k]
            if not bat.has(k) or hi <= lo:
                continue
            p = bat.powers[k]
            lit = bat.charging[k]
            edges = np.flatnonzero(np.diff(lit.astype(np.int8)))
            ends = np.r_[edges[lit[edges + 1]] + 1, bat.n]  # shadow exits and the end [steps]
            cum = np.r_[0.0, np.cumsum(bat.base[k])]
            budget = p.initial_wh - bat.margin_wh + cum[ends]
            img = p.imaging_w * (e[lo:hi] - s[lo:hi]) * _WH
            unit = _UNIT_OBS * (float(img.mean()) + p.slew_w * pb.far[k] * 0.5 * _WH)
            self.sats.append(
                {
                    "k": k,
                    "lo": lo,
                    "hi": hi,
                    "ib": np.searchsorted(ends * bat.dt, e[lo:hi], side="left"),
                    "e": img,
                    "slew_wh": p.slew_w * _WH,
                    "off": sum(b.size for b in budgets),
                    "n_ends": ends.size,
                }
            )
            budgets.append(budget)
            units.append(np.full(ends.size, unit))
        budget = np.concatenate(budgets) if budgets else np.zeros(0)
        self._n_all = budget.size
        # kept constraint -> its place among all; a budget <= 0 is one the empty plan
        # already breaks (the model then refuses every insertion): priced, it would pull
        # the bound below that plan's value, so it is left out like any other
        self._index = np.flatnonzero(budget > 0.0)
        self.budget = budget[self._index]
        self.unit = (np.concatenate(units) if units else np.zeros(0))[self._index]
        self.m = self.budget.size

    def restrict(self, keep: np.ndarray) -> None:
        """Keep only the constraints where ``keep`` (bool [m]) is True (any subset of
        the budgets is still a relaxation of the battery rule)."""
        keep = np.asarray(keep, bool)
        self._index = self._index[keep]
        self.budget, self.unit = self.budget[keep], self.unit[keep]
        self.m = self.budget.size

    def _full(self, x: np.ndarray) -> np.ndarray:
        """A vector over the kept constraints, spread over all of them (0 elsewhere)."""
        out = np.zeros(self._n_all)
        out[self._index] = x
        return out

    def penalties(self, nu: np.ndarray):
        """Per option the price of its imaging energy, and the near pairs' prices.

        Args:
          nu: float [m], prices of the kept budgets (>= 0).
        Returns:
          ``(node, arc)``: float [N] and a :class:`NeedPrice` (value per second of each
          near pair's required time, by destination).
        """
        per_wh = self._full(nu / self.unit)
        node = np.zeros(self.n_options)
        rate = np.zeros(self.n_options)
        for sk in self.sats:
            g = per_wh[sk["off"] : sk["off"] + sk["n_ends"]]
            r = np.cumsum(g[::-1])[::-1][sk["ib"]]  # sum over the budgets j ends by
            node[sk["lo"] : sk["hi"]] = r * sk["e"]
            rate[sk["lo"] : sk["hi"]] = r * sk["slew_wh"]
        return node, NeedPrice(rate, self.need, _SLEW_TOL)

    def subgradient(self, paths, used) -> np.ndarray:
        """``(usage - budget) / unit`` of each kept budget for DP paths.

        Args:
          paths: per satellite the option ids of its path.
          used: the near-pair positions the paths take (``pb.pairs`` order).
        Returns:
          float [m].
        """
        q = np.asarray(used, np.int64)
        dst = self.rows[np.searchsorted(self.ptr, q, side="right") - 1]
        slew = np.maximum(self.need[q].astype(np.float64) - _SLEW_TOL, 0.0)
        usage = np.zeros(self._n_all)
        for sk in self.sats:
            lo, hi, n_e = sk["lo"], sk["hi"], sk["n_ends"]
            mine = np.asarray(paths[sk["k"]], np.int64) - lo
            per = np.bincount(sk["ib"][mine], sk["e"][mine], minlength=n_e)
            a = (dst >= lo) & (dst < hi)
            per += np.bincount(sk["ib"][dst[a] - lo], slew[a] * sk["slew_wh"], minlength=n_e)
            usage[sk["off"] : sk["off"] + n_e] = np.cumsum(per)
        return (usage[self._index] - self.budget) / self.unit
