"""Generated inputs over every key of the scenario schema (used by ``test_fuzz_readers.py``).

One small valid scenario uses every section: a TLE satellite with every area-strip key
(``fov_deg``, ``edge_off_nadir_deg``, ``strip_duration_s``, ``duty_s_per_orbit``), a
circular one with a battery, a flexible one placed with ``over``, point and strip
targets with windows and desired times, a stereo target with every stereo key and a
``[stereo]`` table with all of its keys (the TLE satellite with ``ifov_deg``, the
circular one with ``ifov_deg`` and ``pixels``), a targets CSV with every column, random
targets, an inline area ring, a GeoJSON area and an area of samples (``smp.csv``)
between them using every area key, and every planner key. For every numeric key (TOML
keys and CSV columns, :data:`jaxspline.readers.ranges.RANGES`) the generator puts
values outside its range (below, above, NaN, infinities, ``1e300``), values of the
wrong type, and values at both ends of its range; for strings, control characters and
over-long names; for TLEs, a damaged checksum, a cut line, swapped lines, an epoch
months away; for GeoJSON, positions given as strings, collinear and zero-area polygons,
a bowtie; for areas, the retired keys of the strip-cutting reader, two polygons or
none, entries that are not tables, bad cells of the sample file; for stereo targets,
bad product names, bands outside the convergence, quality weights not summing to 1,
keys of one kind on a target of another, a field of view that ``pixels x ifov_deg``
contradicts, CSV stereo cells.
Each case says what must happen: ``error`` (a ``ValueError`` naming the file and the
field), ``ok`` (accepted, the value where it belongs) or ``either`` (a value inside
its range that another rule may still refuse, e.g. a geometry step the time step is
no multiple of: accepted, or refused by name).
"""

from __future__ import annotations

import copy
import json
import math
import random

from _fuzz_inputs import Fuzz, _toml

from jaxspline.readers.ranges import HORIZON, RANGES

