"""Battery-aware moves of the LNS: value per Wh and making room for an observation.

When a satellite's battery binds (its lowest level is within the energy of
:data:`_TIGHT_S` seconds of imaging and slewing of the margin), energy, not time, is
the scarce resource on it:

* destroy around a scheduled observation: the one of least value per Wh among
  :data:`_TOURNAMENT` random ones of the satellite;
* re-insertion order: targets by value per Wh (:meth:`EnergyRank.order`) instead of
  value, so that the energy goes to the observations that pay most for it;
* making room (:func:`make_room`): an option that fails on the battery alone gets
  energy by removing the satellite's observations of least value per Wh among those
  whose removal can reach it: after the last instant before it at full charge (energy
  freed earlier is spilled at capacity) and before the first later instant where the
  level would drop below the margin. Removal stops as soon as the option fits, and
  gives up when the removed value reaches the option's.

The energy of a scheduled observation is what its removal frees: imaging plus the
maneuvers into and out of it less the one that replaces them
(:meth:`EnergyRank.removal_wh`); an unscheduled target is ranked by its cheapest option
with a maneuver of :data:`_SLEW_REF_S` seconds.
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.search.timeline import Timeline

__all__ = ["EnergyRank", "make_room", "option_wh"]

_TIGHT_S = 60.0  # [s] imaging + slewing whose energy above the margin marks a binding battery
_SLEW_REF_S = 30.0  # [s] maneuver per observation when ranking targets by value per Wh
_RANK_NOISE = 0.2  # relative noise of the value-per-Wh ranks
_FULL_TOL = 1e-9  # [Wh] a level this close to capacity counts as full
_WH = 1.0 / 3600.0  # [Wh / J]
_TOURNAMENT = 3  # observations drawn when a destroy move starts at a cheap one
_MIN_WH = 1e-9  # [Wh] floor of an energy in a value-per-Wh ratio


def option_wh(pb, c: int, maneuver: float) -> float:
    """Imaging plus slew energy of option c after a maneuver of ``maneuver`` s.

    Args:
      pb: :class:`jaxspline.search.Problem`.
      c: int, option id.
      maneuver: float [s].
    Returns:
      float [Wh] (0 for a satellite without a power model).
    """
    p = pb.battery.powers[pb.option_sat[c]]
    if p is None:
        return 0.0
    return (p.imaging_w * (pb.option_end[c] - pb.option_start[c]) + p.slew_w * maneuver) * _WH


class EnergyRank:
    """Value per Wh of targets and options; which satellites' batteries bind.

    Args:
      pb: :class:`jaxspline.search.Problem`.
      target_options: per target its options on offer (a timeline's
        ``target_options``); None: ``pb.target_options``.
    """

    def __init__(self, pb, target_options=None):
        self.pb = pb
        self.target_options = pb.target_options if target_options is None else target_options
        bat = pb.battery
        self.tight_wh = [
            (p.imaging_w + p.slew_w) * _TIGHT_S * _WH if p is not None else math.inf
            for p in bat.powers
        ]
        self.target_wh = []
        for options in self.target_options:
            wh = [self.option_wh(c, _SLEW_REF_S) for c in options if bat.has(pb.option_sat[c])]
            self.target_wh.append(min(wh) if len(wh) == len(options) and wh else 0.0)
        self._dens = self._mean = self._sats = None  # target_weights' constants, once needed

    def option_wh(self, c: int, maneuver: float) -> float:
        """:func:`option_wh` of this rank's problem."""
        return option_wh(self.pb, c, maneuver)

    def removal_wh(self, tl: Timeline, k: int, i: int) -> float:
        """Energy freed by removing position i of satellite k's timeline.

        Its imaging, the maneuvers into it and out of it, less the maneuver that
        replaces them (into the successor from the predecessor).

        Args:
          tl: Timeline.
          k: int, satellite index.
          i: int, position.
        Returns:
          float [Wh], at least the imaging energy.
        """
        pb = self.pb
        line = tl.lines[k]
        man = tl.maneuver_into(k, i)
        if i + 1 < len(line):
            q = line[i + 1]
            new = pb.option_first[q] if i == 0 else tl.need(line[i - 1], q)
            man += tl.maneuver_into(k, i + 1) - new
        return self.option_wh(line[i], max(man, 0.0))

    def cheap_pick(self, tl: Timeline, k: int, rng) -> int:
        """The observation of least value per Wh among :data:`_TOURNAMENT` random ones.

        Args:
          tl: Timeline.
          k: int, satellite index (with observations).
          rng: ``random.Random``.
        Returns:
          int, option id.
        """
        line = tl.lines[k]
        pick = [rng.randrange(len(line)) for _ in range(_TOURNAMENT)]
        w = self.pb.target_value
        option_target = self.pb.option_target
        return line[
            min(
                pick,
                key=lambda i: w[option_target[line[i]]] / max(self.removal_wh(tl, k, i), _MIN_WH),
            )
        ]

    def binds(self, tl: Timeline, k: int) -> bool:
        """Whether satellite k's battery binds in the current plan (module docstring).

        Args:
          tl: Timeline.
          k: int, satellite index.
        Returns:
          bool.
        """
        low = tl.battery_low(k)
        return low is not None and low < tl.pb.battery.margin_wh + self.tight_wh[k]

    def target_weights(self, tl: Timeline, targets):
        """Odds of picking each target as the aim of a targeted LNS move.

        Its value, times its value per Wh relative to the mean over all targets when
        every satellite that can image it binds.

        Args:
          tl: Timeline.
          targets: list of target indices.
        Returns:
          list of floats.
        """
        pb = self.pb
        bound = [self.binds(tl, k) for k in range(pb.n_sats)]
        if not any(bound):
            return [pb.target_value[t] for t in targets]
        if self._dens is None:  # constants of the problem, made once
            self._dens = [
                pb.target_value[t] / wh if wh > 0.0 else 0.0 for t, wh in enumerate(self.target_wh)
            ]
            self._mean = sum(self._dens) / max(1, sum(d > 0.0 for d in self._dens))
            self._sats = [sorted({pb.option_sat[c] for c in opts}) for opts in self.target_options]
        dens, mean, sats = self._dens, self._mean, self._sats
        out = []
        for t in targets:
            w = pb.target_value[t]
            if dens[t] > 0.0 and all(bound[k] for k in sats[t]):
                w *= dens[t] / mean
            out.append(w)
        return out

    def order(self, targets, rng):
        """Targets by value per Wh, best first, with relative noise (ties: target id).

        Args:
          targets: iterable of target indices.
          rng: ``random.Random``, or None for no noise.
        Returns:
          list of target indices.
        """
        w, wh = self.pb.target_value, self.target_wh

        def key(t):
            dens = w[t] / wh[t] if wh[t] > 0.0 else math.inf
            return (-dens * (1.0 + (0.0 if rng is None else _RANK_NOISE * rng.random())), t)

        return sorted(targets, key=key)


