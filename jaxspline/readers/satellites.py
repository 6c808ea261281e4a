"""Satellite tables of scenario files: orbits (TLE or circular), agility, sensor, battery.

The schema is documented with the rest of the scenario file in
:mod:`jaxspline.readers.scenario`; the ranges of the numbers in
:mod:`jaxspline.readers.ranges`. Every error is a ``ValueError`` naming the field
(``satellites[1].rate_deg_s``), its TOML line and the value.

A TLE is two 69-column lines in the NORAD format: line numbers ``1`` and ``2``, the
same catalogue number on both, and the modulo-10 checksum in column 69 (the sum of
the digits of columns 1-68, each minus sign counting 1). The TLE's epoch (line 1,
columns 19-32) must lie within :data:`jaxspline.readers.ranges.MAX_TLE_AGE_DAYS` of
every instant of the horizon: SGP4 is meaningful for days to weeks around it.
"""

from __future__ import annotations

import datetime as _dt
import math

import numpy as np

from jaxspline.base.elements import (
    circular_orbit,
    circular_orbit_over,
    gmst,
    jd_split,
    julian_date,
    parse_tle,
    sso_inclination,
)
from jaxspline.base.models import maneuver_model
from jaxspline.kernels.flex import mode_suppressible
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.fields import (
    field_bool,
    field_int,
    field_number,
    field_pair,
    field_str,
    field_table,
    field_tables,
)
from jaxspline.readers.mission import DEFAULT_SWATH, FlexMode, Power, Satellite
from jaxspline.readers.ranges import MAX_NAME_CHARS, MAX_TLE_AGE_DAYS, RANGES, bounds

__all__ = ["SATELLITE_KEYS", "parse_satellites", "tle_epoch", "tle_line_problem"]

DEFAULT_ALTITUDE_KM = 600.0
DEFAULT_RATE_DEG_S = 2.0
DEFAULT_ACCEL_DEG_S2 = 1.0
DEFAULT_OFF_NADIR_DEG = 45.0
DEFAULT_SENSOR = "visible"
DEFAULT_SWATH_KM = DEFAULT_SWATH / 1e3
TLE_COLUMNS = 69
#: Largest relative difference of ``fov_deg`` and ``pixels x ifov_deg`` when both are given.
FOV_TOLERANCE = 1e-3
_SECONDS_PER_DAY = 86400.0

#: Angles of TLE line 2: (name, first column index, end index, upper end [deg]).
_TLE_ANGLES = (
    ("inclination", 8, 16, 180.0),
    ("right ascension of the node", 17, 25, 360.0),
    ("argument of perigee", 34, 42, 360.0),
    ("mean anomaly", 43, 51, 360.0),
)
_ORBIT_KEYS = ("altitude_km", "inclination_deg", "raan_deg", "arg_lat_deg", "over")
#: Keys of a ``[[satellites]]`` table and of its inline tables.
SATELLITE_KEYS = {
    name: frozenset(keys.split())
    for name, keys in {
        "satellite": " ".join(_ORBIT_KEYS) + " name tle model rate_deg_s accel_deg_s2 "
        "off_nadir_max_deg sensor settle_s flex power swath_km fov_deg ifov_deg pixels "
        "edge_off_nadir_deg strip_duration_s duty_s_per_orbit",
        "over": "lat_deg lon_deg t_s descending",
        "flex": "freq_hz damping tolerance_deg",
        "power": "capacity_wh initial_wh idle_w imaging_w slew_w charge_w",
    }.items()
}


def _num(ctx, field, value, key, horizon=None, **kw) -> float:
    """``value`` checked against the range of ``satellites[].<key>``."""
    return field_number(ctx, field, value, **bounds(f"satellites[].{key}", horizon), **kw)


# --- TLE ---


def tle_checksum(line: str) -> int:
    """The TLE checksum of a line: digits summed, ``-`` counts 1, modulo 10 (columns 1-68).

    Args:
      line: TLE line.
    Returns:
      int in 0..9.
    """
    return sum(int(c) if c.isdigit() else c == "-" for c in line[: TLE_COLUMNS - 1]) % 10


