"""Independent checker of stereo_imaging solutions: every rule of RULES.md and the score.

Shares no code with a solver: it imports only the case reader, its own
:mod:`~jaxspline.stereo.check_geometry` and :mod:`~jaxspline.stereo.check_products`, and
the frame / Sun models of the aeossp checker (:mod:`jaxspline.aeossp.check_frames`).

What the official verifier does (public repository Mtrya/astro-reason,
``benchmarks/stereo_imaging/verifier/engine.py``, read for facts) and how this checker
follows it:

* Propagation: skyfield ``EarthSatellite`` (SGP4, WGS72 constants) read in skyfield's
  ITRS, i.e. ``R3(GMST(UT1)) r_teme`` with skyfield's own UT1 - UTC prediction. Here:
  python-sgp4 with WGS72 and ``R3(GMST82)`` at that UT1 - UTC
  (:data:`~jaxspline.stereo.check_geometry.UT1_MINUS_UTC_S`, a parameter of
  :func:`check_solution`).
* Sun: brahe ``sun_position`` (the low-precision series) turned Earth-fixed with brahe's
  IAU 2006/2000A rotation, zero EOP. Here: the same series and a truncated IAU 1976/1980
  rotation (the direction agrees to well under 0.01 deg).
* Staging as official: an action with an unknown satellite or target id is reported and
  left out of everything else; one breaking its own rules (time order, horizon,
  duration, off-nadir) keeps its place in the schedule and in the products; one failing
  the access test over its window takes part in no product. Same-satellite sorting is
  by start time, ties in file order; two overlapping actions are one ``overlap``
  violation (the official also adds a slew violation, which changes no verdict).
* Access intervals: the test at the start, every ``access_step_s`` and at the end; an
  accepted action's interval grows outwards in the same steps while the test holds
  (bounded by the horizon); intervals of one (satellite, target) that touch or overlap
  share one id. (The official verifier gives an action that lies inside an interval
  already found that interval's id without testing its own samples; the two differ only
  if the test fails for less than one step inside a pass.)
* Overlap: a deterministic lattice quadrature of the area fraction
  (:func:`~jaxspline.stereo.check_geometry.disk_lattice`, :data:`OVERLAP_POINTS` points),
  where the official checker draws 100 seeded pseudo-random points (80 for the edges of a
  triple). The official figure is therefore a binomial draw around this one: see
  :data:`SAFE_OVERLAP` and ``docs/stereo.md`` for the margin a solver should keep;
  :attr:`CheckReport.at_risk` lists the covered targets whose coverage leans on an
  overlap below it.
* Deviations: an action whose boresight misses the Earth at its midpoint (impossible
  within 60 deg off nadir) is a violation and forms no product (the official still pairs
  it, with the target centre as its ground point); violation indices are positions in the
  file's ``actions`` list (the official counts observation entries only).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field

import numpy as np

from jaxspline.aeossp.check_frames import angle_deg, bang_coast_bang_time
from jaxspline.stereo.case import Case, Solution, format_time, parse_solution
from jaxspline.stereo.check_geometry import (
    ANGLE_TOL_DEG,
    OVERLAP_POINTS,
    UT1_MINUS_UTC_S,
    Track,
    access_mask,
    access_terms,
    boresight,
    combined_off_nadir_deg,
    enu_basis,
    ground_point,
    solar_elevation_deg,
    strip_polyline,
    target_ecef,
    window_samples,
)
from jaxspline.stereo.check_products import Look, evaluate_products

__all__ = [
    "OVERLAP_POINTS",
    "SAFE_OVERLAP",
    "CheckReport",
    "Derived",
    "Violation",
    "check_solution",
    "format_report",
]

DURATION_TOL_S = 1e-9
GAP_TOL_S = 1e-6
#: Geometric overlap a solver should keep for the official 100-point estimate to pass
#: the 0.8 threshold with high probability (``docs/stereo.md``, "Overlap margin").
SAFE_OVERLAP = 0.9
#: Access samples evaluated per batch while an interval grows.
GROW_CHUNK = 128


@dataclass(frozen=True)
class Violation:
    """One broken rule.

    Attributes:
      rule: ``satellite``, ``target``, ``time_order``, ``horizon``, ``duration``,
        ``off_nadir``, ``ray``, ``access``, ``overlap`` or ``slew``.
      action: index into the solution's actions (None: not tied to one action).
      message: what is wrong, with the numbers.
    """

    rule: str
    action: int | None
    message: str

    def __str__(self) -> str:
        where = f"actions[{self.action}]" if self.action is not None else "-"
        return f"{self.rule} {where}: {self.message}"


@dataclass(frozen=True)
class Derived:
    """What the checker derived for one observation with known ids.

    Attributes:
      action: index into the solution's actions.
      satellite_id: the satellite.
      target_id: the target.
      midpoint: the midpoint (ISO 8601).
      off_nadir_deg: combined off-nadir angle of the steering [deg].
      slant_range_m: boresight slant range at the midpoint [m] (NaN if the ray misses).
      pixel_scale_m: slant range x IFOV [m].
      solar_elevation_deg: Sun elevation at the target at the midpoint [deg].
      access_interval: ``satellite::target::k``, or ``none`` when the access test failed.
    """

    action: int
    satellite_id: str
    target_id: str
    midpoint: str
    off_nadir_deg: float
    slant_range_m: float
    pixel_scale_m: float
    solar_elevation_deg: float
    access_interval: str


@dataclass
class CheckReport:
    """Result of :func:`check_solution`.

    Attributes:
      valid: no violation.
      violations: list of Violation.
      coverage_ratio: share of targets with a valid pair or tri-stereo set.
      normalized_quality: mean over all targets of the best product quality (0 if none).
      num_targets: targets in the case.
      num_covered: targets with a valid product.
      num_observations: observation actions read.
      num_skipped: ``actions`` entries skipped (``type`` not ``observation``).
      best: target id -> its best Product (None when uncovered).
      at_risk: covered targets whose every valid product leans on an overlap below
        :data:`SAFE_OVERLAP`.
      derived: list of Derived, one per observation with known ids.
      pairs: list of PairResult (every pair that passed the mode rules).
      triples: list of TripleResult (every triple whose edges passed them).
    """

    valid: bool
    violations: list
    coverage_ratio: float
    normalized_quality: float
    num_targets: int
    num_covered: int
    num_observations: int
    num_skipped: int
    best: dict
    at_risk: list
    derived: list = field(default_factory=list)
    pairs: list = field(default_factory=list)
    triples: list = field(default_factory=list)

    def to_dict(self) -> dict:
        """The report as JSON-ready data.

        Returns:
          dict.
        """
        data = asdict(self)
        data["best"] = {k: (asdict(v) if v else None) for k, v in self.best.items()}
        data["pairs"] = [dict(asdict(p), valid=p.valid) for p in self.pairs]
        data["triples"] = [dict(asdict(t), valid=t.valid) for t in self.triples]
        return _finite_or_none(json.loads(json.dumps(data, default=_jsonable)))

    def to_json(self) -> str:
        """The report as indented JSON text (NaN written as null).

        Returns:
          str.
        """
        return json.dumps(self.to_dict(), indent=2, allow_nan=False)


def _finite_or_none(value):
    """``value`` with every NaN / infinity replaced by None (JSON has no such numbers)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, list):
        return [_finite_or_none(v) for v in value]
    if isinstance(value, dict):
        return {k: _finite_or_none(v) for k, v in value.items()}
    return value


