"""Independent checker of regional_coverage solutions: every rule of RULES.md and the score.

Shares no code with the solver (it imports only the case reader, its own
:mod:`~jaxspline.regional.check_geometry` and the frame / Sun models of the other
benchmark's checker, :mod:`jaxspline.aeossp.check_frames`).

What the official verifier does (public repository Mtrya/astro-reason,
``benchmarks/regional_coverage/verifier.py``, read for facts; its SPEC.md pins "brahe +
TLE + GCRF/ITRF") and how this checker follows it:

* Propagation: brahe ``SGPPropagator`` (Rust ``sgp4`` crate, WGS84 constants) with a
  zero EOP provider (UT1 = UTC, no polar motion). Its ``state_ecef`` is
  ``R3(GMST82) r_teme`` and ``R3(GMST82) v_teme - ω × r`` (brahe's ``state_pef``, then
  the identity polar motion). Here: python-sgp4 (WGS84) and the same rotation; measured
  against brahe 1.8.0 on case_0003: position 4 mm, velocity 4e-6 m/s.
* Sunlight: brahe ``sun_position`` (low-precision analytic series, Montenbruck & Gill
  §3.3.2, EME2000 ~ GCRF) and the satellite's ``state_eci`` (ITRF -> GCRF, IAU
  2006/2000A); sunlit unless ``r·ŝ < 0`` and ``|r - (r·ŝ)ŝ| < R_EARTH`` (6378136.3 m).
  Here: the same Sun series, a truncated IAU 1976/1980 rotation (GCRF 3 m from brahe's)
  and the same cylinder: 0 mismatches in 7006 instants on case_0003.
* Strip rays: nadir / along / across and ``n + tan(a) c`` as in RULES.md; WGS84 ray
  intersection, nearest root > 1e-9 m; the center ray must hit too. Ground points to
  geodetic lon/lat; each quad (inner_a, outer_a, outer_b, inner_b) is a shapely
  ``Polygon`` of the raw longitudes (no wrap handling at ±180°: a quad crossing the
  antimeridian spans the long way round; the canonical cases avoid it), a quad of area
  <= 1e-9 deg² invalidates the action, a sample counts if the polygon ``covers`` it
  (border inclusive). Here: the even-odd test with a border tolerance (1e-12 relative).
* Slew: the official angle is the angle between the Earth-fixed boresights (center
  roll) at the previous end and the next start, which includes the frame's rotation
  during the gap; RULES.md says ``|r2 - r1|``. Here ``d = max(|r2 - r1|, boresight
  angle)``: at least as strict as both. Maneuver windows (battery) use the same ``d``.
* Duty: the official orbit period is ``86400 / float(line2.split()[-2])``; on a line
  whose mean motion and revolution number touch (``15.47631360225573``) that token is
  the mean anomaly, so its window is shorter (e.g. 372 s). Here the window is the longer
  of that and ``86400 / mean motion`` (columns 53-63), so both are implied.
* Tolerances as official: band 1e-6 deg, duration bounds 1e-6 s, grid alignment 1e-6
  steps, gap 1e-6 s, duty 1e-6 s, battery -1e-9 Wh, region minimum 1e-9.
* Staging as official: an action failing its own rules (structure, horizon, grid,
  duration, band) is left out of everything else; one whose rays miss keeps its place
  in the schedule (slew, duty, battery) but covers nothing. Deviation: an action whose
  ``type`` is not ``"strip_observation"`` is a violation here (the official verifier
  skips it, though it counts toward the action cap); a ``start_time`` without a zone
  is refused by both.

Agreement with a replica of the official metric path written on brahe 1.8.0 + shapely
(not part of the package): on 64-action valid solutions of case_0001 and case_0004 the
covered sample sets are identical (coverage_ratio equal to the last digit) and the
lowest battery level agrees to 5e-12 Wh.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from datetime import datetime

import numpy as np

from jaxspline.aeossp.check_frames import angle_deg, bang_coast_bang_time, sunlit
from jaxspline.regional.case import Case, format_time
from jaxspline.regional.check_geometry import (
    Track,
    covered_by_quads,
    ecef_to_lonlat,
    look_direction,
    quad_area,
    sample_offsets,
    strip_ground,
    strip_quads,
)

ACTION_TYPE = "strip_observation"
BAND_TOL_DEG = 1e-6
DURATION_TOL_S = 1e-6
ALIGN_TOL = 1e-6
GAP_TOL_S = 1e-6
DUTY_TOL_S = 1e-6
BATTERY_TOL_WH = 1e-9
REGION_TOL = 1e-9
MIN_QUAD_AREA_DEG2 = 1e-9
#: Maneuver window starts are rounded to this [s] (the official datetimes' microseconds).
TIME_RESOLUTION_S = 1e-6
SECONDS_PER_HOUR = 3600.0


@dataclass(frozen=True)
class Violation:
    """One broken rule.

    Attributes:
      rule: ``action_cap``, ``structure``, ``satellite``, ``horizon``, ``time_grid``,
        ``duration``, ``band``, ``ray``, ``geometry``, ``overlap``, ``slew``, ``duty``,
        ``battery`` or ``region_min``.
      action: index into the solution's actions (None: satellite / region level).
      message: what is wrong, with the numbers.
    """

    rule: str
    action: int | None
    message: str

    def __str__(self) -> str:
        where = f"actions[{self.action}]" if self.action is not None else "-"
        return f"{self.rule} {where}: {self.message}"


@dataclass
class CheckReport:
    """Result of :func:`check_solution`.

    Attributes:
      valid: no violation.
      violations: list of Violation.
      coverage_ratio: region-weight-weighted mean of the region ratios.
      weighted_coverage_ratio: covered weight / total weight over all regions.
      region_ratios: region_id -> covered weight / ``total_weight_m2``.
      num_actions: number of actions in the solution.
      min_battery_wh: lowest battery level over all satellites [Wh].
      covered_weight_m2: unique covered sample weight [m²].
      action_covered_m2: per action, the sample weight it covers alone or not [m²].
      covered: bool [N], the covered grid samples (not in :meth:`to_dict`).
    """

    valid: bool
    violations: list
    coverage_ratio: float
    weighted_coverage_ratio: float
    region_ratios: dict
    num_actions: int
    min_battery_wh: float
    covered_weight_m2: float = 0.0
    action_covered_m2: list = field(default_factory=list)
    covered: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool), repr=False)

    def to_dict(self) -> dict:
        """The report as JSON-ready data (violations as dicts).

        Returns:
          dict.
        """
        data = asdict(self)
        data.pop("covered")
        data["violations"] = [asdict(v) for v in self.violations]
        return data

    def to_json(self) -> str:
        """The report as indented JSON text.

        Returns:
          str.
        """
        return json.dumps(self.to_dict(), indent=2, allow_nan=False)


@dataclass
class ParsedAction:
    """One readable action, in seconds from the horizon start.

    Attributes:
      index: position in the solution's actions.
      sat: satellite index in ``Case.satellites``.
      start: start [s].
      end: end [s].
      roll: roll [deg].
    """

    index: int
    sat: int
    start: float
    end: float
    roll: float


def _number(raw: dict, key: str, where: str, out: list) -> float | None:
    value = raw.get(key)
    if key not in raw:
        out.append(Violation("structure", None, f"{where}: missing {key}"))
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        out.append(Violation("structure", None, f"{where}.{key}: not a number: {value!r}"))
        return None
    if not math.isfinite(float(value)):
        out.append(Violation("structure", None, f"{where}.{key}: not finite: {value!r}"))
        return None
    return float(value)


def _start_seconds(case: Case, raw: dict, where: str, out: list) -> float | None:
    text = raw.get("start_time")
    if not isinstance(text, str):
        out.append(Violation("structure", None, f"{where}.start_time: not a string: {text!r}"))
        return None
    s = text.strip()
    s = s[:-1] + "+00:00" if s.endswith(("Z", "z")) else s
    try:
        value = datetime.fromisoformat(s)
    except ValueError:
        out.append(Violation("structure", None, f"{where}.start_time: not ISO 8601: {text!r}"))
        return None
    if value.tzinfo is None:
        out.append(Violation("structure", None, f"{where}.start_time: no time zone: {text!r}"))
        return None
    return case.seconds(value)


def _parse(case: Case, actions: list, out: list) -> list[ParsedAction]:
    """Structure and satellite ids; returns the actions that could be read."""
    sat_index = case.satellite_index()
    acts = []
    for i, raw in enumerate(actions):
        where = f"actions[{i}]"
        errs: list = []
        if not isinstance(raw, dict):
            out.append(Violation("structure", i, f"{where}: not an object"))
            continue
        if raw.get("type") != ACTION_TYPE:
            errs.append(Violation("structure", None, f"{where}.type: {raw.get('type')!r}"))
        sid = raw.get("satellite_id")
        if not isinstance(sid, str):
            errs.append(Violation("structure", None, f"{where}.satellite_id: {sid!r}"))
        elif sid not in sat_index:
            errs.append(Violation("satellite", None, f"{where}: unknown satellite_id {sid!r}"))
        start = _start_seconds(case, raw, where, errs)
        dur = _number(raw, "duration_s", where, errs)
        roll = _number(raw, "roll_deg", where, errs)
        out.extend(Violation(v.rule, i, v.message) for v in errs)
        if not errs:
            acts.append(ParsedAction(i, sat_index[sid], start, start + dur, roll))
    return acts


def _aligned(value: float, step: float) -> bool:
    q = value / step
    return abs(q - round(q)) <= ALIGN_TOL


def _own_rules(case: Case, act: ParsedAction) -> list[Violation]:
    """Rules 2-3 of one action (horizon, grid, duration, band)."""
    sat = case.satellites[act.sat]
    sen, dur, i = sat.sensor, act.end - act.start, act.index
    out = []
    if act.start < 0.0 or act.end > case.horizon_s:
        out.append(Violation("horizon", i, f"[{act.start:g}, {act.end:g}] s outside the horizon"))
    if not _aligned(act.start, case.time_step_s):
        out.append(Violation("time_grid", i, f"start {act.start:g} s not on the grid"))
    if not dur > 0.0:
        out.append(Violation("duration", i, f"duration_s {dur:g} must be > 0"))
    if not _aligned(dur, case.time_step_s):
        out.append(Violation("duration", i, f"duration_s {dur:g} not a multiple of the step"))
    if dur < sen.min_duration_s - DURATION_TOL_S or dur > sen.max_duration_s + DURATION_TOL_S:
        out.append(
            Violation(
                "duration",
                i,
                f"duration_s {dur:g} outside [{sen.min_duration_s:g}, {sen.max_duration_s:g}]",
            )
        )
    inner, outer = abs(act.roll) - sen.fov_deg / 2, abs(act.roll) + sen.fov_deg / 2
    if inner < sen.min_edge_deg - BAND_TOL_DEG:
        out.append(Violation("band", i, f"inner edge {inner:.6f} < {sen.min_edge_deg:g} deg"))
    if outer > sen.max_edge_deg + BAND_TOL_DEG:
        out.append(Violation("band", i, f"outer edge {outer:.6f} > {sen.max_edge_deg:g} deg"))
    return out


def _coverage(case: Case, act: ParsedAction, track: Track, out: list) -> np.ndarray | None:
    """Rays, quads and the covered sample mask of one action (None if its rays fail)."""
    sen = case.satellites[act.sat].sensor
    offsets = sample_offsets(act.end - act.start, case.sample_step_s)
    inner = math.copysign(abs(act.roll) - sen.fov_deg / 2, act.roll)
    outer = math.copysign(abs(act.roll) + sen.fov_deg / 2, act.roll)
    ground = strip_ground(track, act.start, offsets, [inner, act.roll, outer])
    miss = np.isnan(ground).any(axis=(1, 2))
    if miss.any():
        t = case.time_at(act.start + offsets[np.argmax(miss)])
        out.append(Violation("ray", act.index, f"a ray misses the Earth at {format_time(t)}"))
        return None
    lon, lat = ecef_to_lonlat(ground)
    lonlat = np.stack([lon, lat], -1)
    quads = strip_quads(lonlat[:, 0], lonlat[:, 2])
    if np.any(quad_area(quads) <= MIN_QUAD_AREA_DEG2):
        out.append(Violation("geometry", act.index, "a strip quad collapsed to zero area"))
        return None
    return covered_by_quads(quads, case.grid.lon_deg, case.grid.lat_deg)


def slew_angle(track: Track, prev: ParsedAction, nxt: ParsedAction) -> float:
    """Slew angle between two actions of one satellite: max(|Δroll|, boresight angle).

    The boresight angle is the angle between the Earth-fixed center-roll look directions
    at ``prev``'s end and ``nxt``'s start (the official verifier's angle).

    Args:
      track: the satellite's Track.
      prev: the earlier action (its end and roll).
      nxt: the later action (its start and roll).
    Returns:
      float [deg].
    """
    pos, vel = track.ecef(np.array([prev.end, nxt.start]))
    b = look_direction(pos, vel, np.array([prev.roll, nxt.roll]))
    return max(abs(nxt.roll - prev.roll), float(angle_deg(b[0], b[1])))


def _schedule(case: Case, acts: list, tracks: list, out: list) -> dict:
    """Rule 4: overlap and slew + settling per satellite; returns maneuver windows."""
    windows: dict = {k: [] for k in range(len(case.satellites))}
    for k, sat in enumerate(case.satellites):
        mine = sorted((a for a in acts if a.sat == k), key=lambda a: (a.start, a.end))
        ag = sat.agility
        for prev, nxt in zip(mine, mine[1:], strict=False):
            if nxt.start < prev.end:
                out.append(
                    Violation(
                        "overlap",
                        nxt.index,
                        f"{sat.id}: overlaps actions[{prev.index}] "
                        f"([{prev.start:g}, {prev.end:g}] and [{nxt.start:g}, {nxt.end:g}] s)",
                    )
                )
                continue
            d = slew_angle(tracks[k], prev, nxt)
            need = bang_coast_bang_time(d, ag.rate_deg_s, ag.accel_deg_s2) + ag.settling_s
            gap = nxt.start - prev.end
            if gap + GAP_TOL_S < need:
                out.append(
                    Violation(
                        "slew",
                        nxt.index,
                        f"{sat.id}: gap {gap:.3f} s after actions[{prev.index}] < "
                        f"slew + settling {need:.3f} s ({d:.4f} deg)",
                    )
                )
                continue
            begin = round((nxt.start - need) / TIME_RESOLUTION_S) * TIME_RESOLUTION_S
            windows[k].append((begin, nxt.start))
    return windows


def duty_window_s(sat) -> float:
    """Duty-cycle window: the longer of the TLE period and the official parse's (docstring).

    Args:
      sat: Satellite.
    Returns:
      float [s].
    """
    try:
        quirk = 86400.0 / float(sat.tle2.split()[-2])
    except (ValueError, ZeroDivisionError, IndexError):
        quirk = 0.0
    return max(sat.orbit_period_s, quirk if quirk > 0 else 0.0)


def _duty(case: Case, acts: list, out: list) -> None:
    """Rule 5: imaging time inside [T - period, T] at every action start / end T."""
    for k, sat in enumerate(case.satellites):
        limit = sat.power.duty_limit_s
        mine = [a for a in acts if a.sat == k]
        if limit is None or not mine:
            continue
        period = duty_window_s(sat)
        s = np.array([a.start for a in mine])
        e = np.array([a.end for a in mine])
        for t in np.unique(np.concatenate([s, e])):
            used = float(np.sum(np.clip(np.minimum(e, t) - np.maximum(s, t - period), 0, None)))
            if used > limit + DUTY_TOL_S:
                out.append(
                    Violation(
                        "duty",
                        None,
                        f"{sat.id}: {used:.3f} s of imaging in the orbit before "
                        f"{format_time(case.time_at(t))} > limit {limit:g} s",
                    )
                )
                break


def battery_trace(case: Case, k: int, acts: list, windows: list, track: Track):
    """Rule 6 for satellite ``k``: the battery on the refined mesh.

    Args:
      case: Case.
      k: satellite index.
      acts: that satellite's scheduled actions (ParsedAction).
      windows: its maneuver windows [(start, end)] [s].
      track: its Track.
    Returns:
      (times [M+1] s, levels [M+1] Wh after the clamp, first index whose unclamped
      level is below -1e-9 Wh or None).
    """
    p = case.satellites[k].power
    h = case.horizon_s
    grid = np.append(np.arange(0.0, h, case.sample_step_s), h)
    extra = [x for a in acts for x in (a.start, a.end)] + [x for w in windows for x in w]
    t = np.unique(np.concatenate([grid, np.asarray(extra, dtype=float)]))
    dt = np.diff(t)
    mid = t[:-1] + dt / 2
    charge = np.where(sunlit(track.gcrf_position(mid), track.unix(mid)), p.charge_w, 0.0)
    imaging = np.zeros(mid.shape, dtype=bool)
    for a in acts:
        imaging |= (a.start <= mid) & (mid < a.end)
    slewing = np.zeros(mid.shape, dtype=bool)
    for w0, w1 in windows:
        slewing |= (w0 <= mid) & (mid < w1)
    load = p.idle_w + imaging * p.imaging_w + slewing * p.slew_w
    s = p.initial_wh + np.cumsum((charge - load) * dt / SECONDS_PER_HOUR)
    excess = np.maximum.accumulate(np.maximum(s - p.capacity_wh, 0.0))
    level = s - excess
    before = s - np.concatenate([[0.0], excess[:-1]])  # unclamped level of each interval
    low = np.flatnonzero(before < -BATTERY_TOL_WH)
    first = int(low[0]) if low.size else None
    return t, np.concatenate([[p.initial_wh], level]), first


def _battery(case: Case, acts: list, windows: dict, tracks: list, out: list) -> float:
    """Rule 6 for every satellite; returns the lowest level (up to the first breach)."""
    lowest = math.inf
    for k, sat in enumerate(case.satellites):
        mine = [a for a in acts if a.sat == k]
        t, level, first = battery_trace(case, k, mine, windows[k], tracks[k])
        if first is not None:
            level = level[: first + 2]
            mid = (t[first] + t[first + 1]) / 2
            out.append(
                Violation(
                    "battery",
                    None,
                    f"{sat.id}: battery {level[-1]:.3f} Wh < 0 around "
                    f"{format_time(case.time_at(round(mid)))}",
                )
            )
        lowest = min(lowest, float(level.min()))
    return lowest


def _metrics(case: Case, covered: np.ndarray) -> tuple[float, float, dict, float]:
    """coverage_ratio, weighted_coverage_ratio, region ratios, covered weight."""
    g = case.grid
    per_region = np.bincount(g.region, weights=g.weight_m2 * covered, minlength=len(case.regions))
    ratios = per_region / g.region_total_m2
    weights = np.array([r.weight for r in case.regions])
    cr = float(np.sum(weights * ratios) / np.sum(weights)) if weights.sum() > 0 else 0.0
    wcr = float(per_region.sum() / g.region_total_m2.sum())
    named = {r.id: float(x) for r, x in zip(case.regions, ratios, strict=True)}
    return cr, wcr, named, float(per_region.sum())


def check_solution(case: Case, solution) -> CheckReport:
    """Check a solution against every rule of RULES.md and score it.

    Args:
      case: the loaded Case.
      solution: ``{"actions": [...]}`` or the list of actions.
    Returns:
      CheckReport (coverage is reported over the actions that passed their own rules,
      also when the solution is invalid; a solution over the action cap is refused by
      that rule alone, at once, with the scores 0).
    Raises:
      ValueError: ``solution`` is not a list of actions nor an object holding one.
    """
    actions = solution.get("actions") if isinstance(solution, dict) else solution
    if not isinstance(actions, list):
        raise ValueError("solution: actions: expected a list of action objects")
    out: list = []
    if len(actions) > case.max_actions:  # first, and alone: the rest is work for nothing
        cap = case.max_actions
        why = f"{len(actions)} actions > cap {cap} (scoring.max_actions_total); the other "
        out.append(Violation("action_cap", None, why + "rules and the coverage are not checked"))
        zero = {r.id: 0.0 for r in case.regions}
        return CheckReport(False, out, 0.0, 0.0, zero, len(actions), 0.0)
    acts = []
    for act in _parse(case, actions, out):
        own = _own_rules(case, act)
        out.extend(own)
        if not own:
            acts.append(act)
    tracks = [Track(s, case.start) for s in case.satellites]
    covered = np.zeros(case.grid.size, dtype=bool)
    action_cov = [0.0] * len(actions)
    for act in acts:
        mask = _coverage(case, act, tracks[act.sat], out)
        if mask is not None:
            covered |= mask
            action_cov[act.index] = float(case.grid.weight_m2[mask].sum())
    windows = _schedule(case, acts, tracks, out)
    _duty(case, acts, out)
    min_battery = _battery(case, acts, windows, tracks, out)
    cr, wcr, ratios, cov_w = _metrics(case, covered)
    for r in case.regions:
        if r.min_coverage is not None and ratios[r.id] + REGION_TOL < r.min_coverage:
            out.append(
                Violation(
                    "region_min",
                    None,
                    f"{r.id}: coverage {ratios[r.id]:.6f} < required {r.min_coverage:.6f}",
                )
            )
    return CheckReport(
        valid=not out,
        violations=out,
        coverage_ratio=cr,
        weighted_coverage_ratio=wcr,
        region_ratios=ratios,
        num_actions=len(actions),
        min_battery_wh=min_battery,
        covered_weight_m2=cov_w,
        action_covered_m2=action_cov,
        covered=covered,
    )


def format_report(report: CheckReport, max_violations: int = 50) -> str:
    """Readable summary: validity, metrics, region ratios and the first violations.

    Args:
      report: CheckReport.
      max_violations: violations listed at most (the rest counted).
    Returns:
      str (several lines).
    """
    lines = [
        f"valid: {'yes' if report.valid else 'NO'}",
        f"coverage_ratio: {report.coverage_ratio:.6f}",
        f"weighted_coverage_ratio: {report.weighted_coverage_ratio:.6f}",
        f"num_actions: {report.num_actions}",
        f"min_battery_wh: {report.min_battery_wh:.3f}",
    ]
    lines += [f"  region {rid}: {x:.6f}" for rid, x in report.region_ratios.items()]
    n = len(report.violations)
    lines.append(f"violations: {n}")
    lines += [f"  {v}" for v in report.violations[:max_violations]]
    if n > max_violations:
        lines.append(f"  ... and {n - max_violations} more")
    return "\n".join(lines)
