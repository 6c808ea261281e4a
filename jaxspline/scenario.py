"""Planning scenarios: the TOML schema, loading with named errors, and the built-in default.

Schema (TOML; every section but ``[satellite]`` is optional; angles in degrees in the
file, radians inside the library)::

    [scenario]
    name = "example"                    # free text
    epoch = "2026-06-21T10:00:00Z"      # ISO-8601 UTC; t = 0 of the plan
    duration_s = 600.0                  # plan span [0, duration_s] seconds

    [satellite]
    altitude_km = 600.0                 # circular orbit (default 600)
    inclination_deg = 97.79             # optional; omitted -> Sun-synchronous (J2)
    raan_deg = 0.0                      # node at the epoch (ignored with [satellite.over])
    arg_lat_deg = 0.0                   # argument of latitude at the epoch
    # or place the pass: sub-satellite point (lat, lon) at time t_s
    over = { lat_deg = 46.0, lon_deg = 15.0, t_s = 300.0, descending = true }
    # or a real orbit (overrides the elements; SGP4, tabulated every 20 s)
    # tle = ["1 25544U ...", "2 25544 ..."]
    off_nadir_max_deg = 45.0            # visibility / pointing limit
    rate_deg_s = [2.0, 2.0, 2.0]        # per channel (roll, pitch, yaw) or one number
    accel_deg_s2 = [1.0, 1.0, 1.0]
    jerk_deg_s3 = 1.0                   # optional; recorded, not used by the screening model
    sun_elevation_min_deg = 10.0        # optional; targets must be lit at the start

    [[routes]]                          # any number of explicit routes
    kind = "point"                      # "point" or "strip"
    lat_deg = 45.5
    lon_deg = 14.2
    duration_s = 6.0                    # point: imaging (tracking) time
    priority = 5.0                      # value if imaged (> 0; default 1)
    window_s = [100.0, 400.0]           # optional start-time window (s from epoch)

    [[routes]]
    kind = "strip"
    lat_deg = 47.0                      # start point
    lon_deg = 16.0
    azimuth_deg = 190.0                 # direction, clockwise from north
    length_km = 40.0                    # duration = length / scan speed

    [random_targets]                    # optional generator (added to [[routes]])
    seed = 0
    count = 300
    lat_deg = [38.0, 54.0]              # region (uniform in lat and lon)
    lon_deg = [10.0, 20.0]
    strip_fraction = 0.2                # share of strips
    duration_s = [4.0, 8.0]             # point durations (uniform)
    length_km = [20.0, 60.0]            # strip lengths (uniform)
    azimuth_deg = [0.0, 360.0]          # strip azimuths (uniform)
    priority = [1, 10]                  # integer priorities (uniform, inclusive)

    [planner]
    beam_width = 16                     # beam search width
    t0_grid = 5                         # start times per route window
    scan_speeds_km_s = [4.0, 7.0]       # strip ground scan speeds (options)
    refine_steps = 200                  # optax steps of start-time refinement (0 = off)
    refine_learning_rate = 0.002        # Adam step, in fractions of each route's window
    max_gap_s = 30.0                    # longest retarget considered between routes
    scan_samples = 9                    # samples per scan for the scan_ok check

A bad file raises ``ValueError`` naming the field (``routes[3].lat_deg``) and,
where it can be located, the TOML line. Unknown keys are errors (typos fail loudly).
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from pathlib import Path

import numpy as np

from jaxspline.limits import AxisLimits
from jaxspline.orbit import (
    circular_orbit,
    circular_orbit_over,
    gmst,
    julian_date,
    tle_orbit,
)
from jaxspline.routes import POINT, STRIP, RouteSpec, make_route_spec

__all__ = [
    "PlannerOptions",
    "Scenario",
    "load_scenario",
    "parse_scenario",
    "default_scenario",
    "DEFAULT_SCENARIO",
]


@dataclasses.dataclass(frozen=True)
class PlannerOptions:
    """Planner settings (static configuration). Speeds in m/s, times in s."""

    beam_width: int = 16
    t0_grid: int = 5
    scan_speeds: tuple[float, ...] = (4000.0, 7000.0)
    refine_steps: int = 200
    refine_learning_rate: float = 0.002
    max_gap: float = 30.0
    scan_samples: int = 9


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A loaded scenario (SI units, radians).

    Attributes:
      name, epoch: labels; epoch_jd: Julian date (UTC) of t = 0; duration: span [s].
      orbit: CircularOrbit or HermiteOrbit (jaxspline.orbit); gmst0: Earth rotation
        angle at t = 0 [rad].
      max_off_nadir [rad]; limits: AxisLimits with [3] arrays (roll, pitch, yaw)
        [rad/s, rad/s^2, rad/s^3]; sun_elevation_min [rad] or None.
      routes: RouteSpec (explicit routes first, then generated ones).
      planner: PlannerOptions.
    """

    name: str
    epoch: str
    epoch_jd: float
    duration: float
    orbit: object
    gmst0: float
    max_off_nadir: float
    limits: AxisLimits
    sun_elevation_min: float | None
    routes: RouteSpec
    planner: PlannerOptions

    def scene(self):
        """The :class:`jaxspline.pointing.Scene` of this scenario."""
        import jax.numpy as jnp

        from jaxspline.pointing import Scene

        return Scene(self.orbit, jnp.asarray(self.gmst0))

    def route_set(self):
        """The scenario's routes with their visibility windows (:class:`RouteSet`)."""
        from jaxspline.routes import make_route_set

        return make_route_set(
            self.scene(),
            self.routes,
            0.0,
            self.duration,
            self.max_off_nadir,
            nominal_speed=max(self.planner.scan_speeds),
        )

    def route_options(self, routes, progress: bool = False):
        """All start options of ``routes`` under this scenario's planner settings.

        Returns ``(RouteOptions, OptionInfo)`` for every option (``scan_ok`` marks the
        feasible ones), as :func:`jaxspline.routes.build_route_options`.
        """
        from jaxspline.routes import build_route_options

        pl = self.planner
        return build_route_options(
            routes,
            self.limits,
            self.max_off_nadir,
            n_t0=pl.t0_grid,
            scan_speeds=pl.scan_speeds,
            samples=pl.scan_samples,
            epoch_jd=self.epoch_jd,
            sun_elevation_min=self.sun_elevation_min,
            progress=progress,
        )


