"""Planning scenarios from files: the TOML schema, loading with named errors, the default.

A scenario file is TOML (UTF-8; a byte-order mark and CRLF line ends are accepted);
angles are degrees in the file and radians in the
:class:`jaxspline.readers.mission.Scenario` it becomes; times are seconds from the epoch.
Unknown keys are errors (typos fail loudly); every error is a ``ValueError`` naming
the field (``satellites[1].rate_deg_s``) and, where it can be located, the TOML line.
Only ``[scenario]``, at least one satellite and at least one target (or area) are
required::

    targets_csv = "cities.csv"          # top-level key (before any [table]): a CSV of
                                        # targets, path relative to this file's folder;
                                        # a list of paths is accepted too
    [scenario]
    name = "example"                    # label (default: the file's stem)
    epoch = "2026-04-14T00:00:00Z"      # ISO-8601 UTC date-time of t = 0 (required)
    duration_h = 1.0                    # horizon [h], or duration_s [s] (one required;
                                        # at most 30 days)

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
    model = "per_channel"               # "per_channel" | "eigen_axis" | "flexible"
    rate_deg_s = [3.0, 3.0, 2.0]        # rate bound [deg/s]; per_channel: one number or
    accel_deg_s2 = [1.5, 1.5, 1.0]      # [roll, pitch, yaw]; other models: one number
                                        # about the eigen-axis (defaults 2 and 1)
    off_nadir_max_deg = 45.0            # pointing limit [deg] (default 45)
    sensor = "visible"                  # sensor type (default "visible")
    settle_s = 0.0                      # settling time after a rest-to-rest slew [s]
    swath_km = 20.0                     # ground width imaged across a strip [km] (default
                                        # 20, at most 5000): default strip width of areas,
                                        # footprints
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
    kind = "point"                      # "point" (default) or "strip"
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

    [[areas]]                           # polygon area targets (jaxspline.readers.areas), cut into
                                        # strips along the ground tracks of the passes
    name = "karst"                      # default "area_1", "area_2", ... (unique)
    geojson = "karst.geojson"           # GeoJSON file (relative to this file's folder):
                                        # Polygon / MultiPolygon, Feature or
                                        # FeatureCollection (its polygons united), [lon, lat]
    lonlat_deg = [[13.6, 45.6], [14.2, 45.6], [14.2, 45.9], [13.6, 45.9]]
                                        # or one ring of [lon, lat] [deg] (not both)
    priority = 20.0                     # value of the whole area (> 0, default 1), split
                                        # over the strips of a cutting by area share
    swath_km = 15.0                     # strip width [km]; default: the narrowest swath_km
                                        # of the satellites whose sensor the area accepts
    max_length_km = 60.0                # longer strips are split [km] (default: no limit)
    sensor = ""                         # required sensor type ("" = any)
    window_s = [0.0, 3600.0]            # imaging window of every strip [s from the epoch]

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
    exact_max_options = 60              # solve exactly up to this many options
    lagrangian_share = 0.3              # search budget share of the Lagrangian phase
    bound_worker = true                 # iterate the bound on a second CPU during the search
    refine_steps = 100                  # optax steps refining per-channel start times (0 = off)
    time_limit_s = 30.0                 # default search budget [s]

The target sections (``targets_csv``, ``[[targets]]``/``[[routes]]``,
``[targets_file]``, ``[random_targets]``) are read by :mod:`jaxspline.readers.targets`,
whose docstring lists the CSV columns with their units and how random targets are
drawn; :func:`~jaxspline.readers.targets.load_targets_csv` reads them. ``[[areas]]``
(alias ``[area]``) are read by :mod:`jaxspline.readers.area_files` and cut into strip targets by
:mod:`jaxspline.readers.areas` (method there); their
strips follow every other target, and a file with areas needs no other targets.

:func:`default_scenario` loads the packaged ``data/default.toml``: six satellites over
six hours with about 1500 city targets (``data/cities.csv``, made by
``scripts/make_default_targets.py``) and 200 random land strips.
"""

