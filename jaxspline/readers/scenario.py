"""Planning scenarios from files: the TOML schema, loading with named errors, the default.

A scenario file is TOML (UTF-8; a byte-order mark and CRLF line ends are accepted);
angles are degrees in the file and radians in the
:class:`jaxspline.readers.mission.Scenario` it becomes; times are seconds from the epoch.
Unknown keys are errors (typos fail loudly); every error is a ``ValueError`` naming
the field (``satellites[1].rate_deg_s``) and, where it can be located, the TOML line.
Every number has a physical range (:data:`jaxspline.readers.ranges.RANGES`; times
from the epoch lie in the horizon), every TLE is checked (columns, checksums, its epoch
within 30 days of the horizon: :mod:`jaxspline.readers.satellites`), and names hold no
control characters. Only ``[scenario]``, at least one satellite and at least one target
(or area) are required::

    targets_csv = "cities.csv"          # top-level key (before any [table]): a CSV of
                                        # targets, path relative to this file's folder;
                                        # a list of paths is accepted too
    [scenario]
    name = "example"                    # label (default: the file's stem)
    epoch = "2026-04-14T00:00:00Z"      # ISO-8601 UTC date-time of t = 0 (required)
    duration_h = 1.0                    # horizon [h], or duration_s [s] (one required;
                                        # 1 s to 30 days)

    [[satellites]]                      # one table per satellite; a single [satellite]
    name = "sat1"                       # table is accepted as an alias. Name defaults
                                        # to "sat1", "sat2", ... (unique)
    # orbit, one of three forms:
    tle = ["1 28649U ...", "2 28649 ..."]   # (a) real orbit: the two TLE lines (SGP4)
    altitude_km = 600.0                 # (b) circular orbit [km] (default 600)
    inclination_deg = 97.8              #     [deg]; omitted -> Sun-synchronous (J2)
    raan_deg = 0.0                      #     ascending node at the epoch [deg]
    arg_lat_deg = 0.0                   #     argument of latitude at the epoch [deg]
    over = { lat_deg = 46.0, lon_deg = 15.0, t_s = 1800.0, descending = true }
                                        # (c) circular orbit (altitude_km, inclination_deg
                                        #     as in (b)) whose sub-satellite point is at
                                        #     (lat, lon) [deg] at t_s [s] (default: mid-horizon)
    model = "per_channel"               # "per_channel" | "eigen_axis" | "flexible" |
                                        # "roll_only" (one roll axis, rest-to-rest: images
                                        # area strips and stereo looks only)
    rate_deg_s = [3.0, 3.0, 2.0]        # rate bound [deg/s]; per_channel: one number or
    accel_deg_s2 = [1.5, 1.5, 1.0]      # [roll, pitch, yaw]; other models: one number
                                        # about the eigen-axis (defaults 2 and 1)
    off_nadir_max_deg = 45.0            # pointing limit [deg] (default 45)
    sensor = "visible"                  # sensor type (default "visible")
    settle_s = 0.0                      # settling time after a rest-to-rest slew [s]
    swath_km = 20.0                     # ground width imaged across a strip [km] (default
                                        # 20, at most 5000): footprints, and the field of
                                        # view of area strips when fov_deg is not given
    fov_deg = 1.2                       # cross-track field of view of area strips and
                                        # stereo looks [deg]
    ifov_deg = 6.5e-5                   # the angle one detector pixel sees [deg]: a stereo
                                        # look's pixel scale is slant range x it (default:
                                        # none, stereo products ignore the pixel scale)
    pixels = 12000                      # detector pixels across the track: without fov_deg,
                                        # fov_deg = pixels x ifov_deg (needs ifov_deg; with
                                        # fov_deg too, the two agree within 0.1 %)
    edge_off_nadir_deg = [0.0, 30.0]    # off-nadir band an area strip's edges lie in [deg]
                                        # (default: 0 to off_nadir_max_deg)
    strip_duration_s = [0.0, 60.0]      # shortest and longest area strip or stereo look [s]
    duty_s_per_orbit = 300.0            # imaging seconds in any window of one orbital
                                        # period (default: no rule)
    flex = { freq_hz = 0.5, damping = 0.01, tolerance_deg = 1e-4 }
                                        # structural mode (model "flexible" only, required
                                        # there): frequency [Hz] (2 pi f rad/s inside),
                                        # damping ratio (default 0.01), residual amplitude
                                        # tolerance [deg] (default 1e-7 rad)
    power = { capacity_wh = 1300.0, initial_wh = 800.0, idle_w = 20.0, imaging_w = 420.0,
              slew_w = 360.0, charge_w = 85.0 }
                                        # battery [Wh] (initial defaults to capacity) and
                                        # loads [W] (default 0); omitted -> no battery rule

    [[targets]]                         # explicit targets ([[routes]] is an alias)
    kind = "point"                      # "point" (default), "strip" or "stereo"
    name = "Ljubljana"                  # default "target_1", "target_2", ...
    lat_deg = 46.05                     # geodetic latitude [deg] in [-90, 90] (required)
    lon_deg = 14.51                     # longitude [deg] in [-180, 180] (required)
    alt_m = 295.0                       # height above the WGS84 ellipsoid [m] (default 0)
    duration_s = 10.0                   # point: imaging time [s] (default 10)
    length_km = 40.0                    # strip: length [km] (required for a strip)
    azimuth_deg = 190.0                 # strip: direction at the start, clockwise from
                                        # north [deg] (default 0)
    priority = 5.0                      # value if imaged (> 0, default 1)
    window_s = [100.0, 900.0]           # start >= lo and end <= hi [s from the epoch]
    sensor = ""                         # required sensor type ("" = any, the default)
    desired_s = 450.0                   # desired time of the imaging midpoint (start +
    tolerance_s = 30.0                  # end) / 2 [s from the epoch] and its tolerance
                                        # [s]: the midpoint lies in desired +- tolerance
                                        # (tolerance_s required with desired_s)
    min_duration_s = 8.0                # shortest imaging time end - start [s] (default
                                        # 0); strips: only scan speeds with length /
                                        # speed >= it; points: duration_s defaults to
                                        # max(10, min_duration_s) and must reach it
    # a stereo target (kind = "stereo"): a disk imaged by a pair or a triple of looks
    # from different angles; takes name, lat_deg, lon_deg, alt_m, priority, window_s and
    # sensor as above (not duration_s, length_km, azimuth_deg, min_duration_s,
    # desired_s, tolerance_s), and, each defaulting to the [stereo] table's:
    product = "tri"                     # "pair" or "tri" (a triple preferred, a pair
                                        # still counts)
    radius_m = 5000.0                   # radius of the ground disk to image [m]
    band_deg = [8.0, 18.0]              # preferred convergence angles [deg] (quality),
                                        # within the table's convergence_deg
    tri_bonus = 0.12                    # a triple's quality over its best pair's

    [[areas]]                           # area targets: the weight of their samples covered
                                        # by strips at a held roll (and pitch) counts
    name = "karst"                      # default "area_1", "area_2", ... (unique)
    geojson = "karst.geojson"           # GeoJSON file (relative to this file's folder):
                                        # Polygon / MultiPolygon, Feature or
                                        # FeatureCollection (its polygons united), [lon, lat]
    lonlat_deg = [[13.6, 45.6], [14.2, 45.6], [14.2, 45.9], [13.6, 45.9]]
                                        # or one ring of [lon, lat] [deg] (not both)
    samples_csv = "karst_samples.csv"   # or the area's own samples: lon_deg, lat_deg,
                                        # weight (shares of the area, summing to <= 1)
    priority = 20.0                     # value of the whole area (> 0, default 1): a
                                        # sample is worth priority x its weight
    sensor = ""                         # required sensor type ("" = any)
    window_s = [0.0, 3600.0]            # imaging window of every strip [s from the epoch]
    grid_km = 4.0                       # sample spacing [km] (0.01-1000; default a third
                                        # of the narrowest swath; at most 200000 samples)
    min_coverage = 0.5                  # share the plan should reach (the search favours
                                        # areas below it; default: none)

    [stereo]                            # rules and defaults of every stereo target (all
                                        # optional; defaults: the stereo_imaging benchmark)
    product = "pair"                    # default product of a stereo target
    radius_m = 5000.0                   # default disk radius [m]
    min_overlap = 0.8                   # least share of the disk inside every look's strip
    convergence_deg = [5.0, 45.0]       # accepted convergence angles at the target [deg]
    band_deg = [8.0, 18.0]              # default preferred convergence [deg] (urban)
    max_scale_ratio = 1.5               # largest ratio of two looks' pixel scales
    max_separation_s = 3600.0           # largest time between two looks' midpoints [s]
    cross_satellite = true              # two satellites may make a pair
    anchor_off_nadir_deg = 10.0         # a triple needs a look within this of nadir [deg]
    quality_weights = [0.5, 0.35, 0.15] # a pair's quality: geometry (convergence in the
                                        # band), overlap, resolution (scale ratio); sum 1
    tri_bonus = 0.1                     # default bonus of a triple over its best pair
    quality_weight = 1.0                # share of a target's priority that quality
                                        # decides: value = priority x (1 - w + w quality)

    [targets_file]                      # alternative to targets_csv
    path = "more_targets.csv"

    [random_targets]                    # generated targets (added after the others)
    seed = 0                            # numpy default_rng seed (default 0)
    count = 200                         # how many (required)
    lat_deg = [-60.0, 70.0]             # region [deg] (uniform in lat and lon;
    lon_deg = [-180.0, 180.0]           # defaults: the whole globe)
    land_only = true                    # reject points at sea (global_land_mask)
    strip_fraction = 1.0                # share of strips (default 0.2)
    duration_s = [10.0, 30.0]           # point imaging times [s] (uniform)
    length_km = [20.0, 60.0]            # strip lengths [km] (uniform)
    azimuth_deg = [0.0, 360.0]          # strip azimuths [deg] (uniform)
    priority = [1, 10]                  # integer priorities (uniform, inclusive)

    [planner]                           # every key optional (PlannerConfig defaults)
    time_step_s = 5.0                   # action grid: observation starts [s]
    geometry_step_s = 5.0               # ephemeris / visibility grid [s] (divides time_step_s;
                                        # at most 10^6 steps over the horizon)
    scan_speeds_km_s = [7.0]            # strip ground scan speeds [km/s] (at most 100)
    sun_elevation_min_deg = 10.0        # daylight rule at the target [deg] (default: none)
    off_nadir_margin_deg = 0.01         # kept back from off_nadir_max_deg [deg]
    horizon_margin = 0.0                # sine of target elevation must exceed this
    gap_margin_s = 0.1                  # added to every rest-to-rest slew time [s]
    battery_margin_wh = 10.0            # battery level kept >= this [Wh]
    shadow_guard_steps = 0              # battery steps of sunlight required around a step
    exact_max_options = 60              # solve exactly up to this many options (<= 500)
    lagrangian_share = 0.3              # search share of the Lagrangian phase (no worker)
    bound_worker = true                 # iterate the bound on a second CPU during the search
    refine_steps = 100                  # optax steps refining per-channel start times (0 = off)
    time_limit_s = 30.0                 # default search budget [s]
    max_actions = 500                   # most observations of a plan (default: no cap)
    area_roll_step_deg = 0.25           # roll grid of area strips [deg]
    area_pitch_step_deg = 2.0           # pitch grid of an agile satellite's area strips
                                        # [deg] (default: one action step of ground track)
    duty_margin_s = 0.5                 # kept below duty_s_per_orbit [s]

The target sections (``targets_csv``, ``[[targets]]``/``[[routes]]``,
``[targets_file]``, ``[random_targets]``) are read by :mod:`jaxspline.readers.targets`,
whose docstring lists the CSV columns with their units and how random targets are
drawn; :func:`~jaxspline.readers.targets.load_targets_csv` reads them. ``[[areas]]``
(alias ``[area]``) are read by :mod:`jaxspline.readers.area_files`, each one target of
kind ``AREA`` after every other target (a file with areas needs no other targets); the
planner lays their strips out (:mod:`jaxspline.planner.area_options`). Stereo targets
(``kind = "stereo"`` in ``[[targets]]`` or a CSV file) and the ``[stereo]`` table are read
by :mod:`jaxspline.readers.stereo_files`, each one
:class:`~jaxspline.readers.stereo_request.Stereo` request of ``Scenario.stereo``, whose
docstring defines the products, their quality and value; the planner builds their looks
(:mod:`jaxspline.planner.stereo_options`). ``jaxspline/data/stereo_example.toml`` plans
stereo products over 30 cities.

:func:`default_scenario` loads the packaged ``data/default.toml``: six satellites over
six hours with about 1500 city targets (``data/cities.csv``, made by
``scripts/make_default_targets.py``) and 200 random land strips.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import importlib.resources
import json
import math
import tomllib
from pathlib import Path

import numpy as np
import shapely.geometry

from jaxspline.readers.config import Margins, PlannerConfig
from jaxspline.readers.fields import (
    FieldContext,
    field_bool,
    field_int,
    field_number,
    field_str,
    field_table,
    read_text,
)
from jaxspline.readers.mission import AREA, Area, Scenario, make_targets
from jaxspline.readers.ranges import EPOCH_RANGE, MAX_SCAN_SPEEDS, RANGES, bounds
from jaxspline.readers.satellites import parse_satellites
from jaxspline.readers.stereo_files import parse_stereo_table
from jaxspline.readers.targets import TARGET_SECTIONS, read_targets

__all__ = [
    "DEFAULT_SCENARIO_PATH",
    "default_scenario",
    "load_scenario",
    "parse_scenario",
    "scenario_from",
]

#: The packaged default scenario (six satellites, six hours, ~1700 targets).
DEFAULT_SCENARIO_PATH = Path(str(importlib.resources.files("jaxspline") / "data" / "default.toml"))

SECONDS_PER_HOUR = 3600.0
MAX_DURATION_S = RANGES["scenario.duration_s"][1]  # longest horizon [s]: TLEs are days, not months
MAX_GRID_POINTS = 1_000_000  # longest ephemeris grid, duration / geometry_step_s
MAX_TOML_BYTES = 16 << 20  # characters (16 MiB): a scenario is a few kB, targets come in CSV

_KEYS = {
    name: frozenset(keys.split())
    for name, keys in {
        "scenario": "name epoch duration_s duration_h",
        "planner": "time_step_s geometry_step_s scan_speeds_km_s sun_elevation_min_deg "
        "off_nadir_margin_deg horizon_margin gap_margin_s battery_margin_wh shadow_guard_steps "
        "exact_max_options lagrangian_share bound_worker refine_steps time_limit_s "
        "max_actions area_roll_step_deg area_pitch_step_deg duty_margin_s",
    }.items()
}
_TOP = frozenset("scenario satellites satellite planner areas area stereo".split())
_TOP |= TARGET_SECTIONS


# --- planner ---


def _int(ctx, pl, key, default) -> int:
    lo, hi = RANGES[f"planner.{key}"]
    return field_int(ctx, f"planner.{key}", pl.get(key, default), lo, hi)


def _steps(ctx, pl, d: PlannerConfig, duration: float) -> tuple[float, float]:
    """``(time_step_s, geometry_step_s)`` [s]: in range, the first a whole multiple of the
    second, and at most :data:`MAX_GRID_POINTS` geometry steps over the horizon."""

    def num(key, default):
        return field_number(ctx, f"planner.{key}", pl.get(key, default), **bounds(f"planner.{key}"))

    time_step = num("time_step_s", d.time_step)
    geometry_step = num("geometry_step_s", d.geometry_step)
    ratio = time_step / geometry_step
    if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-9:
        raise ctx.error(
            "planner.time_step_s",
            f"must be a whole multiple of planner.geometry_step_s = {geometry_step:g}, "
            f"got {time_step:g}",
        )
    if duration / geometry_step > MAX_GRID_POINTS:
        raise ctx.error(
            "planner.geometry_step_s",
            f"{geometry_step:g} s steps over the {duration:g} s horizon are "
            f"{duration / geometry_step:.3g} grid points (at most {MAX_GRID_POINTS:g}); "
            "use a coarser step or a shorter horizon",
        )
    return time_step, geometry_step


def _speeds(ctx, pl, d: PlannerConfig) -> tuple[float, ...]:
    """The strip scan speeds [m/s] of ``planner.scan_speeds_km_s``."""
    key = "planner.scan_speeds_km_s"
    speeds = pl.get("scan_speeds_km_s", [s / 1e3 for s in d.scan_speeds])
    if not isinstance(speeds, list) or not speeds or len(speeds) > MAX_SCAN_SPEEDS:
        raise ctx.error(
            key, f"must be a list of 1 to {MAX_SCAN_SPEEDS} speeds [km/s], got {speeds!r}"
        )
    return tuple(1e3 * field_number(ctx, key, s, **bounds(key)) for s in speeds)


def _margins(ctx, pl, sats) -> Margins:
    """The planner's margins; the off-nadir margin below every satellite's limit."""
    dm = Margins()

    def num(key, default):
        return field_number(ctx, f"planner.{key}", pl.get(key, default), **bounds(f"planner.{key}"))

    off = num("off_nadir_margin_deg", math.degrees(dm.off_nadir))
    least = min(math.degrees(s.off_nadir_max) for s in sats)
    if off >= least:
        raise ctx.error(
            "planner.off_nadir_margin_deg",
            f"must be below every satellite's off_nadir_max_deg (the least is {least:g}), "
            f"got {off:g}",
        )
    return Margins(
        off_nadir=math.radians(off),
        horizon=num("horizon_margin", dm.horizon),
        gap=num("gap_margin_s", dm.gap),
        battery_wh=num("battery_margin_wh", dm.battery_wh),
        shadow_guard=_int(ctx, pl, "shadow_guard_steps", dm.shadow_guard),
        duty=num("duty_margin_s", dm.duty),
    )


def _planner(ctx, pl, duration: float, sats) -> PlannerConfig:
    pl = field_table(ctx, "planner", pl, _KEYS["planner"])
    d = PlannerConfig()

    def num(key, default):
        return field_number(ctx, f"planner.{key}", pl.get(key, default), **bounds(f"planner.{key}"))

    time_step, geometry_step = _steps(ctx, pl, d, duration)
    sun = pl.get("sun_elevation_min_deg")
    if sun is not None:
        sun = math.radians(num("sun_elevation_min_deg", sun))
    kw = {
        "time_step": time_step,
        "geometry_step": geometry_step,
        "scan_speeds": _speeds(ctx, pl, d),
        "sun_elevation_min": sun,
        "margins": _margins(ctx, pl, sats),
        "exact_max_options": _int(ctx, pl, "exact_max_options", d.exact_max_options),
        "lagrangian_share": num("lagrangian_share", d.lagrangian_share),
        "bound_worker": field_bool(
            ctx, "planner.bound_worker", pl.get("bound_worker", d.bound_worker)
        ),
        "refine_steps": _int(ctx, pl, "refine_steps", d.refine_steps),
        "default_time_limit": num("time_limit_s", d.default_time_limit),
        "max_actions": _int(ctx, pl, "max_actions", None) if "max_actions" in pl else None,
        "area_roll_step": math.radians(num("area_roll_step_deg", math.degrees(d.area_roll_step))),
        "area_pitch_step": (
            math.radians(num("area_pitch_step_deg", None)) if "area_pitch_step_deg" in pl else None
        ),
    }
    try:
        return PlannerConfig(**kw)
    except ValueError as exc:  # PlannerConfig's own checks (the fields are checked above)
        raise ctx.error("planner", str(exc)) from None


# --- scenario header ---


def _epoch(ctx, value) -> _dt.datetime:
    """``scenario.epoch``: a date-time with its time zone (``Z`` or an offset), in UTC."""
    written = value
    if isinstance(value, str):
        text = value.strip()
        try:
            value = _dt.datetime.fromisoformat(text[:-1] + "+00:00" if text[-1:] in "Zz" else text)
        except ValueError:
            pass
    if isinstance(value, _dt.date) and (
        not isinstance(value, _dt.datetime) or value.tzinfo is None
    ):  # "2026-04-14", TOML's local date-times and dates: which zone is meant is unknown
        shown = written if isinstance(written, str) else value.isoformat()
        raise ctx.error(
            "scenario.epoch",
            f"{shown} has no time zone: add Z (UTC) or an offset, e.g. 2026-04-14T00:00:00Z",
        )
    if not isinstance(value, _dt.datetime):
        raise ctx.error("scenario.epoch", f"must be an ISO-8601 UTC date-time, got {value!r}")
    value = value.astimezone(_dt.UTC)
    lo, hi = EPOCH_RANGE
    if not lo <= value <= hi:
        raise ctx.error(
            "scenario.epoch",
            f"must be within [{lo:%Y-%m-%d}, {hi:%Y-%m-%d}] (UTC), got {value.isoformat()}",
        )
    return value


def _header(ctx, data, source: str) -> tuple[str, _dt.datetime, float]:
    """``(name, epoch, duration [s])`` of the ``[scenario]`` table."""
    if "scenario" not in data:
        raise ctx.error("scenario", "missing section [scenario] (epoch, duration_s)")
    sc = field_table(ctx, "scenario", data["scenario"], _KEYS["scenario"])
    name = field_str(ctx, "scenario.name", sc.get("name", Path(source).stem), max_chars=256)
    epoch = _epoch(ctx, sc.get("epoch"))
    if ("duration_s" in sc) == ("duration_h" in sc):
        raise ctx.error("scenario.duration_s", "give exactly one of duration_s, duration_h")
    key = "duration_s" if "duration_s" in sc else "duration_h"
    duration = field_number(ctx, f"scenario.{key}", sc[key], **bounds(f"scenario.{key}"))
    return name, epoch, duration * (SECONDS_PER_HOUR if key == "duration_h" else 1.0)


def parse_scenario(
    data: dict, source: str = "<scenario>", text: str | None = None, base_dir=None
) -> Scenario:
    """Build a :class:`Scenario` from parsed TOML ``data`` (schema: module docstring).

    Args:
      data: dict, the parsed TOML.
      source: name of the source in error messages.
      text: the raw TOML, lets errors cite line numbers.
      base_dir: folder that relative CSV paths start from (None: the working directory).
    Returns:
      Scenario.
    Raises:
      ValueError: naming the field.
    """
    ctx = FieldContext(source, text)
    if not isinstance(data, dict):
        raise ValueError(f"{source}: a scenario must be a table, got {type(data).__name__}")
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise ctx.error(unknown[0], f"unknown section or key (allowed: {sorted(_TOP)})")
    name, epoch, duration = _header(ctx, data, source)
    sats = parse_satellites(ctx, data, epoch, duration)
    has_areas = "areas" in data or "area" in data
    template = parse_stereo_table(ctx, data)
    targets, stereo = read_targets(
        ctx, data, base_dir, required=not has_areas, horizon=duration, stereo=template
    )
    planner = _planner(ctx, data.get("planner", {}), duration, sats)
    if not has_areas:
        return Scenario(name, epoch, duration, sats, targets, planner, stereo=stereo)
    if targets is None:
        targets = make_targets(
            np.zeros(0, np.int64), np.zeros(0), np.zeros(0), name=np.zeros(0, str)
        )
    sc = Scenario(name, epoch, duration, sats, targets, planner, stereo=stereo)
    return _with_areas(ctx, data, base_dir, sc)


def _with_areas(ctx, data, base_dir, sc: Scenario) -> Scenario:
    """``sc`` with the ``[[areas]]`` of ``data``: each a target of kind AREA after its
    targets (priority, window, sensor, its centre) and an :class:`Area`."""
    from jaxspline.readers.area_files import parse_areas

    specs = parse_areas(ctx, data, base_dir, sc.satellites, horizon=sc.duration)
    lat, lon, areas = [], [], []
    first = len(sc.targets)
    for i, a in enumerate(specs):
        if a.samples.shape[0]:
            w = a.samples[:, 2] if a.samples[:, 2].sum() > 0 else None
            lon.append(math.radians(float(np.average(a.samples[:, 0], weights=w))))
            lat.append(math.radians(float(np.average(a.samples[:, 1], weights=w))))
        else:
            c = a.polygon.centroid  # (lon, lat) [deg], geodetic as the file gives them
            lat.append(math.radians(float(c.y)))
            lon.append(math.radians(float(c.x)))
        geometry = None if a.polygon is None else shapely.geometry.mapping(a.polygon)
        areas.append(Area(a.name, first + i, _plain(geometry), a.grid, a.samples, a.min_share))
    rows = make_targets(
        np.full(len(specs), AREA),
        lat,
        lon,
        value=[a.value for a in specs],
        t_lo=[a.t_lo for a in specs],
        t_hi=[a.t_hi for a in specs],
        sensor=[a.sensor for a in specs],
        name=[a.name for a in specs],
    )
    return dataclasses.replace(sc, targets=sc.targets.concat(rows), areas=tuple(areas))


def _plain(geometry):
    """A GeoJSON geometry mapping as plain nested lists (shapely gives tuples)."""
    if geometry is None:
        return None
    return json.loads(json.dumps(geometry))


def load_scenario(path) -> Scenario:
    """Load a scenario TOML file.

    Relative CSV paths in the file start from the file's folder.

    Args:
      path: str or Path of the TOML file.
    Returns:
      Scenario.
    Raises:
      FileNotFoundError: the file is missing.
      ValueError: invalid TOML, or bad content (naming the field / TOML line), or the
        path is not a readable file (a directory, a device) of at most 16 MiB.
    """
    path = Path(path)
    try:
        text = read_text(path)  # UTF-8, a byte-order mark dropped
    except FileNotFoundError:
        raise FileNotFoundError(f"scenario file not found: {path}") from None
    if len(text) > MAX_TOML_BYTES:
        raise ValueError(
            f"{path}: {len(text):,} characters, more than the {MAX_TOML_BYTES:,} (16 MiB) "
            "a scenario file may have (put targets in a CSV file)"
        )
    try:
        data = tomllib.loads(text)
    except ValueError as exc:  # TOMLDecodeError, or an integer of over 4,300 digits
        raise ValueError(f"{path}: invalid TOML: {exc}") from None
    except RecursionError:  # thousands of nested arrays or inline tables
        raise ValueError(f"{path}: invalid TOML: arrays or tables nested too deeply") from None
    return parse_scenario(data, source=str(path), text=text, base_dir=path.parent)


def default_scenario() -> Scenario:
    """The built-in scenario (``data/default.toml``, see :data:`DEFAULT_SCENARIO_PATH`).

    Six satellites on real TLE orbits from the aeossp_standard benchmark (two
    per-channel, two eigen-axis with batteries, one of them infrared, two flexible),
    epoch 2026-04-14 00:00 UTC, six hours; ~1500 city point targets
    (``data/cities.csv``) and 200 random land strips 20-60 km long.

    Returns:
      Scenario.
    """
    return load_scenario(DEFAULT_SCENARIO_PATH)


def scenario_from(scenario) -> Scenario:
    """The scenario a command was given: a Scenario as is, a TOML path loaded, None the default.

    Args:
      scenario: Scenario, str or Path of a scenario TOML file, or None.
    Returns:
      Scenario.
    Raises:
      ValueError / FileNotFoundError: as :func:`load_scenario`.
    """
    if scenario is None:
        return default_scenario()
    if isinstance(scenario, Scenario):
        return scenario
    return load_scenario(scenario)