_KEYS = {
    "scenario": {"name", "epoch", "duration_s"},
    "satellite": {
        "altitude_km",
        "inclination_deg",
        "raan_deg",
        "arg_lat_deg",
        "over",
        "tle",
        "off_nadir_max_deg",
        "rate_deg_s",
        "accel_deg_s2",
        "jerk_deg_s3",
        "sun_elevation_min_deg",
    },
    "over": {"lat_deg", "lon_deg", "t_s", "descending"},
    "route": {
        "kind",
        "lat_deg",
        "lon_deg",
        "duration_s",
        "azimuth_deg",
        "length_km",
        "priority",
        "window_s",
    },
    "random_targets": {
        "seed",
        "count",
        "lat_deg",
        "lon_deg",
        "strip_fraction",
        "duration_s",
        "length_km",
        "azimuth_deg",
        "priority",
    },
    "planner": {
        "beam_width",
        "t0_grid",
        "scan_speeds_km_s",
        "refine_steps",
        "refine_learning_rate",
        "max_gap_s",
        "scan_samples",
    },
}
_TOP = {"scenario", "satellite", "routes", "random_targets", "planner"}


class _Ctx:
    """Error helper: names the field and, when the raw text is known, its TOML line."""

    def __init__(self, source: str, text: str | None):
        self.source = source
        self.lines = text.splitlines() if text is not None else None

    def line_of(self, field: str) -> int | None:
        if self.lines is None:
            return None
        parts = re.findall(r"[A-Za-z_]+|\[\d+\]", field)
        if not parts:
            return None
        table, key = parts[0], parts[-1]
        index = int(parts[1][1:-1]) if len(parts) > 2 and parts[1].startswith("[") else None
        header = re.compile(r"^\s*\[\[?\s*" + re.escape(table) + r"\s*\]\]?\s*$")
        start, seen = None, -1
        for i, ln in enumerate(self.lines):
            if header.match(ln):
                seen += 1
                if index is None or seen == index:
                    start = i
                    break
        if start is None:
            return None
        pat = re.compile(r"^\s*" + re.escape(key) + r"\s*=|[{,]\s*" + re.escape(key) + r"\s*=")
        for i in range(start, len(self.lines)):
            if i > start and re.match(r"^\s*\[", self.lines[i]):
                break
            if pat.search(self.lines[i]):
                return i + 1
        return start + 1

    def error(self, field: str, msg: str) -> ValueError:
        line = self.line_of(field)
        where = f" (line {line})" if line is not None else ""
        return ValueError(f"{self.source}: {field}{where}: {msg}")