def _jsonable(value):
    if isinstance(value, (tuple, np.ndarray)):
        return list(value)
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON: {type(value).__name__}")


def _own_rules(case: Case, o, sat, out: list) -> None:
    """Rules 2-4 of one observation (time order, horizon, duration, off-nadir)."""
    i = o.index
    dur = (o.end - o.start).total_seconds()
    if not dur > 0.0:
        out.append(Violation("time_order", i, f"end_time {format_time(o.end)} not after start"))
    if o.start < case.start or o.end > case.end:
        span = f"[{format_time(o.start)}, {format_time(o.end)}]"
        out.append(Violation("horizon", i, f"{span} outside the horizon"))
    if sat is None:
        return
    if dur + DURATION_TOL_S < sat.min_duration_s or dur - DURATION_TOL_S > sat.max_duration_s:
        out.append(
            Violation(
                "duration",
                i,
                f"{dur:g} s outside [{sat.min_duration_s:g}, {sat.max_duration_s:g}] s",
            )
        )
    off = float(combined_off_nadir_deg(o.along_deg, o.across_deg))
    if off - ANGLE_TOL_DEG > sat.max_off_nadir_deg:
        out.append(
            Violation(
                "off_nadir", i, f"combined off-nadir {off:.6f} > {sat.max_off_nadir_deg:g} deg"
            )
        )


def _known(case: Case, sol: Solution, out: list) -> list:
    """Rule 1 and the action's own rules; returns (obs, sat index, target index) of the
    observations with known ids."""
    sats, tgts = case.satellite_index(), case.target_index()
    known = []
    for o in sol.observations:
        k, t = sats.get(o.satellite_id), tgts.get(o.target_id)
        _own_rules(case, o, case.satellites[k] if k is not None else None, out)
        if k is None:
            out.append(Violation("satellite", o.index, f"unknown satellite_id {o.satellite_id!r}"))
        elif t is None:
            out.append(Violation("target", o.index, f"unknown target_id {o.target_id!r}"))
        else:
            known.append((o, k, t))
    return known


