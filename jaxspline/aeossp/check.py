"""Independent checker for aeossp_standard solutions (rules 1-8 and metrics).

This module re-implements the benchmark rules (``RULES.md``) with its own frame
chain, written to follow the official verifier's chain as closely as possible and
independently of the solver:

* SGP4 with WGS84 geopotential constants (the official propagator uses the Rust
  ``sgp4`` crate's ``Constants::from_elements``, which is WGS84) -> TEME.
* TEME -> Earth-fixed (ITRF, zero polar motion, UT1 = UTC):
  ``r_ecef = R3(GMST82) r_teme`` (GMST 1982 in seconds of time, Vallado 2006).
* Earth-fixed -> inertial (GCRF): ``r_gcrf = P(IAU 1976)^T N^T R3(-GAST) r_ecef`` with
  a truncated IAU 1980 nutation (4 terms, ~0.5" accuracy) and GAST = GMST82 + Δψ cos ε.
  Frame bias (23 mas) is ignored. The official chain (IAU 2006/2000A, CIO based)
  differs by < 1" in absolute orientation; rule 7 uses only angles between vectors at
  nearby instants, which depend on the change of that rotation (Earth rotation) only.
* Sun: low-precision analytic series (Montenbruck & Gill 2012, §3.3.2), J2000
  equatorial, TT = UTC + 69.184 s; cylindrical shadow with R = 6378136.3 m.
* Targets: WGS84 geodetic -> Earth-fixed.

Measured against brahe 1.8.0 (the official verifier's library, zero EOP) on case_0001
with a 1505-action solution: off-nadir max |Δ| 1.5e-7 deg, slew angle 3.6e-7 deg,
sunlit flag 0 of 34560 midpoints; satellite Earth-fixed position 1.2 mm, GCRF 0.9 m,
Sun direction 0.02".

Staging follows the official verifier: an action failing rules 1-4 is not checked
for geometry; an action failing geometry is not part of the slew chain; an action
failing overlap or slew is dropped from the chain (the next action is checked
against the last accepted one); the battery is simulated on the accepted actions.
Any violation makes the solution invalid (official metrics then are CR = WCR = PC = 0,
TAT = None); the metrics of the accepted subset are reported as ``accepted_metrics``.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from jaxspline.aeossp.case import Case, Satellite, Task, format_time, parse_time

# the reference models are also reachable as jaxspline.aeossp.check.<name>
from jaxspline.aeossp.check_frames import (  # noqa: F401
    EPS,
    Ephemeris,
    angle_deg,
    bang_coast_bang_time,
    ecef_to_gcrf_matrix,
    geodetic_to_ecef,
    gmst82,
    sun_position_gcrf,
    sunlit,
    teme_to_ecef,
)

__all__ = [
    "check_solution",
    "format_report",
]

OFF_NADIR_TOL_DEG = 1e-6


# --------------------------------------------------------------------------- report
@dataclass(frozen=True)
class Violation:
    """One rule violation.

    Attributes:
      rule: rule number of RULES.md (1-8).
      message: what is wrong, with the numbers.
      action_index: index into the solution's actions (None = satellite level).
      satellite_id: satellite concerned, if any.
      task_id: task concerned, if any.
      time: ISO time of the violation, if any.
    """

    rule: int
    message: str
    action_index: int | None = None
    satellite_id: str | None = None
    task_id: str | None = None
    time: str | None = None

    def __str__(self) -> str:
        where = f"actions[{self.action_index}]" if self.action_index is not None else "satellite"
        who = "/".join(x for x in (self.satellite_id, self.task_id) if x)
        at = f" at {self.time}" if self.time else ""
        return f"rule {self.rule} {where} {who}: {self.message}{at}"


@dataclass
class CheckReport:
    """Result of ``check_solution``: validity, violations, official metrics, diagnostics.

    Attributes:
      case_id: the case.
      valid: no violation.
      violations: the violations.
      metrics: official metrics (CR, WCR, TAT [s], PC [Wh]; zeros / None when invalid).
      accepted_metrics: the same over the actions that passed.
      n_actions: number of actions in the solution.
      n_accepted: number of actions that passed.
      satellites: per-satellite battery summaries.
      maneuvers: the maneuver windows.
      margins: tightest off-nadir slack [deg], slew-gap slack [s], lowest battery [Wh]
        over accepted actions.
    """

    case_id: str
    valid: bool
    violations: list[Violation]
    metrics: dict[str, Any]
    accepted_metrics: dict[str, Any]
    n_actions: int
    n_accepted: int
    satellites: dict[str, dict[str, Any]] = field(default_factory=dict)
    maneuvers: list[dict[str, Any]] = field(default_factory=list)
    margins: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-serialisable dictionary.

        Returns:
          dict (violations as dicts).
        """
        d = asdict(self)
        d["violations"] = [asdict(v) for v in self.violations]
        return d

    def to_json(self, indent: int | None = 2) -> str:
        """JSON text of ``to_dict()``.

        Args:
          indent: JSON indentation (None: compact).
        Returns:
          str.
        """
        return json.dumps(self.to_dict(), indent=indent)