def tle_line_problem(line: str, num: int) -> str | None:
    """What is wrong with one TLE line, or None: its columns, its line number, its
    checksum and, on line 2, its angles (inclination in [0, 180] deg, the node, perigee
    and mean anomaly in [0, 360] deg; SGP4 takes other values without a word).

    Args:
      line: the line, trailing blanks removed.
      num: 1 or 2.
    Returns:
      str (a message without the field's name) or None.
    """
    if len(line) != TLE_COLUMNS or line[:2] != f"{num} ":
        return (
            f"line {num} must have {TLE_COLUMNS} columns and start with '{num} ', "
            f"got {len(line)} columns: {line!r}"
        )
    if not line[-1].isdigit() or int(line[-1]) != tle_checksum(line):
        return (
            f"line {num} checksum (column 69) is {line[-1]!r}, the line's digits give "
            f"{tle_checksum(line)}: a damaged or edited line"
        )
    for name, a, b, hi in _TLE_ANGLES if num == 2 else ():
        try:
            value = float(line[a:b])
        except ValueError:
            return f"line 2 {name} (columns {a + 1}-{b}) is not a number: {line[a:b]!r}"
        if not 0.0 <= value <= hi:
            return (
                f"line 2 {name} (columns {a + 1}-{b}) must be within [0, {hi:g}] deg, got {value:g}"
            )
    return None


def tle_epoch(line1: str) -> _dt.datetime:
    """The epoch of a TLE (line 1, columns 19-32: two-digit year, day of the year).

    Args:
      line1: the first TLE line.
    Returns:
      datetime (UTC); years 57-99 are 1957-1999, 00-56 are 2000-2056.
    Raises:
      ValueError: the columns are not a year and a day of the year.
    """
    field = line1[18:32]
    try:
        yy, day = int(field[:2]), float(field[2:])
    except ValueError:
        raise ValueError(
            f"line 1 columns 19-32 must be the epoch YYDDD.DDDDDDDD, got {field!r}"
        ) from None
    if not 1.0 <= day < 367.0:
        raise ValueError(f"line 1 epoch day of the year must be in [1, 367), got {day!r}")
    year = 1900 + yy if yy >= 57 else 2000 + yy
    return _dt.datetime(year, 1, 1, tzinfo=_dt.UTC) + _dt.timedelta(days=day - 1.0)


def _tle_lines(ctx, field, tle) -> tuple[str, str]:
    """The two lines of a TLE, checked (format, catalogue number, checksums)."""
    if not (isinstance(tle, list) and len(tle) == 2 and all(isinstance(s, str) for s in tle)):
        raise ctx.error(field, f"must be a list of the two TLE lines, got {tle!r}")
    lines = tuple(s.rstrip() for s in tle)
    for k, line in enumerate(lines, 1):
        field_str(ctx, field, line)  # no control characters
        problem = tle_line_problem(line, k)
        if problem:
            raise ctx.error(field, problem)
    if lines[0][2:7] != lines[1][2:7]:
        raise ctx.error(
            field,
            f"the lines are of two satellites (catalogue numbers {lines[0][2:7]!r} and "
            f"{lines[1][2:7]!r})",
        )
    return lines


def _tle(ctx, f, sat, epoch, duration) -> tuple[str, str]:
    """The orbit of a satellite given by ``tle``: checked lines, epoch near the horizon."""
    clash = [k for k in _ORBIT_KEYS if k in sat]
    if clash:
        raise ctx.error(f"{f}.{clash[0]}", "cannot be combined with tle (a TLE is the orbit)")
    lines = _tle_lines(ctx, f"{f}.tle", sat["tle"])
    try:
        t_tle = tle_epoch(lines[0])
    except ValueError as exc:
        raise ctx.error(f"{f}.tle", str(exc)) from None
    end = epoch + _dt.timedelta(seconds=duration)
    age = max(abs((epoch - t_tle).total_seconds()), abs((end - t_tle).total_seconds()))
    if age > MAX_TLE_AGE_DAYS * _SECONDS_PER_DAY:
        raise ctx.error(
            f"{f}.tle",
            f"the TLE's epoch {t_tle:%Y-%m-%d %H:%M} UTC is {age / _SECONDS_PER_DAY:.1f} days "
            f"from the horizon (scenario.epoch {epoch:%Y-%m-%d %H:%M} UTC + duration); SGP4 "
            f"is meaningful within {MAX_TLE_AGE_DAYS:g} days: use a TLE of the scenario's dates",
        )
    try:
        err = parse_tle(lines[0], lines[1]).sgp4(*jd_split(julian_date(epoch), 0.0))[0]
    except ValueError as exc:
        raise ctx.error(f"{f}.tle", str(exc)) from None
    if int(err) != 0:
        raise ctx.error(f"{f}.tle", f"SGP4 error code {int(err)} at the epoch")
    return lines


# --- circular orbits ---