SEED = 20261126
DURATION_S = 3600.0
TLE = [
    "1 44622U 19066A   26103.98739708  .00000848  00000+0  11127-3 0  9997",
    "2 44622  98.0448  57.1255 0005574   1.4726 358.6503 14.82916452352865",
]
BASE = {
    "targets_csv": "t.csv",
    "scenario": {"name": "fuzz", "epoch": "2026-04-14T06:00:00Z", "duration_s": DURATION_S},
    "satellites": [
        {"name": "tle", "tle": TLE, "model": "per_channel", "rate_deg_s": [3.0, 3.0, 2.0],
         "accel_deg_s2": [1.5, 1.5, 1.0], "off_nadir_max_deg": 30.0, "sensor": "visible",
         "swath_km": 15.0, "fov_deg": 1.2, "ifov_deg": 5e-4, "edge_off_nadir_deg": [0.0, 25.0],
         "strip_duration_s": [5.0, 60.0], "duty_s_per_orbit": 600.0},
        {"name": "circ", "altitude_km": 600.0, "inclination_deg": 97.8, "raan_deg": 10.0,
         "arg_lat_deg": 20.0, "model": "eigen_axis", "rate_deg_s": 1.8, "accel_deg_s2": 0.4,
         "settle_s": 2.0, "ifov_deg": 6.5e-5, "pixels": 12000,
         "power": {"capacity_wh": 1300.0, "initial_wh": 800.0,
         "idle_w": 20.0, "imaging_w": 420.0, "slew_w": 360.0, "charge_w": 85.0}},
        {"name": "flex", "over": {"lat_deg": 46.0, "lon_deg": 14.5, "t_s": 1800.0,
         "descending": True}, "model": "flexible", "rate_deg_s": 1.5, "accel_deg_s2": 0.3,
         "flex": {"freq_hz": 0.5, "damping": 0.01, "tolerance_deg": 0.006}},
    ],
    "targets": [
        {"kind": "point", "name": "p", "lat_deg": 46.05, "lon_deg": 14.51, "alt_m": 295.0,
         "duration_s": 10.0, "priority": 5.0, "window_s": [100.0, 3000.0], "sensor": "",
         "desired_s": 1800.0, "tolerance_s": 900.0, "min_duration_s": 8.0},
        {"kind": "strip", "name": "s", "lat_deg": 46.3, "lon_deg": 14.2, "length_km": 40.0,
         "azimuth_deg": 190.0, "priority": 3.0},
        {"kind": "stereo", "name": "st", "lat_deg": 46.1, "lon_deg": 14.6, "alt_m": 300.0,
         "priority": 2.0, "window_s": [0.0, 3000.0], "sensor": "visible", "product": "tri",
         "radius_m": 4000.0, "band_deg": [10.0, 20.0], "tri_bonus": 0.1},
    ],
    "stereo": {"product": "pair", "radius_m": 5000.0, "min_overlap": 0.8,
               "convergence_deg": [5.0, 45.0], "band_deg": [8.0, 18.0], "max_scale_ratio": 1.5,
               "max_separation_s": 3600.0, "cross_satellite": True,
               "anchor_off_nadir_deg": 10.0, "quality_weights": [0.5, 0.35, 0.15],
               "tri_bonus": 0.12, "quality_weight": 0.5},
    "random_targets": {"seed": 1, "count": 5, "lat_deg": [40.0, 50.0], "lon_deg": [10.0, 20.0],
                       "land_only": False, "strip_fraction": 0.5, "duration_s": [10.0, 20.0],
                       "length_km": [20.0, 40.0], "azimuth_deg": [0.0, 180.0],
                       "priority": [1, 5]},
    "areas": [
        {"name": "ring", "lonlat_deg": [[14.0, 45.9], [14.3, 45.9], [14.3, 46.1], [14.0, 46.1]],
         "priority": 10.0, "sensor": "", "window_s": [0.0, DURATION_S], "grid_km": 4.0,
         "min_coverage": 0.2},
        {"name": "file", "geojson": "a.geojson", "priority": 4.0},
        {"name": "samples", "samples_csv": "smp.csv", "priority": 2.0, "sensor": "visible",
         "min_coverage": 0.5},
    ],
    "planner": {"time_step_s": 10.0, "geometry_step_s": 5.0, "scan_speeds_km_s": [5.0, 7.0],
                "sun_elevation_min_deg": -10.0, "off_nadir_margin_deg": 0.01,
                "horizon_margin": 0.0, "gap_margin_s": 0.1, "battery_margin_wh": 10.0,
                "shadow_guard_steps": 1, "exact_max_options": 60, "lagrangian_share": 0.3,
                "bound_worker": True, "refine_steps": 100, "time_limit_s": 30.0,
                "max_actions": 500, "area_roll_step_deg": 0.5, "area_pitch_step_deg": 5.0,
                "duty_margin_s": 1.0},
}  # fmt: skip
CSV_HEAD = ("name,lat_deg,lon_deg,priority,kind,alt_m,duration_s,length_km,azimuth_deg,"
            "window_lo_s,window_hi_s,sensor,desired_s,tolerance_s,min_duration_s,"
            "product,radius_m,band_lo_deg,band_hi_deg,tri_bonus")  # fmt: skip
CSV_ROWS = [
    "c1,45.5,13.8,2,point,10,12,,,0,3600,,1800,1800,5,,,,,",
    "c2,46.5,15.5,3,strip,0,,25,45,,,visible,,,,,,,,",
    "c3,46.2,14.9,2,stereo,0,,,,0,3600,visible,,,,tri,4500,9,19,0.08",
]
GEOJSON = {
    "type": "Polygon",
    "coordinates": [[[14.6, 46.0], [14.9, 46.0], [14.9, 46.2], [14.6, 46.2], [14.6, 46.0]]],
}
SAMPLES_HEAD = "lon_deg,lat_deg,weight"
SAMPLES_ROWS = ["14.40,46.00,0.3", "14.45,46.02,0.3", "14.50,46.04,0.2"]
#: A value of every retired area key (refused naming the key: "is no longer read").
RETIRED = {"swath_km": 12.0, "max_length_km": 30.0, "objective": "coverage"}


def _paths(prefix, table):
    """(path of a numeric key in BASE, RANGES key) of every number of ``table``."""
    out = []
    for key, value in table.items():
        rng = f"{prefix}.{key}"
        if isinstance(value, dict) and key in ("over", "flex", "power"):
            out += [((key, *p), r) for p, r in _paths(rng, value)]
        elif rng in RANGES:
            out.append(((key,), rng))
    return out


