"""Per-satellite timeline rules of the regional_coverage benchmark, as the search uses them.

A satellite's timeline is a set of strips ``[start, end)`` [s from the horizon start] with
a roll [deg]. :func:`timeline_ok` checks one timeline against the rules of RULES.md,
each with a small safety margin (:class:`Margins`):

* rule 4, maneuver gap: consecutive strips ``i, i+1`` (by start) need
  ``gap >= slew(|r_{i+1} - r_i| + LOOK_RATE_DEG_S * gap) + settling + margin`` with the
  roll-only model's bang-coast-bang rest-to-rest time
  (:mod:`jaxspline.screen.models.roll_only`; the official slew angle is between
  Earth-fixed look directions, which turn with the orbit during the gap);
* rule 5, imaging duty: for every strip start or end instant ``T``, the imaging time in
  ``[T - orbit period, T]`` is at most ``limit - margin``;
* rule 6, battery: :func:`battery_levels` evaluates the 5 s mesh refined by every strip
  and maneuver boundary, exactly as the rule states (clamp at the capacity after each
  piece), with the charge decided by a conservative per-interval sunlit flag (see
  :func:`conservative_sunlit`); the level must stay ``>= margin``.

Everything is plain numpy (timelines hold a few tens of strips; the battery mesh a few
ten thousand pieces). An infeasible timeline is ``False``, never an exception.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jaxspline.screen.models.roll_only import RollLimits, roll_min_gap, roll_need

__all__ = [
    "Margins",
    "SatRules",
    "battery_levels",
    "battery_min_mesh",
    "battery_min_wh",
    "conservative_sunlit",
    "duty_ok",
    "gaps_ok",
    "maneuver_s",
    "maneuver_scalar",
    "roll_limits",
    "sat_rules",
    "timeline_ok",
]

#: Seconds per hour (W * s -> Wh).
SECONDS_PER_HOUR = 3600.0
#: Bound on how fast a fixed-roll look direction turns in the Earth-fixed frame [deg/s]
#: (orbital rate ~0.06 deg/s for these orbits; R1 measured <= 0.07).
LOOK_RATE_DEG_S = 0.08
#: Largest angle between two directions [deg].
MAX_ANGLE_DEG = 180.0
#: Iterations of the smallest-gap fixed point (a contraction: rate * slew' << 1).
FIXED_POINT_ITERATIONS = 8
#: Added to the fixed point's last iterate (it converges from below) [s].
FIXED_POINT_SLACK_S = 0.01


@dataclass(frozen=True)
class Margins:
    """Safety margins the search keeps from each limit.

    Attributes:
      gap_s: extra seconds on every maneuver gap (rule 4) [s].
      duty_s: imaging seconds kept below the duty limit (rule 5) [s].
      battery_wh: the lowest battery level allowed (rule 6 asks >= 0) [Wh].
      roll_deg: how far inside the sensor band a strip's edges stay (rule 3) [deg].
    """

    gap_s: float = 0.05
    duty_s: float = 0.5
    battery_wh: float = 2.0
    roll_deg: float = 1e-4


@dataclass(frozen=True)
class SatRules:
    """The rules of one satellite in the units the search uses.

    Attributes:
      min_dur_s, max_dur_s: strip duration limits [s].
      min_edge_deg, max_edge_deg, fov_deg: sensor band and field of view [deg].
      rate_deg_s, accel_deg_s2, settle_s: agility (bang-coast-bang slew, settling) [deg/s,
        deg/s^2, s].
      period_s: orbit period (duty window) [s].
      duty_limit_s: imaging seconds per orbit period (inf = none) [s].
      capacity_wh, initial_wh: battery capacity and initial level [Wh].
      idle_w, imaging_w, slew_w, charge_w: loads and sunlit charge power [W].
    """

    min_dur_s: float
    max_dur_s: float
    min_edge_deg: float
    max_edge_deg: float
    fov_deg: float
    rate_deg_s: float
    accel_deg_s2: float
    settle_s: float
    period_s: float
    duty_limit_s: float
    capacity_wh: float
    initial_wh: float
    idle_w: float
    imaging_w: float
    slew_w: float
    charge_w: float


def sat_rules(sat) -> SatRules:
    """The :class:`SatRules` of a loaded :class:`jaxspline.regional.case.Satellite`.

    Args:
      sat: Satellite (sensor, agility, power, orbit_period_s).
    Returns:
      SatRules.
    """
    s, a, p = sat.sensor, sat.agility, sat.power
    return SatRules(
        min_dur_s=float(s.min_duration_s),
        max_dur_s=float(s.max_duration_s),
        min_edge_deg=float(s.min_edge_deg),
        max_edge_deg=float(s.max_edge_deg),
        fov_deg=float(s.fov_deg),
        rate_deg_s=float(a.rate_deg_s),
        accel_deg_s2=float(a.accel_deg_s2),
        settle_s=float(a.settling_s),
        period_s=float(sat.orbit_period_s),
        duty_limit_s=np.inf if p.duty_limit_s is None else float(p.duty_limit_s),
        capacity_wh=float(p.capacity_wh),
        initial_wh=float(p.initial_wh),
        idle_w=float(p.idle_w),
        imaging_w=float(p.imaging_w),
        slew_w=float(p.slew_w),
        charge_w=float(p.charge_w),
    )


def roll_limits(rules: SatRules, margins: Margins) -> RollLimits:
    """The roll axis the search plans with: the rules' agility, settling plus the gap margin.

    Args:
      rules: SatRules; margins: Margins (``gap_s`` is added to the settling time).
    Returns:
      :class:`jaxspline.screen.models.roll_only.RollLimits` [deg/s, deg/s^2, s].
    """
    return RollLimits(rules.rate_deg_s, rules.accel_deg_s2, rules.settle_s + margins.gap_s)


def maneuver_s(rules: SatRules, delta_deg, margins: Margins, gap_s=None) -> np.ndarray:
    """The gap one strip needs after another: slew + settling + margin [s].

    The slew is the roll-only model's (:func:`jaxspline.screen.models.roll_only.roll_need`
    of :func:`roll_limits`). The official slew angle is the angle between the Earth-fixed
    look directions at the first strip's end and the second's start, which adds the
    frame's rotation over the gap to the roll change; it is bounded here by
    ``|r2 - r1| + LOOK_RATE_DEG_S * gap``. With ``gap_s`` given, the need at that gap;
    without, the smallest gap ``g`` with ``g >= slew(|dr| + rate g) + settling + margin``
    (:func:`jaxspline.screen.models.roll_only.roll_min_gap`, from below, plus
    :data:`FIXED_POINT_SLACK_S`).

    Args:
      rules: SatRules.
      delta_deg: float or array, |r2 - r1| [deg].
      margins: Margins (``gap_s``).
      gap_s: float or array, the actual gap [s], or None.
    Returns:
      float64 array [s].
    """
    d = np.abs(np.asarray(delta_deg, dtype=np.float64))
    limits = roll_limits(rules, margins)
    if gap_s is not None:
        return roll_need(np.minimum(d + LOOK_RATE_DEG_S * np.asarray(gap_s), MAX_ANGLE_DEG), limits)
    return roll_min_gap(d, limits, LOOK_RATE_DEG_S, FIXED_POINT_ITERATIONS) + FIXED_POINT_SLACK_S


def maneuver_scalar(rules: SatRules, delta_deg: float, margins: Margins) -> float:
    """:func:`maneuver_s` (smallest gap, no ``gap_s``) for one angle, as a float [s].

    Args:
      rules: SatRules; delta_deg: |r2 - r1| [deg]; margins: Margins.
    Returns:
      float [s].
    """
    return float(maneuver_s(rules, float(delta_deg), margins))


def _sorted(starts, ends, rolls):
    s = np.asarray(starts, dtype=np.float64)
    e = np.asarray(ends, dtype=np.float64)
    r = np.asarray(rolls, dtype=np.float64)
    order = np.argsort(s, kind="stable")
    return s[order], e[order], r[order]


def gaps_ok(rules: SatRules, starts, ends, rolls, margins: Margins = Margins()) -> bool:
    """Rule 4 on one timeline: positive durations, no overlap, maneuver gaps.

    Args:
      rules: SatRules.
      starts, ends: float arrays [s] (any order).
      rolls: float array [deg].
      margins: Margins.
    Returns:
      bool.
    """
    s, e, r = _sorted(starts, ends, rolls)
    if np.any(e <= s):
        return False
    if s.size < 2:
        return True
    gap = s[1:] - e[:-1]
    need = maneuver_s(rules, np.abs(np.diff(r)), margins, gap_s=np.maximum(gap, 0.0))
    return bool(np.all(gap >= need))


def duty_ok(rules: SatRules, starts, ends, margins: Margins = Margins()) -> bool:
    """Rule 5 on one timeline: imaging time in ``[T - period, T]`` at every start/end ``T``.

    Args:
      rules: SatRules (``period_s``, ``duty_limit_s``).
      starts, ends: float arrays [s].
      margins: Margins (``duty_s``).
    Returns:
      bool (True when there is no limit).
    """
    if not np.isfinite(rules.duty_limit_s):
        return True
    s = np.asarray(starts, dtype=np.float64)
    e = np.asarray(ends, dtype=np.float64)
    if s.size == 0:
        return True
    t = np.concatenate([s, e])[:, None]
    lo = np.maximum(s[None, :], t - rules.period_s)
    hi = np.minimum(e[None, :], t)
    used = np.sum(np.clip(hi - lo, 0.0, None), axis=1)
    return bool(np.all(used <= rules.duty_limit_s - margins.duty_s))


def conservative_sunlit(sunlit_at_mesh: np.ndarray, guard: int = 1) -> np.ndarray:
    """Per mesh interval: charging counted only if surely sunlit.

    Interval ``k = [t_k, t_{k+1}]`` is sunlit only if the mesh points ``t_k`` and
    ``t_{k+1}`` and ``guard`` more points on each side are sunlit: the rule decides
    charging at each piece's midpoint with its own shadow model, so intervals at a
    shadow boundary count as dark (less charge can only lower the level, and the clamped
    recurrence is monotone in every increment).

    Args:
      sunlit_at_mesh: bool [K+1], sunlit flag at each mesh point.
      guard: extra mesh points required sunlit on each side.
    Returns:
      bool [K].
    """
    lit = np.asarray(sunlit_at_mesh, dtype=bool)
    ok = lit[:-1] & lit[1:]
    for _ in range(int(guard)):
        ok = ok & np.concatenate([[True], ok[:-1]]) & np.concatenate([ok[1:], [True]])
    return ok


def battery_levels(
    rules: SatRules,
    mesh_s: np.ndarray,
    sunlit_iv: np.ndarray,
    starts,
    ends,
    rolls,
    margins: Margins = Margins(),
) -> tuple[np.ndarray, np.ndarray]:
    """Battery level (rule 6) at the end of every piece of the refined mesh.

    The mesh ``mesh_s`` (``horizon start .. end``) is refined by every strip start and end
    and every maneuver window ``[start - maneuver, start)`` of a strip with a predecessor;
    piece ``i`` adds ``(charge_i - load_i) dt_i / 3600`` and the level is clamped at the
    capacity after each piece (closed form: with ``S`` the running sum of increments,
    ``E_n = S_n + min(E_0, min_{m <= n} (C - S_m))``). The maneuver here is slew +
    settling + the gap margin at the rotation-bounded angle, so its window is never
    shorter than the checker's.

    Args:
      rules: SatRules.
      mesh_s: float [K+1], the mesh instants [s], increasing.
      sunlit_iv: bool [K], charging flag of each mesh interval (:func:`conservative_sunlit`).
      starts, ends, rolls: the timeline (any order) [s, s, deg].
      margins: Margins (``gap_s``).
    Returns:
      (t, level): float [P+1] piece boundaries [s] and float [P+1] level [Wh] (level[0] =
      initial).
    """
    s, e, r = _sorted(starts, ends, rolls)
    if s.size > 1:
        man = maneuver_s(rules, np.abs(np.diff(r)), margins, gap_s=np.maximum(s[1:] - e[:-1], 0))
    else:
        man = np.zeros(0)
    mstart = s[1:] - man
    mesh = np.asarray(mesh_s, dtype=np.float64)
    t = np.union1d(mesh, np.concatenate([s, e, mstart]))
    t = t[(t >= mesh[0]) & (t <= mesh[-1])]
    mid = 0.5 * (t[:-1] + t[1:])
    dt = np.diff(t)
    k = np.clip(np.searchsorted(mesh, mid, side="right") - 1, 0, len(sunlit_iv) - 1)
    charge = np.where(np.asarray(sunlit_iv)[k], rules.charge_w, 0.0)
    imaging = np.searchsorted(s, mid, side="right") - np.searchsorted(e, mid, side="right")
    slewing = np.searchsorted(mstart, mid, side="right") - np.searchsorted(s[1:], mid, side="right")
    load = rules.idle_w + rules.imaging_w * (imaging > 0) + rules.slew_w * (slewing > 0)
    d = (charge - load) * dt / SECONDS_PER_HOUR
    cum = np.cumsum(d)
    e0 = min(rules.initial_wh, rules.capacity_wh)
    level = cum + np.minimum.accumulate(np.minimum(e0, rules.capacity_wh - cum))
    return t, np.concatenate([[rules.initial_wh], level])


def battery_min_wh(
    rules: SatRules, mesh_s, sunlit_iv, starts, ends, rolls, margins: Margins = Margins()
) -> float:
    """The lowest battery level over the horizon (see :func:`battery_levels`) [Wh].

    Args:
      rules, mesh_s, sunlit_iv, starts, ends, rolls, margins: as :func:`battery_levels`.
    Returns:
      float [Wh].
    """
    return float(np.min(battery_levels(rules, mesh_s, sunlit_iv, starts, ends, rolls, margins)[1]))


def battery_min_mesh(
    rules: SatRules, step_s: float, sunlit_iv, starts, ends, rolls, margins: Margins = Margins()
) -> float:
    """A lower bound of :func:`battery_min_wh` on the plain uniform mesh (the fast path).

    Pieces are the mesh intervals ``[k step, (k+1) step]`` only: strips must start and
    end on the mesh (the 10 s action grid lies on the 5 s mesh), and each maneuver window
    is widened to start at the mesh instant at or before its true start, so every load is
    at least the rule's and the level (monotone in every increment, clamp included) is at
    most the rule's.

    Args:
      rules: SatRules; step_s: mesh step [s]; sunlit_iv: bool [K] charging flags.
      starts, ends, rolls: the timeline [s, s, deg] (starts/ends multiples of ``step_s``).
      margins: Margins (``gap_s``).
    Returns:
      float, the lowest level [Wh] (the initial level included).
    """
    s, e, r = _sorted(starts, ends, rolls)
    k_n = len(sunlit_iv)
    dt_h = step_s / SECONDS_PER_HOUR
    mark = np.zeros(k_n + 1)
    ks = np.clip(np.rint(s / step_s).astype(np.int64), 0, k_n)
    ke = np.clip(np.rint(e / step_s).astype(np.int64), 0, k_n)
    np.add.at(mark, ks, rules.imaging_w)
    np.add.at(mark, ke, -rules.imaging_w)
    if s.size > 1:
        man = maneuver_s(rules, np.abs(np.diff(r)), margins, gap_s=np.maximum(s[1:] - e[:-1], 0))
        km = np.clip(np.floor((s[1:] - man) / step_s + 1e-9).astype(np.int64), 0, k_n)
        np.add.at(mark, km, rules.slew_w)
        np.add.at(mark, ks[1:], -rules.slew_w)
    load = rules.idle_w + np.cumsum(mark[:-1])
    d = (np.where(sunlit_iv, rules.charge_w, 0.0) - load) * dt_h
    cum = np.cumsum(d)
    e0 = min(rules.initial_wh, rules.capacity_wh)
    level = cum + np.minimum.accumulate(np.minimum(e0, rules.capacity_wh - cum))
    return float(min(rules.initial_wh, level.min()))


def timeline_ok(
    rules: SatRules, mesh_s, sunlit_iv, starts, ends, rolls, margins: Margins = Margins()
) -> tuple[bool, float]:
    """All timeline rules (4, 5, 6) of one satellite, cheapest first.

    Args:
      rules, mesh_s, sunlit_iv, starts, ends, rolls, margins: as :func:`battery_levels`
        (a uniform mesh from 0; the battery is :func:`battery_min_mesh`).
    Returns:
      (ok, min_battery_wh): min_battery is NaN when a cheaper rule already failed.
    """
    if not gaps_ok(rules, starts, ends, rolls, margins):
        return False, float("nan")
    if not duty_ok(rules, starts, ends, margins):
        return False, float("nan")
    step = float(mesh_s[1] - mesh_s[0])
    low = battery_min_mesh(rules, step, sunlit_iv, starts, ends, rolls, margins)
    return low >= margins.battery_wh, low
