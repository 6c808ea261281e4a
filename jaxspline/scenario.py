"""Planning scenarios from files: the TOML/CSV schema, loading with named errors, the default.

A scenario file is TOML; angles are degrees in the file and radians in the
:class:`jaxspline.mission.Scenario` it becomes; times are seconds from the epoch.
Unknown keys are errors (typos fail loudly); every error is a ``ValueError`` naming
the field (``satellites[1].rate_deg_s``) and, where it can be located, the TOML line.
Only ``[scenario]``, at least one satellite and at least one target are required::

    targets_csv = "cities.csv"          # top-level key (before any [table]): a CSV of
                                        # targets, path relative to this file's folder;
                                        # a list of paths is accepted too
    [scenario]
    name = "example"                    # label (default: the file's stem)
    epoch = "2026-04-14T00:00:00Z"      # ISO-8601 UTC date-time of t = 0 (required)
    duration_h = 1.0                    # horizon [h], or duration_s [s] (one required)

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
    geometry_step_s = 5.0               # ephemeris / visibility grid [s] (divides time_step_s)
    scan_speeds_km_s = [7.0]            # strip ground scan speeds [km/s]
    sun_elevation_min_deg = 10.0        # daylight rule at the target [deg] (default: none)
    off_nadir_margin_deg = 0.01         # kept back from off_nadir_max_deg [deg]
    horizon_margin = 0.0                # sine of target elevation must exceed this
    gap_margin_s = 0.1                  # added to every rest-to-rest slew time [s]
    battery_margin_wh = 10.0            # battery level kept >= this [Wh]
    shadow_guard_steps = 0              # battery steps of sunlight required around a step
    exact_max_options = 60              # solve exactly up to this many options
    lagrangian_share = 0.3              # search budget share of the Lagrangian phase
    time_limit_s = 30.0                 # default search budget [s]

CSV targets (``targets_csv``, ``[targets_file]``, :func:`load_targets_csv`): a header
row with the columns ``name,lat_deg,lon_deg,priority`` (required) and optionally
``kind,alt_m,duration_s,length_km,azimuth_deg,window_lo_s,window_hi_s,sensor``, same
meanings and units as in ``[[targets]]``; an empty cell takes the default. A bad cell
raises e.g. ``cities.csv row 17, column 'lat_deg': must be within [-90, 90], got '95.2'``
(row = line number in the file).

:func:`default_scenario` loads the packaged ``data/default.toml``: six satellites over
six hours with about 1500 city targets (``data/cities.csv``, made by
``scripts/make_default_targets.py``) and 200 random land strips.
"""

from __future__ import annotations

import csv
import datetime as _dt
import importlib.resources
import math
import re
import tomllib
from pathlib import Path

import numpy as np

from jaxspline.frames import gmst, jd_split, julian_date
from jaxspline.limits import AxisLimits
from jaxspline.mission import (
    MODELS,
    POINT,
    STRIP,
    FlexMode,
    Margins,
    PlannerConfig,
    Power,
    Satellite,
    Scenario,
    Targets,
    make_targets,
)
from jaxspline.orbit import circular_orbit, circular_orbit_over, propagate_tle