def _number(ctx, field, value, *, positive=False, nonneg=False, lo=None, hi=None):
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ctx.error(field, f"must be a number, got {value!r}")
    v = float(value)
    if not np.isfinite(v):
        raise ctx.error(field, f"must be finite, got {value!r}")
    if positive and v <= 0:
        raise ctx.error(field, f"must be > 0, got {value!r}")
    if nonneg and v < 0:
        raise ctx.error(field, f"must be >= 0, got {value!r}")
    if lo is not None and v < lo or hi is not None and v > hi:
        raise ctx.error(field, f"must be in [{lo}, {hi}], got {value!r}")
    return v


def _int(ctx, field, value, minimum=0):
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.error(field, f"must be an integer, got {value!r}")
    if value < minimum:
        raise ctx.error(field, f"must be >= {minimum}, got {value!r}")
    return int(value)


def _pair(ctx, field, value, **kw):
    if not isinstance(value, list) or len(value) != 2:
        raise ctx.error(field, f"must be a list [lo, hi], got {value!r}")
    lo, hi = (_number(ctx, field, v, **kw) for v in value)
    if lo > hi:
        raise ctx.error(field, f"needs lo <= hi, got {value!r}")
    return lo, hi


def _per_channel(ctx, field, value):
    if isinstance(value, list):
        if len(value) != 3:
            raise ctx.error(field, f"must be one number or 3 (roll, pitch, yaw), got {value!r}")
        vals = [_number(ctx, field, v, positive=True) for v in value]
    else:
        vals = [_number(ctx, field, value, positive=True)] * 3
    return np.radians(np.asarray(vals))


def _table(ctx, data, name, keys):
    tab = data.get(name, {})
    if not isinstance(tab, dict):
        raise ctx.error(name, f"must be a table, got {tab!r}")
    unknown = set(tab) - keys
    if unknown:
        raise ctx.error(f"{name}.{sorted(unknown)[0]}", f"unknown key (allowed: {sorted(keys)})")
    return tab


