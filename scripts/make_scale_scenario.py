"""Write a scale-test scenario (TOML + targets CSV) from documented scenario keys only.

The planner's scaling work needs large, reproducible instances. This script
writes them with nothing but the keys of the scenario schema (``jaxspline/readers/scenario.py``
docstring, README *Scenario files*) and the documented CSV columns
(``jaxspline/readers/targets.py``), so every file it writes loads with
:func:`jaxspline.load_scenario`. Rules, all deterministic (the same arguments give the
same files byte for byte):

* **Satellites.** Optionally first the six real-TLE satellites of
  ``jaxspline/data/default.toml`` (``--tles``), copied table for table (names, models,
  sensors, batteries). Then circular Sun-synchronous orbits (``altitude_km``,
  ``raan_deg``, ``arg_lat_deg``; no ``inclination_deg``, so the loader sets the J2
  Sun-synchronous inclination) in ``--planes`` planes: plane ``p`` has its descending
  node at local solar time ``LTDN_p`` (10:30 for one plane, spread evenly over
  10:30-13:30 for more), i.e. ``raan = RA_sun(epoch) + 15 deg/h * LTDN_p`` (Sun from
  :func:`jaxspline.geometry.frames.sun_direction`); the satellites of a plane are
  evenly spaced in argument of latitude, and plane ``p`` is shifted by
  ``360 deg * p / N`` (Walker phasing F = 1). Generated satellite ``i`` (0-based) flies
  model ``per_channel``, ``eigen_axis``, ``flexible`` for ``i % 3`` = 0, 1, 2, with the
  limits, settling, flexible mode and battery of the first satellite of that model in
  ``default.toml``; every other eigen-axis satellite (``i % 6 == 4``) carries the
  ``infrared`` sensor, the rest ``visible``.
* **Targets** (``<stem>_targets.csv`` beside the TOML, ``targets_csv`` in it). With
  ``--cities`` first the rows of the packaged ``cities.csv`` unchanged; the rest are
  random land targets: positions uniform in area over latitudes ``LAT_RANGE_DEG``
  (uniform ``sin(lat)``), rounded to 1e-5 deg, then kept where
  :func:`jaxspline.base.land.is_land` (the package's offline GLOBE mask) says land, in
  rounds of ``max(4 n, 4096)`` draws. Exactly ``round(strip_fraction * n)`` of them,
  chosen at random, are strips (length uniform in ``LENGTH_KM``, azimuth uniform in
  [0, 360) deg); the others points (imaging time 10, 15, ..., 30 s); priorities are
  integers 1-10.
* **Constraints.** ``--constrained SHARE``: the share of ALL targets (cities included)
  that carry a time window or a required sensor (a city counts when its ``sensor`` cell
  is set). The random targets make up the difference, chosen at random; each gets a
  window (50 %), a sensor (30 %) or both (20 %). A window is ``WINDOW_SHARE`` of the
  horizon wide (uniform, at least 600 s, whole 10 s), placed uniformly inside it; a
  sensor is ``infrared`` (25 %, only when a satellite carries it) or ``visible``.
* **Planner**: the ``[planner]`` table of ``default.toml`` with ``time_limit_s``
  replaced by ``--time-limit``.

Presets (explicit flags override them)::

    12x12h  12 satellites in two 550 km SSO planes, 12 h, 5,000 random land targets,
            10 % strips, no windows or sensors
    day     the six default TLE satellites + 18 in three 550 km SSO planes (24, with
            8 per maneuver model), 24 h, 20,000 targets: the 1,500 cities + 18,500
            random land targets, 10 % strips, a third with windows or sensors;
            shipped as jaxspline/data/constellation_day.toml

Usage::

    python scripts/make_scale_scenario.py --preset 12x12h --out /tmp/scale/12x12h.toml
    python scripts/make_scale_scenario.py --preset day --out jaxspline/data/constellation_day.toml
    python scripts/make_scale_scenario.py --satellites 2 --hours 2 --targets 300 --out tiny.toml
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
import tomllib
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "jaxspline" / "data"
DEFAULT_TOML = DATA / "default.toml"
CITIES_CSV = DATA / "cities.csv"

MODEL_CYCLE = ("per_channel", "eigen_axis", "flexible")
SHORT = {"per_channel": "agile", "eigen_axis": "eigen", "flexible": "flex"}
INFRARED_EVERY = 6  # generated satellite i carries "infrared" when i % 6 == INFRARED_AT
INFRARED_AT = 4  # (every second eigen-axis satellite, like eigen-ir in default.toml)
MODEL_KEYS = (  # copied per model from default.toml: everything but name, orbit, sensor
    "model rate_deg_s accel_deg_s2 settle_s off_nadir_max_deg flex power swath_km".split()
)
LTDN_FIRST_H, LTDN_LAST_H = 10.5, 13.5  # descending-node local times spanned by the planes

LAT_RANGE_DEG = (-60.0, 70.0)  # as default.toml's [random_targets]
COORD_DECIMALS = 5
LAND_ROUNDS = 50
LAND_BATCH_MIN = 4096
POINT_DURATIONS_S = (10, 15, 20, 25, 30)
LENGTH_KM = (20.0, 60.0)
PRIORITY_RANGE = (1, 10)
CONSTRAINT_KINDS = (("window", 0.5), ("sensor", 0.3), ("both", 0.2))
WINDOW_SHARE = (0.1, 0.4)  # window width as a share of the horizon
WINDOW_MIN_S = 600.0
WINDOW_STEP_S = 10.0
INFRARED_SHARE = 0.25  # of sensor-constrained targets, when an infrared satellite exists

CSV_COLUMNS = (
    "name lat_deg lon_deg priority kind alt_m duration_s length_km azimuth_deg "
    "window_lo_s window_hi_s sensor".split()
)


@dataclass(frozen=True)
class Spec:
    """What to generate (see the module docstring for the rules)."""

    name: str = "scale"
    satellites: int = 12  # total, TLE satellites included
    planes: int = 2  # planes of the generated (element) satellites
    altitude_km: float = 550.0
    hours: float = 12.0
    targets: int = 5000  # total, cities included
    strip_fraction: float = 0.1  # of the random targets
    constrained: float = 0.0  # share of all targets with a window or a sensor
    tles: bool = False  # the six default TLE satellites first
    cities: bool = False  # the packaged cities first
    seed: int = 0
    epoch: str = "2026-04-14T00:00:00Z"  # default.toml's (the TLE epochs are 04-13/14)
    time_limit_s: float = 120.0

    def validate(self) -> Spec:
        """Raise ValueError naming a bad field."""
        checks = [
            ("satellites", self.satellites >= 1),
            ("planes", self.planes >= 1),
            ("hours", self.hours > 0),
            ("targets", self.targets >= 1),
            ("strip_fraction", 0.0 <= self.strip_fraction <= 1.0),
            ("constrained", 0.0 <= self.constrained <= 1.0),
            ("altitude_km", 150.0 <= self.altitude_km <= 5000.0),
            ("time_limit_s", self.time_limit_s > 0),
        ]
        for field, ok in checks:
            if not ok:
                raise ValueError(f"{field}={getattr(self, field)!r} is out of range")
        return self


PRESETS = {
    "12x12h": Spec(name="scale_12x12h", satellites=12, planes=2, hours=12.0, targets=5000,
                   seed=1212),
    "day": Spec(name="constellation_day", satellites=24, planes=3, hours=24.0, targets=20000,
                constrained=1 / 3, tles=True, cities=True, seed=2424, time_limit_s=600.0),
}  # fmt: skip


# --- satellites ---


def _default_toml() -> dict:
    return tomllib.loads(DEFAULT_TOML.read_text(encoding="utf-8"))


def _model_templates(default: dict) -> dict[str, dict]:
    """Per model, the model keys of the first default.toml satellite flying it."""
    out = {}
    for sat in default["satellites"]:
        if sat["model"] not in out:
            out[sat["model"]] = {k: sat[k] for k in MODEL_KEYS if k in sat}
    missing = set(MODEL_CYCLE) - set(out)
    if missing:
        raise ValueError(f"{DEFAULT_TOML}: no satellite flies {sorted(missing)}")
    return out


def sun_right_ascension_deg(epoch: str) -> float:
    """Right ascension of the Sun at ``epoch`` [deg] in [0, 360) (mean equator of date)."""
    from jaxspline.base.elements import jd_split, julian_date
    from jaxspline.geometry.frames import sun_direction

    s = sun_direction(*jd_split(julian_date(epoch), 0.0))
    return math.degrees(math.atan2(float(s[1]), float(s[0]))) % 360.0


def plane_ltdn_h(planes: int) -> list[float]:
    """Local solar time of the descending node of each plane [h]."""
    if planes == 1:
        return [LTDN_FIRST_H]
    step = (LTDN_LAST_H - LTDN_FIRST_H) / (planes - 1)
    return [LTDN_FIRST_H + p * step for p in range(planes)]


def satellite_tables(spec: Spec) -> list[dict]:
    """The ``[[satellites]]`` tables, in order (TLE satellites first)."""
    default = _default_toml()
    out = []
    if spec.tles:
        out = [dict(s) for s in default["satellites"] if "tle" in s][: spec.satellites]
    n = spec.satellites - len(out)
    if n <= 0:
        return out
    templates = _model_templates(default)
    planes = min(spec.planes, n)
    ra_sun = sun_right_ascension_deg(spec.epoch)
    ltdn = plane_ltdn_h(planes)
    per_plane = [n // planes + (p < n % planes) for p in range(planes)]
    i = 0
    for p in range(planes):
        raan = round((ra_sun + 15.0 * ltdn[p]) % 360.0, 4)
        for k in range(per_plane[p]):
            model = MODEL_CYCLE[i % len(MODEL_CYCLE)]
            u = round((360.0 * k / per_plane[p] + 360.0 * p / n) % 360.0, 4)
            sensor = "infrared" if i % INFRARED_EVERY == INFRARED_AT else "visible"
            sat = {
                "name": f"sso{p + 1}-{SHORT[model]}-{i + 1:02d}",
                "altitude_km": spec.altitude_km,
                "raan_deg": raan,
                "arg_lat_deg": u,
                **templates[model],
                "sensor": sensor,
            }
            out.append(sat)
            i += 1
    return out


# --- targets ---


def _land_positions(rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` positions [deg] uniform in area over LAT_RANGE_DEG, rounded, on land."""
    from jaxspline.base.land import is_land

    if n == 0:
        return np.zeros(0), np.zeros(0)
    s_lo, s_hi = (math.sin(math.radians(x)) for x in LAT_RANGE_DEG)
    batch = max(4 * n, LAND_BATCH_MIN)
    lats, lons, have = [], [], 0
    for _ in range(LAND_ROUNDS):
        lat = _rounded(np.degrees(np.arcsin(rng.uniform(s_lo, s_hi, batch))))
        lon = _rounded(rng.uniform(-180.0, 180.0, batch))
        keep = is_land(lat, lon)
        lats.append(lat[keep])
        lons.append(lon[keep])
        have += int(keep.sum())
        if have >= n:
            return np.concatenate(lats)[:n], np.concatenate(lons)[:n]
    raise RuntimeError(f"only {have} land points in {LAND_ROUNDS * batch} draws")