def _schedule(case: Case, known: list, tracks, out: list) -> None:
    """Rule 6: per satellite, no overlap and the slew + settling gap."""
    for k, sat in enumerate(case.satellites):
        mine = sorted((o for o, s, _ in known if s == k), key=lambda o: o.start)
        for prev, nxt in zip(mine, mine[1:], strict=False):
            if nxt.start < prev.end:
                out.append(
                    Violation(
                        "overlap",
                        nxt.index,
                        f"{sat.id}: starts {format_time(nxt.start)} before actions"
                        f"[{prev.index}] ends {format_time(prev.end)}",
                    )
                )
                continue
            pos, vel = tracks(k).ecef(np.array([case.seconds(prev.end), case.seconds(nxt.start)]))
            b0 = boresight(pos[0], vel[0], prev.along_deg, prev.across_deg)
            b1 = boresight(pos[1], vel[1], nxt.along_deg, nxt.across_deg)
            d = float(angle_deg(b0, b1))
            need = sat.settling_s + bang_coast_bang_time(d, sat.rate_deg_s, sat.accel_deg_s2)
            gap = (nxt.start - prev.end).total_seconds()
            if gap + GAP_TOL_S < need:
                out.append(
                    Violation(
                        "slew",
                        nxt.index,
                        f"{sat.id}: gap {gap:.3f} s after actions[{prev.index}] < slew + "
                        f"settling {need:.3f} s ({d:.4f} deg)",
                    )
                )


def _access_failure(case, track, point, sat, samples) -> str | None:
    """Why the access test fails over ``samples`` (the first failing instant), or None."""
    th = case.mission.thresholds
    clear, off, sun = access_terms(track, point, samples)
    bad_off = off > sat.max_off_nadir_deg + ANGLE_TOL_DEG
    bad_sun = sun < th.min_solar_elevation_deg - ANGLE_TOL_DEG
    bad = ~clear | bad_off | bad_sun
    if not bad.any():
        return None
    j = int(np.argmax(bad))
    when = format_time(case.time_at(round(float(samples[j]), 6)))
    if bad_off[j]:
        return f"at {when} the target is {off[j]:.3f} deg off nadir > {sat.max_off_nadir_deg:g}"
    if bad_sun[j]:
        return f"at {when} the Sun is {sun[j]:.3f} deg high < {th.min_solar_elevation_deg:g}"
    return f"at {when} the line of sight to the target is blocked by the Earth"


def _grow(case, track, point, sat, edge: float, direction: int) -> float:
    """How far the access test keeps holding from ``edge`` in whole steps (horizon-bound)."""
    bound = 0.0 if direction < 0 else case.horizon_s
    step, reach = sat.access_step_s, edge
    min_sun = case.mission.thresholds.min_solar_elevation_deg
    while (reach > bound) if direction < 0 else (reach < bound):
        k = np.arange(1, GROW_CHUNK + 1, dtype=float)
        t = reach + direction * step * k
        t = np.maximum(t, bound) if direction < 0 else np.minimum(t, bound)
        ok = access_mask(track, point, sat.max_off_nadir_deg, min_sun, t)
        if not ok.all():
            j = int(np.argmin(ok))
            return float(t[j - 1]) if j > 0 else reach
        reach = float(t[-1])
    return reach


def _register(intervals: list, lo: float, hi: float) -> int:
    """The id of [lo, hi] among one (satellite, target)'s intervals (merged on contact)."""
    for k, (a, b) in enumerate(intervals):
        if not (hi < a or b < lo):
            intervals[k] = (min(a, lo), max(b, hi))
            return k
    intervals.append((lo, hi))
    return len(intervals) - 1