def parse_scenario(data: dict, source: str = "<scenario>", text: str | None = None) -> Scenario:
    """Build a :class:`Scenario` from parsed TOML ``data`` (see module docstring for the schema).

    ``text`` (the raw TOML) lets errors cite line numbers. Raises ValueError naming the field.
    """
    ctx = _Ctx(source, text)
    if not isinstance(data, dict):
        raise ValueError(f"{source}: a scenario must be a table, got {type(data).__name__}")
    unknown = set(data) - _TOP
    if unknown:
        raise ctx.error(sorted(unknown)[0], f"unknown section (allowed: {sorted(_TOP)})")
    sc = _table(ctx, data, "scenario", _KEYS["scenario"])
    name = str(sc.get("name", Path(source).stem))
    epoch = sc.get("epoch", "2026-06-21T10:00:00Z")
    if not isinstance(epoch, str):
        epoch = epoch.isoformat() if hasattr(epoch, "isoformat") else epoch
    try:
        epoch_jd = julian_date(epoch)
    except ValueError as exc:
        raise ctx.error("scenario.epoch", str(exc)) from None
    duration = _number(ctx, "scenario.duration_s", sc.get("duration_s", 600.0), positive=True)
    gmst0 = float(gmst(epoch_jd))

    if "satellite" not in data:
        raise ctx.error("satellite", "missing section [satellite]")
    sat = _table(ctx, data, "satellite", _KEYS["satellite"])
    alt = 1e3 * _number(ctx, "satellite.altitude_km", sat.get("altitude_km", 600.0), lo=150, hi=3e4)
    inc = sat.get("inclination_deg")
    inc = (
        None
        if inc is None
        else np.radians(_number(ctx, "satellite.inclination_deg", inc, lo=0, hi=180))
    )
    if "tle" in sat:
        tle = sat["tle"]
        if not (isinstance(tle, list) and len(tle) == 2 and all(isinstance(s, str) for s in tle)):
            raise ctx.error("satellite.tle", "must be a list of the two TLE lines")
        try:
            orbit = tle_orbit(tle[0], tle[1], epoch_jd, duration)
        except ValueError as exc:
            raise ctx.error("satellite.tle", str(exc)) from None
    elif "over" in sat:
        ov = sat["over"]
        if not isinstance(ov, dict):
            raise ctx.error("satellite.over", f"must be an inline table, got {ov!r}")
        bad = set(ov) - _KEYS["over"]
        if bad:
            raise ctx.error(f"satellite.over.{sorted(bad)[0]}", "unknown key")
        lat = _number(ctx, "satellite.over.lat_deg", ov.get("lat_deg", 0.0), lo=-90, hi=90)
        lon = _number(ctx, "satellite.over.lon_deg", ov.get("lon_deg", 0.0))
        t_over = _number(ctx, "satellite.over.t_s", ov.get("t_s", duration / 2))
        desc = ov.get("descending", True)
        if not isinstance(desc, bool):
            raise ctx.error("satellite.over.descending", f"must be true/false, got {desc!r}")
        try:
            orbit = circular_orbit_over(
                np.radians(lat), np.radians(lon), t_over, gmst0, alt, inc, descending=desc
            )
        except ValueError as exc:
            raise ctx.error("satellite.over.lat_deg", str(exc)) from None
    else:
        raan = np.radians(_number(ctx, "satellite.raan_deg", sat.get("raan_deg", 0.0)))
        u0 = np.radians(_number(ctx, "satellite.arg_lat_deg", sat.get("arg_lat_deg", 0.0)))
        orbit = circular_orbit(alt, inc, raan, u0)
    offn = np.radians(
        _number(
            ctx, "satellite.off_nadir_max_deg", sat.get("off_nadir_max_deg", 45.0), lo=0.1, hi=70
        )
    )
    rate = _per_channel(ctx, "satellite.rate_deg_s", sat.get("rate_deg_s", 2.0))
    accel = _per_channel(ctx, "satellite.accel_deg_s2", sat.get("accel_deg_s2", 1.0))
    jerk = (
        _per_channel(ctx, "satellite.jerk_deg_s3", sat["jerk_deg_s3"])
        if "jerk_deg_s3" in sat
        else np.full(3, np.inf)
    )
    sun_min = sat.get("sun_elevation_min_deg")
    if sun_min is not None:
        sun_min = np.radians(
            _number(ctx, "satellite.sun_elevation_min_deg", sun_min, lo=-90, hi=90)
        )

    routes = _parse_routes(ctx, data.get("routes", []))
    if "random_targets" in data:
        routes = _concat(
            routes,
            _random_routes(ctx, _table(ctx, data, "random_targets", _KEYS["random_targets"])),
        )
    if routes is None:
        raise ctx.error("routes", "no routes: give [[routes]] and/or [random_targets]")

    pl = _table(ctx, data, "planner", _KEYS["planner"])
    d = PlannerOptions()
    speeds = pl.get("scan_speeds_km_s", [s / 1e3 for s in d.scan_speeds])
    if not isinstance(speeds, list) or not speeds:
        raise ctx.error("planner.scan_speeds_km_s", f"must be a non-empty list, got {speeds!r}")
    planner = PlannerOptions(
        beam_width=_int(ctx, "planner.beam_width", pl.get("beam_width", d.beam_width), 1),
        t0_grid=_int(ctx, "planner.t0_grid", pl.get("t0_grid", d.t0_grid), 1),
        scan_speeds=tuple(
            1e3 * _number(ctx, "planner.scan_speeds_km_s", s, positive=True) for s in speeds
        ),
        refine_steps=_int(ctx, "planner.refine_steps", pl.get("refine_steps", d.refine_steps), 0),
        refine_learning_rate=_number(
            ctx,
            "planner.refine_learning_rate",
            pl.get("refine_learning_rate", d.refine_learning_rate),
            positive=True,
        ),
        max_gap=_number(ctx, "planner.max_gap_s", pl.get("max_gap_s", d.max_gap), positive=True),
        scan_samples=_int(ctx, "planner.scan_samples", pl.get("scan_samples", d.scan_samples), 2),
    )
    return Scenario(
        name=name,
        epoch=str(epoch),
        epoch_jd=epoch_jd,
        duration=duration,
        orbit=orbit,
        gmst0=gmst0,
        max_off_nadir=float(offn),
        limits=AxisLimits(rate, accel, jerk),
        sun_elevation_min=None if sun_min is None else float(sun_min),
        routes=routes,
        planner=planner,
    )


