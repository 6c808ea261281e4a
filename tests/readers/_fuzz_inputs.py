"""Generated bad inputs of the file readers (used by ``test_fuzz_readers.py``).

Seeded mutations of the packaged valid files and of an aeossp_standard case; each
:class:`Fuzz` case says which reader reads it, what the error must name, and whether
it must be rejected, must give the baseline's result, or may be either.
"""

from __future__ import annotations

import csv
import dataclasses
import datetime as dt
import io
import json
import math
import random
import tomllib
from pathlib import Path

import yaml

import jaxspline

SEED = 20260420
DATA = Path(jaxspline.__file__).parent / "data"
CASE1 = Path("/work/shared/data/aeossp_standard/train/case_0001")
ARRAYS_OF_TABLES = ("satellites", "targets", "routes", "areas", "tasks")
CSV_ROWS = 40  # data rows of cities.csv kept in the CSV baselines
NAN, INF = math.nan, math.inf

# --- generated cases ---


@dataclasses.dataclass
class Fuzz:
    """One generated input.

    Attributes:
      kind: mutation label (``"toml:value:nan"``), the unit of the failure summary.
      files: file name -> bytes written into the case's folder.
      reader: "scenario" | "csv" | "geojson" | "case".
      entry: the file given to the reader ("" for a case folder).
      fields: substrings an error message must contain besides the file name.
      expect: "error" (must be rejected), "same" (the baseline's result) or "either".
      line_key: a TOML key whose line an error must cite (None: no line check).
      base: name of the baseline result a "same" case is compared with.
      file: the file name an error must contain (default: ``entry``).
    """

    kind: str
    files: dict
    reader: str
    entry: str
    fields: tuple = ()
    expect: str = "either"
    line_key: str | None = None
    base: str = ""
    file: str = ""


def _is_number(x) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _leaves(node, path=()):
    """Every path to a value of a parsed document (tables, lists, scalars), depth first."""
    out = [path] if path else []
    if isinstance(node, dict):
        for k, v in node.items():
            out += _leaves(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _leaves(v, (*path, i))
    return out


def _get(doc, path):
    for p in path:
        doc = doc[p]
    return doc


def _copy(doc):
    return json.loads(json.dumps(doc)) if doc is not None else None


def _prefix(path) -> str:
    """``satellites[1]`` for a path inside an array of tables, else its first key."""
    if len(path) > 1 and path[0] in ARRAYS_OF_TABLES and isinstance(path[1], int):
        return f"{path[0]}[{path[1]}]"
    return str(path[0])


def _fields(path) -> tuple:
    keys = [p for p in path if isinstance(p, str)]
    return tuple(dict.fromkeys((_prefix(path), keys[-1])))


# values put in place of a leaf: (label, value)
BAD_VALUES = [
    ("nan", NAN),
    ("inf", INF),
    ("-inf", -INF),
    ("text", "abc"),
    ("empty_text", ""),
    ("bool", True),
    ("list", [1.0, 2.0]),
    ("list4", [1.0, 1.0, 1.0, 1.0]),
    ("table", {"x": 1}),
    ("negative", -1.0),
    ("zero", 0),
    ("huge", 1e308),
    ("tiny", 1e-300),
    ("bigint", 10**12),
    ("lat95", 95.0),
    ("lon-181", -181.0),
    ("int", 7),
    ("unicode", "Ljubljana\u00e9\u2019 \u4e2d"),
]


def _must_fail(old, label, new, key) -> bool:
    """Whether replacing ``old`` (at ``key``) by ``new`` is certainly invalid."""
    if _is_number(old):
        if label in ("nan", "inf", "-inf") or not (_is_number(new) or isinstance(new, list)):
            return True
        if key in ("lat_deg", "latitude_deg") and label == "lat95":
            return True
        if key in ("lon_deg", "longitude_deg") and label == "lon-181":
            return True
        return False
    if isinstance(old, bool):
        return not isinstance(new, bool)
    if isinstance(old, str):
        return not isinstance(new, str | dt.datetime)
    return False


def _structured(rng, doc, n, prefix, skip=()):
    """``n`` (kind, new document, fields, expect, line key) mutations of a parsed doc."""
    paths = [p for p in _leaves(doc) if not any(p[: len(s)] == s for s in skip)]
    out = []
    for _ in range(n):
        path = rng.choice(paths)
        new = _copy(doc)
        parent, key = _get(new, path[:-1]), path[-1]
        old = parent[key]
        name = next((p for p in reversed(path) if isinstance(p, str)), str(path[0]))
        op = rng.choice(["value"] * 6 + ["delete", "unknown", "empty"])
        if op == "value":
            label, value = rng.choice(BAD_VALUES)
            parent[key] = _copy(value) if isinstance(value, list | dict) else value
            expect = "error" if _must_fail(old, label, value, name) else "either"
            out.append((f"{prefix}:value:{label}", new, _fields(path), expect, name))
        elif op == "delete":
            del parent[key]
            out.append((f"{prefix}:delete", new, (_prefix(path),), "either", None))
        elif op == "unknown":
            table = _get(new, path[:-1]) if isinstance(parent, dict) else new
            table["frobnicate_x"] = 1.0
            out.append((f"{prefix}:unknown_key", new, ("frobnicate_x",), "error", None))
        else:
            parent[key] = {} if isinstance(old, dict) else []
            out.append((f"{prefix}:empty", new, (_prefix(path),), "either", None))
    return out


# --- TOML: a small writer (one key a line, nested tables inline, as the packaged files) ---


def _toml_key(k) -> str:
    k = str(k)
    return k if k.replace("_", "a").replace("-", "a").isalnum() and k.isascii() else json.dumps(k)


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return (
            "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
        )
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, dt.datetime | dt.date):
        return v.isoformat()
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"