@dataclass
class _Action:
    index: int
    sat: Satellite
    task: Task
    start: float  # seconds from horizon_start
    end: float
    off_slack: float = math.nan  # deg below max off-nadir (worst sample)
    slew_slack: float = math.nan  # s of gap beyond slew + settle


def _sec(case: Case, text: Any, where: str) -> float:
    return case.seconds(parse_time(text, where=where))


def _structure(case: Case, actions: list, out: list[Violation]) -> list[_Action]:
    sats, tasks = case.satellite_by_id, case.task_by_id
    horizon = case.duration_s
    ok: list[_Action] = []
    for i, raw in enumerate(actions):
        errs: list[tuple[int, str]] = []
        if not isinstance(raw, dict):
            out.append(Violation(1, f"action is not an object: {raw!r}", i))
            continue
        sid, tid = raw.get("satellite_id"), raw.get("task_id")
        sid = sid if isinstance(sid, str) else repr(sid)
        tid = tid if isinstance(tid, str) else repr(tid)
        if raw.get("type") != "observation":
            errs.append((1, f"type must be 'observation', got {raw.get('type')!r}"))
        if sid not in sats:
            errs.append((1, f"unknown satellite_id {sid!r}"))
        if tid not in tasks:
            errs.append((1, f"unknown task_id {tid!r}"))
        try:
            start = _sec(case, raw.get("start_time"), "start_time")
            end = _sec(case, raw.get("end_time"), "end_time")
        except ValueError as exc:
            errs.append((1, f"malformed time: {exc}"))
            start = end = None
        if start is not None:
            if not start < end:
                errs.append(
                    (2, f"start_time must be before end_time (start {start:g} s, end {end:g} s)")
                )
            if start < 0 or end > horizon:
                errs.append(
                    (2, f"outside horizon [0, {horizon:g}] s: start {start:g} s, end {end:g} s")
                )
            for name, s in (("start_time", start), ("end_time", end)):
                k = s / case.action_step_s
                if abs(k - round(k)) > EPS:
                    errs.append(
                        (2, f"{name} {s:g} s is not on the {case.action_step_s:g} s action grid")
                    )
        task = tasks.get(tid)
        sat = sats.get(sid)
        if task is not None and start is not None:
            rel, due = case.seconds(task.release_time), case.seconds(task.due_time)
            if start < rel or end > due:
                errs.append(
                    (3, f"outside task window [{rel:g}, {due:g}] s: [{start:g}, {end:g}] s")
                )
            dur = end - start
            if abs(dur - round(dur)) > EPS or round(dur) != task.required_duration_s:
                errs.append(
                    (3, f"duration {dur:g} s != required_duration_s {task.required_duration_s:g} s")
                )
        if task is not None and sat is not None and sat.sensor_type != task.required_sensor_type:
            errs.append(
                (4, f"sensor {sat.sensor_type!r} != required {task.required_sensor_type!r}")
            )
        for rule, msg in errs:
            out.append(
                Violation(
                    rule,
                    msg,
                    i,
                    sid if isinstance(sid, str) else None,
                    tid if isinstance(tid, str) else None,
                )
            )
        if not errs:
            ok.append(_Action(i, sat, task, start, end))
    return ok