def _parse_routes(ctx, items) -> RouteSpec | None:
    if not isinstance(items, list):
        raise ctx.error("routes", "must be an array of tables [[routes]]")
    rows = []
    for i, rt in enumerate(items):
        f = f"routes[{i}]"
        if not isinstance(rt, dict):
            raise ctx.error(f, "must be a table")
        bad = set(rt) - _KEYS["route"]
        if bad:
            raise ctx.error(
                f"{f}.{sorted(bad)[0]}", f"unknown key (allowed: {sorted(_KEYS['route'])})"
            )
        kind = rt.get("kind", "point")
        if kind not in ("point", "strip"):
            raise ctx.error(f"{f}.kind", f"must be 'point' or 'strip', got {kind!r}")
        for req in ("lat_deg", "lon_deg") + (
            ("length_km",) if kind == "strip" else ("duration_s",)
        ):
            if req not in rt:
                raise ctx.error(f"{f}.{req}", f"missing (required for a {kind})")
        lat = _number(ctx, f"{f}.lat_deg", rt["lat_deg"], lo=-90, hi=90)
        lon = _number(ctx, f"{f}.lon_deg", rt["lon_deg"])
        prio = _number(ctx, f"{f}.priority", rt.get("priority", 1.0), positive=True)
        win = _pair(ctx, f"{f}.window_s", rt["window_s"]) if "window_s" in rt else (-np.inf, np.inf)
        if kind == "strip":
            az = _number(ctx, f"{f}.azimuth_deg", rt.get("azimuth_deg", 0.0))
            length = 1e3 * _number(ctx, f"{f}.length_km", rt["length_km"], positive=True)
            rows.append((STRIP, lat, lon, az, length, 0.0, prio, *win))
        else:
            if "length_km" in rt or "azimuth_deg" in rt:
                raise ctx.error(f"{f}.kind", "a point has no length_km/azimuth_deg (use 'strip')")
            dur = _number(ctx, f"{f}.duration_s", rt["duration_s"], positive=True)
            rows.append((POINT, lat, lon, 0.0, 0.0, dur, prio, *win))
    if not rows:
        return None
    a = np.asarray(rows, dtype=np.float64)
    return make_route_spec(
        a[:, 0].astype(np.int64),
        np.radians(a[:, 1]),
        np.radians(a[:, 2]),
        np.radians(a[:, 3]),
        a[:, 4],
        a[:, 5],
        a[:, 6],
        a[:, 7],
        a[:, 8],
    )