def _reach(tl: Timeline, c: int, need_wh: float):
    """Time span [s] whose observations' energy can reach option c (module docstring)."""
    pb = tl.pb
    k = pb.option_sat[c]
    bat = pb.battery
    lev = tl.battery_level(k)
    cap = bat.powers[k].capacity_wh
    i = min(bat.step_index(pb.option_start[c]), bat.n)
    full = np.flatnonzero(lev[: i + 1] >= cap - _FULL_TOL)
    lo = int(full[-1]) if full.size else 0
    low = np.flatnonzero(lev[i:] < bat.margin_wh + need_wh)
    hi = i + int(low[0]) if low.size else bat.n
    return lo * bat.dt, hi * bat.dt


def make_room(tl: Timeline, c: int, er: EnergyRank, rng):
    """Remove observations of least value per Wh until option c fits (module docstring).

    Call when ``tl.check(c)`` failed on the battery alone. Removals are logged; on
    failure the caller undoes them.

    Args:
      tl: Timeline.
      c: int, option id.
      er: EnergyRank.
      rng: ``random.Random`` (noise of the ranks).
    Returns:
      list of removed option ids when c now fits, else None.
    """
    pb = tl.pb
    k = pb.option_sat[c]
    pos = tl.insert_position(c)
    man = pb.option_first[c] if pos == 0 else tl.need(tl.lines[k][pos - 1], c)
    lo, hi = _reach(tl, c, er.option_wh(c, man))
    line = tl.lines[k]
    removable = []
    for i, x in enumerate(line):
        if lo <= pb.option_start[x] < hi:
            wh = er.removal_wh(tl, k, i)
            dens = pb.target_value[pb.option_target[x]] / wh if wh > 0.0 else math.inf
            removable.append((dens * (1.0 + _RANK_NOISE * rng.random()), x))
    removable.sort()
    budget = pb.target_value[pb.option_target[c]]
    removed = []
    for _, x in removable:
        w = pb.target_value[pb.option_target[x]]
        if w >= budget:
            continue
        mark = len(tl.log)
        p = line.index(x)
        tl.remove(x)
        if not tl.removal_ok(k, p):
            tl.undo_to(mark)
            continue
        budget -= w
        removed.append(x)
        if tl.check(c) is not None:
            return removed
        if not tl.battery_failed:
            return None
    return None
