"""Slew tables: the rest-to-rest required time as one lookup per pair.

A rest-to-rest model (:mod:`jaxspline.screen.models`) needs, for a transition
between two lines of sight, its profile time through the angle between them plus
settling plus the gap margin (``sat.maneuver.slew_time``); the pair is feasible iff that
time fits in the gap ``T = t_start[j] - t_end[i]``.

Rest-to-rest models are evaluated through a per-satellite *slew table*: on the angle
grid ``theta_k = pi (k / N)^2`` (fine near 0, where the time grows like sqrt(theta)) an
angle theta is read at the next grid angle above it (one index, one load). Entry k is
an UPPER BOUND of the exact time (``sat.maneuver.slew_time``) over the whole cell
``(theta_{k-1}, theta_k]`` that reads it, so the planner never needs the plan's final
check (which uses the kernel itself) to reject a slew the table allowed. The exact time
is not monotone: it is non-decreasing on pieces, but the flexible profile drops at the
A -> C switch ``7/6 omega^2/eps`` (from ``sqrt(28/3) b`` to ``3 b``, ``b = omega/eps``,
SPEC section 2), so the entry is the larger of the time at the cell's upper end and the
left limits of the drops inside the cell (``sat.maneuver.time_drops``), evaluated a little
beyond both (``_ANGLE_SLACK``: lookup and angle rounding) plus ``_TIME_PAD``. The excess
is the rise of the time over one cell (below 3e-3 s for the aeossp limits), except in
the single cell holding a drop, which keeps the whole drop (0.055 b). The table is not
monotone; the models' far gaps use its running maximum.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from jaxspline.geometry.frames import angle_between

__all__ = ["SlewTable", "slew_table", "table_time"]

_TABLE_SIZE = 1 << 16  # points of a slew table
#: A slew-table entry bounds the time up to ``theta (1 + rel) + abs`` [rad] above its cell:
#: covers the lookup's index guard (angles up to ``theta_k (1 + 2e-12 / k)`` read entry
#: k) and the ~1e-16 rad differences between the angle formulas of the screen, the search
#: and the plan check (near 0 the time grows like sqrt(theta): 1e-14 rad costs ~3e-6 s).
_ANGLE_SLACK = (1e-9, 1e-14)
#: Added to every slew-table entry [s]: the kernels' own rounding (~1e-13 s).
_TIME_PAD = 1e-9


class SlewTable(NamedTuple):
    """Conservative rest-to-rest slew time of one satellite, including settle and margin.

    Attributes:
      time: [N + 1] required time [s] read by the angles of the cell
        ``(theta_{k-1}, theta_k]``, ``theta_k = pi (k/N)^2``: an upper bound of the
        exact time over the cell (module docstring); not monotone in k.
      size: N.
    """

    time: np.ndarray
    size: int

    def __call__(self, theta) -> np.ndarray:
        """Required time [s] for angles theta [rad] (numpy, never below the exact time)."""
        return self.time[_cell(theta, self.size)]

    def scalar(self, theta: float) -> float:
        """Same as calling the table, for one Python float (the search's hot loop).

        Args:
          theta: float, slew angle [rad] (clipped to [0, pi]).
        Returns:
          float, required time [s].
        """
        k = math.ceil(self.size * math.sqrt(min(max(theta, 0.0), math.pi) / math.pi) - 1e-12)
        return self.time.item(min(k, self.size))  # a Python float, no numpy scalar


def _cell(theta, size: int):
    """Table index read by angles theta [rad] (numpy; the formula of :class:`SlewTable`)."""
    theta = np.clip(np.asarray(theta, np.float64), 0.0, math.pi)
    k = np.minimum(np.ceil(size * np.sqrt(theta / math.pi) - 1e-12), size)
    return k.astype(np.int64)


def slew_table(sat, gap_margin: float = 0.0, size: int = _TABLE_SIZE) -> SlewTable:
    """Tabulate an upper bound of the exact slew time of a rest-to-rest satellite.

    ``time[k] = max(t(theta_k (1 + rel) + abs), left limits of the drops of t in the
    cell) + _TIME_PAD`` with t = ``sat.maneuver.slew_time``, ``(rel, abs) = _ANGLE_SLACK`` and the
    drops of ``sat.maneuver.time_drops`` (t is non-decreasing between them): so ``time[k] >= t``
    on the whole cell ``(theta_{k-1}, theta_k]`` that reads entry k (module docstring).

    Args:
      sat: Satellite with a rest-to-rest model.
      gap_margin: float, extra time added to every slew [s].
      size: int N, the table has N + 1 entries at theta_k = pi (k/N)^2.
    Returns:
      SlewTable (not monotone in the angle; the far gaps take its running maximum).
    Raises:
      ValueError: naming the satellite if the time drops in a cell where no drop is
        known (the bound would not hold: the profile changed, update the model's ``time_drops``).
    """
    rel, abs_ = _ANGLE_SLACK
    theta = math.pi * (np.arange(size + 1) / size) ** 2
    model = sat.maneuver
    if not model.rest_to_rest:
        raise ValueError(f"satellite {sat.name!r}: model {sat.model!r} is not rest-to-rest")
    t = model.slew_time(sat, np.minimum(theta * (1.0 + rel) + abs_, math.pi), gap_margin)
    known = np.zeros(size + 1, bool)
    for lo, hi, t_left in model.time_drops(sat, gap_margin, rel, abs_):
        k0, k1 = _cell([lo, hi], size)
        t[k0 : k1 + 1] = np.maximum(t[k0 : k1 + 1], t_left)
        known[k0 : k1 + 2] = True  # the drop may also show at the next node
    drop = np.flatnonzero(np.diff(t) < 0.0) + 1
    if np.any(~known[drop]):
        k = int(drop[~known[drop]][0])
        raise ValueError(
            f"satellite {sat.name!r}: model {sat.model!r} slew time drops between "
            f"{theta[k - 1]!r} and {theta[k]!r} rad, where no drop is known: the table "
            "would not bound it"
        )
    return SlewTable(t + _TIME_PAD, size)


def table_time(table: SlewTable, frm, i, to, j, available):
    """Table time of the slew from direction ``frm[i]`` to ``to[j]``; inf if over ``available``."""
    t_req = table(angle_between(np.asarray(frm)[i], np.asarray(to)[j]))
    return np.where(available >= t_req, t_req, np.inf)