def _look(case, o, k, t, tracks, intervals, out) -> tuple[Derived, Look | None]:
    """Midpoint geometry, access test and access interval of one observation."""
    sat, target = case.satellites[k], case.targets[t]
    track, point = tracks(k), target_ecef(target)
    s0, s1 = case.seconds(o.start), case.seconds(o.end)
    mid = s0 + (s1 - s0) / 2.0
    pos, vel = track.ecef(np.array([mid]))
    g = ground_point(pos[0], vel[0], o.along_deg, o.across_deg)
    slant = float(np.linalg.norm(g - pos[0]))
    scale = slant * math.radians(sat.ifov_deg)
    off = float(combined_off_nadir_deg(o.along_deg, o.across_deg))
    sun = float(solar_elevation_deg(point, track.unix(mid)))
    look, aid = None, "none"
    if not math.isfinite(slant):
        out.append(Violation("ray", o.index, "the boresight misses the Earth at the midpoint"))
    elif s1 > s0:
        why = _access_failure(case, track, point, sat, window_samples(s0, s1, sat.access_step_s))
        if why is not None:
            out.append(Violation("access", o.index, f"{sat.id} -> {target.id}: {why}"))
        else:
            lo, hi = _grow(case, track, point, sat, s0, -1), _grow(case, track, point, sat, s1, 1)
            n = _register(intervals.setdefault((k, t), []), lo, hi)
            aid = f"{sat.id}::{target.id}::{n}"
            basis = enu_basis(point)
            poly = strip_polyline(track, basis, point, s0, s1, o.along_deg, o.across_deg)
            half = slant * math.tan(math.radians(sat.fov_deg / 2.0))
            look = Look(o.index, k, t, s0, s1, mid, pos[0], off, slant, scale, half, poly, n)
    when = format_time(case.time_at(round(mid, 6)))
    return Derived(o.index, sat.id, target.id, when, off, slant, scale, sun, aid), look


def check_solution(
    case: Case, solution, *, ut1_minus_utc_s: float = UT1_MINUS_UTC_S
) -> CheckReport:
    """Check a solution against every rule of RULES.md and score it.

    Args:
      case: the loaded Case.
      solution: a Solution, or a parsed document ``{"actions": [...]}``.
      ut1_minus_utc_s: UT1 - UTC of the Earth rotation [s] (module docstring).
    Returns:
      CheckReport (products and metrics are computed for invalid solutions too).
    Raises:
      ValueError: ``solution`` is malformed (:func:`~jaxspline.stereo.case.parse_solution`).
    """
    sol = solution if isinstance(solution, Solution) else parse_solution(solution)
    out: list = []
    known = _known(case, sol, out)
    cache: dict = {}

    def tracks(k: int) -> Track:
        if k not in cache:
            cache[k] = Track(case.satellites[k], case.start, ut1_minus_utc_s)
        return cache[k]

    _schedule(case, known, tracks, out)
    derived, looks, intervals = [], [], {}
    for o, k, t in known:
        d, look = _look(case, o, k, t, tracks, intervals, out)
        derived.append(d)
        if look is not None:
            looks.append(look)
    pairs, triples, best = evaluate_products(case, looks)
    n = len(case.targets)
    covered = [b for b in best.values() if b is not None]
    out.sort(key=lambda v: v.action if v.action is not None else -1)
    return CheckReport(
        valid=not out,
        violations=out,
        coverage_ratio=len(covered) / n,
        normalized_quality=sum(b.quality for b in covered) / n,
        num_targets=n,
        num_covered=len(covered),
        num_observations=len(sol.observations),
        num_skipped=len(sol.skipped),
        best=best,
        at_risk=[
            tid for tid, b in best.items() if b is not None and b.safest_overlap < SAFE_OVERLAP
        ],
        derived=derived,
        pairs=pairs,
        triples=triples,
    )


def format_report(report: CheckReport, max_lines: int = 50) -> str:
    """Readable summary: validity, metrics, products, the covered targets, violations.

    Args:
      report: CheckReport.
      max_lines: covered targets and violations listed at most (the rest counted).
    Returns:
      str (several lines).
    """
    vp = sum(p.valid for p in report.pairs)
    vt = sum(t.valid for t in report.triples)
    lines = [
        f"valid: {'yes' if report.valid else 'NO'}",
        f"coverage_ratio: {report.coverage_ratio:.6f} "
        f"({report.num_covered} of {report.num_targets} targets)",
        f"normalized_quality: {report.normalized_quality:.6f}",
        f"observations: {report.num_observations} (skipped entries: {report.num_skipped})",
        f"pairs: {len(report.pairs)} evaluated, {vp} valid; "
        f"triples: {len(report.triples)} evaluated, {vt} valid",
        f"at risk (overlap margin below {SAFE_OVERLAP:g}): {len(report.at_risk)}",
    ]
    covered = [(tid, b) for tid, b in report.best.items() if b is not None]
    for tid, b in covered[:max_lines]:
        acts = "+".join(str(a) for a in b.actions)
        lines.append(
            f"  {tid}: {b.kind} of actions {acts}, quality {b.quality:.4f}, "
            f"weakest overlap {b.weakest_overlap:.3f}"
        )
    if len(covered) > max_lines:
        lines.append(f"  ... and {len(covered) - max_lines} more covered targets")
    n = len(report.violations)
    lines.append(f"violations: {n}")
    lines += [f"  {v}" for v in report.violations[:max_lines]]
    if n > max_lines:
        lines.append(f"  ... and {n - max_lines} more")
    return "\n".join(lines)
