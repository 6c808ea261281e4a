"""stereo_imaging adapter: case -> :class:`Scenario`, :class:`PlanResult` -> solution.

The benchmark (``benchmarks/stereo_imaging`` of the astro-reason project; rules in
``shared/data/stereo_imaging/RULES.md``) is planned by the library's one pipeline,
:func:`jaxspline.plan`, with stereo targets:

* satellites: the case's TLEs (SGP4), model ``roll_only`` (rest-to-rest bang-coast-bang
  slew between Earth-fixed boresights plus settling: the benchmark's slew law, rule 6;
  the roll law holds an along and an across steering angle fixed in the track frame),
  its combined off-nadir limit, field of view (pixels x IFOV), pixel angle and look
  durations (rules 3-4);
* targets: one stereo target each (kind ``STEREO``) at its centre and terrain height,
  its AOI disk, the mission's validity thresholds and quality model (its scene's
  preferred convergence band and tri-stereo bonus), a triple preferred; the value of a
  product is ``1 - w + w * Q`` with ``w = QUALITY_SHARE / targets``, so the quality of
  all targets together weighs less than one more covered target: the plan's value ranks
  coverage first and quality second, as the benchmark does;
* planner: whole-second action grid (the official overlap estimate is seeded by whole
  seconds), the daylight rule (``min_solar_elevation_deg``), no action cap.

Margins: 0.05 s on every slew gap, 0.05 deg under the off-nadir limit (the planner's
SGP4 constants and the checker's differ by about 150 m); the look generator keeps the
overlap above the threshold with a margin and values each product by the chance that
the official 100-point overlap estimates pass.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.config import Margins, PlannerConfig
from jaxspline.readers.mission import STEREO, Satellite, Scenario, make_targets
from jaxspline.readers.stereo_request import Stereo
from jaxspline.stereo.case import SCENE_BANDS_DEG, format_time, load_case

__all__ = ["QUALITY_SHARE", "STEREO_MARGINS", "case_scenario", "solution_of", "steering_deg"]

#: The planner's margins on a stereo case (module docstring).
STEREO_MARGINS = Margins(gap=0.05, off_nadir=math.radians(0.05))
#: The quality of all targets together is worth this share of one covered target.
QUALITY_SHARE = 0.5
#: Action grid [s] (whole seconds).
TIME_STEP_S = 1.0
#: Decimals of a written steering angle [deg].
ANGLE_DECIMALS = 6


def _satellite(s) -> Satellite:
    """The planner's satellite of a case's satellite."""
    return Satellite(
        name=s.id,
        orbit=(s.tle1, s.tle2),
        model="roll_only",
        limits=AxisLimits(math.radians(s.rate_deg_s), math.radians(s.accel_deg_s2)),
        off_nadir_max=math.radians(s.max_off_nadir_deg),
        sensor="optical",
        settle=float(s.settling_s),
        fov=math.radians(s.fov_deg),
        ifov=math.radians(s.ifov_deg),
        strip_duration=(float(s.min_duration_s), float(s.max_duration_s)),
    )


def _request(case, i: int, tgt) -> Stereo:
    """The Stereo request of target ``tgt`` (row ``i``) under the case's mission."""
    m = case.mission
    th, q = m.thresholds, m.quality
    band = SCENE_BANDS_DEG[tgt.scene_type]
    return Stereo(
        name=tgt.id,
        target=i,
        radius=float(tgt.aoi_radius_m),
        product="tri",
        min_overlap=float(th.min_overlap),
        convergence=(math.radians(th.min_convergence_deg), math.radians(th.max_convergence_deg)),
        band=(math.radians(band[0]), math.radians(band[1])),
        max_scale_ratio=float(th.max_pixel_scale_ratio),
        max_separation=float(m.max_pair_separation_s),
        cross_satellite=bool(m.allow_cross_satellite),
        anchor_off_nadir=math.radians(th.anchor_max_off_nadir_deg),
        weights=(float(q.geometry), float(q.overlap), float(q.resolution)),
        tri_bonus=float(q.tri_bonus.get(tgt.scene_type, 0.0)),
        quality_weight=QUALITY_SHARE / len(case.targets),
    )


def case_scenario(case, *, time_limit: float = 120.0) -> Scenario:
    """The :class:`Scenario` of a loaded case (or a case directory).

    Args:
      case: Case, or a path of a case directory.
      time_limit: default planner time budget [s].
    Returns:
      Scenario: one satellite per case satellite, one stereo target per case target.
    """
    case = load_case(case) if isinstance(case, str | Path) else case
    tg = case.targets
    horizon = (case.mission.end - case.mission.start).total_seconds()
    targets = make_targets(
        np.full(len(tg), STEREO),
        np.radians([t.lat_deg for t in tg]),
        np.radians([t.lon_deg for t in tg]),
        alt=[t.elevation_m for t in tg],
        value=1.0,
        t_lo=0.0,
        t_hi=horizon,
        name=[t.id for t in tg],
    )
    planner = PlannerConfig(
        time_step=TIME_STEP_S,
        geometry_step=TIME_STEP_S,
        sun_elevation_min=math.radians(case.mission.thresholds.min_solar_elevation_deg),
        margins=STEREO_MARGINS,
        default_time_limit=time_limit,
        exact_max_options=0,
    )
    return Scenario(
        name=case.case_id,
        epoch=case.mission.start,
        duration=horizon,
        satellites=tuple(_satellite(s) for s in case.satellites),
        targets=targets,
        planner=planner,
        stereo=tuple(_request(case, i, t) for i, t in enumerate(tg)),
    )


def steering_deg(roll: float, pitch: float) -> tuple[float, float]:
    """The benchmark's (along, across) steering [deg] of the roll law's (roll, pitch)
    [rad]: the boresight ``n + tan(along) a + tan(across) c`` is the roll law's
    ``cos(p) n + sin(p) a + tan(r) c``, so along = p and tan(across) = tan(r) / cos(p)."""
    return math.degrees(pitch), math.degrees(math.atan(math.tan(roll) / math.cos(pitch)))


def solution_of(case, result) -> dict:
    """The benchmark's solution document ``{"actions": [...]}`` of a PlanResult.

    Args:
      case: the Case planned; result: its PlanResult.
    Returns:
      dict, JSON-ready: one ``observation`` per look, in time order (whole seconds).
    """
    o = result.observations
    sc = result.scenario
    acts = []
    for i in np.argsort(o.start, kind="stable"):
        if not np.isfinite(o.roll[i]):
            continue
        along, across = steering_deg(float(o.roll[i]), float(o.pitch[i]))
        acts.append(
            {
                "type": "observation",
                "satellite_id": case.satellites[int(o.sat[i])].id,
                "target_id": str(sc.targets.name[int(o.target[i])]),
                "start_time": format_time(case.time_at(round(float(o.start[i])))),
                "end_time": format_time(case.time_at(round(float(o.end[i])))),
                "off_nadir_along_deg": round(along, ANGLE_DECIMALS),
                "off_nadir_across_deg": round(across, ANGLE_DECIMALS),
            }
        )
    return {"actions": acts}
