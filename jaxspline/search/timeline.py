"""Mutable per-satellite timelines with feasibility checks, battery bounds and an undo log.

A :class:`Timeline` holds, per satellite, its chosen options in start order and, per
target, the option that images it (each point or strip target at most once; an area's
options, any number of them, count the samples they cover, :class:`CoverCounts`; a
stereo target's looks count through its complete products, :class:`ProductCounts`).
:meth:`Timeline.check` tests one insertion: no overlap, the transition from the
predecessor (or the first maneuver) and to the successor fit their gaps, the imaging
duty per orbit and the plan's action cap hold (where the problem has them), and the
battery stays above its margin.
Each satellite's starts, ends and the maneuver into each observation are kept beside
its option ids (updated by :meth:`Timeline.insert` and :meth:`Timeline.remove`), so
a test or a battery refresh reads them instead of re-deriving the transitions.
Every change is logged so a search step can be undone. A timeline may withdraw options
of its problem (``withdrawn``): they are no longer offered for any target, while the
:class:`Problem` itself stays as built.

Battery bookkeeping, cheapest test first:

1. ``levels[k]`` (:class:`jaxspline.search.battery.Levels`) is satellite k's
   profile for a past state of its timeline and ``debt[k]`` an upper bound of the load
   energy added since (the clamped battery recursion is monotone in its inputs, so
   ``tail_min - debt`` is a lower bound of the current suffix minimum): an insertion
   whose energy bound fits under it is accepted in O(1);
2. otherwise the profile is refreshed (once per change of the timeline) and the
   insertion's exact load change (imaging, the maneuver into it, the successor's new
   maneuver) is tested on its window alone (:meth:`BatteryModel.change_ok`), spill
   at capacity included;
3. a full re-simulation only when that test cannot tell (the old profile infeasible).
"""

from __future__ import annotations

import bisect

import numpy as np

from jaxspline.search.construct import first_least
from jaxspline.search.cover import CoverCounts
from jaxspline.search.problem import Problem
from jaxspline.search.stereo import (
    ProductCounts,
    is_product_code,
    missing_looks,
    product_choices,
    product_of,
)

__all__ = ["Timeline"]

_CACHE_LIMIT = 1_000_000  # memoized transition times before the cache is cleared (~100 B each)
_TURNAROUND_WEIGHT = 0.02  # tie-break weight of the end time in insertion costs
_INSERT_NOISE = 0.3  # relative noise of randomized insertion costs


