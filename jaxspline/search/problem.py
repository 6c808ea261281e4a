"""The search's view of a planning problem: options, their near pairs, transition rules.

Built by :func:`jaxspline.plan` from the screened options. Times are seconds. The
transition rule between two options i -> j of one satellite is the required time
``need(i, j)`` (:mod:`jaxspline.screen.models`): feasible iff ``t_start[j] - t_end[i] >=
need``. Rest-to-rest satellites evaluate it from the lines of sight through their
slew table (cheap, any pair); per-channel satellites look it up among the screened
near pairs (:class:`jaxspline.search.store.NearPairs`, 8 bytes a pair); pairs
at least ``far[sat]`` apart are always feasible. When the engine
also screened the flown joins (:mod:`jaxspline.planner.join_screen`), every satellite
looks its near pairs up (``lookup``): a pair the join screen removed is infeasible.

Area options (``cover``) and the looks of stereo targets (``stereo``) are never screened
pair by pair: a transition into or out of one takes the model's closed form, the slew
table of rest-to-rest satellites, and for per-channel satellites a time that surely
suffices (:func:`rest_need`: each channel brakes to rest, slews, waits and speeds up to
the next state).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jaxspline.search.battery import BatteryModel
from jaxspline.search.cover import CoverTable
from jaxspline.search.stereo import ProductTable
from jaxspline.search.store import NearPairs, start_order

__all__ = ["JOIN_SAFETY", "SEPTIC_PEAKS", "Problem", "rest_need", "rest_needs", "septic_time"]

#: Peak rate, acceleration and jerk of the rest-to-rest septic (degree-7) join over a
#: unit turn in unit time (SPEC section 3): its time over ``theta`` within bounds is
#: :func:`septic_time`.
SEPTIC_PEAKS = (35.0 / 16.0, 7.513188403792299, 52.5)
#: A closed-form transition flown as a degree-7 join from or to a point or strip target
#: gets this times the septic time of its turn (the motion of the target's law at that
#: end; between two area strips, held in the track frame, the septic time itself).
JOIN_SAFETY = 1.0


def septic_time(theta: float, rate: float, accel: float, jerk: float) -> float:
    """Shortest time [s] of the rest-to-rest septic join over ``theta`` [rad] within the
    rate, acceleration and jerk bounds (jerk inf: none)."""
    k1, k2, k3 = SEPTIC_PEAKS
    t_jerk = (k3 * theta / jerk) ** (1.0 / 3.0) if math.isfinite(jerk) else 0.0
    return max(k1 * theta / rate, math.sqrt(k2 * theta / accel), t_jerk)


def _septic_times(theta, rate, accel):
    """:func:`septic_time` without a jerk bound, element-wise (numpy)."""
    k1, k2, _ = SEPTIC_PEAKS
    return np.maximum(k1 * theta / rate, np.sqrt(k2 * theta / accel))


def rest_need(angle_a, rate_a, angle_b, rate_b, rate, accel) -> float:
    """A transition time that surely suffices for per-channel states [s] (host numpy).

    Each channel brakes from ``(angle_a, rate_a)`` to rest (``|w_a| / a``, ending
    ``w_a |w_a| / (2 a)`` further on), slews at rest to rest by bang-coast-bang to where
    speeding up reaches ``(angle_b, rate_b)`` (``2 sqrt(d / a)`` when ``d <= W^2 / a``,
    else ``d / W + W / a``), waits, and speeds up (``|w_b| / a``). Every phase keeps the
    channel's rate ``W`` and acceleration ``a`` limits, and waiting at rest makes every
    longer gap feasible too: the exact-T reachable set (SPEC section 1) holds every
    gap at least this long. The largest channel's time.

    Args:
      angle_a, rate_a: float [3], the first observation's end state [rad, rad/s].
      angle_b, rate_b: float [3], the next one's start state [rad, rad/s].
      rate, accel: float [3], the channels' limits [rad/s, rad/s^2].
    Returns:
      float [s].
    """
    return float(rest_needs(angle_a, rate_a, angle_b, rate_b, rate, accel))


def rest_needs(angle_a, rate_a, angle_b, rate_b, rate, accel) -> np.ndarray:
    """:func:`rest_need` of many transitions: states float [..., 3] -> float [...] [s]."""
    stop_a = angle_a + rate_a * np.abs(rate_a) / (2.0 * accel)
    go_b = angle_b - rate_b * np.abs(rate_b) / (2.0 * accel)
    d = np.abs(go_b - stop_a)
    slew = np.where(d <= rate * rate / accel, 2.0 * np.sqrt(d / accel), d / rate + rate / accel)
    return np.max(np.abs(rate_a) / accel + slew + np.abs(rate_b) / accel, axis=-1)


def _channel_septic(st, i, j, rate, accel) -> np.ndarray:
    """Per-channel septic time of the turns from options i's ends to options j's starts
    (int arrays, or ints; each channel's stop and start points as in :func:`rest_need`,
    plus its braking and speeding up), the largest channel's [s]."""
    ra, rb = st[3][i], st[1][j]
    d = np.abs(
        (st[0][j] - rb * np.abs(rb) / (2 * accel)) - (st[2][i] + ra * np.abs(ra) / (2 * accel))
    )
    return np.max(_septic_times(d, rate, accel) + (np.abs(ra) + np.abs(rb)) / accel, axis=-1)


