"""aeossp_standard adapter: case -> :class:`Scenario`, :class:`PlanResult` -> solution JSON.

The benchmark (public ``aeossp_standard`` of the astro-reason project; cases hold
``mission.yaml``, ``satellites.yaml``, ``tasks.yaml``, rules in its ``RULES.md``) is
planned by the library's one pipeline, :func:`jaxspline.plan`:

* satellites: the case's TLEs (SGP4, WGS84), model ``eigen_axis`` (bang-coast-bang
  rest-to-rest slew plus settling, RULES.md rule 7), off-nadir limit, sensor type and
  the battery model of rule 8;
* tasks: point targets with their release/due window, duration, sensor and weight;
* planner: starts on the case's action grid (5 s), ephemeris knots on the geometry
  grid, so every instant the checker samples is an exact SGP4 knot.

Margins (what the plan keeps back from each limit), against the frame differences
measured by :mod:`jaxspline.aeossp.check` (this model vs the official GCRF/ITRF
chain: at most 1.5e-7 deg in off-nadir angle and 3.6e-7 deg in slew angle):

* off-nadir 0.005 deg (3e4 x the measured difference); horizon: elevation sine > 0.02;
* maneuver gap 0.05 s: an angle error delta changes the bang-coast-bang time by at
  most ``2 sqrt(delta / a)`` = 3.1e-3 s at the smallest a = 0.15 deg/s^2 (16 x);
* battery: level >= 10 Wh on the conservative profile
  (:class:`jaxspline.search.BatteryModel`), one shadow-guard step.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from jaxspline.aeossp.case import format_time, load_case
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.config import Margins, PlannerConfig
from jaxspline.readers.mission import POINT, Power, Satellite, Scenario, make_targets

__all__ = ["AEOSSP_MARGINS", "case_scenario", "solution_of", "solve_case"]

AEOSSP_MARGINS = Margins(
    off_nadir=math.radians(0.005), horizon=0.02, gap=0.05, battery_wh=10.0, shadow_guard=1
)


def case_scenario(case, *, margins: Margins = AEOSSP_MARGINS, time_limit: float = 60.0):
    """The :class:`Scenario` of a loaded case (or a case directory).

    Every satellite becomes an eigen-axis satellite with its battery; every task a
    point target.

    Args:
      case: Case, or a path of a case directory.
      margins: Margins of the planner.
      time_limit: default planner time budget [s].
    Returns:
      Scenario (angles converted to radians).
    """
    if not hasattr(case, "tasks"):
        case = load_case(case)
    sats = tuple(
        Satellite(
            name=s.satellite_id,
            orbit=(s.tle_line1, s.tle_line2),
            model="eigen_axis",
            limits=AxisLimits(
                np.float64(math.radians(s.max_slew_rate_deg_s)),
                np.float64(math.radians(s.max_slew_accel_deg_s2)),
            ),
            off_nadir_max=math.radians(s.max_off_nadir_deg),
            sensor=s.sensor_type,
            settle=s.settling_time_s,
            power=Power(
                capacity_wh=s.battery_capacity_wh,
                initial_wh=s.initial_battery_wh,
                idle_w=s.idle_power_w,
                imaging_w=s.imaging_power_w,
                slew_w=s.slew_power_w,
                charge_w=s.sunlit_charge_power_w,
            ),
        )
        for s in case.satellites
    )
    tt = case.task_table()
    targets = make_targets(
        POINT,
        np.radians(tt["latitude_deg"]),
        np.radians(tt["longitude_deg"]),
        alt=tt["altitude_m"],
        duration=tt["duration_s"],
        value=tt["weight"],
        t_lo=tt["release_s"],
        t_hi=tt["due_s"],
        sensor=[t.required_sensor_type for t in case.tasks],
        name=[t.task_id for t in case.tasks],
    )
    planner = PlannerConfig(
        time_step=case.action_step_s,
        geometry_step=math.gcd(int(case.action_step_s), int(case.geometry_step_s)) or 1.0,
        margins=margins,
        default_time_limit=time_limit,
        exact_max_options=0,
    )
    return Scenario(
        name=case.case_id,
        epoch=case.horizon_start,
        duration=case.duration_s,
        satellites=sats,
        targets=targets,
        planner=planner,
    )


def solution_of(case, result) -> dict:
    """The benchmark's solution document ``{"actions": [...]}`` of a PlanResult.

    Args:
      case: Case the result was planned for.
      result: PlanResult.
    Returns:
      dict, JSON-ready.
    """
    o = result.observations
    acts = []
    for i in range(len(o)):
        acts.append(
            {
                "type": "observation",
                "satellite_id": case.satellites[int(o.sat[i])].satellite_id,
                "task_id": case.tasks[int(o.target[i])].task_id,
                "start_time": format_time(case.at(o.start[i])),
                "end_time": format_time(case.at(o.end[i])),
            }
        )
    return {"actions": acts}


def solve_case(
    case_dir,
    time_limit: float = 60.0,
    progress: bool = True,
    seed: int = 0,
    max_iters: int | None = None,
):
    """Plan one case through :func:`jaxspline.plan`.

    Args:
      case_dir: path of a case directory, or a loaded Case.
      time_limit: planner time budget [s].
      progress: show progress lines.
      seed: int, seed of the randomized search.
      max_iters: cap on search iterations (reproducible runs); None: the deadline alone.
    Returns:
      ``(solution dict, PlanResult)``.
    """
    from jaxspline.planner.pipeline import plan

    case = load_case(case_dir) if isinstance(case_dir, str | Path) else case_dir
    sc = case_scenario(case, time_limit=time_limit)
    result = plan(sc, time_limit=time_limit, seed=seed, progress=progress, max_iters=max_iters)
    return solution_of(case, result), result