def _circular(ctx, f, sat, epoch_jd, duration):
    """The circular orbit of a satellite given by altitude, inclination and node or ``over``."""
    raw = sat.get("altitude_km", DEFAULT_ALTITUDE_KM)
    alt = _num(ctx, f"{f}.altitude_km", raw, "altitude_km")
    inc = sat.get("inclination_deg")
    if inc is not None:
        inc = math.radians(_num(ctx, f"{f}.inclination_deg", inc, "inclination_deg"))
    else:
        try:
            inc = sso_inclination(1e3 * alt)
        except ValueError:
            raise ctx.error(
                f"{f}.altitude_km",
                f"{raw} km admits no Sun-synchronous orbit (the orbit of a satellite without "
                "inclination_deg): give inclination_deg, or a lower altitude_km",
            ) from None
    if "over" not in sat:
        raan = _num(ctx, f"{f}.raan_deg", sat.get("raan_deg", 0.0), "raan_deg")
        u0 = _num(ctx, f"{f}.arg_lat_deg", sat.get("arg_lat_deg", 0.0), "arg_lat_deg")
        return circular_orbit(1e3 * alt, inc, math.radians(raan), math.radians(u0))
    clash = [k for k in ("raan_deg", "arg_lat_deg") if k in sat]
    if clash:
        raise ctx.error(f"{f}.{clash[0]}", "cannot be combined with over (it places the orbit)")
    ov = field_table(ctx, f"{f}.over", sat["over"], SATELLITE_KEYS["over"])
    lat = _num(ctx, f"{f}.over.lat_deg", ov.get("lat_deg", 0.0), "over.lat_deg")
    lon = _num(ctx, f"{f}.over.lon_deg", ov.get("lon_deg", 0.0), "over.lon_deg")
    t_over = _num(ctx, f"{f}.over.t_s", ov.get("t_s", duration / 2), "over.t_s", duration)
    desc = field_bool(ctx, f"{f}.over.descending", ov.get("descending", True))
    gmst0 = float(gmst(*jd_split(epoch_jd, 0.0)))
    try:
        return circular_orbit_over(
            math.radians(lat), math.radians(lon), t_over, gmst0, 1e3 * alt, inc, descending=desc
        )
    except ValueError:  # |lat| above what the inclination reaches
        reach = circular_orbit(1e3 * alt, inc, 0.0, 0.0).inclination
        reach = math.degrees(min(float(reach), math.pi - float(reach)))
        raise ctx.error(
            f"{f}.over.lat_deg",
            f"{lat:g} deg is not reachable: the orbit's ground track reaches latitudes "
            f"within +-{reach:.4g} deg (its inclination)",
        ) from None


# --- agility, flexible mode, battery ---


def _rate(ctx, field, value, maneuver, key):
    """A rate or acceleration limit [rad/s, rad/s^2]: one number, or 3 per channel."""
    if maneuver.limit_shape == ():
        if isinstance(value, list):
            raise ctx.error(field, f"must be one number for model {maneuver.name!r}, got {value!r}")
        return math.radians(_num(ctx, field, value, key))
    if isinstance(value, list):
        if len(value) != 3:
            raise ctx.error(field, f"must be one number or 3 (roll, pitch, yaw), got {value!r}")
        vals = [_num(ctx, field, v, key) for v in value]
    else:
        vals = [_num(ctx, field, value, key)] * 3
    return np.radians(np.asarray(vals))


def _flex(ctx, f, sat, maneuver, model):
    """The structural mode of a ``flexible`` satellite (None for the other models)."""
    if "flex" not in sat:
        if "flex" in maneuver.extra_fields:
            raise ctx.error(
                f"{f}.model",
                "'flexible' needs flex = { freq_hz = ..., damping = ..., tolerance_deg = ... }",
            )
        return None
    if "flex" not in maneuver.extra_fields:
        raise ctx.error(f"{f}.flex", f"only used by model 'flexible' (model is {model!r})")
    fx = field_table(ctx, f"{f}.flex", sat["flex"], SATELLITE_KEYS["flex"])
    kw = {"freq": 2 * math.pi * _num(ctx, f"{f}.flex.freq_hz", fx.get("freq_hz"), "flex.freq_hz")}
    if "damping" in fx:
        kw["damping"] = _num(ctx, f"{f}.flex.damping", fx["damping"], "flex.damping")
    if "tolerance_deg" in fx:
        tol = _num(ctx, f"{f}.flex.tolerance_deg", fx["tolerance_deg"], "flex.tolerance_deg")
        kw["tolerance"] = math.radians(tol)
    return FlexMode(**kw)