from __future__ import annotations

import datetime as _dt
import importlib.resources
import math
import tomllib
from pathlib import Path

import numpy as np

from jaxspline.geometry.frames import gmst, jd_split, julian_date
from jaxspline.geometry.orbit import circular_orbit, circular_orbit_over, propagate_tle
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.fields import (
    FieldContext,
    field_bool,
    field_int,
    field_number,
    field_str,
    field_table,
    field_tables,
    read_text,
)
from jaxspline.readers.mission import (
    DEFAULT_SWATH,
    FlexMode,
    Margins,
    PlannerConfig,
    Power,
    Satellite,
    Scenario,
    make_targets,
)
from jaxspline.readers.targets import TARGET_SECTIONS, scenario_targets
from jaxspline.screen.models import maneuver_model

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
DEFAULT_ALTITUDE_KM = 600.0
ALTITUDE_RANGE_KM = (150.0, 30000.0)
DEFAULT_RATE_DEG_S = 2.0
DEFAULT_ACCEL_DEG_S2 = 1.0
DEFAULT_OFF_NADIR_DEG = 45.0
MAX_OFF_NADIR_DEG = 80.0
DEFAULT_SENSOR = "visible"
DEFAULT_SWATH_KM = DEFAULT_SWATH / 1e3
MAX_SWATH_KM = 5000.0  # a wider swath is a unit mistake (strip widths are km)
MAX_DURATION_S = 30 * 86400.0  # longest horizon [s]: TLEs and plans are days, not months
MAX_GRID_POINTS = 1_000_000  # longest ephemeris grid, duration / geometry_step_s
MAX_SCAN_SPEED_KM_S = 100.0  # strip ground scan speeds beyond this are unit mistakes

_ORBIT_KEYS = ("altitude_km", "inclination_deg", "raan_deg", "arg_lat_deg", "over")
_SAT_MODEL_KEYS = (
    "name tle model rate_deg_s accel_deg_s2 off_nadir_max_deg sensor settle_s flex power swath_km"
)
_KEYS = {
    name: frozenset(keys.split())
    for name, keys in {
        "scenario": "name epoch duration_s duration_h",
        "satellite": " ".join(_ORBIT_KEYS) + " " + _SAT_MODEL_KEYS,
        "over": "lat_deg lon_deg t_s descending",
        "flex": "freq_hz damping tolerance_deg",
        "power": "capacity_wh initial_wh idle_w imaging_w slew_w charge_w",
        "planner": "time_step_s geometry_step_s scan_speeds_km_s sun_elevation_min_deg "
        "off_nadir_margin_deg horizon_margin gap_margin_s battery_margin_wh shadow_guard_steps "
        "exact_max_options lagrangian_share bound_worker refine_steps time_limit_s",
    }.items()
}
_TOP = frozenset("scenario satellites satellite planner areas area".split()) | TARGET_SECTIONS


# --- satellites ---