def _rounded(x: np.ndarray) -> np.ndarray:
    """x rounded to COORD_DECIMALS through its text: the very floats the CSV loads back."""
    return np.array([float(f"{v:.{COORD_DECIMALS}f}") for v in x.tolist()])


def _fmt(x: float) -> str:
    """Shortest exact text of a float with at most COORD_DECIMALS decimals."""
    return f"{x:.{COORD_DECIMALS}f}".rstrip("0").rstrip(".")


def _city_rows() -> list[dict]:
    with CITIES_CSV.open(newline="", encoding="utf-8") as f:
        return [{k: (v or "") for k, v in row.items()} for row in csv.DictReader(f)]


def target_rows(spec: Spec, sensors: set[str]) -> list[dict]:
    """The targets CSV rows (dicts over CSV_COLUMNS; "" = default), cities first.

    Args:
      spec: what to generate.
      sensors: the sensor types the satellites carry (infrared requests only if there).
    """
    rng = np.random.default_rng(spec.seed)
    cities = _city_rows() if spec.cities else []
    if len(cities) > spec.targets:
        raise ValueError(f"targets={spec.targets} is below the {len(cities)} cities")
    n = spec.targets - len(cities)
    lat, lon = _land_positions(rng, n)
    strip = np.zeros(n, bool)
    strip[rng.permutation(n)[: round(spec.strip_fraction * n)]] = True
    priority = rng.integers(PRIORITY_RANGE[0], PRIORITY_RANGE[1] + 1, n)
    duration = rng.choice(POINT_DURATIONS_S, n)
    length = np.round(rng.uniform(*LENGTH_KM, n), 1)
    azimuth = np.round(rng.uniform(0.0, 360.0, n), 1) % 360.0

    # constraints: the random targets fill the share left after the cities
    city_constrained = sum(bool(c.get("sensor") or c.get("window_lo_s")) for c in cities)
    n_con = min(max(round(spec.constrained * spec.targets) - city_constrained, 0), n)
    chosen = np.zeros(n, bool)
    chosen[rng.permutation(n)[:n_con]] = True
    names, probs = zip(*CONSTRAINT_KINDS, strict=True)
    kind = rng.choice(len(names), n, p=probs)
    horizon = 3600.0 * spec.hours
    width = np.maximum(rng.uniform(*WINDOW_SHARE, n) * horizon, min(WINDOW_MIN_S, horizon))
    width = np.floor(width / WINDOW_STEP_S) * WINDOW_STEP_S
    lo = np.floor(rng.uniform(0.0, 1.0, n) * (horizon - width) / WINDOW_STEP_S) * WINDOW_STEP_S
    infrared = rng.random(n) < (INFRARED_SHARE if "infrared" in sensors else 0.0)

    rows = [{c: city.get(c, "") for c in CSV_COLUMNS} for city in cities]
    for i in range(n):
        row = dict.fromkeys(CSV_COLUMNS, "")
        row.update(name=f"land_{i + 1:05d}", lat_deg=_fmt(lat[i]), lon_deg=_fmt(lon[i]))
        row["priority"] = str(int(priority[i]))
        if strip[i]:
            row.update(kind="strip", length_km=f"{length[i]:g}", azimuth_deg=f"{azimuth[i]:g}")
        else:
            row["duration_s"] = str(int(duration[i]))
        if chosen[i] and names[kind[i]] in ("window", "both"):
            row.update(window_lo_s=f"{lo[i]:g}", window_hi_s=f"{lo[i] + width[i]:g}")
        if chosen[i] and names[kind[i]] in ("sensor", "both"):
            row["sensor"] = "infrared" if infrared[i] else "visible"
        rows.append(row)
    return rows


