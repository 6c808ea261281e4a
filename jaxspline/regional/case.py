"""Loading regional_coverage cases and reading / writing solutions.

A case directory (benchmark ``regional_coverage``, repository Mtrya/astro-reason) holds
``manifest.json``, ``satellites.yaml``, ``regions.geojson`` and ``coverage_grid.json``.
Every field the benchmark defines is validated on load; a missing or malformed field
raises ``ValueError`` naming the file and the field, e.g.
``satellites.yaml: [3].agility.max_roll_rate_deg_per_s: must be > 0, got -1``. A
missing file is a ``ValueError`` too (so a caller catches one type for any bad input).
Files are UTF-8 (a byte-order mark is accepted); a key repeated in one mapping is an
error (JSON and YAML would keep the last); NaN / infinity are refused; fields the loader
does not read are ignored. TLE lines are checked (line numbers, length, checksum, same
catalogue number) and must propagate (SGP4) at the horizon start and end.

Times are timezone-aware UTC ``datetime`` objects; the solution format writes them as
``YYYY-MM-DDTHH:MM:SSZ``. Inside the package times are float seconds from
``Case.start`` (:meth:`Case.seconds`, :meth:`Case.time_at`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np

from jaxspline.readers.case_files import format_time as format_time
from jaxspline.readers.case_files import parse_time as parse_time
from jaxspline.regional.case_fields import (
    check_tle,
    get_field,
    number_field,
    read_json,
    read_yaml,
    string_field,
)

MANIFEST = "manifest.json"
SATELLITES = "satellites.yaml"
REGIONS = "regions.geojson"
GRID = "coverage_grid.json"
#: Seconds per day (orbit period = this / mean motion in rev/day).
SECONDS_PER_DAY = 86400.0
#: Coordinates closer than this [deg] count as one point when counting polygon vertices.
DISTINCT_POINT_DEG = 1e-9

# ----------------------------------------------------------------------------- time


# ----------------------------------------------------------------------------- types


@dataclass(frozen=True)
class Sensor:
    """Strip sensor of one satellite.

    Attributes:
      min_edge_deg: smallest allowed edge off-nadir angle [deg].
      max_edge_deg: largest allowed edge off-nadir angle [deg].
      fov_deg: cross-track field of view [deg].
      min_duration_s: shortest strip [s].
      max_duration_s: longest strip [s].
    """

    min_edge_deg: float
    max_edge_deg: float
    fov_deg: float
    min_duration_s: float
    max_duration_s: float


@dataclass(frozen=True)
class Agility:
    """Roll agility of one satellite.

    Attributes:
      rate_deg_s: maximum roll rate [deg/s].
      accel_deg_s2: maximum roll acceleration [deg/s^2].
      settling_s: settling time after each slew [s].
    """

    rate_deg_s: float
    accel_deg_s2: float
    settling_s: float


@dataclass(frozen=True)
class Power:
    """Battery model of one satellite.

    Attributes:
      capacity_wh: battery capacity [Wh].
      initial_wh: charge at the horizon start [Wh].
      idle_w: constant load [W].
      imaging_w: extra load while imaging [W].
      slew_w: extra load inside a maneuver window [W].
      charge_w: charging power when sunlit [W].
      duty_limit_s: imaging seconds allowed per orbit period, None = no limit [s].
    """

    capacity_wh: float
    initial_wh: float
    idle_w: float
    imaging_w: float
    slew_w: float
    charge_w: float
    duty_limit_s: float | None


@dataclass(frozen=True)
class Satellite:
    """One satellite: TLE, sensor, agility, power.

    Attributes:
      id: ``satellite_id``.
      tle1: TLE line 1.
      tle2: TLE line 2.
      sensor: Sensor.
      agility: Agility.
      power: Power.
    """

    id: str
    tle1: str
    tle2: str
    sensor: Sensor
    agility: Agility
    power: Power

    @property
    def mean_motion_rev_day(self) -> float:
        """Mean motion from TLE line 2 (columns 53-63) [rev/day]."""
        return float(self.tle2[52:63])

    @property
    def orbit_period_s(self) -> float:
        """Orbit period ``86400 / mean motion`` [s] (the duty-cycle window)."""
        return SECONDS_PER_DAY / self.mean_motion_rev_day


@dataclass(frozen=True)
class Region:
    """One region polygon (outer ring only).

    Attributes:
      id: ``region_id``.
      weight: weight in ``coverage_ratio`` (>= 0).
      min_coverage: ``min_required_coverage_ratio`` in [0, 1] or None.
      ring: float64 [n, 2] (longitude, latitude) [deg], as in the file (closed or not).
    """

    id: str
    weight: float
    min_coverage: float | None
    ring: np.ndarray


@dataclass(frozen=True)
class Grid:
    """All coverage samples of a case, flattened over regions (region order of the case).

    Attributes:
      region: int32 [N], index into ``Case.regions``.
      lon_deg: float64 [N] longitude [deg].
      lat_deg: float64 [N] latitude [deg].
      weight_m2: float64 [N] sample weight [m^2].
      sample_id: tuple of N ``sample_id`` strings.
      region_total_m2: float64 [R] ``total_weight_m2`` of each region [m^2].
    """

    region: np.ndarray
    lon_deg: np.ndarray
    lat_deg: np.ndarray
    weight_m2: np.ndarray
    sample_id: tuple
    region_total_m2: np.ndarray

    @property
    def size(self) -> int:
        """Number of samples N."""
        return int(self.region.shape[0])


@dataclass(frozen=True)
class Case:
    """A loaded regional_coverage case.

    Attributes:
      path: case directory.
      case_id: ``manifest.json`` ``case_id`` (the directory name if absent).
      start: horizon start (UTC).
      end: horizon end (UTC).
      time_step_s: action grid [s].
      sample_step_s: coverage / power mesh step (``coverage_sample_step_s``) [s].
      max_actions: ``scoring.max_actions_total``.
      satellites: tuple of Satellite.
      regions: tuple of Region.
      grid: Grid.
    """

    path: Path
    case_id: str
    start: datetime
    end: datetime
    time_step_s: float
    sample_step_s: float
    max_actions: int
    satellites: tuple
    regions: tuple
    grid: Grid

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
        """Map ``satellite_id`` -> index into ``satellites``.

        Returns:
          dict[str, int].
        """
        return {s.id: i for i, s in enumerate(self.satellites)}


def _load_satellite(raw: Any, where: str, start: datetime, end: datetime) -> Satellite:
    sid = string_field(raw, "satellite_id", where)
    l1, l2 = (
        string_field(raw, "tle_line1", where).strip(),
        string_field(raw, "tle_line2", where).strip(),
    )
    check_tle(l1, l2, where, start, end)
    ws, wa, wp = f"{where}.sensor", f"{where}.agility", f"{where}.power"
    sen, agi, pw = (get_field(raw, k, where) for k in ("sensor", "agility", "power"))
    sensor = Sensor(
        min_edge_deg=number_field(sen, "min_edge_off_nadir_deg", ws, lo=0.0, hi=90.0),
        max_edge_deg=number_field(sen, "max_edge_off_nadir_deg", ws, lo=0.0, hi=90.0),
        fov_deg=number_field(sen, "cross_track_fov_deg", ws, lo=0.0, lo_open=True, hi=90.0),
        min_duration_s=number_field(sen, "min_strip_duration_s", ws, lo=0.0, lo_open=True),
        max_duration_s=number_field(sen, "max_strip_duration_s", ws, lo=0.0, lo_open=True),
    )
    if sensor.min_edge_deg > sensor.max_edge_deg:
        raise ValueError(
            f"{ws}.min_edge_off_nadir_deg: {sensor.min_edge_deg:g} > "
            f"max_edge_off_nadir_deg {sensor.max_edge_deg:g}"
        )
    if sensor.min_duration_s > sensor.max_duration_s:
        raise ValueError(
            f"{ws}.min_strip_duration_s: {sensor.min_duration_s:g} > "
            f"max_strip_duration_s {sensor.max_duration_s:g}"
        )
    agility = Agility(
        rate_deg_s=number_field(agi, "max_roll_rate_deg_per_s", wa, lo=0.0, lo_open=True),
        accel_deg_s2=number_field(
            agi, "max_roll_acceleration_deg_per_s2", wa, lo=0.0, lo_open=True
        ),
        settling_s=number_field(agi, "settling_time_s", wa, lo=0.0),
    )
    power = Power(
        capacity_wh=number_field(pw, "battery_capacity_wh", wp, lo=0.0, lo_open=True),
        initial_wh=number_field(pw, "initial_battery_wh", wp, lo=0.0),
        idle_w=number_field(pw, "idle_power_w", wp, lo=0.0),
        imaging_w=number_field(pw, "imaging_power_w", wp, lo=0.0),
        slew_w=number_field(pw, "slew_power_w", wp, lo=0.0),
        charge_w=number_field(pw, "sunlit_charge_power_w", wp, lo=0.0),
        duty_limit_s=number_field(pw, "imaging_duty_limit_s_per_orbit", wp, lo=0.0, null=True),
    )
    if power.initial_wh > power.capacity_wh:
        raise ValueError(
            f"{wp}.initial_battery_wh: {power.initial_wh:g} > "
            f"battery_capacity_wh {power.capacity_wh:g}"
        )
    return Satellite(sid, l1, l2, sensor, agility, power)


def _load_satellites(path: Path, start: datetime, end: datetime) -> tuple:
    raw = read_yaml(path)
    if isinstance(raw, dict) and "satellites" in raw:  # tolerate a wrapped list
        raw = raw["satellites"]
    if not isinstance(raw, list) or not raw:
        raise ValueError(f"{path.name}: expected a non-empty list of satellites")
    sats = tuple(_load_satellite(r, f"{path.name}: [{i}]", start, end) for i, r in enumerate(raw))
    seen: dict = {}
    for i, s in enumerate(sats):
        if s.id in seen:
            raise ValueError(
                f"{path.name}: [{i}].satellite_id: duplicate {s.id!r} (also [{seen[s.id]}])"
            )
        seen[s.id] = i
    return sats


def _ring(coords: Any, where: str) -> np.ndarray:
    if not isinstance(coords, list) or not coords:
        raise ValueError(f"{where}: expected a list of rings")
    ring = coords[0]
    if not isinstance(ring, list):
        raise ValueError(f"{where}[0]: expected a list of [lon, lat] points")
    pts = []
    for j, p in enumerate(ring):
        if (
            not isinstance(p, list)
            or len(p) < 2
            or any(isinstance(c, bool) or not isinstance(c, (int, float)) for c in p[:2])
        ):
            raise ValueError(f"{where}[0][{j}]: expected [lon, lat] numbers, got {p!r}")
        lon, lat = float(p[0]), float(p[1])
        if not (math.isfinite(lon) and math.isfinite(lat)):
            raise ValueError(f"{where}[0][{j}]: must be finite, got {p!r}")
        if not (-180.0 <= lon <= 180.0 and -90.0 <= lat <= 90.0):
            raise ValueError(f"{where}[0][{j}]: outside [-180, 180] x [-90, 90]: {p!r}")
        pts.append((lon, lat))
    arr = np.array(pts, dtype=float).reshape(-1, 2)
    distinct = []
    for p in arr:
        if all(np.max(np.abs(p - q)) > DISTINCT_POINT_DEG for q in distinct):
            distinct.append(p)
    if len(distinct) < 3:
        raise ValueError(f"{where}[0]: a polygon needs >= 3 distinct points, got {len(distinct)}")
    return arr


def _load_regions(path: Path) -> tuple:
    raw = read_json(path)
    feats = get_field(raw, "features", path.name)
    if not isinstance(feats, list) or not feats:
        raise ValueError(f"{path.name}: features: expected a non-empty list")
    regions, seen = [], {}
    for i, f in enumerate(feats):
        where = f"{path.name}: features[{i}]"
        props, geom = get_field(f, "properties", where), get_field(f, "geometry", where)
        rid = string_field(props, "region_id", f"{where}.properties")
        if rid in seen:
            raise ValueError(f"{where}.properties.region_id: duplicate {rid!r}")
        seen[rid] = i
        if get_field(geom, "type", f"{where}.geometry") != "Polygon":
            raise ValueError(f"{where}.geometry.type: expected 'Polygon', got {geom['type']!r}")
        ring = _ring(
            get_field(geom, "coordinates", f"{where}.geometry"), f"{where}.geometry.coordinates"
        )
        wp = f"{where}.properties"
        weight = number_field(props, "weight", wp, lo=0.0)
        mcov = None
        if "min_required_coverage_ratio" in props:
            mcov = number_field(props, "min_required_coverage_ratio", wp, lo=0.0, hi=1.0, null=True)
        regions.append(Region(rid, weight, mcov, ring))
    if not sum(r.weight for r in regions) > 0:
        raise ValueError(f"{path.name}: features[*].properties.weight: all weights are 0")
    return tuple(regions)


def _grid_region(raw: Any, where: str) -> tuple:
    """(region_id, lon, lat, weight, ids, total) of one ``coverage_grid.json`` region."""
    rid = string_field(raw, "region_id", where)
    samples = get_field(raw, "samples", where)
    if not isinstance(samples, list) or not samples:
        raise ValueError(f"{where}.samples: region {rid!r} has no samples")
    n = len(samples)
    lon, lat, wgt = np.empty(n), np.empty(n), np.empty(n)
    ids = []
    for j, s in enumerate(samples):
        ws = f"{where}.samples[{j}]"
        ids.append(string_field(s, "sample_id", ws))
        lon[j] = number_field(s, "longitude_deg", ws, lo=-180.0, hi=180.0)
        lat[j] = number_field(s, "latitude_deg", ws, lo=-90.0, hi=90.0)
        wgt[j] = number_field(s, "weight_m2", ws, lo=0.0)
    total = number_field(raw, "total_weight_m2", where, lo=0.0, lo_open=True)
    return rid, lon, lat, wgt, ids, total


def _load_grid(path: Path, regions: tuple) -> Grid:
    raw = read_json(path)
    items = get_field(raw, "regions", path.name)
    if not isinstance(items, list):
        raise ValueError(f"{path.name}: regions: expected a list")
    by_id: dict = {}
    for i, item in enumerate(items):
        parts = _grid_region(item, f"{path.name}: regions[{i}]")
        if parts[0] in by_id:
            raise ValueError(f"{path.name}: regions[{i}].region_id: duplicate {parts[0]!r}")
        by_id[parts[0]] = parts
    known = {r.id for r in regions}
    for rid in by_id:
        if rid not in known:
            raise ValueError(f"{path.name}: region_id {rid!r} is not in {REGIONS}")
    chunks, seen_ids = [], set()
    for k, region in enumerate(regions):
        if region.id not in by_id:
            raise ValueError(f"{path.name}: regions: no samples for region {region.id!r}")
        _, lon, lat, wgt, ids, total = by_id[region.id]
        for sid in ids:
            if sid in seen_ids:
                raise ValueError(f"{path.name}: sample_id {sid!r} repeated")
            seen_ids.add(sid)
        chunks.append((np.full(lon.shape, k, dtype=np.int32), lon, lat, wgt, ids, total))
    return Grid(
        region=np.concatenate([c[0] for c in chunks]),
        lon_deg=np.concatenate([c[1] for c in chunks]),
        lat_deg=np.concatenate([c[2] for c in chunks]),
        weight_m2=np.concatenate([c[3] for c in chunks]),
        sample_id=tuple(s for c in chunks for s in c[4]),
        region_total_m2=np.array([c[5] for c in chunks], dtype=float),
    )


def _load_manifest(path: Path) -> dict:
    raw = read_json(path)
    w = path.name
    start = parse_time(get_field(raw, "horizon_start", w), where=f"{w}: horizon_start")
    end = parse_time(get_field(raw, "horizon_end", w), where=f"{w}: horizon_end")
    if not end > start:
        raise ValueError(f"{w}: horizon_end: must be after horizon_start")
    step = number_field(raw, "time_step_s", w, lo=0.0, lo_open=True)
    sample = number_field(raw, "coverage_sample_step_s", w, lo=0.0, lo_open=True)
    scoring = get_field(raw, "scoring", w)
    cap = get_field(scoring, "max_actions_total", f"{w}: scoring")
    if isinstance(cap, bool) or not isinstance(cap, int) or cap < 0:
        raise ValueError(f"{w}: scoring.max_actions_total: expected an integer >= 0, got {cap!r}")
    case_id = raw.get("case_id", path.parent.name)
    return dict(
        case_id=str(case_id),
        start=start,
        end=end,
        time_step_s=step,
        sample_step_s=sample,
        max_actions=cap,
    )


def load_case(case_dir: str | os.PathLike) -> Case:
    """Load and validate one regional_coverage case directory.

    Args:
      case_dir: directory with ``manifest.json``, ``satellites.yaml``,
        ``regions.geojson`` and ``coverage_grid.json``.
    Returns:
      Case.
    Raises:
      ValueError: a missing directory or file, or a missing / malformed field
        (naming the file and the field).
    """
    case_dir = Path(case_dir)
    if not case_dir.is_dir():
        raise ValueError(f"{case_dir}: case directory not found")
    man = _load_manifest(case_dir / MANIFEST)
    sats = _load_satellites(case_dir / SATELLITES, man["start"], man["end"])
    regions = _load_regions(case_dir / REGIONS)
    grid = _load_grid(case_dir / GRID, regions)
    return Case(path=case_dir, satellites=sats, regions=regions, grid=grid, **man)


# ----------------------------------------------------------------------------- solutions


def load_solution(path: str | os.PathLike) -> dict:
    """Read a solution file ``{"actions": [...]}`` (strict JSON).

    Only the container is checked here; each action's fields are judged by the checker
    (a malformed action is a violation, not a read error).

    Args:
      path: JSON file.
    Returns:
      dict with an ``actions`` list.
    Raises:
      ValueError: missing file, bad JSON, or not an object with an ``actions`` list.
    """
    path = Path(path)
    data = read_json(path)
    if not isinstance(data, dict) or not isinstance(data.get("actions"), list):
        raise ValueError(f"{path}: actions: expected an object with an 'actions' list")
    return data