def _power(ctx, f, sat):
    """The battery of a satellite (None without a ``power`` table)."""
    if "power" not in sat:
        return None
    pw = field_table(ctx, f"{f}.power", sat["power"], SATELLITE_KEYS["power"])
    vals = {k: _num(ctx, f"{f}.power.{k}", v, f"power.{k}") for k, v in pw.items()}
    if "capacity_wh" not in vals:
        raise ctx.error(f"{f}.power.capacity_wh", "missing (required in a power table)")
    vals.setdefault("initial_wh", vals["capacity_wh"])
    if vals["initial_wh"] > vals["capacity_wh"]:
        raise ctx.error(
            f"{f}.power.initial_wh",
            f"must be <= capacity_wh = {vals['capacity_wh']:g}, got {vals['initial_wh']:g}",
        )
    try:
        return Power(**vals)
    except ValueError as exc:
        raise ctx.error(f"{f}.power", str(exc)) from None


def _satellite(ctx, f, sat, default_name, epoch, duration) -> Satellite:
    """One ``[[satellites]]`` table, checked."""
    sat = field_table(ctx, f, sat, SATELLITE_KEYS["satellite"])
    name = sat.get("name", default_name)
    name = field_str(ctx, f"{f}.name", name, allow_empty=False, max_chars=MAX_NAME_CHARS)
    if "tle" in sat:
        orbit = _tle(ctx, f, sat, epoch, duration)
    else:
        orbit = _circular(ctx, f, sat, julian_date(epoch), duration)
    model = sat.get("model", "per_channel")
    try:
        maneuver = maneuver_model(model)
    except ValueError as exc:
        raise ctx.error(f"{f}.model", str(exc).removeprefix("model ")) from None
    rate = _rate(ctx, f"{f}.rate_deg_s", sat.get("rate_deg_s", DEFAULT_RATE_DEG_S), maneuver,
                 "rate_deg_s")  # fmt: skip
    accel = _rate(ctx, f"{f}.accel_deg_s2", sat.get("accel_deg_s2", DEFAULT_ACCEL_DEG_S2),
                  maneuver, "accel_deg_s2")  # fmt: skip
    off = sat.get("off_nadir_max_deg", DEFAULT_OFF_NADIR_DEG)
    off = _num(ctx, f"{f}.off_nadir_max_deg", off, "off_nadir_max_deg")
    sensor = sat.get("sensor", DEFAULT_SENSOR)
    sensor = field_str(ctx, f"{f}.sensor", sensor, allow_empty=False, max_chars=MAX_NAME_CHARS)
    settle = _num(ctx, f"{f}.settle_s", sat.get("settle_s", 0.0), "settle_s")
    flex = _flex(ctx, f, sat, maneuver, model)
    power = _power(ctx, f, sat)
    swath = _num(ctx, f"{f}.swath_km", sat.get("swath_km", DEFAULT_SWATH_KM), "swath_km")
    limits = AxisLimits(rate, accel)
    if flex is not None and not mode_suppressible(
        flex.tolerance, flex.freq, flex.damping, rate, accel
    ):
        raise ctx.error(
            f"{f}.flex",
            f"no slew profile holds a {flex.freq / (2 * math.pi):g} Hz mode (damping "
            f"{flex.damping:g}) to tolerance_deg = {math.degrees(flex.tolerance):g} at "
            f"rate_deg_s = {math.degrees(rate):g}, accel_deg_s2 = {math.degrees(accel):g}: "
            "give a larger tolerance_deg or freq_hz, or a smaller accel_deg_s2",
        )
    area = _area_fields(ctx, f, sat, off)
    try:
        return Satellite(
            name, orbit, model, limits, math.radians(off), sensor, settle, flex, power,
            1e3 * swath, **area,
        )  # fmt: skip
    except ValueError as exc:
        raise ctx.error(f, str(exc)) from None