def _sample_times(case: Case, start: float, end: float) -> np.ndarray:
    step = case.geometry_step_s
    k0 = math.floor(start / step + EPS) + 1
    inner = [k * step for k in range(k0, math.ceil(end / step - EPS))]
    return np.array([start, *[t for t in inner if start < t < end], end])


def _geometry(case, acts, ephs, targets, out) -> list[_Action]:
    ok = []
    for a in acts:
        ts = _sample_times(case, a.start, a.end)
        sat = ephs[a.sat.satellite_id].ecef(ts)
        tgt = targets[a.task.task_id]
        up = np.sum((sat - tgt) * tgt, axis=-1) / np.linalg.norm(tgt)
        off = angle_deg(-sat, tgt - sat)
        bad_up = np.nonzero(~(up > 0.0))[0]
        bad_off = np.nonzero(off > a.sat.max_off_nadir_deg + OFF_NADIR_TOL_DEG)[0]
        sid, tid = a.sat.satellite_id, a.task.task_id
        if bad_up.size:
            j = bad_up[0]
            out.append(
                Violation(
                    5,
                    f"target below the local horizon (elevation term {up[j]:.1f} m)",
                    a.index,
                    sid,
                    tid,
                    format_time(case.at(ts[j])),
                )
            )
        elif bad_off.size:
            j = bad_off[0]
            out.append(
                Violation(
                    5,
                    f"off-nadir {off[j]:.6f} deg > max {a.sat.max_off_nadir_deg:g} deg",
                    a.index,
                    sid,
                    tid,
                    format_time(case.at(ts[j])),
                )
            )
        else:
            a.off_slack = a.sat.max_off_nadir_deg - float(np.max(off))
            ok.append(a)
    return ok


class _InertialCache:
    """GCRF satellite positions and Earth-fixed -> GCRF matrices at given instants (batched)."""

    def __init__(self, eph: Ephemeris, times):
        ts = np.array(sorted(set(times)), dtype=float)
        self.index = {t: i for i, t in enumerate(ts.tolist())}
        unix = eph.unix(ts)
        self.mat = ecef_to_gcrf_matrix(unix)
        self.sat = np.einsum("nij,nj->ni", self.mat, eph.ecef(ts))

    def nadir(self, t: float) -> np.ndarray:
        return -self.sat[self.index[t]]

    def los(self, target_ecef: np.ndarray, t: float) -> np.ndarray:
        i = self.index[t]
        return self.mat[i] @ target_ecef - self.sat[i]


def _slew(case, acts, ephs, targets, out):
    by_sat: dict[str, list[_Action]] = defaultdict(list)
    for a in acts:
        by_sat[a.sat.satellite_id].append(a)
    accepted, windows = {}, {}
    maneuvers = []
    for sid, lst in by_sat.items():
        lst.sort(key=lambda a: (a.start, a.end, a.index))
        prev, acc, win = None, [], []
        cache = _InertialCache(ephs[sid], [x for a in lst for x in (a.start, a.end)])
        for cur in lst:
            sat, tid = cur.sat, cur.task.task_id
            if prev is not None and prev.end > cur.start:
                out.append(
                    Violation(
                        6,
                        f"overlaps actions[{prev.index}] ({prev.task.task_id}), which ends "
                        f"{prev.end - cur.start:g} s after this start",
                        cur.index,
                        sid,
                        tid,
                        format_time(case.at(cur.start)),
                    )
                )
                continue
            to_vec = cache.los(targets[tid], cur.start)
            if prev is None:
                from_vec, gap, src = cache.nadir(cur.start), cur.start, "nadir"
            else:
                from_vec = cache.los(targets[prev.task.task_id], prev.end)
                gap, src = cur.start - prev.end, prev.task.task_id
            theta = float(angle_deg(from_vec, to_vec))
            need = (
                bang_coast_bang_time(theta, sat.max_slew_rate_deg_s, sat.max_slew_accel_deg_s2)
                + sat.settling_time_s
            )
            if gap + EPS < need:
                out.append(
                    Violation(
                        7,
                        f"slew {theta:.4f} deg from {src} needs {need:.3f} s "
                        f"(incl. settle {sat.settling_time_s:g} s), gap {gap:.3f} s",
                        cur.index,
                        sid,
                        tid,
                        format_time(case.at(cur.start)),
                    )
                )
                continue
            if need > EPS:
                ws = round((cur.start - need) * 1e6) / 1e6  # official: datetime, microseconds
                win.append((ws, cur.start))
                maneuvers.append(
                    {
                        "action_index": cur.index,
                        "satellite_id": sid,
                        "from": src,
                        "to_task_id": tid,
                        "slew_angle_deg": theta,
                        "required_gap_s": need,
                        "available_gap_s": gap,
                    }
                )
            cur.slew_slack = gap - need
            acc.append(cur)
            prev = cur
        accepted[sid], windows[sid] = acc, win
    return accepted, windows, maneuvers