def _orbit(ctx, f, sat, epoch_jd, duration):
    if "tle" in sat:
        clash = [k for k in _ORBIT_KEYS if k in sat]
        if clash:
            raise ctx.error(f"{f}.{clash[0]}", "cannot be combined with tle (a TLE is the orbit)")
        tle = sat["tle"]
        if not (isinstance(tle, list) and len(tle) == 2 and all(isinstance(s, str) for s in tle)):
            raise ctx.error(f"{f}.tle", f"must be a list of the two TLE lines, got {tle!r}")
        try:
            err = propagate_tle(tle[0], tle[1], *jd_split(epoch_jd, 0.0))[2]
        except ValueError as exc:
            raise ctx.error(f"{f}.tle", str(exc)) from None
        if int(err[0]) != 0:
            raise ctx.error(f"{f}.tle", f"SGP4 error code {int(err[0])} at the epoch")
        return (tle[0], tle[1])
    alt = sat.get("altitude_km", DEFAULT_ALTITUDE_KM)
    alt = field_number(
        ctx, f"{f}.altitude_km", alt, lo=ALTITUDE_RANGE_KM[0], hi=ALTITUDE_RANGE_KM[1]
    )
    inc = sat.get("inclination_deg")
    if inc is not None:
        inc = math.radians(field_number(ctx, f"{f}.inclination_deg", inc, lo=0.0, hi=180.0))
    if "over" not in sat:
        raan = field_number(ctx, f"{f}.raan_deg", sat.get("raan_deg", 0.0))
        u0 = field_number(ctx, f"{f}.arg_lat_deg", sat.get("arg_lat_deg", 0.0))
        return circular_orbit(1e3 * alt, inc, math.radians(raan), math.radians(u0))
    clash = [k for k in ("raan_deg", "arg_lat_deg") if k in sat]
    if clash:
        raise ctx.error(f"{f}.{clash[0]}", "cannot be combined with over (it places the orbit)")
    ov = field_table(ctx, f"{f}.over", sat["over"], _KEYS["over"])
    lat = field_number(ctx, f"{f}.over.lat_deg", ov.get("lat_deg", 0.0), lo=-90.0, hi=90.0)
    lon = field_number(ctx, f"{f}.over.lon_deg", ov.get("lon_deg", 0.0), lo=-180.0, hi=180.0)
    t_over = field_number(ctx, f"{f}.over.t_s", ov.get("t_s", duration / 2))
    desc = field_bool(ctx, f"{f}.over.descending", ov.get("descending", True))
    gmst0 = float(gmst(*jd_split(epoch_jd, 0.0)))
    try:
        return circular_orbit_over(
            math.radians(lat), math.radians(lon), t_over, gmst0, 1e3 * alt, inc, descending=desc
        )
    except ValueError as exc:
        raise ctx.error(f"{f}.over.lat_deg", str(exc)) from None


def _rate(ctx, field, value, maneuver):
    if maneuver.limit_shape == ():
        if isinstance(value, list):
            raise ctx.error(field, f"must be one number for model {maneuver.name!r}, got {value!r}")
        return math.radians(field_number(ctx, field, value, positive=True))
    if isinstance(value, list):
        if len(value) != 3:
            raise ctx.error(field, f"must be one number or 3 (roll, pitch, yaw), got {value!r}")
        vals = [field_number(ctx, field, v, positive=True) for v in value]
    else:
        vals = [field_number(ctx, field, value, positive=True)] * 3
    return np.radians(np.asarray(vals))


