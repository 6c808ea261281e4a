"""Fuzzing the file readers: scenario TOML, targets CSV, areas GeoJSON, aeossp case YAML.

Seeded mutations of the packaged valid files (``data/default.toml``, ``cities.csv``,
``areas_example.toml`` / ``.geojson``) and of an aeossp_standard case, each of which
must end in one of two ways:

* a ``ValueError`` (that type exactly) whose message names the file and the mutated
  field (with the TOML line, the CSV row, the YAML list entry where there is one), or
* the input is accepted and every number that must be finite is finite and in range;
  mutations that keep the meaning (UTF-8 byte-order mark, CRLF line ends, reordered
  columns / tables / keys, comments, blank rows) give exactly the baseline's result.

Some mutations are known to be wrong (NaN, inf, text or a boolean where a number
belongs, a latitude of 95 deg, an unknown key or column, a duplicate name, an empty
file): those must be rejected. No reader may write anything: an audit hook records
every ``open`` for writing, rename, removal or directory creation while a reader runs.

An area is read, not cut: one target row of kind AREA (its priority, window and
sensor, at its centre) and one ``Area`` (its polygon and grid spacing, or its samples
``(lon, lat, weight)``, and its least covered share); an accepted area must hold finite
values in range there. Areas across the antimeridian are refused with the remedy in the
message (two areas, one each side), and that remedy is checked to read both halves
where they are. The generators live in ``_fuzz_inputs.py``;
``python tests/readers/test_fuzz_readers.py`` prints a summary of the failing cases by
kind.

The schema cases (``_fuzz_schema.py``, ~1040) go over every key of the schema instead of
mutating at random: every number outside its range, of the wrong type and at both ends
of its range, names with control characters, damaged TLEs, far epochs, degenerate
polygons, GeoJSON positions that are not numbers, the retired area keys (``swath_km``,
``max_length_km``, ``objective``: "is no longer read"), area entries that are not
tables, bad cells of an area's sample file, the stereo rules (product names, a preferred
band inside the accepted convergence, quality weights summing to 1, keys of one kind on
a target of another, a field of view ``pixels x ifov_deg`` contradicts, CSV stereo
cells). The ~1100 that must be refused stop at
validation and run by default (a few seconds); the boundary values that may be accepted
load whole scenarios (orbits, areas) and run with the ``slow`` marker, as does a handful
that plans through the command (a plan or a named error, never a traceback). An
accepted scenario must also hold every number within its range.

The baseline results are parsed once per test; no plan is built. The random targets
of ``default.toml`` are drawn with ``land_only = false`` in the mutated copies (the land
mask costs 0.5 s a read), and its CSV path is made absolute.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import sys
import tomllib
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import shapely
from _fuzz_inputs import (
    CASE1,
    GENERATORS,
    Fuzz,
    _case_baseline,
    _csv_baselines,
    _csv_text,
    _is_number,
    _toml_baselines,
    generated,
)
from _fuzz_schema import RETIRED, schema_cases

from jaxspline.aeossp.case import Case, load_case
from jaxspline.base.elements import CircularOrbit
from jaxspline.readers.area_files import AREA_KEYS, RETIRED_KEYS, read_geojson
from jaxspline.readers.mission import AREA, STEREO, Scenario, Targets
from jaxspline.readers.ranges import RANGES
from jaxspline.readers.scenario import load_scenario
from jaxspline.readers.stereo_files import STEREO_KEYS, TARGET_STEREO_KEYS
from jaxspline.readers.targets import load_targets_csv

# --- no writes: an audit hook, active only while a reader runs ---

_WRITES: list | None = None
_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC
_WRITE_EVENTS = frozenset(
    "os.rename os.remove os.rmdir os.mkdir os.truncate os.symlink os.link os.chmod "
    "os.utime shutil.copyfile shutil.rmtree shutil.move".split()
)
_HOOKED = False


#: The test run's XLA cache (tests/conftest.py): JAX's own files, not a reader's.
_XLA_CACHE = os.environ.get("JAXSPLINE_CACHE_DIR", "")
_XLA_CACHE = _XLA_CACHE if os.path.isabs(_XLA_CACHE) else None


def _audit(event, args):
    if _WRITES is None:
        return
    if _XLA_CACHE and any(str(a).startswith(_XLA_CACHE) for a in args[:2]):
        return
    if event == "open":
        path, mode, flags = (tuple(args) + (None, None))[:3]
        by_mode = isinstance(mode, str) and any(c in mode for c in "wax+")
        if by_mode or (isinstance(flags, int) and flags & _WRITE_FLAGS):
            _WRITES.append(f"open({path!r}, {mode!r})")
    elif event in _WRITE_EVENTS:
        _WRITES.append(f"{event}{tuple(args)!r}")


def _call(fn, *args):
    """(result, exception, writes) of ``fn(*args)``, writes seen by the audit hook."""
    global _WRITES, _HOOKED
    if not _HOOKED:
        sys.addaudithook(_audit)
        _HOOKED = True
    _WRITES = []
    try:
        return fn(*args), None, _WRITES
    except Exception as exc:  # noqa: BLE001 - the type is what is checked
        return None, exc, _WRITES
    finally:
        _WRITES = None


# --- what an accepted input must satisfy ---

_FINITE_TARGET_FIELDS = (
    "lat",
    "lon",
    "alt",
    "duration",
    "length",
    "azimuth",
    "value",
    "min_duration",
)


def _check_targets(tg: Targets) -> list[str]:
    bad = [f for f in _FINITE_TARGET_FIELDS if not np.all(np.isfinite(getattr(tg, f)))]
    bad += [f for f in ("t_lo", "t_hi", "mid_lo", "mid_hi") if np.any(np.isnan(getattr(tg, f)))]
    if len(tg) and not (np.all(np.abs(tg.lat) <= np.pi / 2) and np.all(np.abs(tg.lon) <= np.pi)):
        bad.append("lat/lon out of range")
    if len(tg) and not np.all(tg.value > 0):
        bad.append("value <= 0")
    if len(set(tg.name.tolist())) != len(tg):
        bad.append("duplicate target names")
    return bad


def _finite(*xs) -> bool:
    return all(np.all(np.isfinite(np.asarray(x, np.float64))) for x in xs)


def _check_scenario(sc: Scenario) -> list[str]:
    bad = [] if _finite(sc.duration) and sc.duration > 0 else ["duration"]
    for s in sc.satellites:
        nums = [s.limits.rate, s.limits.accel, s.off_nadir_max, s.settle, s.swath]
        nums += [x for x in (s.fov, s.edge_band, s.duty, s.ifov) if x is not None]
        nums += [s.strip_duration]
        if isinstance(s.orbit, CircularOrbit):
            nums += list(s.orbit)
        if s.flex is not None:
            nums += [s.flex.freq, s.flex.damping, s.flex.tolerance]
        if s.power is not None:
            nums += list(dataclasses.astuple(s.power))
        if not _finite(*nums):
            bad.append(f"satellite {s.name}")
    pl = sc.planner
    m = pl.margins
    nums = [
        pl.time_step,
        pl.geometry_step,
        pl.scan_speeds,
        pl.lagrangian_share,
        pl.default_time_limit,
        pl.area_roll_step,
        m.off_nadir,
        m.horizon,
        m.gap,
        m.battery_wh,
        m.duty,
    ]
    nums += [x for x in (pl.max_actions, pl.area_pitch_step) if x is not None]
    if not _finite(*nums) or (
        pl.sun_elevation_min is not None and not _finite(pl.sun_elevation_min)
    ):
        bad.append("planner")
    bad += _check_targets(sc.targets)
    bad += [f"area {a.name}: {why}" for a in sc.areas for why in _check_area(sc, a)]
    if sorted(a.target for a in sc.areas) != np.flatnonzero(sc.targets.kind == AREA).tolist():
        bad.append("areas and the targets of kind AREA differ")
    if [s.target for s in sc.stereo] != np.flatnonzero(sc.targets.kind == STEREO).tolist():
        bad.append("stereo requests and the targets of kind STEREO differ")
    for s in sc.stereo:
        nums = [s.radius, s.min_overlap, s.convergence, s.band, s.max_scale_ratio]
        nums += [s.max_separation, s.anchor_off_nadir, s.weights, s.tri_bonus, s.quality_weight]
        if not _finite(*nums) or sc.targets.name[s.target] != s.name:
            bad.append(f"stereo {s.name}")
    return bad


def _check_area(sc: Scenario, a) -> list[str]:
    """What is wrong with an :class:`Area` of an accepted scenario: its target row (kind
    AREA, its name), its polygon (finite, in lon/lat range), its samples (finite [N, 3]
    ``(lon, lat, weight)`` in range, weights >= 0 summing to at most 1), its grid
    spacing (> 0 where it has no samples) and its least covered share ([0, 1] or NaN)."""
    bad = []
    tg = sc.targets
    if not (0 <= a.target < len(tg) and tg.kind[a.target] == AREA and tg.name[a.target] == a.name):
        bad.append("target row")
    if a.geometry is not None:
        geom = shapely.geometry.shape(a.geometry)
        xy = shapely.get_coordinates(geom)
        if geom.geom_type not in ("Polygon", "MultiPolygon") or geom.is_empty:
            bad.append(f"a {geom.geom_type}")
        elif not (_finite(xy) and np.all(np.abs(xy) <= (180.0, 90.0))):
            bad.append("polygon coordinates")
    smp = np.asarray(a.samples)
    if smp.ndim != 2 or smp.shape[1] != 3 or not _finite(smp):
        bad.append(f"samples of shape {smp.shape}")
    elif smp.shape[0] and not (
        np.all(np.abs(smp[:, :2]) <= (180.0, 90.0))
        and np.all(smp[:, 2] >= 0.0)
        and smp[:, 2].sum() <= 1.0 + 1e-9
    ):
        bad.append("sample values")
    if a.geometry is None and smp.shape[0] == 0:
        bad.append("neither a polygon nor samples")
    if smp.shape[0] == 0 and not (_finite(a.spacing) and a.spacing > 0):
        bad.append(f"spacing {a.spacing!r}")
    if not (np.isnan(a.min_share) or 0.0 <= a.min_share <= 1.0):
        bad.append(f"min_share {a.min_share!r}")
    return bad


def _check_geometry(geom) -> list[str]:
    if geom.geom_type not in ("Polygon", "MultiPolygon"):
        return [f"a {geom.geom_type}"]
    return [] if _finite(shapely.get_coordinates(geom)) else ["non-finite coordinates"]


def _check_case(case: Case) -> list[str]:
    bad = []
    for s in case.satellites:
        nums = [v for v in dataclasses.astuple(s) if _is_number(v)]
        if not _finite(*nums):
            bad.append(f"satellite {s.satellite_id}")
    for t in case.tasks:
        if not _finite(
            t.latitude_deg, t.longitude_deg, t.altitude_m, t.required_duration_s, t.weight
        ):
            bad.append(f"task {t.task_id}")
        elif abs(t.latitude_deg) > 90 or abs(t.longitude_deg) > 180:
            bad.append(f"task {t.task_id} lat/lon out of range")
    if not (case.satellites and case.tasks):
        bad.append("no satellites or no tasks")
    return bad


def _same_targets(a: Targets, b: Targets) -> list[str]:
    if len(a) != len(b):
        return [f"{len(a)} targets, baseline {len(b)}"]
    return [
        f.name
        for f in dataclasses.fields(a)
        if not np.array_equal(getattr(a, f.name), getattr(b, f.name))
    ]


def _same_scenario(a: Scenario, b: Scenario) -> list[str]:
    diff = (
        []
        if (a.name, a.epoch, a.duration, a.planner) == (b.name, b.epoch, b.duration, b.planner)
        else ["header/planner"]
    )
    for s, t in zip(a.satellites, b.satellites, strict=False):
        if (
            (s.name, s.model, s.sensor, s.flex, s.power)
            != (t.name, t.model, t.sensor, t.flex, t.power)
            or (s.fov, s.edge_band, s.strip_duration, s.duty)
            != (t.fov, t.edge_band, t.strip_duration, t.duty)
            or not all(
                np.array_equal(x, y)
                for x, y in ((s.limits.rate, t.limits.rate), (s.limits.accel, t.limits.accel))
            )
            or ((s.off_nadir_max, s.settle, s.swath) != (t.off_nadir_max, t.settle, t.swath))
            or (str(s.orbit) != str(t.orbit))
        ):
            diff.append(f"satellite {s.name}")
    if len(a.satellites) != len(b.satellites):
        diff.append("satellite count")
    diff += _same_targets(a.targets, b.targets)
    if [(x.name, x.target) for x in a.areas] != [(y.name, y.target) for y in b.areas]:
        diff.append("areas")
    for x, y in zip(a.areas, b.areas, strict=False):
        if (x.geometry is None) != (y.geometry is None) or not (
            x.geometry is None
            or shapely.geometry.shape(x.geometry).equals(shapely.geometry.shape(y.geometry))
        ):
            diff.append(f"area {x.name}: polygon")
        if not (
            x.spacing == y.spacing
            and np.array_equal(x.samples, y.samples)
            and np.array_equal(x.min_share, y.min_share, equal_nan=True)
        ):
            diff.append(f"area {x.name}: spacing, samples or min_share")
    return diff


def _same_geometry(a, b) -> list[str]:
    return [] if a.equals(b) else ["geometry"]


def _same_case(a: Case, b: Case) -> list[str]:
    return [] if a == b else ["case"]


READERS = {
    "scenario": (load_scenario, _check_scenario, _same_scenario),
    "csv": (load_targets_csv, _check_targets, _same_targets),
    "geojson": (read_geojson, _check_geometry, _same_geometry),
    "case": (load_case, _check_case, _same_case),
}


# --- running ---


def _judge(c: Fuzz, result, exc, writes, baselines):
    """None if the case behaved, else (failure kind, detail)."""
    if writes:
        return "wrote to disk", str(writes[:3])
    if exc is not None:
        msg = f"{type(exc).__name__}: {exc}"
        if type(exc) is not ValueError:
            return f"raised {type(exc).__name__}", msg
        if c.expect == "same":
            return "rejected a valid rewrite", msg
        name = c.file or c.entry
        if name not in str(exc):
            return "message without the file name", msg
        missing = [f for f in c.fields if f not in str(exc)]
        if missing:
            return "message without the field", f"wants {missing}: {msg}"
        if c.line_key and c.expect == "error" and c.reader == "scenario":
            text = c.files[c.entry].decode("utf-8", "replace").splitlines()
            line = [int(x) for x in re.findall(r"\(line (\d+)\)", str(exc))]
            if not line:
                return "message without the TOML line", msg
            cited = text[line[0] - 1] if line[0] <= len(text) else ""
            if c.line_key not in cited and not cited.lstrip().startswith("["):
                return "message cites a wrong line", f"{cited!r}: {msg}"
        return None
    if c.expect == "error":
        return "accepted invalid input", ""
    _, check, same = READERS[c.reader]
    bad = check(result)
    if bad:
        return "accepted with bad numbers", str(bad)
    if c.expect == "same":
        diff = same(result, baselines[c.base])
        if diff:
            return "differs from the baseline", str(diff)
    return None


def _baselines(tmp: Path) -> dict:
    """Reader results of the unmutated inputs (the references of "same" cases)."""
    default, areas, geojson = _toml_baselines()
    (tmp / "area.geojson").write_bytes(geojson)
    out = {}
    for name, text in (("default", default), ("areas", areas)):
        (tmp / f"{name}.toml").write_text(text, encoding="utf-8")
        out[name] = load_scenario(tmp / f"{name}.toml")  # both files name the scenario
    for name, rows in _csv_baselines().items():
        (tmp / f"{name}.csv").write_text(_csv_text(rows), encoding="utf-8")
        out[name] = load_targets_csv(tmp / f"{name}.csv")
    out["geojson"] = read_geojson(tmp / "area.geojson")
    if CASE1.is_dir():
        (tmp / "case").mkdir()
        for name, text in _case_baseline().items():
            (tmp / "case" / name).write_text(text, encoding="utf-8")
        out["case"] = load_case(tmp / "case")
    return out


def run_cases(tmp: Path, cases: list[Fuzz], baselines: dict):
    """[(case, (failure kind, detail))] of the cases that broke the contract."""
    failures = []
    for i, c in enumerate(cases):
        folder = tmp / f"c{i:04d}"
        folder.mkdir()
        for name, data in c.files.items():
            (folder / name).write_bytes(data)
        reader = READERS[c.reader][0]
        result, exc, writes = _call(reader, folder / c.entry if c.entry else folder)
        bad = _judge(c, result, exc, writes, baselines)
        if bad is not None:
            failures.append((c, bad))
    return failures


def summary(failures) -> str:
    kinds = Counter(k for _, (k, _) in failures)
    lines = [f"{len(failures)} failing cases"] + [f"  {n:4d}  {k}" for k, n in kinds.most_common()]
    seen = set()
    for c, (k, detail) in failures:
        if (k, c.kind) not in seen:
            seen.add((k, c.kind))
            lines.append(f"  [{k}] {c.kind}: {detail[:300]}")
    return "\n".join(lines)


@pytest.fixture(scope="module")
def baselines(tmp_path_factory):
    return _baselines(tmp_path_factory.mktemp("baselines"))


def test_enough_cases_and_deterministic():
    counts = {name: len(generated(name)) for name in GENERATORS}
    assert sum(counts.values()) >= 300, counts
    assert [c.files for c in generated("csv")[:20]] == [c.files for c in generated("csv")[:20]]
    kinds = Counter(c.expect for name in GENERATORS for c in generated(name))
    assert kinds["error"] >= 100 and kinds["same"] >= 20, kinds


@pytest.mark.parametrize("name", list(GENERATORS))
def test_fuzz_reader(name, baselines, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a relative write would land here
    cases = generated(name)
    if not cases:
        pytest.skip("aeossp benchmark data not present")
    failures = run_cases(tmp_path, cases, baselines)
    assert not failures, summary(failures)
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith("c")) == []


def test_the_write_watch_sees_writes(tmp_path):
    _, _, writes = _call((tmp_path / "x.txt").write_text, "x")
    assert writes and "x.txt" in writes[0]
    _, _, writes = _call((tmp_path / "x.txt").read_text)
    assert writes == []


# --- the schema cases ---


def _in_ranges(sc: Scenario) -> list[str]:
    """Numbers of an accepted scenario outside their ranges (RANGES, in file units)."""
    bad = []

    def within(key, values, scale=1.0):
        lo, hi = RANGES[key]
        hi = sc.duration if hi == "horizon" else hi
        v = np.asarray(values, np.float64) / scale
        if v.size and not (np.all(v >= lo - 1e-9 * abs(lo)) and np.all(v <= hi * (1 + 1e-12))):
            bad.append(key)

    within("scenario.duration_s", sc.duration)
    for s in sc.satellites:
        within("satellites[].rate_deg_s", np.degrees(s.limits.rate))
        within("satellites[].accel_deg_s2", np.degrees(s.limits.accel))
        within("satellites[].off_nadir_max_deg", np.degrees(s.off_nadir_max))
        within("satellites[].settle_s", s.settle)
        within("satellites[].swath_km", s.swath, 1e3)
        if s.fov is not None:
            within("satellites[].fov_deg", np.degrees(s.fov))
        if s.ifov is not None:
            within("satellites[].ifov_deg", np.degrees(s.ifov))
        if s.edge_band is not None:
            within("satellites[].edge_off_nadir_deg", np.degrees(s.edge_band))
        within("satellites[].strip_duration_s", s.strip_duration)
        if s.duty is not None:
            within("satellites[].duty_s_per_orbit", s.duty)
    tg = sc.targets
    area = tg.kind == AREA
    within("targets[].priority", tg.value[~area])
    within("areas[].priority", tg.value[area])
    for f in ("t_lo", "t_hi"):
        v = getattr(tg, f)[area]
        within("areas[].window_s", v[np.isfinite(v)])
    for a in sc.areas:
        if a.spacing:
            within("areas[].grid_km", a.spacing, 1e3)
        if not np.isnan(a.min_share):
            within("areas[].min_coverage", a.min_share)
    point = tg.kind == 0
    within("targets[].duration_s", tg.duration[point])
    for f in ("t_lo", "t_hi"):  # finite windows lie in the horizon
        v = getattr(tg, f)
        within("targets[].window_s", v[np.isfinite(v)])
    for s in sc.stereo:  # a target's own keys share the [stereo] table's ranges
        within("stereo.radius_m", s.radius)
        within("stereo.min_overlap", s.min_overlap)
        within("stereo.convergence_deg", np.degrees(s.convergence))
        within("stereo.band_deg", np.degrees(s.band))
        within("stereo.max_scale_ratio", s.max_scale_ratio)
        within("stereo.max_separation_s", s.max_separation)
        within("stereo.anchor_off_nadir_deg", np.degrees(s.anchor_off_nadir))
        within("stereo.quality_weights", s.weights)
        within("stereo.tri_bonus", s.tri_bonus)
        within("stereo.quality_weight", s.quality_weight)
    pl = sc.planner
    within("planner.time_step_s", pl.time_step)
    within("planner.geometry_step_s", pl.geometry_step)
    within("planner.time_limit_s", pl.default_time_limit)
    within("planner.exact_max_options", pl.exact_max_options)
    if pl.max_actions is not None:
        within("planner.max_actions", pl.max_actions)
    within("planner.area_roll_step_deg", np.degrees(pl.area_roll_step))
    if pl.area_pitch_step is not None:
        within("planner.area_pitch_step_deg", np.degrees(pl.area_pitch_step))
    within("planner.duty_margin_s", pl.margins.duty)
    return bad


def _judge_schema(c: Fuzz, result, exc, writes):
    """None if a schema case behaved, else (failure kind, detail)."""
    if exc is not None and c.expect == "either":
        msg = str(exc)
        if type(exc) is not ValueError:
            return f"raised {type(exc).__name__}", msg
        if not any(name in msg for name in c.files):
            return "message without the file name", msg
        return None if not writes else ("wrote to disk", str(writes[:3]))
    bad = _judge(c, result, exc, writes, {})
    if bad is None and exc is None:
        out = _in_ranges(result)
        return ("accepted a number out of range", str(out)) if out else None
    return bad


def run_schema(tmp: Path, cases: list[Fuzz]):
    """[(case, (failure kind, detail))] of the schema cases that broke the contract."""
    failures = []
    for i, c in enumerate(cases):
        folder = tmp / f"c{i:04d}"
        folder.mkdir()
        for name, data in c.files.items():
            (folder / name).write_bytes(data)
        result, exc, writes = _call(load_scenario, folder / c.entry)
        bad = _judge_schema(c, result, exc, writes)
        if bad is not None:
            failures.append((c, bad))
    return failures


def test_schema_cases_cover_every_key():
    cases = schema_cases()
    kinds = Counter(c.expect for c in cases)
    assert kinds["error"] >= 700 and kinds["either"] >= 100, kinds
    covered = {c.kind.split(":")[1] for c in cases}
    assert set(RANGES) <= covered, sorted(set(RANGES) - covered)
    # every retired area key is refused by name, and the base scenario uses every area key
    assert set(RETIRED) == set(RETIRED_KEYS), sorted(set(RETIRED) ^ set(RETIRED_KEYS))
    retired = {c.kind.split(":")[2] for c in cases if c.kind.startswith("schema:retired:")}
    assert retired == set(RETIRED_KEYS), sorted(set(RETIRED_KEYS) - retired)
    base = next(c for c in cases if c.kind == "schema:base")
    doc = tomllib.loads(base.files["s.toml"].decode())
    used = set().union(*doc["areas"])
    assert used == AREA_KEYS, sorted(AREA_KEYS ^ used)
    # ... every [stereo] key, and a stereo target with every key of its own
    assert set(doc["stereo"]) == STEREO_KEYS, sorted(STEREO_KEYS ^ set(doc["stereo"]))
    stereo = [t for t in doc["targets"] if t.get("kind") == "stereo"]
    assert stereo and set(TARGET_STEREO_KEYS) <= set(stereo[0]), stereo


def test_fuzz_schema_refusals(tmp_path, monkeypatch):
    """Every value that must be refused is refused by name (stops at validation: fast)."""
    monkeypatch.chdir(tmp_path)
    cases = [c for c in schema_cases() if c.expect != "either"]
    failures = run_schema(tmp_path, cases)
    assert not failures, summary(failures)


@pytest.mark.slow
def test_fuzz_schema_boundaries(tmp_path, monkeypatch):
    """Values at the ends of their ranges: accepted with every number in range, or refused
    by another rule with a named error (these load whole scenarios: orbits, areas)."""
    monkeypatch.chdir(tmp_path)
    cases = [c for c in schema_cases() if c.expect == "either"]
    failures = run_schema(tmp_path, cases)
    assert not failures, summary(failures)


@pytest.mark.slow
@pytest.mark.parametrize(
    "kind",
    [
        "schema:base",
        "schema:planner.exact_max_options:hi",
        "schema:targets[].window_s:hi",
        "schema:satellites[].rate_deg_s:hi",
        "schema:planner.time_step_s:hi",
        "schema:satellites[].over.t_s:lo",
        "schema:planner.max_actions:lo",
        "schema:satellites[].duty_s_per_orbit:lo",
        "schema:areas[].min_coverage:hi",
    ],  # fmt: skip
)
def test_fuzz_schema_cases_plan_or_fail_by_name(kind, tmp_path, capfd):
    """Through the command: a plan (exit 0) or a named error (exit 2), never a traceback."""
    from jaxspline.cli import main

    case = next(c for c in schema_cases() if c.kind == kind)  # the first satellite's, ...
    for name, data in case.files.items():
        (tmp_path / name).write_bytes(data)
    out = tmp_path / "out"
    argv = ["plan", str(tmp_path / "s.toml"), "-o", str(out), "--max-iters", "5", "--quiet",
            "--no-aem", "--no-plots", "--no-html", "--time-limit", "600"]  # fmt: skip
    code = main(argv)
    err = capfd.readouterr().err
    assert code in (0, 2) and "Traceback" not in err, (code, err)
    assert (code == 0) == (out / "plan.json").exists()


def _area_scenario(tmp_path, areas: str, name="s.toml"):
    """areas_example.toml without its areas and daylight rule, with ``areas`` instead."""
    _, text, _ = _toml_baselines()
    text = text[: text.index("[[areas]]")] + areas + text[text.index("[[targets]]") :]
    text = text.replace("sun_elevation_min_deg = 10.0\n", "")
    (tmp_path / name).write_text(text, encoding="utf-8")
    return tmp_path / name


def _ring_toml(name, lon0, lon1, lat0=10.0, lat1=10.8):
    ring = [[lon0, lat0], [lon1, lat0], [lon1, lat1], [lon0, lat1]]
    return f'[[areas]]\nname = "{name}"\nlonlat_deg = {ring}\ngrid_km = 4.0\n'


@pytest.mark.parametrize(
    ("ring", "why"),
    [
        ((179.6, -179.6), "span 359.2 deg"),  # a jump across the meridian
        ((179.6, 180.4), "within [-180, 180]"),  # longitudes past 180
        ((-180.4, -179.6), "within [-180, 180]"),
    ],
)
def test_antimeridian_areas_are_refused_with_the_remedy(tmp_path, ring, why):
    with pytest.raises(ValueError) as exc:
        load_scenario(_area_scenario(tmp_path, _ring_toml("dateline", *ring)))
    msg = str(exc.value)
    assert "areas[0].lonlat_deg (line" in msg and why in msg, msg
    assert "antimeridian" in msg and "two areas" in msg, msg


def test_antimeridian_split_geojson_is_refused(tmp_path):
    # RFC 7946 section 3.1.9: an area across the meridian split in two at it
    east = [[179.6, 10], [180, 10], [180, 10.8], [179.6, 10.8], [179.6, 10]]
    west = [[-180, 10], [-179.6, 10], [-179.6, 10.8], [-180, 10.8], [-180, 10]]
    doc = {"type": "MultiPolygon", "coordinates": [[east], [west]]}
    (tmp_path / "d.geojson").write_text(json.dumps(doc), encoding="utf-8")
    assert read_geojson(tmp_path / "d.geojson").geom_type == "MultiPolygon"  # readable
    with pytest.raises(ValueError, match=r"d\.geojson: longitudes span 360 deg.*two areas"):
        load_scenario(_area_scenario(tmp_path, '[[areas]]\ngeojson = "d.geojson"\n'))


def test_areas_either_side_of_the_antimeridian_are_read_in_place(tmp_path):
    """The remedy the error names: one area each side; each is read where it is (its
    polygon as written, its target at its own centre, not on the far side of the Earth)."""
    text = _ring_toml("east", 179.6, 180.0) + _ring_toml("west", -180.0, -179.6)
    sc = load_scenario(_area_scenario(tmp_path, text))
    assert [a.name for a in sc.areas] == ["east", "west"]
    assert not _check_scenario(sc) and not _in_ranges(sc)
    assert [sc.targets.name[a.target] for a in sc.areas] == ["east", "west"]
    for area, lon0 in zip(sc.areas, (179.6, -180.0), strict=True):
        assert sc.targets.kind[area.target] == AREA
        assert area.spacing == 4e3 and area.samples.shape == (0, 3)
        lon, lat = shapely.get_coordinates(shapely.geometry.shape(area.geometry)).T
        np.testing.assert_allclose([lon.min(), lon.max()], [lon0, lon0 + 0.4])
        np.testing.assert_allclose([lat.min(), lat.max()], [10.0, 10.8])
        # its target lies in the area, at the centre's longitude; |lon| wraps at 180
        lat, lon = np.degrees(sc.targets.lat[area.target]), np.degrees(sc.targets.lon[area.target])
        dlon = abs((lon - (lon0 + 0.2) + 180.0) % 360.0 - 180.0)
        assert dlon < 1e-6 and 10.0 < lat < 10.8, (lon, lat)


if __name__ == "__main__":  # python tests/readers/test_fuzz_readers.py: the failure summary
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        base = _baselines(Path(tmp))
        for name in sys.argv[1:] or GENERATORS:
            cases = generated(name)
            (Path(tmp) / name).mkdir()
            fails = run_cases(Path(tmp) / name, cases, base)
            print(f"== {name}: {len(cases)} cases, {len(fails)} failing")
            print(summary(fails))