# --- writing ---


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string for the ASCII we write
    if isinstance(v, int | float):
        return repr(float(v)) if isinstance(v, float) else str(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {v!r} as TOML")


def _command(spec: Spec, preset: str | None, out_name: str) -> str:
    base = PRESETS[preset] if preset else Spec(name=Path(out_name).stem)
    flags = [f"--preset {preset}"] if preset else []
    for f in fields(Spec):
        v = getattr(spec, f.name)
        if v != getattr(base, f.name):
            flag = "--" + f.name.replace("_", "-")
            flags.append(flag if v is True else f"--no-{flag[2:]}" if v is False else f"{flag} {v}")
    return " ".join(["python scripts/make_scale_scenario.py", *flags, f"--out {out_name}"])


def build(spec: Spec, csv_name: str, preset: str | None = None, out_name: str = "") -> tuple:
    """The scenario TOML text and the targets CSV text.

    Args:
      spec: what to generate.
      csv_name: the CSV's file name as the TOML names it (relative to the TOML).
      preset: the preset name, for the header comment only.
      out_name: the TOML path, for the header comment only.
    Returns:
      (toml_text, csv_text, rows, satellites).
    """
    spec.validate()
    default = _default_toml()
    sats = satellite_tables(spec)
    rows = target_rows(spec, {s["sensor"] for s in sats})
    n_strip = sum(r["kind"] == "strip" for r in rows)
    n_con = sum(bool(r["window_lo_s"] or r["sensor"]) for r in rows)
    models = {m: sum(s["model"] == m for s in sats) for m in MODEL_CYCLE}
    lines = [
        f"# Scale scenario {spec.name!r}, generated: do not edit by hand. Remake with",
        f"#   {_command(spec, preset, out_name or spec.name + '.toml')}",
        f"# {len(sats)} satellites ({sum('tle' in s for s in sats)} TLE; "
        + ", ".join(f"{v} {k}" for k, v in models.items())
        + f"), {spec.hours:g} h; {len(rows)} targets in {csv_name} ({n_strip} strips, "
        f"{n_con} with a window or a sensor). Rules: scripts/make_scale_scenario.py.",
        "",
        f"targets_csv = {_toml_value(csv_name)}",
        "",
        "[scenario]",
        f"name = {_toml_value(spec.name)}",
        f"epoch = {_toml_value(spec.epoch)}",
        f"duration_h = {_toml_value(float(spec.hours))}",
    ]
    for s in sats:
        lines += ["", "[[satellites]]"] + [f"{k} = {_toml_value(v)}" for k, v in s.items()]
    planner = dict(default.get("planner", {}), time_limit_s=float(spec.time_limit_s))
    lines += ["", "[planner]"] + [f"{k} = {_toml_value(v)}" for k, v in planner.items()]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=CSV_COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    return "\n".join(lines) + "\n", buf.getvalue(), rows, sats


def write(spec: Spec, out: Path, preset: str | None = None, force: bool = False) -> dict:
    """Write ``out`` (TOML) and ``<stem>_targets.csv`` beside it; return a summary."""
    from jaxspline.planner.files import atomic_write_text

    out = Path(out)
    csv_path = out.with_name(out.stem + "_targets.csv")
    shown = out.resolve()  # the header names the file in the repo, else by name alone
    shown = shown.relative_to(REPO) if shown.is_relative_to(REPO) else Path(out.name)
    toml_text, csv_text, rows, sats = build(spec, csv_path.name, preset, str(shown))
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(csv_path, csv_text, force=force)
    atomic_write_text(out, toml_text, force=force)
    return {
        "toml": str(out),
        "csv": str(csv_path),
        "satellites": len(sats),
        "targets": len(rows),
        "strips": sum(r["kind"] == "strip" for r in rows),
        "windows": sum(bool(r["window_lo_s"]) for r in rows),
        "sensors": sum(bool(r["sensor"]) for r in rows),
    }


def spec_from_args(args) -> Spec:
    """The preset (or the Spec defaults) with the flags given on the command line."""
    spec = PRESETS[args.preset] if args.preset else Spec(name=Path(args.out).stem)
    given = {f.name: getattr(args, f.name) for f in fields(Spec)}
    return replace(spec, **{k: v for k, v in given.items() if v is not None}).validate()


def main(argv: list[str] | None = None) -> int:
    """Command line: write the files and print a summary."""
    ap = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="Rules and presets: the module docstring (python -m pydoc scripts/...).",
    )
    ap.add_argument("--preset", choices=sorted(PRESETS), help="start from a preset")
    ap.add_argument("--out", type=Path, required=True, help="scenario TOML to write")
    ap.add_argument("--force", action="store_true", help="overwrite existing files")
    types = {int: int, float: float, str: str}
    for f, default in asdict(Spec()).items():
        flag = "--" + f.replace("_", "-")
        if isinstance(default, bool):
            ap.add_argument(flag, dest=f, action=argparse.BooleanOptionalAction, default=None)
        else:
            ap.add_argument(flag, dest=f, type=types[type(default)], default=None,
                            help=f"(Spec default {default!r})")  # fmt: skip
    args = ap.parse_args(argv)
    try:
        spec = spec_from_args(args)
        summary = write(spec, args.out, args.preset, args.force)
    except (ValueError, FileExistsError) as exc:
        print(f"make_scale_scenario: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