def _random_routes(ctx, rt) -> RouteSpec:
    f = "random_targets"
    seed = _int(ctx, f"{f}.seed", rt.get("seed", 0))
    count = _int(ctx, f"{f}.count", rt.get("count", 300), 1)
    lat = _pair(ctx, f"{f}.lat_deg", rt.get("lat_deg", [38.0, 54.0]), lo=-90, hi=90)
    lon = _pair(ctx, f"{f}.lon_deg", rt.get("lon_deg", [10.0, 20.0]))
    frac = _number(ctx, f"{f}.strip_fraction", rt.get("strip_fraction", 0.2), lo=0, hi=1)
    dur = _pair(ctx, f"{f}.duration_s", rt.get("duration_s", [4.0, 8.0]), positive=True)
    length = _pair(ctx, f"{f}.length_km", rt.get("length_km", [20.0, 60.0]), positive=True)
    az = _pair(ctx, f"{f}.azimuth_deg", rt.get("azimuth_deg", [0.0, 360.0]))
    prio = _pair(ctx, f"{f}.priority", rt.get("priority", [1, 10]), positive=True)
    rng = np.random.default_rng(seed)
    kind = np.where(rng.random(count) < frac, STRIP, POINT)
    la = rng.uniform(*np.radians(lat), count)
    lo = rng.uniform(*np.radians(lon), count)
    a = rng.uniform(*np.radians(az), count)
    ln = 1e3 * rng.uniform(*length, count)
    du = rng.uniform(*dur, count)
    pr = rng.integers(int(prio[0]), int(prio[1]) + 1, count).astype(np.float64)
    return make_route_spec(
        kind,
        la,
        lo,
        np.where(kind == STRIP, a, 0.0),
        np.where(kind == STRIP, ln, 0.0),
        np.where(kind == POINT, du, 0.0),
        pr,
    )


def _concat(a: RouteSpec | None, b: RouteSpec) -> RouteSpec:
    if a is None:
        return b
    return RouteSpec(*(np.concatenate([x, y]) for x, y in zip(a, b, strict=True)))


def load_scenario(path) -> Scenario:
    """Load a scenario TOML file (ValueError naming the field / TOML line on bad content)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"scenario file not found: {path}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: invalid TOML: {exc}") from None
    return parse_scenario(data, source=str(path), text=text)


DEFAULT_SCENARIO = {
    "scenario": {"name": "default", "epoch": "2026-06-21T10:00:00Z", "duration_s": 600.0},
    "satellite": {
        "altitude_km": 600.0,
        "over": {"lat_deg": 46.0, "lon_deg": 15.0, "t_s": 300.0, "descending": True},
        "off_nadir_max_deg": 45.0,
        "rate_deg_s": [2.0, 2.0, 2.0],
        "accel_deg_s2": [1.0, 1.0, 1.0],
        "sun_elevation_min_deg": 10.0,
    },
    "random_targets": {
        "seed": 0,
        "count": 300,
        "lat_deg": [38.0, 54.0],
        "lon_deg": [10.0, 20.0],
        "strip_fraction": 0.2,
    },
    "planner": {},
}


def default_scenario(count: int | None = None, seed: int | None = None) -> Scenario:
    """The built-in scenario: one 600 km SSO descending pass over central Europe.

    Epoch 2026-06-21 10:00 UTC, 600 s; the sub-satellite point is at (46 N, 15 E) at
    t = 300 s; ``count`` (default 300) random targets (20 % strips 20-60 km, points
    4-8 s, priorities 1-10) in 38-54 N, 10-20 E; limits 2 deg/s and 1 deg/s^2 per
    channel, off-nadir <= 45 deg, Sun elevation >= 10 deg.
    """
    import copy

    data = copy.deepcopy(DEFAULT_SCENARIO)
    if count is not None:
        data["random_targets"]["count"] = int(count)
    if seed is not None:
        data["random_targets"]["seed"] = int(seed)
    return parse_scenario(data, source="<default>")