def _battery(
    case, sat: Satellite, eph: Ephemeris, acts: list[_Action], wins, out
) -> dict[str, Any]:
    grid = np.minimum(
        np.arange(0.0, case.duration_s + case.resource_step_s, case.resource_step_s),
        case.duration_s,
    )
    extra = [x for a in acts for x in (a.start, a.end)] + [x for w in wins for x in w]
    pts = np.unique(np.concatenate([grid, [0.0, case.duration_s], np.asarray(extra, dtype=float)]))
    t0, t1 = pts[:-1], pts[1:]
    mid, dur = 0.5 * (t0 + t1), t1 - t0

    def inside(iv):
        if not iv:
            return np.zeros(mid.shape, bool)
        iv = np.asarray(iv, dtype=float)
        return np.any((mid[:, None] >= iv[None, :, 0]) & (mid[:, None] < iv[None, :, 1]), axis=1)

    obs = inside([(a.start, a.end) for a in acts])
    slew = inside(list(wins))
    load = sat.idle_power_w + obs * sat.imaging_power_w + slew * sat.slew_power_w
    lit = sunlit(eph.gcrf(mid), eph.unix(mid))
    charge = np.where(lit, sat.sunlit_charge_power_w, 0.0)
    batt = sat.initial_battery_wh
    bmin, tmin, gross, failed = batt, 0.0, 0.0, False
    cap = sat.battery_capacity_wh
    loads, nets = (load * dur / 3600.0).tolist(), ((charge - load) * dur / 3600.0).tolist()
    for k, (used, net) in enumerate(zip(loads, nets, strict=True)):
        gross += used
        batt += net
        if batt < -EPS:
            who = next((a for a in acts if a.start <= mid[k] < a.end), None)
            out.append(
                Violation(
                    8,
                    f"battery {batt:.3f} Wh < 0 (load {load[k]:g} W, charge {charge[k]:g} W)",
                    who.index if who else None,
                    sat.satellite_id,
                    who.task.task_id if who else None,
                    format_time(case.at(mid[k])),
                )
            )
            failed = True
            break
        if batt > cap:
            batt = cap
        if batt < bmin:
            bmin, tmin = batt, float(t1[k])
    return {
        "n_actions": len(acts),
        "min_battery_wh": bmin,
        "min_battery_time": format_time(case.at(tmin)),
        "final_battery_wh": batt,
        "gross_consumption_wh": gross,
        "sunlit_fraction": float(np.sum(dur * lit) / np.sum(dur)),
        "failed": failed,
    }


def _metrics(case: Case, acts: list[_Action], pc: float) -> dict[str, Any]:
    first: dict[str, float] = {}
    for a in acts:
        tid = a.task.task_id
        first[tid] = min(first.get(tid, math.inf), a.end)
    tasks = case.task_by_id
    total_w = sum(t.weight for t in case.tasks)
    tat = [e - case.seconds(tasks[tid].release_time) for tid, e in first.items()]
    return {
        "CR": len(first) / len(case.tasks) if case.tasks else 0.0,
        "WCR": sum(tasks[tid].weight for tid in first) / total_w if total_w > 0 else 0.0,
        "TAT": sum(tat) / len(tat) if tat else None,
        "PC": pc,
        "completed_tasks": len(first),
    }