class Timeline:
    """Per-satellite timelines over a :class:`Problem` (see module docstring).

    Args:
      pb: the Problem (read only).
      withdrawn: optional bool [N], options never to offer (e.g. rejected by a check
        after the search); None: every option.

    Attributes:
      pb: the Problem.
      target_options: per target, its option ids on offer (``pb.target_options``
        without the withdrawn ones).
      lines: per satellite, its option ids in start order.
      line_starts: per satellite, their start times [s].
      line_ends: per satellite, their end times [s].
      maneuvers: per satellite, the required time of the maneuver into each of them
        (from the predecessor, or the first maneuver) [s], kept up to date by
        :meth:`insert` and :meth:`remove`.
      assigned: per target, the option that images it (-1: none; always -1 for an
        area, whose options count through ``cover``; for a stereo target a look of the
        product it collects).
      cover: :class:`CoverCounts` of the plan's area options (None: no areas).
      n_area: number of area observations.
      stereo: :class:`ProductCounts` of the plan's looks (None: no stereo targets).
      n_look: number of looks of stereo targets.
      levels: per satellite, the battery :class:`Levels` of a past state (None: not
        computed).
      debt: per satellite, an upper bound of the load energy added since [Wh].
      stale: per satellite, whether its timeline changed since ``levels``.
      battery_failed: whether the last :meth:`check` failed on the battery alone.
      value: total value of the plan (point and strip targets' values plus the covered
        weight of the areas).
      n_observations: number of observations.
      tat: sum of the observations' end times [s] (tie-break).
      log: undo log of the changes since the last :meth:`commit`.
      cache: memoized transition times.
      saved: battery bounds saved for :meth:`undo_to`.
    """

    def __init__(self, pb: Problem, withdrawn=None):
        self.pb = pb
        self.target_options = pb.target_options
        if withdrawn is not None:
            out = np.asarray(withdrawn, bool)
            if out.shape != (pb.n_options,):
                raise ValueError(
                    f"withdrawn has shape {out.shape}, expected one flag an option "
                    f"({pb.n_options},)"
                )
            self.target_options = [[c for c in opts if not out[c]] for opts in pb.target_options]
        n_s = pb.n_sats
        self.lines = [[] for _ in range(n_s)]  # option ids by start
        self.line_starts = [[] for _ in range(n_s)]  # their starts
        self.line_ends = [[] for _ in range(n_s)]  # their ends
        self.maneuvers = [[] for _ in range(n_s)]  # the maneuver into each
        self.assigned = [-1] * pb.n_targets
        self.cover = None if pb.cover is None else CoverCounts(pb.cover)
        self.n_area = 0
        self.stereo = None if pb.stereo is None else ProductCounts(pb.stereo)
        self.n_look = 0
        self.levels = [None] * n_s
        self.debt = [0.0] * n_s
        self.stale = [True] * n_s
        self.battery_failed = False
        self.value = 0.0
        self.n_observations = 0
        self.tat = 0.0
        self.log = []
        self.cache = {}
        self.saved = {}
        self._n = pb.n_options  # key stride of the need cache

    # ------------------------------------------------------------ transitions
    def need(self, i: int, j: int) -> float:
        """Required time from option i to option j (memoized :meth:`Problem.need`).

        Args:
          i: int, option id.
          j: int, option id.
        Returns:
          float [s].
        """
        key = i * self._n + j
        v = self.cache.get(key)
        if v is None:
            if len(self.cache) > _CACHE_LIMIT:
                self.cache.clear()
            v = self.pb.need(i, j)
            self.cache[key] = v
        return v

    def maneuver_into(self, k: int, pos: int) -> float:
        """Required time of the maneuver into position ``pos`` of satellite k's timeline.

        Args:
          k: int, satellite index.
          pos: int, position in its timeline.
        Returns:
          float [s].
        """
        return self.maneuvers[k][pos]

    def insert_position(self, c: int) -> int:
        """Position option c would take in its satellite's timeline.

        Args:
          c: int, option id.
        Returns:
          int.
        """
        return bisect.bisect_left(self.line_starts[self.pb.option_sat[c]], self.pb.option_start[c])

    def score(self):
        """Comparable quality: (value, count, -sum of end times); with areas first the
        areas' summed shortfall below their least share (negated), and the count is the
        point and strip observations minus the area ones (an area strip that adds
        nothing only spends an action).

        Returns:
          tuple, larger is better.
        """
        if self.cover is None and self.stereo is None:
            return (round(self.value, 9), self.n_observations, -round(self.tat, 6))
        count = self.n_observations - 2 * (self.n_area + self.n_look)
        if self.cover is None:
            return (0.0, round(self.value, 9), count, -round(self.tat, 6))
        return (
            -round(self.cover.shortfall(), 12),
            round(self.value, 9),
            count,
            -round(self.tat, 6),
        )

    def plan(self) -> list:
        """The option ids of the plan, satellite by satellite in time order.

        Returns:
          list of int (what :meth:`restore` takes).
        """
        return [c for line in self.lines for c in line]

    # ------------------------------------------------------------ battery
    def _timeline_loads(self, k, extra=None):
        """(starts, ends, maneuvers) of satellite k's timeline, with option ``extra``."""
        starts, ends, man = self.line_starts[k], self.line_ends[k], self.maneuvers[k]
        if extra is None:
            return starts, ends, man
        pb = self.pb
        line = self.lines[k]
        pos = bisect.bisect_left(starts, pb.option_start[extra])
        starts, ends, man = list(starts), list(ends), list(man)
        starts.insert(pos, pb.option_start[extra])
        ends.insert(pos, pb.option_end[extra])
        man.insert(pos, pb.option_first[extra] if pos == 0 else self.need(line[pos - 1], extra))
        if pos < len(line):
            man[pos + 1] = self.need(extra, line[pos])
        return starts, ends, man

    def _levels(self, k):
        """Satellite k's current battery Levels (recomputed when stale)."""
        if self.stale[k] or self.levels[k] is None:
            bat = self.pb.battery
            loads = bat.loads(k, self.line_starts[k], self.line_ends[k], self.maneuvers[k])
            self.levels[k] = bat.levels_of(k, loads)
            self.debt[k] = 0.0
            self.stale[k] = False
        return self.levels[k]

    def battery_level(self, k: int):
        """Battery level of satellite k's current timeline at the grid instants.

        Args:
          k: int, satellite index.
        Returns:
          float [n + 1] [Wh], or None without a power model.
        """
        return self._levels(k).level if self.pb.battery.has(k) else None

    def battery_low(self, k: int):
        """Lowest battery level of satellite k, from the last computed profile (cheap:
        no re-simulation unless none exists; a heuristic's view, not a feasibility test).

        Args:
          k: int, satellite index.
        Returns:
          float [Wh], or None without a power model.
        """
        if not self.pb.battery.has(k):
            return None
        lv = self.levels[k] if self.levels[k] is not None else self._levels(k)
        return float(lv.tail_min[0])

    def _battery_ok(self, k, c, n_in, q, n_out, n_old):
        """Battery test of inserting c (maneuver n_in) before q (maneuver n_out, was n_old)."""
        bat = self.pb.battery
        changes = self._changes(k, c, n_in, q, n_out, n_old)
        lv = self.levels[k]
        if lv is not None:
            k0 = min((lo for lo, _, _ in changes), default=bat.n)
            if lv.tail_min[k0] - self.debt[k] - self._added_wh(changes) >= bat.margin_wh:
                return True
        ok = bat.change_ok(k, self._levels(k), changes)
        if ok is None:
            ok = bool(bat.profile(k, *self._timeline_loads(k, extra=c)).min() >= bat.margin_wh)
        return ok

    def _changes(self, k, c, n_in, q, n_out, n_old):
        """Load changes ``(lo, hi, watts)`` of inserting c (maneuver n_in) before q."""
        pb = self.pb
        bat = pb.battery
        p = bat.powers[k]
        s = pb.option_start[c]
        out = bat.segments(s, pb.option_end[c], p.imaging_w)
        out += bat.segments(s - n_in, s, p.slew_w)
        if q >= 0:
            out += self._slew_change(k, q, n_old, n_out)
        return out

    def _slew_change(self, k, q, was, now):
        """Load change of q's maneuver window when its maneuver goes from ``was`` to
        ``now`` s: ``[(lo, hi, watts)]``, empty when it does not change."""
        bat = self.pb.battery
        s = self.pb.option_start[q]
        if now > was:
            return bat.segments(s - now, s - was, bat.powers[k].slew_w)
        return bat.segments(s - was, s - now, -bat.powers[k].slew_w)

    def _added_wh(self, changes):
        """Energy the load changes ``(lo, hi, watts)`` add: their positive part [Wh]."""
        steps_w = sum((hi - lo) * w for lo, hi, w in changes if w > 0.0 and hi > lo)
        return steps_w * self.pb.battery.dt / 3600.0

    # ------------------------------------------------------------ moves
    def check(self, c: int, collected: bool = False):
        """Feasibility of inserting option c.

        Args:
          c: int, option id.
          collected: allow an option of a target the plan already collects (a backup
            look of a stereo target, :func:`jaxspline.search.stereo.add_backups`).
        Returns:
          float, the time it consumes [s], or None when infeasible.
        """
        pb = self.pb
        self.battery_failed = False
        if not collected and self.assigned[pb.option_target[c]] >= 0:
            return None
        if pb.max_actions is not None and self.n_observations >= pb.max_actions:
            return None
        k = pb.option_sat[c]
        pos = self._slot(k, pb.option_start[c], pb.option_end[c])
        return None if pos < 0 else self._fit(c, k, pos)

    def _slot(self, k, s, e):
        """Position of an interval [s, e] in satellite k's timeline; -1 when it overlaps."""
        starts = self.line_starts[k]
        pos = bisect.bisect_left(starts, s)
        if (pos > 0 and self.line_ends[k][pos - 1] > s) or (pos < len(starts) and e > starts[pos]):
            return -1
        return pos

    def _fit(self, c, k, pos):
        """:meth:`check` of option c once it overlaps nothing at position ``pos`` of
        satellite k's timeline: the transitions and the battery."""
        pb = self.pb
        s, e = pb.option_start[c], pb.option_end[c]
        line = self.lines[k]
        if pos > 0:
            p = line[pos - 1]
            n_in = self.need(p, c)
            if s - self.line_ends[k][pos - 1] < n_in:
                return None
        else:
            p = -1
            n_in = pb.option_first[c]
            if s < n_in:
                return None
        if pos < len(line):
            q = line[pos]
            n_out = self.need(c, q)
            if self.line_starts[k][pos] - e < n_out:
                return None
            n_old = self.maneuvers[k][pos]
        else:
            q = -1
            n_out = n_old = 0.0
        if pb.duty is not None and pb.duty[k] is not None and not self._duty_ok(k, pos, s, e):
            return None
        if pb.battery.has(k) and not self._battery_ok(k, c, n_in, q, n_out, n_old):
            self.battery_failed = True
            return None
        return n_in + (e - s) + n_out - n_old

    def _duty_ok(self, k: int, pos: int, s: float, e: float) -> bool:
        """Whether inserting ``[s, e]`` at position ``pos`` of satellite k keeps the imaging
        time in every window ``[T - period, T]`` ending at an observation's start or end
        within the limit (``pb.duty[k] = (period, limit)``, the margin taken off)."""
        period, limit = self.pb.duty[k]
        starts, ends = self.line_starts[k], self.line_ends[k]
        lo = bisect.bisect_left(ends, s - period)  # the first interval ending in reach
        hi = bisect.bisect_right(starts, e + period)
        iv = list(zip(starts[lo:pos], ends[lo:pos], strict=True)) + [(s, e)]
        iv += list(zip(starts[pos:hi], ends[pos:hi], strict=True))
        for t in {x for a, b in iv for x in (a, b) if s <= x <= e + period}:
            used = sum(max(0.0, min(b, t) - max(a, t - period)) for a, b in iv)
            if used > limit:
                return False
        return True

    def insert(self, c: int):
        """Insert option c (feasibility is the caller's business: :meth:`check`).

        Args:
          c: int, option id, or a product's candidate id from :meth:`insert_choices`
            (its missing looks go in).
        """
        if is_product_code(c):
            for look in missing_looks(self, product_of(c)):
                self.insert(look)
            return
        pb = self.pb
        k, t = pb.option_sat[c], pb.option_target[c]
        pos = bisect.bisect_left(self.line_starts[k], pb.option_start[c])
        line = self.lines[k]
        if k not in self.saved:
            self.saved[k] = (self.levels[k], self.debt[k], self.stale[k])
        self.stale[k] = True
        n_in = pb.option_first[c] if pos == 0 else self.need(line[pos - 1], c)
        n_out = self.need(c, line[pos]) if pos < len(line) else 0.0
        if pb.battery.has(k):  # the load the insertion adds, exactly as the profile counts it
            q, n_old = (line[pos], self.maneuvers[k][pos]) if pos < len(line) else (-1, 0.0)
            self.debt[k] += self._added_wh(self._changes(k, c, n_in, q, n_out, n_old))
        line.insert(pos, c)
        self.line_starts[k].insert(pos, pb.option_start[c])
        self.line_ends[k].insert(pos, pb.option_end[c])
        man = self.maneuvers[k]
        man.insert(pos, n_in)
        if pos + 1 < len(line):
            man[pos + 1] = n_out
        if self.cover is not None and pb.cover.option_group[c] >= 0:
            self.value += self.cover.change(c, +1)
            self.n_area += 1
        elif self.stereo is not None and pb.stereo.is_look[c]:
            self._look_change(c, t, +1)
        else:
            self.assigned[t] = c
            self.value += pb.target_value[t]
        self.n_observations += 1
        self.tat += pb.option_end[c]
        self.log.append(("i", c))

    def remove(self, c: int):
        """Remove option c from its satellite's timeline.

        Args:
          c: int, option id.
        """
        pb = self.pb
        k, t = pb.option_sat[c], pb.option_target[c]
        line = self.lines[k]
        if k not in self.saved:
            self.saved[k] = (self.levels[k], self.debt[k], self.stale[k])
        self.stale[k] = True
        pos = bisect.bisect_left(self.line_starts[k], pb.option_start[c])
        if pos >= len(line) or line[pos] != c:
            pos = line.index(c)
        del line[pos]
        del self.line_starts[k][pos]
        del self.line_ends[k][pos]
        man = self.maneuvers[k]
        del man[pos]
        if pos < len(line):  # the successor's maneuver, now from the predecessor
            q = line[pos]
            n_was = man[pos]
            man[pos] = pb.option_first[q] if pos == 0 else self.need(line[pos - 1], q)
            if pb.battery.has(k):  # its maneuver window may start earlier: the only added load
                self.debt[k] += self._added_wh(self._slew_change(k, q, n_was, man[pos]))
        if self.cover is not None and pb.cover.option_group[c] >= 0:
            self.value += self.cover.change(c, -1)
            self.n_area -= 1
        elif self.stereo is not None and pb.stereo.is_look[c]:
            self._look_change(c, t, -1)
        else:
            self.assigned[t] = -1
            self.value -= pb.target_value[t]
        self.n_observations -= 1
        self.tat -= pb.option_end[c]
        self.log.append(("r", c))

    def _look_change(self, c: int, t: int, sign: int) -> None:
        """Count look c of stereo target t in (+1) or out (-1)."""
        self.value += self.stereo.change(c, sign)
        self.n_look += sign
        best = self.stereo.best[t]
        self.assigned[t] = self.pb.stereo.looks[best][0] if best >= 0 else -1

    def removal_ok(self, k: int, pos: int) -> bool:
        """Whether a removal at index ``pos`` of satellite k keeps the plan feasible.

        After removing a block at ``pos``: the new transition into ``line[pos]`` and the
        battery still hold.

        Args:
          k: int, satellite index.
          pos: int, position in its timeline.
        Returns:
          bool.
        """
        pb = self.pb
        line = self.lines[k]
        if pos < len(line):
            q = line[pos]
            prev_end = 0.0 if pos == 0 else pb.option_end[line[pos - 1]]
            if pb.option_start[q] - prev_end < self.maneuver_into(k, pos):
                return False
        if not pb.battery.has(k):
            return True
        margin = pb.battery.margin_wh
        lv = self.levels[k]
        if lv is not None and lv.tail_min[0] - self.debt[k] >= margin:
            return True
        return bool(self._levels(k).tail_min[0] >= margin)

    def commit(self):
        """Forget the undo log (the current state becomes the base of the next step)."""
        self.log.clear()
        self.saved.clear()

    def undo_to(self, mark: int):
        """Undo the changes logged after ``mark``; at mark 0 the battery bounds come back too.

        Args:
          mark: int, length of the log to return to.
        """
        while len(self.log) > mark:
            op, c = self.log.pop()
            if op == "i":
                self.remove(c)
            else:
                self.insert(c)
            self.log.pop()
        if mark == 0:
            for k, (lv, debt, stale) in self.saved.items():
                self.levels[k], self.debt[k], self.stale[k] = lv, debt, stale
            self.saved.clear()

    def insert_choices(self, t: int, rng=None, span=None):
        """Target t's options that fit now and their insertion costs (one greedy decision).

        The cost of an option is the timeline time it consumes (:meth:`check`) plus
        :data:`_TURNAROUND_WEIGHT` times its end, times ``1 + U(0, 0.3)`` with ``rng``
        (one draw per option that fits, in ``target_options`` order).

        Args:
          t: int, target index.
          rng: ``random.Random`` for randomized costs, or None.
          span: ``(lo, hi)``, only the option ids ``lo <= c < hi`` (satellite k's options
            are the ids ``sat_lo[k]:sat_hi[k]``, in start order); None: every option.
        Returns:
          (options, costs), two lists in ``target_options`` order; empty when the target
          is already imaged.
        """
        pb = self.pb
        if pb.stereo is not None and pb.stereo.target_products[t]:
            return product_choices(self, t, rng, _TURNAROUND_WEIGHT, _INSERT_NOISE)
        option_sat, option_start, option_end = pb.option_sat, pb.option_start, pb.option_end
        options, costs = [], []
        if self.assigned[t] >= 0:
            return options, costs
        if pb.max_actions is not None and self.n_observations >= pb.max_actions:
            return options, costs
        opts = self.target_options[t]
        if span is not None:  # ascending ids: one slice
            opts = opts[bisect.bisect_left(opts, span[0]) : bisect.bisect_left(opts, span[1])]
        line_starts, line_ends, bisect_left = self.line_starts, self.line_ends, bisect.bisect_left
        for c in opts:
            k, s = option_sat[c], option_start[c]
            starts = line_starts[k]
            pos = bisect_left(starts, s)
            # :meth:`_slot` inline (the hot path: most options overlap an observation)
            if (pos > 0 and line_ends[k][pos - 1] > s) or (
                pos < len(starts) and option_end[c] > starts[pos]
            ):
                continue
            self.battery_failed = False
            cost = self._fit(c, k, pos)
            if cost is None:
                continue
            cost += _TURNAROUND_WEIGHT * option_end[c]
            if rng is not None:
                cost *= 1.0 + _INSERT_NOISE * rng.random()
            options.append(c)
            costs.append(cost)
        return options, costs

    def best_insert(self, t: int, rng=None, span=None) -> bool:
        """Insert target t at its cheapest feasible option (:meth:`insert_choices`).

        Args:
          t: int, target index.
          rng: ``random.Random`` for randomized costs, or None.
          span: ``(lo, hi)``, only the option ids ``lo <= c < hi``; None: every option.
        Returns:
          bool, whether the target was inserted.
        """
        options, costs = self.insert_choices(t, rng, span)
        k = first_least(costs)
        if k >= 0:
            self.insert(options[k])
        return k >= 0

    def restore(self, assigned):
        """Reset to the plan of the given options (what :meth:`plan` returns; -1 entries,
        as in a target -> option assignment, are skipped).

        Args:
          assigned: list of option ids.
        """
        pb = self.pb
        for k in range(pb.n_sats):
            self.lines[k], self.line_starts[k], self.line_ends[k] = [], [], []
            self.maneuvers[k] = []
            self.levels[k], self.debt[k], self.stale[k] = None, 0.0, True
        self.assigned = [-1] * pb.n_targets
        if self.cover is not None:
            self.cover = CoverCounts(pb.cover)
        if self.stereo is not None:
            self.stereo = ProductCounts(pb.stereo)
        self.n_area = self.n_look = 0
        self.value, self.n_observations, self.tat = 0.0, 0, 0.0
        for c in sorted((c for c in assigned if c >= 0), key=lambda c: pb.option_start[c]):
            self.insert(c)
        self.commit()