def numeric_paths():
    """(document path, RANGES key) of every numeric key of :data:`BASE`."""
    out = [(("scenario", "duration_s"), "scenario.duration_s")]
    out += [(("stereo", *p), r) for p, r in _paths("stereo", BASE["stereo"])]
    for i, sat in enumerate(BASE["satellites"]):
        out += [(("satellites", i, *p), r) for p, r in _paths("satellites[]", sat)]
    for i, tg in enumerate(BASE["targets"]):
        out += [(("targets", i, *p), r) for p, r in _paths("targets[]", tg)]
    out += [(("areas", 0, *p), r) for p, r in _paths("areas[]", BASE["areas"][0])]
    out += [
        (("random_targets", *p), r) for p, r in _paths("random_targets", BASE["random_targets"])
    ]
    out += [(("planner", *p), r) for p, r in _paths("planner", BASE["planner"])]
    return out


def _label(path) -> str:
    """``satellites[1].power.capacity_wh`` of a document path."""
    text = str(path[0])
    for p in path[1:]:
        text += f"[{p}]" if isinstance(p, int) else f".{p}"
    return text


#: Keys of the stereo schema: four bad values each (below, above, 1e300 or NaN, text), not
#: ten; their checks are the shared field readers that every other key exercises in full,
#: and the file's run time stays what it was (a case costs ~3 ms, most of it TOML).
FEW_BAD_KEYS = frozenset(k for k in RANGES if k.startswith("stereo.")) | {
    "targets[].radius_m", "targets[].band_deg", "targets[].tri_bonus",
    "satellites[].ifov_deg", "satellites[].pixels",
}  # fmt: skip
_FEW_LABELS = ("below", "above", "1e300", "nan", "text")


def _bad_values(rng_key, old):
    """(label, value) that must be refused at ``rng_key`` (old: the valid value there)."""
    lo, hi = RANGES[rng_key]
    hi = DURATION_S if hi == HORIZON else hi
    integer = isinstance(lo, int) and isinstance(hi, int)
    step = max(abs(hi - lo), 1.0)
    out = [
        ("below", lo - (1 if integer else 0.5 * step)),
        ("above", hi + (1 if integer else 0.5 * step)),
        ("1e300", 1e300 if not integer else 10**30),
        ("-1e300", -1e300 if not integer else -(10**30)),
        ("text", "5"),
        ("bool", True),
        ("table", {"x": 1}),
    ]
    if not integer:
        out += [("nan", math.nan), ("inf", math.inf), ("-inf", -math.inf)]
    if rng_key in FEW_BAD_KEYS:
        out = [(lab, v) for lab, v in out if lab in _FEW_LABELS and (integer or lab != "1e300")]
    if isinstance(old, list):  # a pair or a per-channel list: spoil one entry
        spoil = ("below", "above", "1e300", "-1e300")
        out = [(f"{lab}[0]", [v, *old[1:]]) if lab in spoil else (lab, v) for lab, v in out]
    return out


def _good_values(rng_key, old):
    lo, hi = RANGES[rng_key]
    hi = DURATION_S if hi == HORIZON else hi
    vals = [("lo", lo), ("hi", hi)]
    if isinstance(old, list):
        vals = [(lab, [v] * len(old)) for lab, v in vals]
    return vals


def _set(doc, path, value):
    node = doc
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value


def _get(doc, path):
    for p in path:
        doc = doc[p]
    return doc


def _case(kind, doc, fields, expect, csv_rows=None, geojson=None, line_key=None, samples=None):
    """A schema case; a spoiled ``csv_rows`` / ``geojson`` / ``samples`` (rows of
    ``smp.csv``, header included) is the file its error must name."""
    files = {
        "s.toml": _toml(doc).encode(),
        "t.csv": "\n".join([CSV_HEAD, *(CSV_ROWS if csv_rows is None else csv_rows)]).encode(),
        "a.geojson": json.dumps(GEOJSON if geojson is None else geojson).encode(),
        "smp.csv": "\n".join(
            [SAMPLES_HEAD, *SAMPLES_ROWS] if samples is None else samples
        ).encode(),
    }
    file = (
        "t.csv" if csv_rows is not None
        else "a.geojson" if geojson is not None
        else "smp.csv" if samples is not None
        else ""
    )  # fmt: skip
    return Fuzz(kind, files, "scenario", "s.toml", fields, expect, line_key, "schema", file)