def _optics(ctx, f, sat) -> dict:
    """``fov`` and ``ifov`` [rad] of ``fov_deg``, ``ifov_deg`` and ``pixels`` (each only
    where given): without ``fov_deg`` the field of view is ``pixels x ifov_deg``; with
    all three they agree within :data:`FOV_TOLERANCE`; a pixel is no wider than the field."""
    fov = _num(ctx, f"{f}.fov_deg", sat["fov_deg"], "fov_deg") if "fov_deg" in sat else None
    ifov = _num(ctx, f"{f}.ifov_deg", sat["ifov_deg"], "ifov_deg") if "ifov_deg" in sat else None
    if "pixels" in sat:
        n = field_int(ctx, f"{f}.pixels", sat["pixels"], *RANGES["satellites[].pixels"])
        if ifov is None:
            raise ctx.error(
                f"{f}.pixels", "needs ifov_deg (the pixel angle): fov_deg = pixels x ifov_deg"
            )
        across = n * ifov
        if fov is None:
            lo, hi = RANGES["satellites[].fov_deg"]
            if not lo <= across <= hi:
                raise ctx.error(
                    f"{f}.pixels",
                    f"pixels x ifov_deg = {n} x {ifov:g} = {across:g} deg, the field of view, "
                    f"must be within [{lo:g}, {hi:g}] deg",
                )
            fov = across
        elif abs(fov - across) > FOV_TOLERANCE * fov:
            raise ctx.error(
                f"{f}.fov_deg",
                f"{fov:g} deg disagrees with pixels x ifov_deg = {n} x {ifov:g} = {across:g} "
                f"deg by more than {100 * FOV_TOLERANCE:g} %: give one of fov_deg and pixels",
            )
    if fov is not None and ifov is not None and ifov > fov:
        raise ctx.error(
            f"{f}.ifov_deg",
            f"the pixel angle {ifov:g} deg must be <= the field of view fov_deg = {fov:g} deg",
        )
    out = {} if fov is None else {"fov": math.radians(fov)}
    return out if ifov is None else {**out, "ifov": math.radians(ifov)}


def _area_fields(ctx, f, sat, off_deg: float) -> dict:
    """The fields of a satellite's area strips and stereo looks: ``fov_deg``,
    ``ifov_deg`` and ``pixels`` (:func:`_optics`), ``edge_off_nadir_deg`` (its edges'
    band, within the off-nadir limit), ``strip_duration_s`` and ``duty_s_per_orbit``
    (each only where given)."""
    out = _optics(ctx, f, sat)
    if "edge_off_nadir_deg" in sat:
        lo, hi = field_pair(ctx, f"{f}.edge_off_nadir_deg", sat["edge_off_nadir_deg"],
                            **bounds("satellites[].edge_off_nadir_deg"))  # fmt: skip
        if not lo < hi:
            raise ctx.error(f"{f}.edge_off_nadir_deg", f"needs inner < outer, got [{lo:g}, {hi:g}]")
        if hi > off_deg:
            raise ctx.error(
                f"{f}.edge_off_nadir_deg",
                f"the band's outer edge {hi:g} deg must be <= off_nadir_max_deg = {off_deg:g}",
            )
        out["edge_band"] = (math.radians(lo), math.radians(hi))
    if "strip_duration_s" in sat:
        lo, hi = field_pair(ctx, f"{f}.strip_duration_s", sat["strip_duration_s"],
                            **bounds("satellites[].strip_duration_s"))  # fmt: skip
        if not 0.0 < hi:
            raise ctx.error(f"{f}.strip_duration_s", f"needs a longest > 0, got [{lo:g}, {hi:g}]")
        out["strip_duration"] = (lo, hi)
    if "duty_s_per_orbit" in sat:
        out["duty"] = _num(ctx, f"{f}.duty_s_per_orbit", sat["duty_s_per_orbit"],
                           "duty_s_per_orbit")  # fmt: skip
    return out


def parse_satellites(ctx, data: dict, epoch: _dt.datetime, duration: float) -> tuple:
    """The ``[[satellites]]`` (alias ``[satellite]``) tables of a parsed scenario, checked.

    Args:
      ctx: :class:`jaxspline.readers.fields.FieldContext` of the file.
      data: dict, the parsed scenario TOML.
      epoch: the scenario's epoch (UTC datetime).
      duration: the horizon [s].
    Returns:
      tuple of :class:`jaxspline.readers.mission.Satellite` (unique names, file order).
    Raises:
      ValueError: naming the field (``satellites[1].rate_deg_s``), its TOML line and value.
    """
    items = field_tables(ctx, data, "satellites", "satellite")
    if not items:
        raise ctx.error("satellites", "missing: give at least one [[satellites]] table")
    sats, names = [], {}
    for i, (f, sat) in enumerate(items):
        s = _satellite(ctx, f, sat, f"sat{i + 1}", epoch, duration)
        if s.name in names:
            raise ctx.error(
                f"{f}.name", f"duplicate satellite name {s.name!r} (also {names[s.name]})"
            )
        names[s.name] = f
        sats.append(s)
    return tuple(sats)
