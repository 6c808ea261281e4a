"""Loading aeossp_standard cases and reading / writing solutions.

A case directory holds ``mission.yaml``, ``satellites.yaml`` and ``tasks.yaml``
(benchmark ``aeossp_standard``, repository Mtrya/astro-reason). Every field is
validated on load; a missing or malformed field raises ``ValueError`` naming the
file and the field. Files are UTF-8 (a byte-order mark and CRLF line ends are
accepted); a key repeated in one mapping is an error (YAML would keep the last);
fields the loader does not read are ignored. Each TLE must propagate (SGP4) at the
horizon start; task positions lie in [-90, 90] x [-180, 180] deg, altitudes in
:data:`_ALTITUDE_RANGE_M`; a case has at least one satellite and one task. Times are
timezone-aware UTC ``datetime`` objects; the solution format uses ISO 8601 strings
ending in ``Z``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from jaxspline.base.elements import jd_split, julian_date
from jaxspline.geometry.orbit import propagate_tle
from jaxspline.readers.case_files import UniqueKeyLoader, format_time
from jaxspline.readers.case_files import parse_time as _parse_time
from jaxspline.readers.fields import read_text
from jaxspline.readers.satellites import tle_line_problem

__all__ = [
    "Case",
    "Satellite",
    "Task",
    "format_time",
    "load_case",
    "load_solution",
    "parse_time",
]


#: Task altitudes [m]: ground targets, the deepest trench to above the highest peak.
_ALTITUDE_RANGE_M = (-12e3, 12e3)


def parse_time(text, *, where: str = "time") -> datetime:
    """Parse an ISO 8601 UTC time (``2026-04-14T04:00:00Z``) or a ``datetime`` (YAML reads
    unquoted times as one) to an aware UTC ``datetime``
    (:func:`jaxspline.readers.case_files.parse_time`).

    Args:
      text: the time string or datetime.
      where: names the field in the error message.
    Returns:
      datetime in UTC.
    Raises:
      ValueError: malformed input (naming ``where``).
    """
    return _parse_time(text, where=where, allow_datetime=True)


@dataclass(frozen=True)
class Satellite:
    """One satellite of a case: TLE, sensor, attitude and battery model.

    Units as in the files (degrees, seconds, watt-hours, watts).

    Attributes:
      satellite_id: identifier.
      norad_id: NORAD catalogue number.
      tle_line1: TLE line 1.
      tle_line2: TLE line 2.
      sensor_type: sensor type.
      max_slew_rate_deg_s: eigen-axis rate bound [deg/s].
      max_slew_accel_deg_s2: eigen-axis acceleration bound [deg/s²].
      settling_time_s: settling time after a slew [s].
      max_off_nadir_deg: pointing limit [deg].
      battery_capacity_wh: battery capacity [Wh].
      initial_battery_wh: battery level at the horizon start [Wh].
      idle_power_w: idle load [W].
      imaging_power_w: extra load while imaging [W].
      slew_power_w: extra load while slewing [W].
      sunlit_charge_power_w: charging power in sunlight [W].
    """

    satellite_id: str
    norad_id: int
    tle_line1: str
    tle_line2: str
    sensor_type: str
    max_slew_rate_deg_s: float
    max_slew_accel_deg_s2: float
    settling_time_s: float
    max_off_nadir_deg: float
    battery_capacity_wh: float
    initial_battery_wh: float
    idle_power_w: float
    imaging_power_w: float
    slew_power_w: float
    sunlit_charge_power_w: float


@dataclass(frozen=True)
class Task:
    """One point target: WGS84 geodetic position, time window, duration, sensor, weight.

    Attributes:
      task_id: identifier.
      name: label.
      latitude_deg: geodetic latitude [deg].
      longitude_deg: longitude [deg].
      altitude_m: height above the ellipsoid [m].
      release_time: earliest imaging start (UTC).
      due_time: latest imaging end (UTC).
      required_duration_s: imaging time [s].
      required_sensor_type: sensor type needed.
      weight: value collected if imaged.
    """

    task_id: str
    name: str
    latitude_deg: float
    longitude_deg: float
    altitude_m: float
    release_time: datetime
    due_time: datetime
    required_duration_s: float
    required_sensor_type: str
    weight: float


@dataclass(frozen=True)
class Case:
    """A loaded aeossp_standard case (horizon, grids, satellites, tasks).

    Attributes:
      case_id: identifier.
      horizon_start: start of the horizon (UTC).
      horizon_end: end of the horizon (UTC).
      action_step_s: grid of action times [s].
      geometry_step_s: grid of the geometry checks [s].
      resource_step_s: grid of the battery recursion [s].
      satellites: the satellites.
      tasks: the tasks.
    """

    case_id: str
    horizon_start: datetime
    horizon_end: datetime
    action_step_s: float
    geometry_step_s: float
    resource_step_s: float
    satellites: tuple[Satellite, ...]
    tasks: tuple[Task, ...]

    @property
    def duration_s(self) -> float:
        """Horizon length in seconds."""
        return (self.horizon_end - self.horizon_start).total_seconds()

    def seconds(self, value: datetime) -> float:
        """Seconds from ``horizon_start`` to ``value``.

        Args:
          value: aware datetime.
        Returns:
          float [s].
        """
        return (value - self.horizon_start).total_seconds()

    def at(self, seconds: float) -> datetime:
        """The instant ``seconds`` after ``horizon_start``.

        Args:
          seconds: float [s].
        Returns:
          datetime (UTC).
        """
        return self.horizon_start + timedelta(seconds=float(seconds))

    @property
    def satellite_by_id(self) -> dict[str, Satellite]:
        """Satellites keyed by id."""
        return {s.satellite_id: s for s in self.satellites}

    @property
    def task_by_id(self) -> dict[str, Task]:
        """Tasks keyed by id."""
        return {t.task_id: t for t in self.tasks}

    def task_table(self) -> dict[str, np.ndarray]:
        """Tasks as struct-of-arrays (float64; times in seconds from ``horizon_start``).

        Returns:
          dict of arrays [T]: ``latitude_deg``, ``longitude_deg``, ``altitude_m``,
          ``release_s``, ``due_s``, ``duration_s``, ``weight``, ``infrared`` (bool).
        """
        ts = self.tasks
        return {
            "latitude_deg": np.array([t.latitude_deg for t in ts], dtype=float),
            "longitude_deg": np.array([t.longitude_deg for t in ts], dtype=float),
            "altitude_m": np.array([t.altitude_m for t in ts], dtype=float),
            "release_s": np.array([self.seconds(t.release_time) for t in ts], dtype=float),
            "due_s": np.array([self.seconds(t.due_time) for t in ts], dtype=float),
            "duration_s": np.array([t.required_duration_s for t in ts], dtype=float),
            "weight": np.array([t.weight for t in ts], dtype=float),
            "infrared": np.array([t.required_sensor_type == "infrared" for t in ts]),
        }


_SENSORS = ("visible", "infrared")


def _read_yaml(path: Path) -> Any:
    if not path.is_file():
        raise FileNotFoundError(f"{path}: case file not found")
    text = read_text(path)  # UTF-8 (a byte-order mark dropped), else names the line
    try:
        return yaml.load(text, Loader=UniqueKeyLoader)
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML: {exc}") from None
    except RecursionError:
        raise ValueError(f"{path}: not valid YAML here: nested too deeply") from None


def _get(mapping: Any, key: str, where: str) -> Any:
    if not isinstance(mapping, dict) or key not in mapping:
        raise ValueError(f"{where}: missing field {key!r}")
    return mapping[key]


def _num(mapping: Any, key: str, where: str, *, positive=False, nonneg=False) -> float:
    value = _get(mapping, key, where)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where}.{key}: expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{where}.{key}: must be finite, got {value!r}")
    if positive and not value > 0:
        raise ValueError(f"{where}.{key}: must be > 0, got {value!r}")
    if nonneg and not value >= 0:
        raise ValueError(f"{where}.{key}: must be >= 0, got {value!r}")
    return value


def _str(mapping: Any, key: str, where: str) -> str:
    value = _get(mapping, key, where)
    if not isinstance(value, str) or not value:
        raise ValueError(f"{where}.{key}: expected a non-empty string, got {value!r}")
    return value


def _sensor(mapping: Any, key: str, where: str) -> str:
    value = _str(mapping, key, where)
    if value not in _SENSORS:
        raise ValueError(f"{where}.{key}: expected one of {_SENSORS}, got {value!r}")
    return value


def _time(mapping: Any, key: str, where: str) -> datetime:
    return parse_time(_get(mapping, key, where), where=f"{where}.{key}")


def _check_tle(l1: str, l2: str, where: str, start: datetime) -> None:
    """Parse the TLE and propagate it to the horizon start (SGP4), naming the line."""
    try:
        err = propagate_tle(l1, l2, *jd_split(julian_date(start), 0.0))[2]
    except ValueError as exc:
        raise ValueError(f"{where}.tle_line1/tle_line2: not a valid TLE: {exc}") from None
    if int(err[0]) != 0:
        raise ValueError(
            f"{where}.tle_line1/tle_line2: SGP4 error code {int(err[0])} at horizon_start"
        )


def _load_satellite(raw: Any, where: str, start: datetime) -> Satellite:
    sid = _str(raw, "satellite_id", where)
    where = f"{where}[{sid}]"
    norad = _get(raw, "norad_catalog_id", where)
    if isinstance(norad, bool) or not isinstance(norad, int):
        raise ValueError(f"{where}.norad_catalog_id: expected an integer, got {norad!r}")
    l1, l2 = _str(raw, "tle_line1", where), _str(raw, "tle_line2", where)
    for num, line in ((1, l1), (2, l2)):
        problem = tle_line_problem(line.rstrip(), num)
        if problem:
            raise ValueError(f"{where}.tle_line{num}: {problem}")
    _check_tle(l1, l2, where, start)
    sensor = _get(raw, "sensor", where)
    att = _get(raw, "attitude_model", where)
    res = _get(raw, "resource_model", where)
    wa, wr = f"{where}.attitude_model", f"{where}.resource_model"
    sat = Satellite(
        satellite_id=sid,
        norad_id=norad,
        tle_line1=l1,
        tle_line2=l2,
        sensor_type=_sensor(sensor, "sensor_type", f"{where}.sensor"),
        max_slew_rate_deg_s=_num(att, "max_slew_velocity_deg_per_s", wa, positive=True),
        max_slew_accel_deg_s2=_num(att, "max_slew_acceleration_deg_per_s2", wa, positive=True),
        settling_time_s=_num(att, "settling_time_s", wa, nonneg=True),
        max_off_nadir_deg=_num(att, "max_off_nadir_deg", wa, positive=True),
        battery_capacity_wh=_num(res, "battery_capacity_wh", wr, positive=True),
        initial_battery_wh=_num(res, "initial_battery_wh", wr, nonneg=True),
        idle_power_w=_num(res, "idle_power_w", wr, nonneg=True),
        imaging_power_w=_num(res, "imaging_power_w", wr, nonneg=True),
        slew_power_w=_num(res, "slew_power_w", wr, nonneg=True),
        sunlit_charge_power_w=_num(res, "sunlit_charge_power_w", wr, nonneg=True),
    )
    if sat.initial_battery_wh > sat.battery_capacity_wh:
        raise ValueError(
            f"{wr}.initial_battery_wh: {sat.initial_battery_wh} exceeds "
            f"battery_capacity_wh {sat.battery_capacity_wh}"
        )
    return sat


def _load_task(raw: Any, where: str) -> Task:
    tid = _str(raw, "task_id", where)
    where = f"{where}[{tid}]"
    name = raw.get("name", tid) if isinstance(raw, dict) else tid
    task = Task(
        task_id=tid,
        name=str(name),
        latitude_deg=_num(raw, "latitude_deg", where),
        longitude_deg=_num(raw, "longitude_deg", where),
        altitude_m=_num(raw, "altitude_m", where),
        release_time=_time(raw, "release_time", where),
        due_time=_time(raw, "due_time", where),
        required_duration_s=_num(raw, "required_duration_s", where, positive=True),
        required_sensor_type=_sensor(raw, "required_sensor_type", where),
        weight=_num(raw, "weight", where, nonneg=True),
    )
    if not -90.0 <= task.latitude_deg <= 90.0:
        raise ValueError(f"{where}.latitude_deg: outside [-90, 90]: {task.latitude_deg}")
    if not -180.0 <= task.longitude_deg <= 180.0:
        raise ValueError(f"{where}.longitude_deg: outside [-180, 180]: {task.longitude_deg}")
    lo, hi = _ALTITUDE_RANGE_M
    if not lo <= task.altitude_m <= hi:
        raise ValueError(f"{where}.altitude_m: outside [{lo:g}, {hi:g}]: {task.altitude_m}")
    if task.due_time < task.release_time:
        raise ValueError(f"{where}.due_time: before release_time")
    return task


def load_case(case_dir: str | os.PathLike) -> Case:
    """Load and validate one aeossp_standard case directory.

    Args:
      case_dir: path of the case directory.
    Returns:
      Case.
    Raises:
      FileNotFoundError: a file is missing.
      ValueError: naming the file and the field for a missing or malformed field,
        duplicate ids, or a bad horizon.
    """
    case_dir = Path(case_dir)
    if not case_dir.is_dir():
        raise FileNotFoundError(f"{case_dir}: case directory not found")
    mpath = case_dir / "mission.yaml"
    mission = _get(_read_yaml(mpath), "mission", str(mpath))
    w = f"{mpath}: mission"
    start, end = _time(mission, "horizon_start", w), _time(mission, "horizon_end", w)
    if not end > start:
        raise ValueError(f"{w}.horizon_end: must be after horizon_start")
    steps = [
        _num(mission, key, w, positive=True)
        for key in ("action_time_step_s", "geometry_sample_step_s", "resource_sample_step_s")
    ]
    case_id = str(_get(mission, "case_id", w))

    spath = case_dir / "satellites.yaml"
    raw_sats = _get(_read_yaml(spath), "satellites", str(spath))
    if not isinstance(raw_sats, list) or not raw_sats:
        raise ValueError(f"{spath}: field 'satellites' must be a non-empty list")
    sats = tuple(
        _load_satellite(r, f"{spath}: satellites[{i}]", start) for i, r in enumerate(raw_sats)
    )

    tpath = case_dir / "tasks.yaml"
    raw_tasks = _get(_read_yaml(tpath), "tasks", str(tpath))
    if not isinstance(raw_tasks, list) or not raw_tasks:
        raise ValueError(f"{tpath}: field 'tasks' must be a non-empty list")
    tasks = tuple(_load_task(r, f"{tpath}: tasks[{i}]") for i, r in enumerate(raw_tasks))

    for path, items, key in ((spath, sats, "satellite_id"), (tpath, tasks, "task_id")):
        seen: set[str] = set()
        for item in items:
            ident = getattr(item, key)
            if ident in seen:
                raise ValueError(f"{path}: duplicate {key} {ident!r}")
            seen.add(ident)
    return Case(case_id, start, end, *steps, satellites=sats, tasks=tasks)


def load_solution(path: str | os.PathLike) -> dict:
    """Read a solution JSON file ``{"actions": [...]}``.

    Args:
      path: path of the JSON file.
    Returns:
      dict, the solution.
    Raises:
      ValueError: the file is not valid JSON or not an object with an "actions" list.
    """
    path = Path(path)
    try:
        data = json.loads(read_text(path))  # UTF-8, else names the line
    except ValueError as exc:  # JSONDecodeError, or an integer of over 4,300 digits
        raise ValueError(f"{path}: not valid JSON: {exc}") from None
    except RecursionError:
        raise ValueError(f"{path}: not valid JSON here: nested too deeply") from None
    if not isinstance(data, dict) or not isinstance(data.get("actions"), list):
        raise ValueError(f"{path}: expected an object with an 'actions' list")
    return data