def _satellite(ctx, f, sat, default_name, epoch_jd, duration) -> Satellite:
    sat = field_table(ctx, f, sat, _KEYS["satellite"])
    name = field_str(ctx, f"{f}.name", sat.get("name", default_name), allow_empty=False)
    orbit = _orbit(ctx, f, sat, epoch_jd, duration)
    model = sat.get("model", "per_channel")
    try:
        maneuver = maneuver_model(model)
    except ValueError as exc:
        raise ctx.error(f"{f}.model", str(exc).removeprefix("model ")) from None
    rate = _rate(ctx, f"{f}.rate_deg_s", sat.get("rate_deg_s", DEFAULT_RATE_DEG_S), maneuver)
    accel = _rate(ctx, f"{f}.accel_deg_s2", sat.get("accel_deg_s2", DEFAULT_ACCEL_DEG_S2), maneuver)
    off = field_number(
        ctx,
        f"{f}.off_nadir_max_deg",
        sat.get("off_nadir_max_deg", DEFAULT_OFF_NADIR_DEG),
        positive=True,
        hi=MAX_OFF_NADIR_DEG,
    )
    sensor = field_str(ctx, f"{f}.sensor", sat.get("sensor", DEFAULT_SENSOR), allow_empty=False)
    settle = field_number(ctx, f"{f}.settle_s", sat.get("settle_s", 0.0), nonneg=True)
    flex = None
    if "flex" in sat:
        if "flex" not in maneuver.extra_fields:
            raise ctx.error(f"{f}.flex", f"only used by model 'flexible' (model is {model!r})")
        fx = field_table(ctx, f"{f}.flex", sat["flex"], _KEYS["flex"])
        freq_hz = field_number(ctx, f"{f}.flex.freq_hz", fx.get("freq_hz"), positive=True)
        kw = {"freq": 2 * math.pi * freq_hz}
        if "damping" in fx:
            kw["damping"] = field_number(ctx, f"{f}.flex.damping", fx["damping"], nonneg=True)
        if "tolerance_deg" in fx:
            tol = field_number(ctx, f"{f}.flex.tolerance_deg", fx["tolerance_deg"], positive=True)
            kw["tolerance"] = math.radians(tol)
        flex = FlexMode(**kw)
    elif "flex" in maneuver.extra_fields:
        raise ctx.error(
            f"{f}.model",
            "'flexible' needs flex = { freq_hz = ..., damping = ..., tolerance_deg = ... }",
        )
    power = None
    if "power" in sat:
        pw = field_table(ctx, f"{f}.power", sat["power"], _KEYS["power"])
        vals = {k: field_number(ctx, f"{f}.power.{k}", v, nonneg=True) for k, v in pw.items()}
        if "capacity_wh" not in vals:
            raise ctx.error(f"{f}.power.capacity_wh", "missing (required in a power table)")
        vals.setdefault("initial_wh", vals["capacity_wh"])
        try:
            power = Power(**vals)
        except ValueError as exc:
            raise ctx.error(f"{f}.power", str(exc)) from None
    swath = sat.get("swath_km", DEFAULT_SWATH_KM)
    swath = field_number(ctx, f"{f}.swath_km", swath, positive=True, hi=MAX_SWATH_KM)
    limits = AxisLimits(rate, accel)
    try:
        return Satellite(
            name, orbit, model, limits, math.radians(off), sensor, settle, flex, power, 1e3 * swath
        )
    except ValueError as exc:
        raise ctx.error(f, str(exc)) from None


# --- planner, scenario (targets: jaxspline.readers.targets) ---


def _planner(ctx, pl, duration: float) -> PlannerConfig:
    pl = field_table(ctx, "planner", pl, _KEYS["planner"])
    d, dm = PlannerConfig(), Margins()

    def num(key, default, **kw):
        return field_number(ctx, f"planner.{key}", pl.get(key, default), **kw)

    speeds = pl.get("scan_speeds_km_s", [s / 1e3 for s in d.scan_speeds])
    if not isinstance(speeds, list) or not speeds:
        raise ctx.error("planner.scan_speeds_km_s", f"must be a non-empty list, got {speeds!r}")
    speeds = tuple(
        1e3
        * field_number(ctx, "planner.scan_speeds_km_s", s, positive=True, hi=MAX_SCAN_SPEED_KM_S)
        for s in speeds
    )
    sun = pl.get("sun_elevation_min_deg")
    if sun is not None:
        sun = math.radians(
            field_number(ctx, "planner.sun_elevation_min_deg", sun, lo=-90.0, hi=90.0)
        )
    margins = Margins(
        off_nadir=math.radians(num("off_nadir_margin_deg", dm.off_nadir, nonneg=True)),
        horizon=num("horizon_margin", dm.horizon, lo=0.0, hi=1.0),
        gap=num("gap_margin_s", dm.gap, nonneg=True),
        battery_wh=num("battery_margin_wh", dm.battery_wh, nonneg=True),
        shadow_guard=field_int(ctx, "planner.shadow_guard_steps", pl.get("shadow_guard_steps", 0)),
    )
    time_step = num("time_step_s", d.time_step, positive=True)
    geometry_step = num("geometry_step_s", d.geometry_step, positive=True)
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
    try:
        return PlannerConfig(
            time_step=time_step,
            geometry_step=geometry_step,
            scan_speeds=speeds,
            sun_elevation_min=sun,
            margins=margins,
            exact_max_options=field_int(
                ctx, "planner.exact_max_options", pl.get("exact_max_options", d.exact_max_options)
            ),
            lagrangian_share=num("lagrangian_share", d.lagrangian_share, lo=0.0, hi=0.99),
            bound_worker=field_bool(
                ctx, "planner.bound_worker", pl.get("bound_worker", d.bound_worker)
            ),
            refine_steps=field_int(
                ctx, "planner.refine_steps", pl.get("refine_steps", d.refine_steps)
            ),
            default_time_limit=num("time_limit_s", d.default_time_limit, positive=True),
        )
    except ValueError as exc:  # PlannerConfig's own checks (the fields are checked above)
        raise ctx.error("planner", str(exc)) from None