def _toml(doc) -> str:
    def aot(v):
        return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)

    lines = [
        f"{_toml_key(k)} = {_toml_value(v)}"
        for k, v in doc.items()
        if not (isinstance(v, dict) or aot(v))
    ]
    for k, v in doc.items():
        for table, head in (([v], f"[{k}]") if isinstance(v, dict) else (v, f"[[{k}]]"),):
            if not (isinstance(v, dict) or aot(v)):
                continue
            for t in table:
                lines += ["", head] + [f"{_toml_key(a)} = {_toml_value(b)}" for a, b in t.items()]
    return "\n".join(lines) + "\n"


def _text_mutations(rng, text: str, prefix: str, n_random: int):
    """(kind, bytes, expect) of file-level mutations of a text file (all formats)."""
    raw = text.encode()
    lines = text.splitlines(keepends=True)
    out = [
        (f"{prefix}:bom", b"\xef\xbb\xbf" + raw, "same"),
        (f"{prefix}:crlf", text.replace("\n", "\r\n").encode(), "same"),
        (f"{prefix}:bom_crlf", b"\xef\xbb\xbf" + text.replace("\n", "\r\n").encode(), "same"),
        (f"{prefix}:empty", b"", "error"),
        (f"{prefix}:blank", b"  \n\n\t\n", "error"),
        (
            f"{prefix}:non_utf8",
            raw[: len(raw) // 2] + b"\xff\xfe\xc3" + raw[len(raw) // 2 :],
            "error",
        ),
        (f"{prefix}:latin1", text.replace("a", "\u00e4", 3).encode("latin-1", "replace"), "either"),
    ]
    for _ in range(n_random):
        op = rng.choice(["truncate", "drop_line", "dup_line", "garbage", "nul", "drop_char"])
        if op == "truncate":
            data = raw[: rng.randrange(1, len(raw))]
        elif op == "drop_line":
            k = rng.randrange(len(lines))
            data = "".join(lines[:k] + lines[k + 1 :]).encode()
        elif op == "dup_line":
            k = rng.randrange(len(lines))
            data = "".join(lines[: k + 1] + lines[k:]).encode()
        elif op == "garbage":
            k = rng.randrange(len(raw))
            junk = rng.choice([b"{", b"]", b'"', b"=", b",", b"\t", b"- ", b":", b"[[", b"\\"])
            data = raw[:k] + junk + raw[k:]
        elif op == "nul":
            k = rng.randrange(len(raw))
            data = raw[:k] + b"\x00" + raw[k:]
        else:
            k = rng.randrange(len(raw))
            data = raw[:k] + raw[k + 1 :]
        out.append((f"{prefix}:{op}", data, "either"))
    return out


# numbers that size work (horizon, grids, strip counts): every extreme value is tried
EXTREME_PATHS = {
    "default": [
        ("scenario", "duration_h"),
        ("random_targets", "count"),
        ("random_targets", "length_km", 1),
        ("planner", "scan_speeds_km_s", 0),
    ],
    "areas": [
        ("scenario", "duration_h"),
        ("planner", "time_step_s"),
        ("planner", "geometry_step_s"),
        ("satellites", 0, "swath_km"),
        ("areas", 0, "grid_km"),
        ("areas", 1, "grid_km"),
        ("areas", 1, "min_coverage"),
        ("areas", 1, "lonlat_deg", 0, 0),
        ("targets", 0, "desired_s"),
    ],
}


def _toml_baselines():
    default = (DATA / "default.toml").read_text(encoding="utf-8")
    default = default.replace('"cities.csv"', json.dumps(str(DATA / "cities.csv")))
    default = default.replace("land_only = true", "land_only = false")
    areas = (DATA / "areas_example.toml").read_text(encoding="utf-8")
    areas = areas.replace('"areas_example.geojson"', '"area.geojson"')
    geojson = (DATA / "areas_example.geojson").read_bytes()
    return default, areas, geojson


def toml_cases(rng) -> list[Fuzz]:
    default, areas, geojson = _toml_baselines()
    out = []
    for base, text, n, extra in (
        ("default", default, 90, {}),
        ("areas", areas, 60, {"area.geojson": geojson}),
    ):

        def add(kind, data, fields=(), expect="either", key=None, base=base, extra=extra):
            data = data if isinstance(data, bytes) else _toml(data).encode()
            out.append(Fuzz(kind, {"s.toml": data, **extra}, "scenario", "s.toml", fields,
                            expect, key, base))  # fmt: skip

        doc = tomllib.loads(text)
        for kind, new, fields, expect, key in _structured(rng, doc, n, f"toml:{base}"):
            add(kind, new, fields, expect, key)
        for kind, data, expect in _text_mutations(rng, text, f"toml:{base}", 14):
            add(kind, data, (), expect)
        # the same content written otherwise: re-serialised, tables and keys reordered,
        # comments after the values
        add(f"toml:{base}:rewritten", doc, (), "same")
        add(f"toml:{base}:tables_reordered", dict(reversed(doc.items())), (), "same")
        flip = {k: dict(reversed(v.items())) if isinstance(v, dict) else v for k, v in doc.items()}
        add(f"toml:{base}:keys_reordered", flip, (), "same")
        plain = [ln for ln in text.splitlines() if "=" in ln and not ln.rstrip().endswith("[")]
        commented = text
        for ln in plain:
            commented = commented.replace(ln + "\n", f"{ln}  # c\n")
        add(f"toml:{base}:comments", commented.encode(), (), "same")
        dup = tomllib.loads(text)
        dup["satellites"].append(dict(dup["satellites"][0]))
        last = f"satellites[{len(dup['satellites']) - 1}]"
        add(f"toml:{base}:dup_satellite", dup, (last, "name"), "error")
        for path in EXTREME_PATHS[base]:
            for label in ("tiny", "huge", "bigint", "negative"):
                doc = tomllib.loads(text)
                _get(doc, path[:-1])[path[-1]] = dict(BAD_VALUES)[label]
                add(f"toml:{base}:extreme:{_fields(path)[-1]}:{label}", doc, _fields(path))
        if base == "areas":
            for table, i in (("areas", 1), ("targets", 0)):
                doc = tomllib.loads(text)
                doc[table].append(dict(doc[table][i]))
                add(f"toml:areas:dup_{table}", doc, (f"{table}[2]", "name"), "error")
    return out


# --- CSV ---

CSV_NUMERIC = tuple(
    "lat_deg lon_deg priority alt_m duration_s length_km azimuth_deg window_lo_s window_hi_s "
    "desired_s tolerance_s min_duration_s".split()
)
CSV_NOT_NUMBERS = tuple("nan NaN inf -inf 1e999 abc 0x1A true strip point".split())
CSV_CELLS = [*CSV_NOT_NUMBERS, "", " ", "95", "-90.5", "181", "-181", "-1", "0", "1e308", " 12 "]
CSV_HEAD = ["name", "lat_deg", "lon_deg", "priority", "kind", *CSV_NUMERIC[3:9], "sensor",
            *CSV_NUMERIC[9:]]  # fmt: skip


def _csv_text(rows) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    return buf.getvalue()


def _csv_baselines():
    with open(DATA / "cities.csv", encoding="utf-8-sig", newline="") as f:
        rows = list(csv.reader(f))[: CSV_ROWS + 1]
    head = CSV_HEAD
    ext = [head]
    for i, r in enumerate(rows[1:]):
        rec = dict(zip(rows[0], r, strict=True))
        strip, win, des = i % 3 == 1, i % 4 == 0, i % 5 == 0 and i % 3 != 1
        ext.append([rec["name"], rec["lat_deg"], rec["lon_deg"], rec["priority"],
                    "strip" if strip else "point", rec["alt_m"], "" if strip else rec["duration_s"],
                    "30" * strip, "45" * strip, "600" * win, "7200" * win, rec["sensor"],
                    "1800" * des, "60" * des, "5" * (i % 7 == 0)])  # fmt: skip
    return {"cities": rows, "extended": ext}


def _csv_structured(rng, rows, base, n):
    head, body = rows[0], rows[1:]
    out = []
    for _ in range(n):
        ops = "drop_col unknown_col dup_col rename_col reorder extra_cell short_row dup_name "
        op = rng.choice(["cell"] * 8 + (ops + "blank_rows quote_all spaces").split())
        new = [list(r) for r in rows]
        r = rng.randrange(1, len(rows))
        expect, fields = "either", ()
        if op == "cell":
            c = rng.randrange(len(head))
            col, val = head[c], rng.choice(CSV_CELLS)
            new[r][c] = val
            bad_num = val.strip() in CSV_NOT_NUMBERS
            if (
                (col in CSV_NUMERIC and bad_num and new[r][c].strip())
                or (col in ("lat_deg", "lon_deg") and not val.strip())
                or (col == "lat_deg" and val in ("95", "-90.5"))
                or (col == "lon_deg" and val in ("181", "-181"))
                or (col == "priority" and val in ("0", "-1"))
                or (col == "name" and not val.strip())
                or (col == "kind" and val in ("abc", "0x1A"))
            ):
                expect = "error"
            if not (col == "name" and val.strip() in [x[0] for x in body]):
                fields = (f"row {r + 1}", col)
            op = f"cell:{col in CSV_NUMERIC and 'num' or col}:{val.strip() or 'empty'}"
        elif op == "drop_col":
            c = rng.randrange(len(head))
            new = [x[:c] + x[c + 1 :] for x in new]
            if head[c] in ("name", "lat_deg", "lon_deg", "priority"):
                expect, fields = "error", ("row 1", head[c])
        elif op in ("unknown_col", "dup_col", "rename_col"):
            c = rng.randrange(len(head))
            name = {"unknown_col": "elevation_m", "dup_col": head[c]}.get(op, head[c].upper())
            new = [x + [name if i == 0 else x[c]] for i, x in enumerate(new)]
            expect, fields = "error", ("row 1", name)
        elif op == "reorder":
            order = list(range(len(head)))
            rng.shuffle(order)
            new = [[x[i] for i in order] for x in new]
            expect = "same"
        elif op in ("extra_cell", "short_row"):
            new[r] = new[r] + ["1"] if op == "extra_cell" else new[r][:-1]
            expect, fields = "error", (f"row {r + 1}",)
        elif op == "dup_name":
            k = rng.randrange(1, len(rows))
            while k == r:
                k = rng.randrange(1, len(rows))
            new[max(r, k)][0] = new[min(r, k)][0]
            expect, fields = "error", (f"row {max(r, k) + 1}", "name")
        elif op == "blank_rows":
            new = new[:r] + [[], [""] * len(head)] + new[r:]
            expect = "same"
        elif op == "quote_all":
            text = "\n".join(",".join('"' + c.replace('"', '""') + '"' for c in x) for x in new)
            out.append((f"csv:{base}:{op}", text + "\n", "same", ()))
            continue
        else:
            text = "\n".join(
                " , ".join(x) if "," not in "".join(x) else _csv_text([x]).strip() for x in new
            )
            out.append((f"csv:{base}:{op}", text + "\n", "same", ()))
            continue
        out.append((f"csv:{base}:{op}", _csv_text(new), expect, fields))
    return out


def csv_cases(rng) -> list[Fuzz]:
    out = []
    for base, rows in _csv_baselines().items():
        text = _csv_text(rows)
        for kind, data, expect, fields in _csv_structured(rng, rows, base, 60):
            out.append(
                Fuzz(kind, {"t.csv": data.encode()}, "csv", "t.csv", fields, expect, base=base)
            )
        for kind, data, expect in _text_mutations(rng, text, f"csv:{base}", 10):
            fields = ("row",) if kind.endswith("non_utf8") else ()
            out.append(Fuzz(kind, {"t.csv": data}, "csv", "t.csv", fields, expect, base=base))
        head = ",".join(rows[0]) + "\n"
        for kind, data, expect, fields in (
            ("header_only", head, "error", ()),
            ("semicolons", text.replace(",", ";"), "error", ("row 1",)),
            ("nul_cell", text.replace(rows[3][0], rows[3][0] + "\x00", 1), "either", ()),
            ("huge_cell", text.replace(rows[3][0], "x" * 200_000, 1), "either", ()),
            ("open_quote", text.replace(rows[5][1], '"' + rows[5][1], 1), "error", ()),
            ("trailing_blank", text + "\n\n,,,\n", "same", ()),
        ):
            out.append(Fuzz(f"csv:{base}:{kind}", {"t.csv": data.encode()}, "csv", "t.csv",
                            fields, expect, base=base))  # fmt: skip
    # CSV errors reached through a scenario file still name the CSV file and row
    toml = (
        b'targets_csv = "t.csv"\n[scenario]\nepoch = "2026-04-14T00:00:00Z"\n'
        b"duration_s = 600.0\n[[satellites]]\naltitude_km = 600.0\n"
    )
    rows = _csv_baselines()["cities"]
    for r, col, val in ((3, 1, "95"), (7, 2, "nan"), (12, 4, "-1"), (20, 0, ""), (30, 5, "x")):
        new = [list(x) for x in rows]
        new[r][col] = val
        files = {"s.toml": toml, "t.csv": _csv_text(new).encode()}
        fields = (f"row {r + 1}", rows[0][col])
        out.append(Fuzz(f"csv:via_toml:{rows[0][col]}", files, "scenario", "s.toml", fields,
                        "error", base="via_toml", file="t.csv"))  # fmt: skip
    return out


# --- GeoJSON (read directly and as the area of areas_example.toml) ---


def _ring(lon0, lat0, dlon, dlat):
    return [
        [lon0, lat0],
        [lon0 + dlon, lat0],
        [lon0 + dlon, lat0 + dlat],
        [lon0, lat0 + dlat],
        [lon0, lat0],
    ]


def _fc(*polygons):
    feats = [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": p}}
        for p in polygons
    ]
    return {"type": "FeatureCollection", "features": feats}


def _geojson_docs(doc):
    """(kind, document or raw text, expect of read_geojson, expect of the scenario)."""
    ring = doc["features"][0]["geometry"]["coordinates"][0]
    geom = doc["features"][0]["geometry"]
    return [
        ("bare_polygon", geom, "either", "same"),
        ("feature", doc["features"][0], "either", "same"),
        ("reversed_ring", _fc([ring[::-1]]), "either", "either"),
        ("unclosed_ring", _fc([ring[:-1]]), "either", "either"),
        (
            "foreign_members",
            {**doc, "crs": None, "bbox": [0, 0, 1, 1], "name": "x"},
            "either",
            "same",
        ),
        ("multipolygon", {"type": "MultiPolygon", "coordinates": [[ring]]}, "either", "either"),
        ("hole", _fc([ring, _ring(14.4, 46.0, 0.1, 0.1)[::-1]]), "either", "either"),
        ("z_coordinates", _fc([[[*p, 300.0] for p in ring]]), "either", "either"),
        (
            "bowtie",
            _fc([[[14, 46], [15, 46.5], [15, 46], [14, 46.5], [14, 46]]]),
            "either",
            "error",
        ),
        ("two_points", _fc([[[14, 46], [15, 46], [14, 46]]]), "either", "error"),
        ("collinear", _fc([[[14, 46], [14.5, 46], [15, 46], [14, 46]]]), "either", "error"),
        ("point", {"type": "Point", "coordinates": [14, 46]}, "error", "error"),
        ("linestring", {"type": "LineString", "coordinates": ring}, "error", "error"),
        ("null_geometry", {"type": "Feature", "geometry": None}, "error", "error"),
        ("no_features", {"type": "FeatureCollection", "features": []}, "error", "error"),
        ("top_list", [doc], "error", "error"),
        ("top_null", None, "error", "error"),
        ("top_number", 3, "error", "error"),
        ("wrong_depth", {"type": "Polygon", "coordinates": ring}, "error", "error"),
        ("nan_literal", json.dumps(_fc([[[14, NAN], *ring[1:]]])), "error", "error"),
        ("inf_literal", json.dumps(_fc([[*ring[:2], [INF, 46.0], *ring[3:]]])), "error", "error"),
        (
            "huge_integer",
            json.dumps(_fc([ring])).replace("46.3]", "1" * 400 + "]"),
            "error",
            "error",
        ),
        ("lon_plus_360", _fc([[[x + 360.0, y] for x, y in ring]]), "either", "error"),
        ("too_large", _fc([_ring(0.0, 0.0, 30.0, 30.0)]), "either", "error"),
        (
            "antimeridian_ring",
            _fc([[[179.5, 10], [-179.5, 10], [-179.5, 11], [179.5, 11], [179.5, 10]]]),
            "either",
            "error",
        ),
        (
            "antimeridian_split",
            _fc([_ring(179.5, 10, 0.5, 1)], [_ring(-180, 10, 0.5, 1)]),
            "either",
            "error",
        ),
        ("antimeridian_360", _fc([_ring(179.5, 10, 1.0, 1.0)]), "either", "error"),
        (
            "polar_cap",
            _fc([[[-180, 85], [180, 85], [180, 90], [-180, 90], [-180, 85]]]),
            "either",
            "error",
        ),
    ]


def geojson_cases(rng) -> list[Fuzz]:
    _, areas_toml, raw = _toml_baselines()
    doc = json.loads(raw)
    toml = areas_toml.encode()
    out = []

    def add(kind, data, expect_read, expect_scenario):
        if not isinstance(data, bytes):
            data = (data if isinstance(data, str) else json.dumps(data)).encode()
        out.append(Fuzz(f"geojson:read:{kind}", {"area.geojson": data}, "geojson",
                        "area.geojson", (), expect_read, base="geojson"))  # fmt: skip
        out.append(Fuzz(f"geojson:area:{kind}", {"area.geojson": data, "s.toml": toml},
                        "scenario", "s.toml", ("areas[0].geojson",), expect_scenario,
                        base="areas", file="area.geojson"))  # fmt: skip

    for kind, d, e_read, e_sc in _geojson_docs(doc):
        add(kind, d, e_read, e_sc)
    skip = [("features", 0, "properties")]
    for kind, new, _, expect, _ in _structured(rng, doc, 45, "x", skip):
        kind = kind.split(":", 1)[1]
        if kind == "unknown_key":  # GeoJSON allows foreign members
            add(kind, new, "same", "same")
        elif kind in ("value:lat95", "value:lon-181"):  # the area's range check may refuse
            add(kind, new, expect, "either")
        else:
            add(kind, new, expect, expect)
    for kind, data, expect in _text_mutations(rng, raw.decode(), "text", 10):
        add(kind.split(":", 1)[1], data, expect, expect)
    return out


# --- aeossp case YAML (case_0001 cut to 3 satellites and 8 tasks) ---


def _cut_list(text: str, marker: str, keep: int) -> str:
    at = [i for i in range(len(text)) if text.startswith(marker, i)]
    return text[: at[keep] + 1] if len(at) > keep else text


def _case_baseline() -> dict:
    return {
        "mission.yaml": (CASE1 / "mission.yaml").read_text(encoding="utf-8"),
        "satellites.yaml": _cut_list(
            (CASE1 / "satellites.yaml").read_text(encoding="utf-8"), "\n- satellite_id:", 3
        ),
        "tasks.yaml": _cut_list(
            (CASE1 / "tasks.yaml").read_text(encoding="utf-8"), "\n- task_id:", 8
        ),
    }


def _yaml_dump(doc) -> str:
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True)