def number_cases(rng) -> list[Fuzz]:
    """Out-of-range, wrong-type and boundary values at every numeric key of the TOML."""
    out = []
    hours = copy.deepcopy(BASE)  # the horizon in hours instead
    del hours["scenario"]["duration_s"]
    for lab, value in _bad_values("scenario.duration_h", 1.0):
        hours["scenario"]["duration_h"] = value
        out.append(_case(f"schema:scenario.duration_h:{lab}", hours, ("scenario.duration_h",),
                         "error", line_key="duration_h"))  # fmt: skip
    for path, key in numeric_paths():
        old = _get(BASE, path)
        label, name = _label(path), str(path[-1])
        for lab, value in _bad_values(key, old):
            doc = copy.deepcopy(BASE)
            _set(doc, path, value)
            out.append(_case(f"schema:{key}:{lab}", doc, (label,), "error", line_key=name))
        for lab, value in _good_values(key, old):
            doc = copy.deepcopy(BASE)
            _set(doc, path, value)
            out.append(_case(f"schema:{key}:{lab}", doc, (), "either"))
    return out


CSV_COLUMNS = {
    "lat_deg": "targets[].lat_deg", "lon_deg": "targets[].lon_deg",
    "priority": "targets[].priority", "alt_m": "targets[].alt_m",
    "duration_s": "targets[].duration_s", "window_lo_s": "targets[].window_s",
    "window_hi_s": "targets[].window_s", "desired_s": "targets[].desired_s",
    "tolerance_s": "targets[].tolerance_s", "min_duration_s": "targets[].min_duration_s",
}  # fmt: skip
CSV_STRIP_COLUMNS = {"length_km": "targets[].length_km", "azimuth_deg": "targets[].azimuth_deg"}
CSV_STEREO_COLUMNS = {
    "radius_m": "targets[].radius_m", "band_lo_deg": "targets[].band_deg",
    "band_hi_deg": "targets[].band_deg", "tri_bonus": "targets[].tri_bonus",
}  # fmt: skip


def csv_cases(rng) -> list[Fuzz]:
    """Out-of-range and non-numeric cells in every numeric CSV column, control characters."""
    head = CSV_HEAD.split(",")
    out = []
    for cols, row in ((CSV_COLUMNS, 0), (CSV_STRIP_COLUMNS, 1), (CSV_STEREO_COLUMNS, 2)):
        for col, key in cols.items():
            lo, hi = RANGES[key]
            hi = DURATION_S if hi == HORIZON else hi
            for lab, cell in [("below", lo - max(1.0, abs(hi - lo))), ("above", 2 * hi + 1),
                              ("1e300", 1e300), ("nan", "nan"), ("text", "abc")]:  # fmt: skip
                cells = CSV_ROWS[row].split(",")
                cells[head.index(col)] = str(cell)
                rows = list(CSV_ROWS)
                rows[row] = ",".join(cells)
                fields = (f"row {row + 2}", f"column {col!r}")
                out.append(_case(f"schema:csv:{col}:{lab}", BASE, fields, "error", rows))
    for lab, name in (("nul", "a\x00b"), ("esc", "a\x1bb"), ("bell", "x\x07"), ("long", "n" * 300)):
        rows = [name + CSV_ROWS[0][2:], *CSV_ROWS[1:]]
        out.append(_case(f"schema:csv:name:{lab}", BASE, ("row 2", "column 'name'"), "error", rows))
    return out


def _tle_line(line: str) -> str:
    """``line`` (69 columns) with its checksum recomputed."""
    body = line[:68]
    return body + str(sum(int(c) if c.isdigit() else c == "-" for c in body) % 10)