def check_solution(case: Case, solution: dict) -> CheckReport:
    """Check a solution dict ``{"actions": [...]}`` against every rule of RULES.md.

    Args:
      case: Case.
      solution: dict ``{"actions": [...]}``.
    Returns:
      CheckReport (``valid``, violations with rule, action index, satellite/task and
      numbers, official metrics, accepted metrics, battery summaries, maneuver windows
      and margins).
    """
    if not isinstance(solution, dict) or not isinstance(solution.get("actions", []), list):
        raise ValueError("solution: expected an object with an 'actions' list")
    actions = solution.get("actions", [])
    out: list[Violation] = []
    acts = _structure(case, actions, out)
    ephs = {s.satellite_id: Ephemeris(s, case.horizon_start) for s in case.satellites}
    used = {a.task.task_id: a.task for a in acts}
    targets = {
        tid: geodetic_to_ecef(t.latitude_deg, t.longitude_deg, t.altitude_m)
        for tid, t in used.items()
    }
    acts = _geometry(case, acts, ephs, targets, out)
    accepted, windows, maneuvers = _slew(case, acts, ephs, targets, out)
    sats: dict[str, dict[str, Any]] = {}
    pc = 0.0
    for sat in case.satellites:
        sid = sat.satellite_id
        summary = _battery(case, sat, ephs[sid], accepted.get(sid, []), windows.get(sid, []), out)
        sats[sid] = summary
        if not summary["failed"]:
            pc += summary["gross_consumption_wh"]
    acc = [a for lst in accepted.values() for a in lst]
    acc_metrics = _metrics(case, acc, pc)
    valid = not out
    metrics = (
        {k: acc_metrics[k] for k in ("CR", "WCR", "TAT", "PC")}
        if valid
        else {"CR": 0.0, "WCR": 0.0, "TAT": None, "PC": 0.0}
    )
    out.sort(key=lambda v: (v.action_index if v.action_index is not None else 1 << 30, v.rule))
    margins = {
        "min_off_nadir_slack_deg": min((a.off_slack for a in acc), default=None),
        "min_slew_slack_s": min((a.slew_slack for a in acc), default=None),
        "min_battery_wh": min((v["min_battery_wh"] for v in sats.values()), default=None),
    }
    return CheckReport(
        case.case_id,
        valid,
        out,
        metrics,
        acc_metrics,
        len(actions),
        len(acc),
        sats,
        maneuvers,
        margins,
    )


def format_report(report: CheckReport, max_violations: int = 50) -> str:
    """Readable multi-line text of a ``CheckReport``.

    Args:
      report: CheckReport.
      max_violations: violations listed; the rest is counted in one line.
    Returns:
      str.
    """
    lines = [
        f"case {report.case_id}: {'VALID' if report.valid else 'INVALID'} "
        f"({report.n_accepted}/{report.n_actions} actions accepted, "
        f"{len(report.violations)} violations)"
    ]
    m = report.metrics
    tat = "n/a" if m["TAT"] is None else f"{m['TAT']:.1f} s"
    lines.append(f"  WCR {m['WCR']:.4f}  CR {m['CR']:.4f}  TAT {tat}  PC {m['PC']:.1f} Wh")
    if not report.valid:
        a = report.accepted_metrics
        lines.append(
            f"  (accepted subset: WCR {a['WCR']:.4f}  CR {a['CR']:.4f}  "
            f"completed {a['completed_tasks']})"
        )
        counts: dict[int, int] = defaultdict(int)
        for v in report.violations:
            counts[v.rule] += 1
        lines.append(
            "  violations by rule: " + ", ".join(f"{r}: {c}" for r, c in sorted(counts.items()))
        )
        for v in report.violations[:max_violations]:
            lines.append(f"  - {v}")
        if len(report.violations) > max_violations:
            lines.append(f"  ... {len(report.violations) - max_violations} more")
    mg = report.margins
    if mg.get("min_off_nadir_slack_deg") is not None:
        lines.append(
            f"  tightest margins: off-nadir {mg['min_off_nadir_slack_deg']:.2e} deg, "
            f"slew gap {mg['min_slew_slack_s']:.3f} s"
        )
    low = min(report.satellites.items(), key=lambda kv: kv[1]["min_battery_wh"], default=None)
    if low is not None:
        lines.append(
            f"  lowest battery: {low[0]} {low[1]['min_battery_wh']:.1f} Wh "
            f"at {low[1]['min_battery_time']}"
        )
    return "\n".join(lines)
