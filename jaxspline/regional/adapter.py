"""regional_coverage adapter: case -> :class:`Scenario`, :class:`PlanResult` -> solution.

The benchmark (``benchmarks/regional_coverage`` of the astro-reason project; rules in
``shared/data/regional_coverage/RULES.md``) is planned by the library's one pipeline,
:func:`jaxspline.plan`, as areas:

* satellites: the case's TLEs (SGP4, WGS84), model ``roll_only`` (bang-coast-bang roll
  slew plus settling between Earth-fixed look directions, rule 4), its sensor's field of
  view and edge band (rule 3), strip durations (rule 2), battery (rule 6) and imaging duty
  per orbit (rule 5);
* regions: one area each, on the case's own sample grid: a sample's weight is its
  ``weight_m2`` over the region's ``total_weight_m2`` and the area's priority is the
  region's share of the region weights, so the plan's value is the benchmark's
  ``coverage_ratio``; a region's ``min_required_coverage_ratio`` is the area's least
  share (rule 7);
* planner: starts on the case's action grid (``time_step_s``), ephemeris knots on its
  power and geometry mesh (``coverage_sample_step_s``), the action cap (rule 1).

Margins (what the plan keeps back from each limit): 0.05 s on every maneuver gap, 0.5 s
of imaging under the duty limit, 2 Wh of battery, one mesh step of guard at each shadow
boundary; the roll grid keeps the strips' edges 1e-4 deg inside the band.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from jaxspline.geometry.routes import AREA
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.config import Margins, PlannerConfig
from jaxspline.readers.mission import Area, Power, Satellite, Scenario, make_targets
from jaxspline.regional.case import format_time, load_case

__all__ = ["REGIONAL_MARGINS", "case_scenario", "solution_of", "solve_case"]

#: The planner's margins on a regional case (module docstring).
REGIONAL_MARGINS = Margins(gap=0.05, battery_wh=2.0, shadow_guard=1, duty=0.5)
#: Decimals of a written roll (the roll grid's).
ROLL_DECIMALS = 4


def _satellite(s) -> Satellite:
    """The planner's roll-only satellite of a case's satellite."""
    sen, agi, pw = s.sensor, s.agility, s.power
    return Satellite(
        name=s.id,
        orbit=(s.tle1, s.tle2),
        model="roll_only",
        limits=AxisLimits(math.radians(agi.rate_deg_s), math.radians(agi.accel_deg_s2)),
        off_nadir_max=math.radians(sen.max_edge_deg),
        sensor="strip",
        settle=float(agi.settling_s),
        power=Power(
            capacity_wh=pw.capacity_wh,
            initial_wh=pw.initial_wh,
            idle_w=pw.idle_w,
            imaging_w=pw.imaging_w,
            slew_w=pw.slew_w,
            charge_w=pw.charge_w,
        ),
        fov=math.radians(sen.fov_deg),
        edge_band=(math.radians(sen.min_edge_deg), math.radians(sen.max_edge_deg)),
        strip_duration=(float(sen.min_duration_s), float(sen.max_duration_s)),
        duty=pw.duty_limit_s,
    )


def case_scenario(case, *, margins: Margins = REGIONAL_MARGINS, time_limit: float = 120.0):
    """The :class:`Scenario` of a loaded case (or a case directory).

    Args:
      case: Case, or a path of a case directory.
      margins: Margins of the planner.
      time_limit: default planner time budget [s].
    Returns:
      Scenario: one roll-only satellite per case satellite, one area per region.
    """
    case = load_case(case) if isinstance(case, str | Path) else case
    grid = case.grid
    w = np.array([r.weight for r in case.regions], np.float64)
    prio = w / w.sum() if w.sum() > 0 else np.full(w.size, 1.0 / max(w.size, 1))
    areas, lat, lon = [], [], []
    for i, region in enumerate(case.regions):
        m = grid.region == i
        share = grid.weight_m2[m] / grid.region_total_m2[i]
        samples = np.stack([grid.lon_deg[m], grid.lat_deg[m], share], -1)
        lat.append(float(np.radians(np.average(grid.lat_deg[m], weights=share))))
        lon.append(float(np.radians(np.average(grid.lon_deg[m], weights=share))))
        ring = region.ring.tolist()
        if ring[0] != ring[-1]:
            ring.append(ring[0])
        areas.append(
            Area(
                name=region.id,
                target=i,
                geometry={"type": "Polygon", "coordinates": [ring]},
                samples=samples,
                min_share=math.nan if region.min_coverage is None else region.min_coverage,
            )
        )
    targets = make_targets(
        np.full(len(areas), AREA),
        lat,
        lon,
        value=np.maximum(prio, 1e-12),
        t_lo=0.0,
        t_hi=case.horizon_s,
        name=[r.id for r in case.regions],
    )
    planner = PlannerConfig(
        time_step=case.time_step_s,
        geometry_step=case.sample_step_s,
        margins=margins,
        default_time_limit=time_limit,
        exact_max_options=0,
        max_actions=case.max_actions,
    )
    return Scenario(
        name=case.case_id,
        epoch=case.start,
        duration=case.horizon_s,
        satellites=tuple(_satellite(s) for s in case.satellites),
        targets=targets,
        planner=planner,
        areas=tuple(areas),
    )


def solution_of(case, result) -> dict:
    """The benchmark's solution document ``{"actions": [...]}`` of a PlanResult.

    Args:
      case: the Case planned; result: its PlanResult.
    Returns:
      dict, JSON-ready: one ``strip_observation`` per area strip, in time order.
    """
    o = result.observations
    acts = []
    for i in np.argsort(o.start, kind="stable"):
        if not np.isfinite(o.roll[i]):
            continue
        dur = float(o.end[i] - o.start[i])
        dur_r = round(dur / case.time_step_s) * case.time_step_s
        acts.append(
            {
                "type": "strip_observation",
                "satellite_id": case.satellites[int(o.sat[i])].id,
                "start_time": format_time(case.time_at(float(o.start[i]))),
                "duration_s": int(dur_r) if float(dur_r).is_integer() else dur_r,
                "roll_deg": round(math.degrees(float(o.roll[i])), ROLL_DECIMALS),
            }
        )
    return {"actions": acts}


def solve_case(case, time_limit: float = 120.0, progress: bool = True, seed: int = 0, **plan_kw):
    """Plan one case through :func:`jaxspline.plan`.

    Args:
      case: path of a case directory, or a loaded Case.
      time_limit: planner time budget [s].
      progress: show progress lines.
      seed: seed of the search.
      **plan_kw: further keywords of :func:`jaxspline.plan` (``max_iters``, ``deadline``).
    Returns:
      ``(solution dict, PlanResult)``.
    """
    from jaxspline.planner.pipeline import plan

    case = load_case(case) if isinstance(case, str | Path) else case
    sc = case_scenario(case, time_limit=time_limit)
    result = plan(sc, time_limit=time_limit, seed=seed, progress=progress, **plan_kw)
    return solution_of(case, result), result
