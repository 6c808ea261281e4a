"""Loading stereo_imaging cases and reading / writing solutions.

A case directory (benchmark ``stereo_imaging``, repository Mtrya/astro-reason) holds
``mission.yaml`` (one top-level ``mission`` mapping: horizon, stereo policy, validity
thresholds, quality model), ``satellites.yaml`` (a list: TLE, sensor, agility) and
``targets.yaml`` (a list: centre, AOI radius, terrain height, scene type). Every field the
benchmark defines is validated on load (:mod:`jaxspline.stereo.case_fields`); a missing or
malformed field raises ``ValueError`` naming the file and the field, e.g.
``satellites.yaml: [3].max_off_nadir_deg: must be > 0, got -1``. Times must carry ``Z`` or
an explicit offset (the official checker refuses naive times). Fields the loader does not
read are ignored.

A solution is ``{"actions": [...]}``; entries whose ``type`` is not ``"observation"`` are
skipped, as by the official checker. :func:`load_solution` refuses what makes the official
checker stop without a report (a root that is not an object, a missing or mistyped field,
a time without a zone) and, with ``strict=True``, also what the checker would report as a
violation of the input itself (unknown ids, an end not after the start, times off the
horizon), for callers that want a clean solution.

Times are timezone-aware UTC ``datetime`` objects; solutions write them as
``YYYY-MM-DDTHH:MM:SSZ`` (:func:`format_time`). Inside the package times are float
seconds from ``Case.start`` (:meth:`Case.seconds`, :meth:`Case.time_at`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

from jaxspline.readers.case_files import format_time as format_time
from jaxspline.readers.case_files import parse_time as parse_time
from jaxspline.regional.case_fields import read_json
from jaxspline.stereo.case_fields import (
    load_mission,
    load_satellites,
    load_targets,
    number,
    text,
    zoned_time,
)

__all__ = [
    "ACTION_TYPE",
    "MISSION",
    "SATELLITES",
    "SCENE_BANDS_DEG",
    "SCENE_TYPES",
    "TARGETS",
    "Case",
    "Mission",
    "Observation",
    "QualityModel",
    "Satellite",
    "Solution",
    "Target",
    "Thresholds",
    "format_time",
    "load_case",
    "load_solution",
    "parse_solution",
    "parse_time",
    "solution_document",
]

MISSION = "mission.yaml"
SATELLITES = "satellites.yaml"
TARGETS = "targets.yaml"
#: The ``type`` of the actions the checker reads (others are skipped).
ACTION_TYPE = "observation"
#: Preferred convergence band per scene type [deg], fixed in the official checker.
SCENE_BANDS_DEG = {
    "urban_structured": (8.0, 18.0),
    "vegetated": (8.0, 14.0),
    "rugged": (10.0, 20.0),
    "open": (15.0, 25.0),
}
SCENE_TYPES = tuple(SCENE_BANDS_DEG)

# ----------------------------------------------------------------------------- types


@dataclass(frozen=True)
class Thresholds:
    """``mission.validity_thresholds``.

    Attributes:
      min_overlap: ``min_overlap_fraction`` in [0, 1].
      min_convergence_deg: smallest convergence angle of a pair [deg].
      max_convergence_deg: largest convergence angle of a pair [deg].
      max_pixel_scale_ratio: largest ratio of two pixel scales (>= 1).
      min_solar_elevation_deg: lowest Sun elevation at the target [deg].
      anchor_max_off_nadir_deg: ``near_nadir_anchor_max_off_nadir_deg`` [deg].
    """

    min_overlap: float
    min_convergence_deg: float
    max_convergence_deg: float
    max_pixel_scale_ratio: float
    min_solar_elevation_deg: float
    anchor_max_off_nadir_deg: float


@dataclass(frozen=True)
class QualityModel:
    """``mission.quality_model``.

    Attributes:
      geometry: pair weight of the convergence-band term.
      overlap: pair weight of the overlap term.
      resolution: pair weight of the pixel-scale term.
      tri_bonus: scene type -> tri-stereo bonus beta.
    """

    geometry: float
    overlap: float
    resolution: float
    tri_bonus: dict


@dataclass(frozen=True)
class Mission:
    """``mission.yaml``.

    Attributes:
      start: horizon start (UTC).
      end: horizon end (UTC).
      allow_cross_satellite: ``allow_cross_satellite_stereo``.
      max_pair_separation_s: ``max_stereo_pair_separation_s`` [s].
      thresholds: Thresholds.
      quality: QualityModel.
    """

    start: datetime
    end: datetime
    allow_cross_satellite: bool
    max_pair_separation_s: float
    thresholds: Thresholds
    quality: QualityModel


@dataclass(frozen=True)
class Satellite:
    """One satellite: TLE, push-broom sensor, agility.

    Attributes:
      id: ``id``.
      norad_id: ``norad_catalog_id``.
      tle1: TLE line 1.
      tle2: TLE line 2.
      ifov_deg: ``pixel_ifov_deg``, angle of one detector pixel [deg].
      pixels: ``cross_track_pixels``.
      max_off_nadir_deg: largest combined off-nadir angle [deg].
      rate_deg_s: ``max_slew_velocity_deg_per_s`` [deg/s].
      accel_deg_s2: ``max_slew_acceleration_deg_per_s2`` [deg/s^2].
      settling_s: ``settling_time_s`` [s].
      min_duration_s: ``min_obs_duration_s`` [s].
      max_duration_s: ``max_obs_duration_s`` [s].
    """

    id: str
    norad_id: int
    tle1: str
    tle2: str
    ifov_deg: float
    pixels: int
    max_off_nadir_deg: float
    rate_deg_s: float
    accel_deg_s2: float
    settling_s: float
    min_duration_s: float
    max_duration_s: float

    @property
    def fov_deg(self) -> float:
        """Cross-track field of view, ``pixels * ifov_deg`` [deg]."""
        return self.pixels * self.ifov_deg

    @property
    def access_step_s(self) -> float:
        """Step of the access test, ``max(0.25, min(1, min_duration_s / 2))`` [s]."""
        return max(0.25, min(1.0, self.min_duration_s / 2.0))


@dataclass(frozen=True)
class Target:
    """One ground target: a disk around a geodetic centre.

    Attributes:
      id: ``id``.
      lat_deg: geodetic latitude [deg].
      lon_deg: longitude [deg].
      aoi_radius_m: radius of the area of interest [m].
      elevation_m: ``elevation_ref_m``, height above the WGS84 ellipsoid [m].
      scene_type: one of :data:`SCENE_TYPES`.
    """

    id: str
    lat_deg: float
    lon_deg: float
    aoi_radius_m: float
    elevation_m: float
    scene_type: str


@dataclass(frozen=True)
class Case:
    """A loaded stereo_imaging case.

    Attributes:
      path: case directory.
      case_id: the directory name.
      mission: Mission.
      satellites: tuple of Satellite.
      targets: tuple of Target.
    """

    path: Path
    case_id: str
    mission: Mission
    satellites: tuple
    targets: tuple

    @property
    def start(self) -> datetime:
        """Horizon start (UTC)."""
        return self.mission.start

    @property
    def end(self) -> datetime:
        """Horizon end (UTC)."""
        return self.mission.end

    @property
    def horizon_s(self) -> float:
        """Horizon length [s]."""
        return (self.end - self.start).total_seconds()

    def seconds(self, value: datetime) -> float:
        """Seconds from ``start`` to ``value``.

        Args:
          value: aware datetime.
        Returns:
          float [s].
        """
        return (value - self.start).total_seconds()

    def time_at(self, seconds: float) -> datetime:
        """The instant ``seconds`` after ``start``.

        Args:
          seconds: float [s].
        Returns:
          datetime (UTC).
        """
        return self.start + timedelta(seconds=float(seconds))

    def satellite_index(self) -> dict:
        """Map satellite ``id`` -> index into ``satellites``.

        Returns:
          dict[str, int].
        """
        return {s.id: i for i, s in enumerate(self.satellites)}

    def target_index(self) -> dict:
        """Map target ``id`` -> index into ``targets``.

        Returns:
          dict[str, int].
        """
        return {t.id: i for i, t in enumerate(self.targets)}


def load_case(case_dir: str | os.PathLike) -> Case:
    """Load and validate one stereo_imaging case directory.

    Args:
      case_dir: directory with ``mission.yaml``, ``satellites.yaml`` and ``targets.yaml``.
    Returns:
      Case.
    Raises:
      ValueError: a missing directory or file, or a missing / malformed field (naming
        the file and the field).
    """
    case_dir = Path(case_dir)
    if not case_dir.is_dir():
        raise ValueError(f"{case_dir}: case directory not found")
    m = load_mission(case_dir / MISSION, SCENE_TYPES)
    thresholds = Thresholds(**m.pop("thresholds"))
    quality = QualityModel(**m.pop("quality"))
    mission = Mission(thresholds=thresholds, quality=quality, **m)
    sats = tuple(Satellite(**s) for s in load_satellites(case_dir / SATELLITES, mission))
    targets = tuple(Target(**t) for t in load_targets(case_dir / TARGETS, SCENE_TYPES))
    return Case(case_dir, case_dir.name, mission, sats, targets)


# ----------------------------------------------------------------------------- solutions


@dataclass(frozen=True)
class Observation:
    """One observation action: a push-broom look with fixed steering angles.

    Attributes:
      satellite_id: the satellite.
      target_id: the target.
      start: start (aware UTC datetime).
      end: end (aware UTC datetime).
      along_deg: ``off_nadir_along_deg`` [deg] (positive: forward).
      across_deg: ``off_nadir_across_deg`` [deg] (positive: left of the ground track).
      index: position in the file's ``actions`` list (-1 when built in code).
    """

    satellite_id: str
    target_id: str
    start: datetime
    end: datetime
    along_deg: float
    across_deg: float
    index: int = -1

    def to_dict(self) -> dict:
        """The action as the solution file writes it.

        Returns:
          dict.
        """
        return {
            "type": ACTION_TYPE,
            "satellite_id": self.satellite_id,
            "target_id": self.target_id,
            "start_time": format_time(self.start),
            "end_time": format_time(self.end),
            "off_nadir_along_deg": self.along_deg,
            "off_nadir_across_deg": self.across_deg,
        }


@dataclass(frozen=True)
class Solution:
    """A read solution.

    Attributes:
      observations: tuple of Observation, in file order.
      skipped: indices of the ``actions`` entries whose ``type`` is not ``observation``.
    """

    observations: tuple
    skipped: tuple = field(default_factory=tuple)

    def to_dict(self) -> dict:
        """``{"actions": [...]}`` of the observations.

        Returns:
          dict.
        """
        return {"actions": [o.to_dict() for o in self.observations]}


_ACTION_KEYS = ("satellite_id", "target_id", "start_time", "end_time")


def _observation(raw: dict, i: int, where: str) -> Observation:
    w = f"{where}: actions[{i}]"
    sid, tid = (text(raw, k, w) for k in _ACTION_KEYS[:2])
    start, end = (zoned_time(raw, k, w) for k in _ACTION_KEYS[2:])
    along = number(raw, "off_nadir_along_deg", w)
    across = number(raw, "off_nadir_across_deg", w)
    return Observation(sid, tid, start, end, along, across, i)


def _strict_checks(obs: Observation, case: Case, where: str) -> None:
    w = f"{where}: actions[{obs.index}]"
    if obs.satellite_id not in case.satellite_index():
        raise ValueError(f"{w}.satellite_id: unknown satellite {obs.satellite_id!r}")
    if obs.target_id not in case.target_index():
        raise ValueError(f"{w}.target_id: unknown target {obs.target_id!r}")
    if not obs.end > obs.start:
        raise ValueError(f"{w}.end_time: {format_time(obs.end)} is not after start_time")
    if obs.start < case.start:
        raise ValueError(f"{w}.start_time: {format_time(obs.start)} is before horizon_start")
    if obs.end > case.end:
        raise ValueError(f"{w}.end_time: {format_time(obs.end)} is after horizon_end")


def parse_solution(
    data: Any, case: Case | None = None, *, where: str = "solution", strict: bool = False
) -> Solution:
    """Read a parsed solution document ``{"actions": [...]}``.

    Args:
      data: the parsed JSON.
      case: the Case (needed with ``strict``).
      where: names the source in messages (the file name).
      strict: also refuse unknown satellite / target ids, an end not after its start and
        times off the horizon (otherwise the checker reports them as violations).
    Returns:
      Solution.
    Raises:
      ValueError: naming ``where``, the action and the field.
    """
    if not isinstance(data, dict):
        raise ValueError(f"{where}: expected an object with an 'actions' list")
    actions = data.get("actions")
    if not isinstance(actions, list):
        raise ValueError(f"{where}: actions: expected a list, got {type(actions).__name__}")
    obs, skipped = [], []
    for i, raw in enumerate(actions):
        if not isinstance(raw, dict):
            raise ValueError(f"{where}: actions[{i}]: expected an object, got {raw!r}")
        if raw.get("type") != ACTION_TYPE:
            skipped.append(i)
            continue
        obs.append(_observation(raw, i, where))
    if strict:
        if case is None:
            raise ValueError("parse_solution: strict=True needs the case")
        for o in obs:
            _strict_checks(o, case, where)
    return Solution(tuple(obs), tuple(skipped))


def load_solution(
    path: str | os.PathLike, case: Case | None = None, *, strict: bool = False
) -> Solution:
    """Read a solution file (strict JSON) with :func:`parse_solution`.

    Args:
      path: JSON file.
      case: the Case (needed with ``strict``).
      strict: see :func:`parse_solution`.
    Returns:
      Solution.
    Raises:
      ValueError: missing file, bad JSON, or a malformed action (naming the file, the
        action and the field).
    """
    path = Path(path)
    return parse_solution(read_json(path), case, where=path.name, strict=strict)


def solution_document(solution, where: str = "solution") -> dict:
    """The JSON document of a solution, checked by :func:`parse_solution` (what
    :func:`jaxspline.cli.case_commands.write_solution` writes).

    Args:
      solution: a Solution, a list of Observation (or action dicts), or a document with
        an ``actions`` list; where: the name errors start with.
    Returns:
      ``{"actions": [...]}``.
    Raises:
      ValueError: the solution is not readable back, naming the first bad action.
    """
    data = {"actions": _action_dicts(solution)}
    parse_solution(data, where=where)
    return data


def _action_dicts(solution) -> list:
    if isinstance(solution, Solution):
        return solution.to_dict()["actions"]
    if isinstance(solution, dict):
        actions = solution.get("actions")
        if not isinstance(actions, list):
            raise ValueError("solution: actions: expected a list of action objects")
        return list(actions)
    return [o.to_dict() if isinstance(o, Observation) else o for o in solution]