def text_cases(rng) -> list[Fuzz]:
    """Names with control characters, TLE damage, epochs far from the TLEs, polygons."""
    out = []
    where = [("satellites", 0, "name"), ("satellites", 1, "sensor"), ("targets", 0, "name"),
             ("targets", 1, "sensor"), ("areas", 0, "name"), ("scenario", "name")]  # fmt: skip
    for path in where:
        for lab, text in (("nul", "a\x00b"), ("newline", "a\nb"), ("esc", "\x1b[31m"),
                          ("c1", "x\x9b"), ("long", "n" * 300)):  # fmt: skip
            doc = copy.deepcopy(BASE)
            _set(doc, path, text)
            out.append(_case(f"schema:text:{lab}", doc, (_label(path),), "error"))
    l1, l2 = TLE
    damaged = {
        "checksum": [l1[:68] + str((int(l1[68]) + 1) % 10), l2],
        "digit": [l1[:30] + ("1" if l1[30] != "1" else "2") + l1[31:], l2],
        "cut": [l1[:60], l2],
        "swapped": [l2, l1],
        "other_sat": [l1, _tle_line(l2[:2] + "12345" + l2[7:])],
        "one_line": [l1],
        "far_epoch": None,
    }
    for lab, tle in damaged.items():
        doc = copy.deepcopy(BASE)
        if tle is None:
            doc["scenario"]["epoch"] = "2026-09-01T00:00:00Z"  # months from the TLE
            fields = ("satellites[0].tle", "30 days")
        else:
            doc["satellites"][0]["tle"] = tle
            fields = ("satellites[0].tle",)
        out.append(_case(f"schema:tle:{lab}", doc, fields, "error"))
    for lab, epoch in (("y9999", "9999-12-31T00:00:00Z"), ("y1900", "1900-01-01T00:00:00Z"),
                       ("text", "yesterday")):  # fmt: skip
        doc = copy.deepcopy(BASE)
        doc["scenario"]["epoch"] = epoch
        out.append(_case(f"schema:epoch:{lab}", doc, ("scenario.epoch",), "error"))
    out += _polygon_cases()
    out += area_cases()
    return out


def area_cases() -> list[Fuzz]:
    """The area tables' own rules: retired keys, a polygon or samples, the sample file."""
    out = []
    for i in (0, 1, 2):  # the keys of the strip-cutting reader are refused by name
        for key, value in RETIRED.items():
            doc = copy.deepcopy(BASE)
            doc["areas"][i][key] = value
            fields = (f"areas[{i}].{key}", "is no longer read")
            out.append(_case(f"schema:retired:{key}", doc, fields, "error", line_key=key))
    wrong = {  # label: (area, changed keys (None: deleted), fields named, TOML line key)
        "both_polygons": (0, {"geojson": "a.geojson"}, ("areas[0].geojson",), "geojson"),
        "no_polygon": (0, {"lonlat_deg": None}, ("areas[0].geojson",), None),
        "unknown_key": (1, {"swath": 10.0}, ("areas[1].swath",), None),
        "no_sensor": (1, {"sensor": "radar"}, ("areas[1].sensor", "radar"), "sensor"),
        "samples_number": (2, {"samples_csv": 3}, ("areas[2].samples_csv",), "samples_csv"),
        "samples_empty": (2, {"samples_csv": ""}, ("areas[2].samples_csv",), "samples_csv"),
        "samples_missing": (2, {"samples_csv": "none.csv"}, ("areas[2].samples_csv", "none.csv"),
                            "samples_csv"),
        "geojson_missing": (1, {"geojson": "none.geojson"}, ("areas[1].geojson", "none.geojson"),
                            "geojson"),
        "dup_name": (2, {"name": "ring"}, ("areas[2].name", "areas[0]"), "name"),
    }  # fmt: skip
    for lab, (i, change, fields, line_key) in wrong.items():
        doc = copy.deepcopy(BASE)
        for key, value in change.items():
            if value is None:
                del doc["areas"][i][key]
            else:
                doc["areas"][i][key] = value
        out.append(_case(f"schema:area:{lab}", doc, fields, "error", line_key=line_key))
    for lab, entry in (("number", 95.0), ("bool", True), ("text", "ring"), ("list", [1.0])):
        doc = copy.deepcopy(BASE)  # an [[areas]] entry that is not a table
        doc["areas"].append(entry)
        out.append(_case(f"schema:area:entry_{lab}", doc, ("areas[3]",), "error"))
    both = copy.deepcopy(BASE)  # samples with their polygon (drawn, not sampled)
    both["areas"][2]["lonlat_deg"] = BASE["areas"][0]["lonlat_deg"]
    out.append(_case("schema:area:samples_and_polygon", both, (), "either"))
    cells = {
        ("lon_deg", "nan"), ("lon_deg", "181"), ("lon_deg", "-180.5"), ("lon_deg", "abc"),
        ("lon_deg", ""), ("lat_deg", "95"), ("lat_deg", "-inf"), ("lat_deg", "1e300"),
        ("weight", "-0.1"), ("weight", "1.5"), ("weight", "nan"), ("weight", "true"),
    }  # fmt: skip
    head = SAMPLES_HEAD.split(",")
    for col, cell in sorted(cells):
        for row in (0, 2):
            cells_ = SAMPLES_ROWS[row].split(",")
            cells_[head.index(col)] = cell
            rows = [SAMPLES_HEAD, *SAMPLES_ROWS]
            rows[row + 1] = ",".join(cells_)
            fields = ("areas[2].samples_csv", f"row {row + 2}", col)
            out.append(_case(f"schema:samples:{col}:{cell or 'empty'}", BASE, fields, "error",
                             line_key="samples_csv", samples=rows))  # fmt: skip
    files = {
        "sum": ([SAMPLES_HEAD, *SAMPLES_ROWS, "14.55,46.06,0.3"], "sum"),
        "missing_column": (["lon_deg,lat_deg,w", *SAMPLES_ROWS], "'weight'"),
        "no_rows": ([SAMPLES_HEAD], "no samples"),
        "empty": ([], "lon_deg"),
        "short_row": ([SAMPLES_HEAD, "14.40,46.00", *SAMPLES_ROWS[1:]], "row 2"),
    }
    for lab, (rows, what) in files.items():
        out.append(_case(f"schema:samples:{lab}", BASE, ("areas[2].samples_csv", what), "error",
                         line_key="samples_csv", samples=rows))  # fmt: skip
    return out