__all__ = [
    "DEFAULT_SCENARIO_PATH",
    "Scenario",
    "default_scenario",
    "load_scenario",
    "load_targets_csv",
    "parse_scenario",
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
DEFAULT_POINT_DURATION_S = 10.0
DEFAULT_STRIP_FRACTION = 0.2
DEFAULT_RANDOM_DURATION_S = (10.0, 30.0)
DEFAULT_RANDOM_LENGTH_KM = (20.0, 60.0)
DEFAULT_RANDOM_PRIORITY = (1, 10)
LAT_RANGE_DEG = (-90.0, 90.0)
LON_RANGE_DEG = (-180.0, 180.0)
LAND_SAMPLE_ROUNDS = 200  # rejection-sampling batches before giving up on a region
LAND_BATCH_MIN = 1024

_ORBIT_KEYS = ("altitude_km", "inclination_deg", "raan_deg", "arg_lat_deg", "over")
_SAT_MODEL_KEYS = (
    "name tle model rate_deg_s accel_deg_s2 off_nadir_max_deg sensor settle_s flex power"
)
_KEYS = {
    name: frozenset(keys.split())
    for name, keys in {
        "scenario": "name epoch duration_s duration_h",
        "satellite": " ".join(_ORBIT_KEYS) + " " + _SAT_MODEL_KEYS,
        "over": "lat_deg lon_deg t_s descending",
        "flex": "freq_hz damping tolerance_deg",
        "power": "capacity_wh initial_wh idle_w imaging_w slew_w charge_w",
        "target": "kind name lat_deg lon_deg alt_m duration_s length_km azimuth_deg priority "
        "window_s sensor",
        "targets_file": "path",
        "random_targets": "seed count lat_deg lon_deg land_only strip_fraction duration_s "
        "length_km azimuth_deg priority",
        "planner": "time_step_s geometry_step_s scan_speeds_km_s sun_elevation_min_deg "
        "off_nadir_margin_deg horizon_margin gap_margin_s battery_margin_wh shadow_guard_steps "
        "exact_max_options lagrangian_share time_limit_s",
    }.items()
}
_TOP = frozenset(
    "scenario satellites satellite targets routes targets_csv targets_file random_targets "
    "planner".split()
)
CSV_REQUIRED = ("name", "lat_deg", "lon_deg", "priority")
CSV_OPTIONAL = tuple(
    "kind alt_m duration_s length_km azimuth_deg window_lo_s window_hi_s sensor".split()
)
_KINDS = {"point": POINT, "strip": STRIP}
_IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


class _Ctx:
    """Error helper: names the field and, when the raw text is known, its TOML line."""

    def __init__(self, source: str, text: str | None):
        self.source = source
        self.lines = text.splitlines() if text is not None else None

    def _find(self, pattern: re.Pattern, start: int, stop_at_header: bool) -> int | None:
        for i in range(start, len(self.lines)):
            if stop_at_header and i > start and re.match(r"^\s*\[", self.lines[i]):
                return None
            if pattern.search(self.lines[i]):
                return i
        return None

    def line_of(self, field: str) -> int | None:
        """1-based TOML line of ``field`` (``table[index].key...``), or None."""
        if self.lines is None:
            return None
        parts = re.findall(_IDENT + r"|\[\d+\]", field)
        if not parts:
            return None
        table = parts[0]
        index = int(parts[1][1:-1]) if len(parts) > 1 and parts[1].startswith("[") else None
        keys = [p for p in parts[1:] if not p.startswith("[")]
        if len(parts) == 1:  # a top-level key before the first header, or a table header
            top = re.compile(r"^\s*" + re.escape(table) + r"\s*=")
            for i, ln in enumerate(self.lines):
                if re.match(r"^\s*\[", ln):
                    break
                if top.search(ln):
                    return i + 1
        header = re.compile(r"^\s*\[\[?\s*" + re.escape(table) + r"\s*\]\]?\s*(#.*)?$")
        start, seen = None, -1
        for i, ln in enumerate(self.lines):
            if header.match(ln):
                seen += 1
                if index is None or seen == index:
                    start = i
                    break
        if start is None:
            return None
        if not keys:
            return start + 1
        for key in reversed(keys):  # a missing inner key: the line of its parent
            pat = re.compile(r"(^|[{,])\s*" + re.escape(key) + r"\s*=")
            found = self._find(pat, start, True)
            if found is not None:
                return found + 1
        return start + 1

    def error(self, field: str, msg: str) -> ValueError:
        """A ValueError ``source: field (line N): msg``."""
        line = self.line_of(field)
        where = f" (line {line})" if line is not None else ""
        return ValueError(f"{self.source}: {field}{where}: {msg}")


_REQUIRED = object()


def _num(
    raw, err, *, default=_REQUIRED, text=False, positive=False, nonneg=False, lo=None, hi=None
):
    """``raw`` as a checked float; ``err(msg)`` builds the error; ``text`` parses strings."""
    if raw is None:
        if default is _REQUIRED:
            raise err("missing")
        return default
    if text and isinstance(raw, str):
        try:
            v = float(raw)
        except ValueError:
            raise err(f"must be a number, got {raw!r}") from None
    elif isinstance(raw, bool) or not isinstance(raw, int | float):
        raise err(f"must be a number, got {raw!r}")
    else:
        v = float(raw)
    if not math.isfinite(v):
        raise err(f"must be finite, got {raw!r}")
    if positive and v <= 0:
        raise err(f"must be > 0, got {raw!r}")
    if nonneg and v < 0:
        raise err(f"must be >= 0, got {raw!r}")
    if lo is not None and hi is not None and not lo <= v <= hi:
        raise err(f"must be within [{lo:g}, {hi:g}], got {raw!r}")
    if hi is not None and lo is None and v > hi:
        raise err(f"must be <= {hi:g}, got {raw!r}")
    return v


def _number(ctx, field, value, **kw) -> float:
    return _num(value, lambda m: ctx.error(field, m), **kw)


def _int(ctx, field, value, minimum=0) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.error(field, f"must be an integer, got {value!r}")
    if value < minimum:
        raise ctx.error(field, f"must be >= {minimum}, got {value!r}")
    return int(value)


def _bool(ctx, field, value) -> bool:
    if not isinstance(value, bool):
        raise ctx.error(field, f"must be true or false, got {value!r}")
    return value


def _str(ctx, field, value, allow_empty=True) -> str:
    if not isinstance(value, str) or (not allow_empty and not value.strip()):
        raise ctx.error(
            field, f"must be a {'' if allow_empty else 'non-empty '}string, got {value!r}"
        )
    return value


def _pair(ctx, field, value, **kw) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise ctx.error(field, f"must be a list [lo, hi], got {value!r}")
    lo, hi = (_number(ctx, field, v, **kw) for v in value)
    if lo > hi:
        raise ctx.error(field, f"needs lo <= hi, got {value!r}")
    return lo, hi


def _table(ctx, field, tab, keys) -> dict:
    if not isinstance(tab, dict):
        raise ctx.error(field, f"must be a table, got {tab!r}")
    unknown = sorted(set(tab) - keys)
    if unknown:
        raise ctx.error(f"{field}.{unknown[0]}", f"unknown key (allowed: {sorted(keys)})")
    return tab


def _tables(ctx, data, name, alias) -> list[tuple[str, dict]]:
    """(field label, table) of each entry of array ``name`` or its alias (one table or many)."""
    if name in data and alias in data:
        raise ctx.error(alias, f"give either [[{name}]] or its alias [{alias}], not both")
    key = name if name in data else alias
    items = data.get(key, [])
    if isinstance(items, dict):
        return [(key, items)]
    if not isinstance(items, list):
        raise ctx.error(key, f"must be an array of tables [[{key}]], got {items!r}")
    return [(f"{key}[{i}]", it) for i, it in enumerate(items)]


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
    alt = _number(ctx, f"{f}.altitude_km", alt, lo=ALTITUDE_RANGE_KM[0], hi=ALTITUDE_RANGE_KM[1])
    inc = sat.get("inclination_deg")
    if inc is not None:
        inc = math.radians(_number(ctx, f"{f}.inclination_deg", inc, lo=0.0, hi=180.0))
    if "over" not in sat:
        raan = _number(ctx, f"{f}.raan_deg", sat.get("raan_deg", 0.0))
        u0 = _number(ctx, f"{f}.arg_lat_deg", sat.get("arg_lat_deg", 0.0))
        return circular_orbit(1e3 * alt, inc, math.radians(raan), math.radians(u0))
    clash = [k for k in ("raan_deg", "arg_lat_deg") if k in sat]
    if clash:
        raise ctx.error(f"{f}.{clash[0]}", "cannot be combined with over (it places the orbit)")
    ov = _table(ctx, f"{f}.over", sat["over"], _KEYS["over"])
    lat = _number(ctx, f"{f}.over.lat_deg", ov.get("lat_deg", 0.0), lo=-90.0, hi=90.0)
    lon = _number(ctx, f"{f}.over.lon_deg", ov.get("lon_deg", 0.0))
    t_over = _number(ctx, f"{f}.over.t_s", ov.get("t_s", duration / 2))
    desc = _bool(ctx, f"{f}.over.descending", ov.get("descending", True))
    gmst0 = float(gmst(*jd_split(epoch_jd, 0.0)))
    try:
        return circular_orbit_over(
            math.radians(lat), math.radians(lon), t_over, gmst0, 1e3 * alt, inc, descending=desc
        )
    except ValueError as exc:
        raise ctx.error(f"{f}.over.lat_deg", str(exc)) from None


def _rate(ctx, field, value, model):
    if model != "per_channel":
        if isinstance(value, list):
            raise ctx.error(field, f"must be one number for model {model!r}, got {value!r}")
        return math.radians(_number(ctx, field, value, positive=True))
    if isinstance(value, list):
        if len(value) != 3:
            raise ctx.error(field, f"must be one number or 3 (roll, pitch, yaw), got {value!r}")
        vals = [_number(ctx, field, v, positive=True) for v in value]
    else:
        vals = [_number(ctx, field, value, positive=True)] * 3
    return np.radians(np.asarray(vals))


def _satellite(ctx, f, sat, default_name, epoch_jd, duration) -> Satellite:
    sat = _table(ctx, f, sat, _KEYS["satellite"])
    name = _str(ctx, f"{f}.name", sat.get("name", default_name), allow_empty=False)
    orbit = _orbit(ctx, f, sat, epoch_jd, duration)
    model = sat.get("model", "per_channel")
    if model not in MODELS:
        raise ctx.error(f"{f}.model", f"must be one of {MODELS}, got {model!r}")
    rate = _rate(ctx, f"{f}.rate_deg_s", sat.get("rate_deg_s", DEFAULT_RATE_DEG_S), model)
    accel = _rate(ctx, f"{f}.accel_deg_s2", sat.get("accel_deg_s2", DEFAULT_ACCEL_DEG_S2), model)
    off = _number(
        ctx,
        f"{f}.off_nadir_max_deg",
        sat.get("off_nadir_max_deg", DEFAULT_OFF_NADIR_DEG),
        positive=True,
        hi=MAX_OFF_NADIR_DEG,
    )
    sensor = _str(ctx, f"{f}.sensor", sat.get("sensor", DEFAULT_SENSOR), allow_empty=False)
    settle = _number(ctx, f"{f}.settle_s", sat.get("settle_s", 0.0), nonneg=True)
    flex = None
    if "flex" in sat:
        if model != "flexible":
            raise ctx.error(f"{f}.flex", f"only used by model 'flexible' (model is {model!r})")
        fx = _table(ctx, f"{f}.flex", sat["flex"], _KEYS["flex"])
        freq_hz = _number(ctx, f"{f}.flex.freq_hz", fx.get("freq_hz"), positive=True)
        kw = {"freq": 2 * math.pi * freq_hz}
        if "damping" in fx:
            kw["damping"] = _number(ctx, f"{f}.flex.damping", fx["damping"], nonneg=True)
        if "tolerance_deg" in fx:
            tol = _number(ctx, f"{f}.flex.tolerance_deg", fx["tolerance_deg"], positive=True)
            kw["tolerance"] = math.radians(tol)
        flex = FlexMode(**kw)
    elif model == "flexible":
        raise ctx.error(
            f"{f}.model",
            "'flexible' needs flex = { freq_hz = ..., damping = ..., tolerance_deg = ... }",
        )
    power = None
    if "power" in sat:
        pw = _table(ctx, f"{f}.power", sat["power"], _KEYS["power"])
        vals = {k: _number(ctx, f"{f}.power.{k}", v, nonneg=True) for k, v in pw.items()}
        if "capacity_wh" not in vals:
            raise ctx.error(f"{f}.power.capacity_wh", "missing (required in a power table)")
        vals.setdefault("initial_wh", vals["capacity_wh"])
        try:
            power = Power(**vals)
        except ValueError as exc:
            raise ctx.error(f"{f}.power", str(exc)) from None
    limits = AxisLimits(rate, accel)
    try:
        return Satellite(name, orbit, model, limits, math.radians(off), sensor, settle, flex, power)
    except ValueError as exc:
        raise ctx.error(f, str(exc)) from None


# --- targets ---


def _target_row(get, err, default_name, text=False) -> tuple:
    """One target from ``get(column) -> raw or None``; ``err(column)(msg)`` builds errors.

    Columns as in the CSV format. Returns (name, kind, lat, lon, alt, duration, length,
    azimuth, priority, t_lo, t_hi, sensor) in degrees, metres, seconds.
    """

    def num(col, **kw):
        return _num(get(col), err(col), text=text, **kw)

    def string(col, default):
        raw = get(col)
        if raw is None:
            return default
        if not isinstance(raw, str):
            raise err(col)(f"must be a string, got {raw!r}")
        return raw.strip()

    name = string("name", default_name) or default_name
    kind = string("kind", "point")
    if kind not in _KINDS:
        raise err("kind")(f"must be 'point' or 'strip', got {kind!r}")
    lat = num("lat_deg", lo=LAT_RANGE_DEG[0], hi=LAT_RANGE_DEG[1])
    lon = num("lon_deg", lo=LON_RANGE_DEG[0], hi=LON_RANGE_DEG[1])
    alt = num("alt_m", default=0.0)
    prio = num("priority", default=1.0, positive=True)
    if kind == "strip":
        if get("duration_s") is not None:
            raise err("duration_s")("a strip has no duration_s (it is length / scan speed)")
        length = 1e3 * num("length_km", positive=True)
        az = num("azimuth_deg", default=0.0)
        dur = 0.0
    else:
        for col in ("length_km", "azimuth_deg"):
            if get(col) is not None:
                raise err(col)("a point has no length_km / azimuth_deg (use kind 'strip')")
        dur, length, az = num("duration_s", default=DEFAULT_POINT_DURATION_S, positive=True), 0, 0
    t_lo = num("window_lo_s", default=-np.inf)
    t_hi = num("window_hi_s", default=np.inf)
    if t_hi < t_lo:
        raise err("window_hi_s")(f"window needs lo <= hi, got [{t_lo:g}, {t_hi:g}]")
    if t_hi < t_lo + dur:
        raise err("window_hi_s")(
            f"window [{t_lo:g}, {t_hi:g}] s is shorter than the imaging time {dur:g} s"
        )
    sensor = string("sensor", "")
    return (name, _KINDS[kind], lat, lon, alt, dur, length, az, prio, t_lo, t_hi, sensor)


def _targets_from_rows(rows) -> Targets:
    cols = list(zip(*rows, strict=True))
    num = [np.asarray(c, np.float64) for c in cols[2:11]]
    lat, lon, alt, dur, length, az, prio, t_lo, t_hi = num
    return make_targets(
        np.asarray(cols[1], np.int64),
        np.radians(lat),
        np.radians(lon),
        alt=alt,
        duration=dur,
        length=length,
        azimuth=np.radians(az),
        value=prio,
        t_lo=t_lo,
        t_hi=t_hi,
        sensor=np.asarray(cols[11], dtype=object),
        name=np.asarray(cols[0], dtype=str),
    )


def _toml_targets(ctx, items) -> Targets | None:
    rows = []
    for i, (f, rt) in enumerate(items):
        rt = dict(_table(ctx, f, rt, _KEYS["target"]))
        if "window_s" in rt:
            win = rt.pop("window_s")
            if not isinstance(win, list) or len(win) != 2:
                raise ctx.error(f"{f}.window_s", f"must be a list [lo, hi], got {win!r}")
            rt["window_lo_s"], rt["window_hi_s"] = win

        def err(col, f=f):
            key = "window_s" if col.startswith("window_") else col
            return lambda m: ctx.error(f"{f}.{key}", m)

        rows.append(_target_row(rt.get, err, f"target_{i + 1}"))
    return _targets_from_rows(rows) if rows else None


def load_targets_csv(path) -> Targets:
    """Targets from a CSV file (columns in the module docstring; angles in degrees).

    Raises FileNotFoundError for a missing file and ValueError naming the file, the
    row (line number) and the column for bad content.
    """
    path = Path(path)
    label = path.name
    try:
        f = path.open(newline="", encoding="utf-8-sig")
    except FileNotFoundError:
        raise FileNotFoundError(f"targets CSV not found: {path}") from None
    rows = []
    with f:
        reader = csv.reader(f)
        header = [h.strip() for h in next(reader, [])]
        allowed = CSV_REQUIRED + CSV_OPTIONAL
        for h in header:
            if h not in allowed:
                raise ValueError(
                    f"{label} row 1, column {h!r}: unknown column (allowed: {allowed})"
                )
            if header.count(h) > 1:
                raise ValueError(f"{label} row 1, column {h!r}: appears twice")
        for h in CSV_REQUIRED:
            if h not in header:
                raise ValueError(f"{label} row 1, column {h!r}: missing (required: {CSV_REQUIRED})")
        for cells in reader:
            line = reader.line_num
            if not any(c.strip() for c in cells):
                continue
            if len(cells) != len(header):
                raise ValueError(
                    f"{label} row {line}: {len(cells)} cells, the header has {len(header)}"
                )
            rec = {h: (c.strip() or None) for h, c in zip(header, cells, strict=True)}
            if rec["name"] is None:
                raise ValueError(f"{label} row {line}, column 'name': must not be empty")

            def err(col, line=line):
                return lambda m: ValueError(f"{label} row {line}, column {col!r}: {m}")

            rows.append(_target_row(rec.get, err, f"row_{line}", text=True))
    if not rows:
        raise ValueError(f"{label}: no target rows (a header row and at least one target)")
    return _targets_from_rows(rows)


def _land_positions(ctx, rng, count, lat, lon):
    """``count`` uniform (lat, lon) [deg] in the box, rejecting sea (global_land_mask)."""
    from global_land_mask import globe

    batch = max(4 * count, LAND_BATCH_MIN)
    got_lat, got_lon, have = [], [], 0
    for _ in range(LAND_SAMPLE_ROUNDS):
        la, lo = rng.uniform(*lat, batch), rng.uniform(*lon, batch)
        keep = np.asarray(globe.is_land(la, lo), bool)
        got_lat.append(la[keep])
        got_lon.append(lo[keep])
        have += int(keep.sum())
        if have >= count:
            return np.concatenate(got_lat)[:count], np.concatenate(got_lon)[:count]
    raise ctx.error(
        "random_targets.land_only",
        f"found only {have} land points in {LAND_SAMPLE_ROUNDS * batch} draws in "
        f"lat {list(lat)}, lon {list(lon)} deg; widen the region or set land_only = false",
    )


def _random_targets(ctx, rt) -> Targets:
    f = "random_targets"
    rt = _table(ctx, f, rt, _KEYS[f])
    seed = _int(ctx, f"{f}.seed", rt.get("seed", 0))
    if "count" not in rt:
        raise ctx.error(f"{f}.count", "missing (how many targets to generate)")
    count = _int(ctx, f"{f}.count", rt["count"], 1)

    def pair(key, default, **kw):
        return _pair(ctx, f"{f}.{key}", rt.get(key, list(default)), **kw)

    lat = pair("lat_deg", LAT_RANGE_DEG, lo=LAT_RANGE_DEG[0], hi=LAT_RANGE_DEG[1])
    lon = pair("lon_deg", LON_RANGE_DEG, lo=LON_RANGE_DEG[0], hi=LON_RANGE_DEG[1])
    land = _bool(ctx, f"{f}.land_only", rt.get("land_only", False))
    frac = rt.get("strip_fraction", DEFAULT_STRIP_FRACTION)
    frac = _number(ctx, f"{f}.strip_fraction", frac, lo=0.0, hi=1.0)
    dur = pair("duration_s", DEFAULT_RANDOM_DURATION_S, positive=True)
    length = pair("length_km", DEFAULT_RANDOM_LENGTH_KM, positive=True)
    az = pair("azimuth_deg", (0.0, 360.0))
    prio = rt.get("priority", list(DEFAULT_RANDOM_PRIORITY))
    if not isinstance(prio, list) or len(prio) != 2:
        raise ctx.error(f"{f}.priority", f"must be a list [lo, hi] of integers, got {prio!r}")
    p_lo, p_hi = (_int(ctx, f"{f}.priority", p, 1) for p in prio)
    if p_lo > p_hi:
        raise ctx.error(f"{f}.priority", f"needs lo <= hi, got {prio!r}")
    rng = np.random.default_rng(seed)
    if land:
        la, lo = _land_positions(ctx, rng, count, lat, lon)
    else:
        la, lo = rng.uniform(*lat, count), rng.uniform(*lon, count)
    kind = np.where(rng.random(count) < frac, STRIP, POINT)
    return make_targets(
        kind,
        np.radians(la),
        np.radians(lo),
        duration=rng.uniform(*dur, count),
        length=1e3 * rng.uniform(*length, count),
        azimuth=np.radians(rng.uniform(*az, count)),
        value=rng.integers(p_lo, p_hi + 1, count).astype(np.float64),
        name=np.array([f"random_{i + 1:04d}" for i in range(count)]),
    )


def _csv_paths(ctx, data, base_dir) -> list[Path]:
    """The target CSV files named by ``targets_csv`` and ``[targets_file]``, resolved."""
    out = []
    sources = [("targets_csv", data.get("targets_csv"))]
    if "targets_file" in data:
        tf = _table(ctx, "targets_file", data["targets_file"], _KEYS["targets_file"])
        sources.append(("targets_file.path", tf.get("path")))
        if "path" not in tf:
            raise ctx.error("targets_file.path", "missing (the CSV file)")
    for field, value in sources:
        if value is None:
            continue
        for p in value if isinstance(value, list) else [value]:
            p = Path(_str(ctx, field, p, allow_empty=False))
            if not p.is_absolute() and base_dir is not None:
                p = Path(base_dir) / p
            if not p.is_file():
                raise ctx.error(field, f"targets CSV not found: {p}")
            out.append(p)
    return out


# --- planner, scenario ---


def _planner(ctx, pl) -> PlannerConfig:
    pl = _table(ctx, "planner", pl, _KEYS["planner"])
    d, dm = PlannerConfig(), Margins()

    def num(key, default, **kw):
        return _number(ctx, f"planner.{key}", pl.get(key, default), **kw)

    speeds = pl.get("scan_speeds_km_s", [s / 1e3 for s in d.scan_speeds])
    if not isinstance(speeds, list) or not speeds:
        raise ctx.error("planner.scan_speeds_km_s", f"must be a non-empty list, got {speeds!r}")
    sun = pl.get("sun_elevation_min_deg")
    if sun is not None:
        sun = math.radians(_number(ctx, "planner.sun_elevation_min_deg", sun, lo=-90.0, hi=90.0))
    margins = Margins(
        off_nadir=math.radians(num("off_nadir_margin_deg", dm.off_nadir, nonneg=True)),
        horizon=num("horizon_margin", dm.horizon, lo=0.0, hi=1.0),
        gap=num("gap_margin_s", dm.gap, nonneg=True),
        battery_wh=num("battery_margin_wh", dm.battery_wh, nonneg=True),
        shadow_guard=_int(ctx, "planner.shadow_guard_steps", pl.get("shadow_guard_steps", 0)),
    )
    try:
        return PlannerConfig(
            time_step=num("time_step_s", d.time_step, positive=True),
            geometry_step=num("geometry_step_s", d.geometry_step, positive=True),
            scan_speeds=tuple(
                1e3 * _number(ctx, "planner.scan_speeds_km_s", s, positive=True) for s in speeds
            ),
            sun_elevation_min=sun,
            margins=margins,
            exact_max_options=_int(
                ctx, "planner.exact_max_options", pl.get("exact_max_options", d.exact_max_options)
            ),
            lagrangian_share=num("lagrangian_share", d.lagrangian_share, lo=0.0, hi=0.99),
            default_time_limit=num("time_limit_s", d.default_time_limit, positive=True),
        )
    except ValueError as exc:
        raise ctx.error("planner.time_step_s", str(exc)) from None


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

    ``text`` (the raw TOML) lets errors cite line numbers; ``base_dir`` is the folder
    that relative CSV paths start from (None: the working directory). Raises
    ValueError naming the field.
    """
    ctx = _Ctx(source, text)
    if not isinstance(data, dict):
        raise ValueError(f"{source}: a scenario must be a table, got {type(data).__name__}")
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise ctx.error(unknown[0], f"unknown section or key (allowed: {sorted(_TOP)})")
    if "scenario" not in data:
        raise ctx.error("scenario", "missing section [scenario] (epoch, duration_s)")
    sc = _table(ctx, "scenario", data["scenario"], _KEYS["scenario"])
    name = _str(ctx, "scenario.name", sc.get("name", Path(source).stem))
    epoch = _epoch(ctx, sc.get("epoch"))
    if ("duration_s" in sc) == ("duration_h" in sc):
        raise ctx.error("scenario.duration_s", "give exactly one of duration_s, duration_h")
    if "duration_s" in sc:
        duration = _number(ctx, "scenario.duration_s", sc["duration_s"], positive=True)
    else:
        hours = _number(ctx, "scenario.duration_h", sc["duration_h"], positive=True)
        duration = SECONDS_PER_HOUR * hours
    epoch_jd = julian_date(epoch)

    sat_items = _tables(ctx, data, "satellites", "satellite")
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

    parts = []
    explicit = _toml_targets(ctx, _tables(ctx, data, "targets", "routes"))
    if explicit is not None:
        parts.append(explicit)
    parts += [load_targets_csv(p) for p in _csv_paths(ctx, data, base_dir)]
    if "random_targets" in data:
        parts.append(_random_targets(ctx, data["random_targets"]))
    if not parts:
        raise ctx.error(
            "targets", "no targets: give [[targets]], targets_csv and/or [random_targets]"
        )
    targets = parts[0]
    for more in parts[1:]:
        targets = targets.concat(more)

    planner = _planner(ctx, data.get("planner", {}))
    return Scenario(name, epoch, duration, tuple(sats), targets, planner)


def load_scenario(path) -> Scenario:
    """Load a scenario TOML file (ValueError naming the field / TOML line on bad content).

    Relative CSV paths in the file start from the file's folder.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
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
    """
    return load_scenario(DEFAULT_SCENARIO_PATH)