def case_cases(rng) -> list[Fuzz]:
    if not CASE1.is_dir():
        return []
    base = _case_baseline()
    files = {k: v.encode() for k, v in base.items()}
    out = []

    def add(kind, name, data, fields, expect):
        out.append(Fuzz(f"yaml:{kind}", {**files, name: data}, "case", "", fields, expect,
                        base="case", file=name))  # fmt: skip

    for name, n in (("mission.yaml", 15), ("satellites.yaml", 30), ("tasks.yaml", 35)):
        doc = yaml.safe_load(base[name])
        skip = [("mission", "propagation"), ("mission", "scoring")]  # not read
        for kind, new, fields, expect, _ in _structured(rng, doc, n, name.split(".")[0], skip):
            if kind.endswith("unknown_key"):  # extra fields are the benchmark's business
                expect, fields = "same", ()
            if fields[-1:] in (("name",), ("case_id",)):  # labels: str() of any scalar
                expect = "either"
            add(kind, name, _yaml_dump(new).encode(), fields, expect)
        for kind, data, expect in _text_mutations(rng, base[name], name.split(".")[0], 6):
            add(kind, name, data, ("line",) if kind.endswith("non_utf8") else (), expect)
        add(f"{name.split('.')[0]}:top_list", name, b"- 1\n- 2\n", (), "error")
        add(
            f"{name.split('.')[0]}:tabs",
            name,
            base[name].replace("  ", "\t", 1).encode(),
            (),
            "either",
        )
    sats, tasks = yaml.safe_load(base["satellites.yaml"]), yaml.safe_load(base["tasks.yaml"])
    for kind, name, doc, fields in (
        (
            "dup_satellite_id",
            "satellites.yaml",
            {"satellites": sats["satellites"] + sats["satellites"][:1]},
            ("satellite_id",),
        ),
        (
            "dup_task_id",
            "tasks.yaml",
            {"tasks": tasks["tasks"] + tasks["tasks"][2:3]},
            ("task_id",),
        ),
        ("no_satellites", "satellites.yaml", {"satellites": []}, ("satellites",)),
        ("no_tasks", "tasks.yaml", {"tasks": []}, ("tasks",)),
    ):
        add(kind, name, _yaml_dump(doc).encode(), fields, "error")
    line2 = sats["satellites"][0]["tle_line2"]
    for name, path, value, expect in (
        ("tasks.yaml", ("tasks", 0, "longitude_deg"), -181.0, "error"),
        ("tasks.yaml", ("tasks", 1, "longitude_deg"), 540.0, "error"),
        ("tasks.yaml", ("tasks", 2, "altitude_m"), 1e7, "either"),
        ("satellites.yaml", ("satellites", 0, "tle_line2"), line2[:8] + "ABCDEFGH" + line2[16:],
         "error"),
        ("satellites.yaml", ("satellites", 1, "tle_line1"), "1 " + "9" * 67, "error"),
    ):  # fmt: skip
        doc = yaml.safe_load(base[name])
        _get(doc, path[:-1])[path[-1]] = value
        add(f"{name.split('.')[0]}:{path[-1]}:{value!s:.12}", name, _yaml_dump(doc).encode(),
            _fields(path), expect)  # fmt: skip
    dup_key = base["tasks.yaml"].replace("  weight: 1.0\n", "  weight: 1.0\n  weight: 5.0\n", 1)
    add("dup_key", "tasks.yaml", dup_key.encode(), ("weight",), "error")
    swapped = (
        base["satellites.yaml"]
        .replace("tle_line1", "tle_lineX")
        .replace("tle_line2", "tle_line1")
        .replace("tle_lineX", "tle_line2")
    )
    add("swapped_tle_lines", "satellites.yaml", swapped.encode(), ("tle_line1",), "error")
    return out


GENERATORS = {"toml": toml_cases, "csv": csv_cases, "geojson": geojson_cases, "case": case_cases}


def generated(name: str) -> list[Fuzz]:
    return GENERATORS[name](random.Random(f"{SEED}:{name}"))