_NOT_STEREO = {"duration_s": 10.0, "length_km": 5.0, "azimuth_deg": 10.0, "min_duration_s": 2.0,
               "desired_s": 100.0, "tolerance_s": 10.0}  # fmt: skip
_STEREO_ONLY = {"product": "pair", "radius_m": 5000.0, "band_deg": [8.0, 18.0], "tri_bonus": 0.1}
STEREO_WRONG = {  # label: (table's path, changes (None: deleted), fields named, TOML line key)
    "table_product": (("stereo",), {"product": "quad"}, ("stereo.product", "quad"), "product"),
    "table_product_number": (("stereo",), {"product": 2}, ("stereo.product",), "product"),
    "target_product": (("targets", 2), {"product": "pairs"}, ("targets[2].product", "pairs"),
                       "product"),
    "cross_satellite": (("stereo",), {"cross_satellite": "yes"}, ("stereo.cross_satellite",),
                        "cross_satellite"),
    "weights_two": (("stereo",), {"quality_weights": [0.5, 0.5]}, ("stereo.quality_weights",),
                    "quality_weights"),
    "weights_sum": (("stereo",), {"quality_weights": [0.5, 0.5, 0.5]},
                    ("stereo.quality_weights", "sum to 1"), "quality_weights"),
    "weights_number": (("stereo",), {"quality_weights": 1.0}, ("stereo.quality_weights",),
                       "quality_weights"),
    "table_band_outside": (("stereo",), {"band_deg": [2.0, 18.0]},
                           ("stereo.band_deg", "convergence_deg"), "band_deg"),
    "target_band_outside": (("targets", 2), {"band_deg": [30.0, 50.0]},
                            ("targets[2].band_deg", "convergence_deg"), "band_deg"),
    "target_band_order": (("targets", 2), {"band_deg": [20.0, 10.0]}, ("targets[2].band_deg",),
                          "band_deg"),
    "target_band_one": (("targets", 2), {"band_deg": [10.0]}, ("targets[2].band_deg",),
                        "band_deg"),
    "unknown_key": (("stereo",), {"overlap": 0.8}, ("stereo.overlap",), None),
    "pixels_no_ifov": (("satellites", 1), {"ifov_deg": None}, ("satellites[1].pixels", "ifov_deg"),
                       "pixels"),
    "fov_disagrees": (("satellites", 1), {"fov_deg": 1.0}, ("satellites[1].fov_deg", "disagrees"),
                      "fov_deg"),
    "ifov_over_fov": (("satellites", 0), {"ifov_deg": 0.9, "fov_deg": 0.5},
                      ("satellites[0].ifov_deg", "field of view"), "ifov_deg"),
    "pixels_float": (("satellites", 1), {"pixels": 12000.0}, ("satellites[1].pixels",), "pixels"),
    **{f"stereo_{k}": (("targets", 2), {k: v}, (f"targets[2].{k}", "stereo target takes no"), k)
       for k, v in _NOT_STEREO.items()},
    **{f"point_{k}": (("targets", 0), {k: v}, (f"targets[0].{k}", "only a stereo target"), k)
       for k, v in _STEREO_ONLY.items()},
}  # fmt: skip
#: CSV cells of the stereo rules: (row, column, cell, words of the message).
STEREO_CELLS = [
    (2, "product", "quad", "'quad'"),
    (2, "band_hi_deg", "", "give both"),
    (2, "band_lo_deg", "2", "convergence_deg"),
    (2, "duration_s", "10", "stereo target takes no"),
    (0, "tri_bonus", "0.1", "only a stereo target"),
    (1, "radius_m", "4000", "only a stereo target"),
]