@dataclass
class Problem:
    """Targets, options and transition data for the search (see module docstring).

    Attributes:
      n_sats: number of satellites.
      target_value: per target its value (collected once if imaged).
      option_target, option_sat: per option its target / satellite index.
      option_start, option_end: per option its imaging interval [s].
      option_first: per option the time it needs before it as its satellite's first
        observation [s] (inf: not allowed first).
      option_start_los, option_end_los: per option its unit lines of sight (tuples) at
        start / end.
      tables: per satellite a :class:`jaxspline.screen.slew_table.SlewTable` (rest-to-rest) or None.
      pairs: :class:`NearPairs`, every feasible near pair (every model) by destination.
      far: per satellite the always-feasible gap [s].
      battery: :class:`BatteryModel`.
      target_options: per target its option ids, ascending (so one satellite's are a
        contiguous run, options being sorted by satellite).
      sat_lo, sat_hi: option id range per satellite (options sorted by sat, start).
      sat_starts: per satellite the sorted starts of its options.
      near_slack: the near pairs include every feasible pair with gap < far + this [s]
        (at least the shortest observation: the DP's block width, see ``dp_prepare``).
      lookup: per satellite, True when pairs closer than ``far`` are feasible only if
        they are among the near pairs (per-channel satellites, and every satellite
        whose joins were screened).
      cover: :class:`jaxspline.search.cover.CoverTable` of the areas (None: no areas;
        an area's ``target_value`` is 0, its value lies in its samples).
      stereo: :class:`jaxspline.search.stereo.ProductTable` of the stereo targets (None:
        none; a stereo target's ``target_value`` is its best product's value).
      max_actions: most observations of a plan, all satellites together (None: no cap).
      duty: per satellite ``(period, limit)`` [s]: the imaging time in any window of one
        period ending at an observation's start or end is at most ``limit`` (None, or a
        None entry: no duty rule).
      area_index: what the area moves precompute, built once on first use
        (:func:`jaxspline.search.area_fill.area_index`).
      channels: with areas, per option its boundary states ``(start angle, start rate,
        end angle, end rate)`` [N, 3] each (per-channel satellites' transitions into and
        out of area options, :func:`rest_need`); None without areas.
      limits: with areas, per satellite its per-channel ``(rate [3], accel [3])`` or None.
      gap_margin: added to every closed-form transition time [s].
      joins: per satellite the limits ``(rate, accel, jerk)`` its flown degree-7 joins
        keep (scalars about the eigen-axis, or per channel [3]; with the join screen);
        None: no joins are flown. A closed-form transition then also takes
        :data:`JOIN_SAFETY` times the septic time of its turn.
    """

    n_sats: int
    target_value: list
    option_target: list
    option_sat: list
    option_start: list
    option_end: list
    option_first: list
    option_start_los: list
    option_end_los: list
    tables: list
    pairs: NearPairs
    far: list
    battery: BatteryModel
    target_options: list
    sat_lo: list
    sat_hi: list
    sat_starts: list
    near_slack: float = 0.0
    lookup: list | None = None
    cover: CoverTable | None = None
    max_actions: int | None = None
    duty: list | None = None
    area_index: object = None
    channels: tuple | None = None
    limits: list | None = None
    gap_margin: float = 0.0
    joins: list | None = None
    stereo: ProductTable | None = None

    def __post_init__(self):
        if self.lookup is None:  # the model alone decides: tables where there are tables
            self.lookup = [t is None for t in self.tables]
        # the hot path of need(): tables of satellites whose near pairs are not looked up
        self._free = [None if look else t for t, look in zip(self.tables, self.lookup, strict=True)]
        closed = self.closed_options()
        self._area = None if closed is None else closed.tolist()
        self._los = None  # the lines of sight as arrays, for closed_needs (on first use)
        rows = start_order(self.option_start, self.option_sat)
        if not np.array_equal(self.pairs.rows, rows):  # the DP walks rows in start order
            p = self.pairs
            self.pairs = NearPairs.from_arrays(self.n_options, p.src, p.dst(), p.need, rows)

    @property
    def near_src(self) -> np.ndarray:
        """int64 [P] source of every near pair (``pairs`` order; built on demand)."""
        return self.pairs.src.astype(np.int64)

    @property
    def near_dst(self) -> np.ndarray:
        """int64 [P] destination of every near pair (``pairs`` order; built on demand)."""
        return self.pairs.dst()

    @property
    def n_options(self) -> int:
        """Number of options."""
        return len(self.option_target)

    @property
    def n_targets(self) -> int:
        """Number of targets (with options or not)."""
        return len(self.target_value)

    def need(self, i: int, j: int) -> float:
        """Required time between the end of option i and the start of option j (same satellite).

        Args:
          i: int, option id.
          j: int, option id.
        Returns:
          float [s]; inf when (i, j) is not a feasible near pair of a per-channel satellite.
        """
        k = self.option_sat[j]
        if self._area is not None and (self._area[i] or self._area[j]):
            return self._closed_need(i, j, k)
        table = self._free[k]
        if table is None:
            gap = self.option_start[j] - self.option_end[i]
            if gap < self.far[k]:
                return self.pairs.lookup(i, j)
            table = self.tables[k]
            if table is None:
                return self.far[k]
        a, b = self.option_end_los[i], self.option_start_los[j]
        cx = a[1] * b[2] - a[2] * b[1]
        cy = a[2] * b[0] - a[0] * b[2]
        cz = a[0] * b[1] - a[1] * b[0]
        th = math.atan2(
            math.sqrt(cx * cx + cy * cy + cz * cz), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
        )
        return table.scalar(th)

    def closed_options(self) -> np.ndarray | None:
        """bool [N]: the options whose transitions take the closed form (area options and
        looks), None when there are none."""
        if self.cover is None and self.stereo is None:
            return None
        out = np.zeros(self.n_options, bool)
        if self.cover is not None:
            out |= self.cover.option_group >= 0
        if self.stereo is not None:
            out |= self.stereo.is_look
        return out

    def is_closed(self, c: int) -> bool:
        """Whether option c is an area option or a look (:meth:`closed_options`)."""
        return self._area is not None and self._area[c]

    def is_look(self, c: int) -> bool:
        """Whether option c is a look of a stereo target (it counts through ``stereo``)."""
        return self.stereo is not None and bool(self.stereo.is_look[c])

    def is_area(self, c: int) -> bool:
        """Whether option c is an area option (it counts through ``cover``)."""
        return self.cover is not None and self.cover.option_group[c] >= 0

    def exclusive_targets(self) -> list:
        """The targets imaged at most once (every target but the areas)."""
        if self.cover is None:
            return list(range(self.n_targets))
        areas = set(self.cover.area_target.tolist())
        return [t for t in range(self.n_targets) if t not in areas]

    def _closed_need(self, i: int, j: int, k: int) -> float:
        """The closed-form transition time i -> j of satellite k (module docstring)."""
        table = self.tables[k]
        joins = None if self.joins is None else self.joins[k]
        safety = 1.0 if self._area[i] and self._area[j] else JOIN_SAFETY
        if table is None:
            st = self.channels
            rate, accel = self.limits[k]
            t = rest_need(st[2][i], st[3][i], st[0][j], st[1][j], rate, accel)
            if joins is not None:
                t = max(t, safety * float(_channel_septic(st, i, j, joins[0], joins[1])))
            return t + self.gap_margin
        a, b = self.option_end_los[i], self.option_start_los[j]
        cx = a[1] * b[2] - a[2] * b[1]
        cy = a[2] * b[0] - a[0] * b[2]
        cz = a[0] * b[1] - a[1] * b[0]
        th = math.atan2(
            math.sqrt(cx * cx + cy * cy + cz * cz), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
        )
        t = table.scalar(th)
        if joins is not None:
            t = max(t, safety * septic_time(th, *joins) + self.gap_margin)
        return t

    def closed_needs(self, i, j, k: int) -> np.ndarray:
        """:meth:`need` of many pairs of satellite k each with an area option (the closed
        form of the module docstring, element-wise).

        Args:
          i: int [P], option ids of the first observations (satellite k).
          j: int [P], option ids of the next ones (in each pair one is an area option or
            a look).
          k: the satellite.
        Returns:
          float [P] [s].
        """
        i, j = np.asarray(i, np.int64), np.asarray(j, np.int64)
        area = np.asarray(self._area, bool)
        safety = np.where(area[i] & area[j], 1.0, JOIN_SAFETY)
        table = self.tables[k]
        joins = None if self.joins is None else self.joins[k]
        if table is None:
            st = self.channels
            rate, accel = self.limits[k]
            t = rest_needs(st[2][i], st[3][i], st[0][j], st[1][j], rate, accel)
            if joins is not None:
                t = np.maximum(t, safety * _channel_septic(st, i, j, joins[0], joins[1]))
            return t + self.gap_margin
        if self._los is None:
            self._los = (np.asarray(self.option_end_los), np.asarray(self.option_start_los))
        a, b = self._los[0][i], self._los[1][j]
        c = np.cross(a, b)
        th = np.arctan2(np.sqrt(np.sum(c * c, axis=-1)), np.sum(a * b, axis=-1))
        t = table(th)
        if joins is not None:
            rate, accel, jerk = joins
            sep = _septic_times(th, rate, accel)
            if math.isfinite(jerk):
                sep = np.maximum(sep, np.cbrt(SEPTIC_PEAKS[2] * th / jerk))
            t = np.maximum(t, safety * sep + self.gap_margin)
        return t

    @classmethod
    def build(cls, opp, sats, first, near_pairs, far, tables, battery, target_values,
              lookup=None, cover=None, max_actions=None, duty=None, gap_margin=0.0,
              joins=None, stereo=None):  # fmt: skip
        """Assemble from numpy data.

        Args:
          opp: :class:`jaxspline.planner.opportunities.Opportunities` sorted by (sat, start).
          sats: the scenario's satellites.
          first: [N] required time before each option as a first observation.
          near_pairs: :class:`NearPairs`, or (src, dst, need) arrays of the feasible
            pairs closer than far.
          far: [S] always-feasible gaps.
          tables: per satellite its model's screen model (``sat.maneuver.screen_model``);
            kept for rest-to-rest satellites (their SlewTable), None for the others.
          battery: :class:`BatteryModel`.
          target_values: per target its value.
          lookup: [S] bool, satellites whose near pairs are authoritative (default:
            the per-channel ones).
          cover: CoverTable of the areas, or None.
          max_actions: most observations of a plan, or None.
          duty: per satellite ``(period, limit)`` [s] or None, or None.
          gap_margin: added to closed-form transition times [s] (the planner's gap margin).
          joins: per satellite its join limits (see the class docstring), or None.
          stereo: ProductTable of the stereo targets, or None.
        """
        o = opp.options
        sat = np.asarray(o.sat, np.int64)
        n = sat.size
        n_s = len(sats)
        target = np.asarray(o.route, np.int64)
        target_options = [[] for _ in range(len(target_values))]
        for c, t in enumerate(target.tolist()):
            target_options[t].append(c)
        lo = np.searchsorted(sat, np.arange(n_s), side="left").tolist()
        hi = np.searchsorted(sat, np.arange(n_s), side="right").tolist()
        starts = np.asarray(o.t_start, np.float64).tolist()
        if not isinstance(near_pairs, NearPairs):
            near_pairs = NearPairs.from_arrays(n, *near_pairs, rows=start_order(o.t_start, sat))
        pc = np.array([not s.maneuver.rest_to_rest for s in sats], bool)
        look = pc if lookup is None else np.asarray(lookup, bool) | pc
        closed = cover is not None or stereo is not None
        channels, limits = _channel_rules(o, sats, pc) if closed else (None, None)
        return cls(
            n_sats=n_s,
            target_value=[float(v) for v in target_values],
            option_target=target.tolist(),
            option_sat=sat.tolist(),
            option_start=starts,
            option_end=np.asarray(o.t_end, np.float64).tolist(),
            option_first=np.asarray(first, np.float64).tolist(),
            option_start_los=[tuple(v) for v in np.asarray(o.start_los).tolist()],
            option_end_los=[tuple(v) for v in np.asarray(o.end_los).tolist()],
            tables=[
                t if s.maneuver.rest_to_rest else None for s, t in zip(sats, tables, strict=True)
            ],
            pairs=near_pairs,
            far=[float(f) for f in far],
            battery=battery,
            target_options=target_options,
            sat_lo=lo,
            sat_hi=hi,
            sat_starts=[starts[a:b] for a, b in zip(lo, hi, strict=True)],
            lookup=look.tolist(),
            cover=cover,
            max_actions=max_actions,
            duty=duty,
            channels=channels,
            limits=limits,
            gap_margin=gap_margin,
            joins=joins,
            stereo=stereo,
        )


def _channel_rules(o, sats, per_channel):
    """The options' channel states (start angle, start rate, end angle, end rate, each
    [N, 3]) and per satellite its (rate, accel) bounds [3] (None for rest-to-rest ones):
    what the closed-form area transitions of per-channel satellites read."""
    channels = tuple(
        np.asarray(x, np.float64) for x in (o.start_angle, o.start_rate, o.end_angle, o.end_rate)
    )
    limits = [
        (np.broadcast_to(s.limits.rate, 3), np.broadcast_to(s.limits.accel, 3)) if p else None
        for s, p in zip(sats, per_channel, strict=True)
    ]
    return channels, limits