def _epoch(ctx, value) -> _dt.datetime:
    if isinstance(value, str):
        text = value.strip()
        try:
            value = _dt.datetime.fromisoformat(text[:-1] + "+00:00" if text[-1:] in "Zz" else text)
        except ValueError:
            pass
    if not isinstance(value, _dt.datetime):
        raise ctx.error("scenario.epoch", f"must be an ISO-8601 UTC date-time, got {value!r}")
    return value.replace(tzinfo=_dt.UTC) if value.tzinfo is None else value.astimezone(_dt.UTC)


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
    if "scenario" not in data:
        raise ctx.error("scenario", "missing section [scenario] (epoch, duration_s)")
    sc = field_table(ctx, "scenario", data["scenario"], _KEYS["scenario"])
    name = field_str(ctx, "scenario.name", sc.get("name", Path(source).stem))
    epoch = _epoch(ctx, sc.get("epoch"))
    if ("duration_s" in sc) == ("duration_h" in sc):
        raise ctx.error("scenario.duration_s", "give exactly one of duration_s, duration_h")
    if "duration_s" in sc:
        duration = field_number(
            ctx, "scenario.duration_s", sc["duration_s"], positive=True, hi=MAX_DURATION_S
        )
    else:
        hours = field_number(
            ctx,
            "scenario.duration_h",
            sc["duration_h"],
            positive=True,
            hi=MAX_DURATION_S / SECONDS_PER_HOUR,
        )
        duration = SECONDS_PER_HOUR * hours
    epoch_jd = julian_date(epoch)

    sat_items = field_tables(ctx, data, "satellites", "satellite")
    if not sat_items:
        raise ctx.error("satellites", "missing: give at least one [[satellites]] table")
    sats, names = [], {}
    for i, (f, sat) in enumerate(sat_items):
        s = _satellite(ctx, f, sat, f"sat{i + 1}", epoch_jd, duration)
        if s.name in names:
            raise ctx.error(
                f"{f}.name", f"duplicate satellite name {s.name!r} (also {names[s.name]})"
            )
        names[s.name] = f
        sats.append(s)

    has_areas = "areas" in data or "area" in data
    targets = scenario_targets(ctx, data, base_dir, required=not has_areas)
    planner = _planner(ctx, data.get("planner", {}), duration)
    if not has_areas:
        return Scenario(name, epoch, duration, tuple(sats), targets, planner)

    from jaxspline.readers.area_files import parse_areas
    from jaxspline.readers.areas import cut_areas

    specs = parse_areas(ctx, data, base_dir, sats)
    if targets is None:
        targets = make_targets(
            np.zeros(0, np.int64), np.zeros(0), np.zeros(0), name=np.zeros(0, str)
        )
    sc = cut_areas(Scenario(name, epoch, duration, tuple(sats), targets, planner), specs)
    if len(sc.targets) == 0:
        raise ctx.error(
            "areas", "no targets: no satellite passes over any area and no other targets are given"
        )
    return sc


def load_scenario(path) -> Scenario:
    """Load a scenario TOML file.

    Relative CSV paths in the file start from the file's folder.

    Args:
      path: str or Path of the TOML file.
    Returns:
      Scenario.
    Raises:
      FileNotFoundError: the file is missing.
      ValueError: invalid TOML, or bad content (naming the field / TOML line).
    """
    path = Path(path)
    try:
        text = read_text(path)  # UTF-8, a byte-order mark dropped
    except FileNotFoundError:
        raise FileNotFoundError(f"scenario file not found: {path}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: invalid TOML: {exc}") from None
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