def stereo_cases() -> list[Fuzz]:
    """The stereo rules beyond ranges: product names, the band inside the convergence,
    the quality weights, keys of one kind on a target of another, a field of view of
    pixels, a ``[stereo]`` that is not a table, the CSV stereo cells."""
    out = []
    for lab, (path, change, fields, line_key) in STEREO_WRONG.items():
        doc = copy.deepcopy(BASE)
        table = _get(doc, path)
        for key, value in change.items():
            if value is None:
                del table[key]
            else:
                table[key] = value
        out.append(_case(f"schema:stereo:{lab}", doc, fields, "error", line_key=line_key))
    for lab, value in (("number", 5), ("list", [{"product": "pair"}])):
        doc = copy.deepcopy(BASE)
        doc["stereo"] = value
        out.append(_case(f"schema:stereo:table_{lab}", doc, ("stereo",), "error"))
    head = CSV_HEAD.split(",")
    for row, col, cell, what in STEREO_CELLS:
        cells = CSV_ROWS[row].split(",")
        cells[head.index(col)] = cell
        rows = list(CSV_ROWS)
        rows[row] = ",".join(cells)
        fields = (f"row {row + 2}", f"column {col!r}", what)
        out.append(_case(f"schema:stereo:csv_{col}", BASE, fields, "error", rows))
    return out


def _polygon_cases() -> list[Fuzz]:
    out = []
    rings = {
        "collinear": [[14.0, 46.0], [14.1, 46.1], [14.2, 46.2]],
        "zero_area": [[14.0, 46.0], [14.2, 46.0], [14.0, 46.0], [14.2, 46.0]],
        "bowtie": [[14.0, 46.0], [14.2, 46.2], [14.2, 46.0], [14.0, 46.2]],
        "repeated": [[14.0, 46.0], [14.0, 46.0], [14.0, 46.0]],
    }
    for lab, ring in rings.items():
        doc = copy.deepcopy(BASE)
        doc["areas"][0]["lonlat_deg"] = ring
        out.append(_case(f"schema:ring:{lab}", doc, ("areas[0].lonlat_deg",), "error"))
        closed = ring + [ring[0]]
        out.append(_case(f"schema:geojson:{lab}", BASE, ("areas[1].geojson",), "error",
                         geojson={"type": "Polygon", "coordinates": [closed]}))  # fmt: skip
    spoiled = {
        "string_lon": [["14.6", 46.0], [14.9, 46.0], [14.9, 46.2], [14.6, 46.0]],
        "bool_lat": [[14.6, True], [14.9, 46.0], [14.9, 46.2], [14.6, True]],
        "null": [[14.6, None], [14.9, 46.0], [14.9, 46.2], [14.6, None]],
        "one_number": [[14.6], [14.9, 46.0], [14.9, 46.2], [14.6]],
    }
    for lab, ring in spoiled.items():
        out.append(_case(f"schema:geojson:{lab}", BASE, ("areas[1].geojson", "coordinates"),
                         "error", geojson={"type": "Polygon", "coordinates": [ring]}))  # fmt: skip
    return out


def schema_cases(rng=None) -> list[Fuzz]:
    """All the cases of this module, in a fixed order (``rng`` unused: no randomness)."""
    rng = rng or random.Random(SEED)
    return (
        number_cases(rng)
        + csv_cases(rng)
        + text_cases(rng)
        + stereo_cases()
        + [_case("schema:base", BASE, (), "ok")]
    )
