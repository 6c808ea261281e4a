"""Area tables of scenario files: ``[[areas]]``, GeoJSON polygons or sample files, named errors.

The schema is documented with the rest of the scenario file in
:mod:`jaxspline.readers.scenario`. An area is read, never cut: each becomes a target of
kind ``AREA`` (its priority, imaging window and sensor) and an
:class:`jaxspline.readers.mission.Area` (its polygon and grid spacing, or its own samples),
which the planner lays out and plans (:mod:`jaxspline.planner.area_options`). Every error
is a ``ValueError`` naming the field (``areas[1].grid_km``), its TOML line and the value;
GeoJSON content errors name ``areas[i].geojson`` and what is wrong with the file.
Polygons: GeoJSON Polygon / MultiPolygon, a Feature of one, or a FeatureCollection of
them (united), or one inline ring ``lonlat_deg`` of ``[lon, lat]`` pairs [deg]; finite,
valid (no self-intersection), with area, within [-180, 180] x [-90, 90] deg, less than
180 deg wide in longitude and no vertex farther than :data:`MAX_RADIUS_DEG` from the
centre. Samples (``samples_csv``): a CSV file with columns ``lon_deg``, ``lat_deg`` and
``weight`` (each sample's share of the area, summing to at most 1).

Areas crossing the antimeridian (the 180 deg meridian) are refused, whether written
with a jump from +180 to -180, with longitudes beyond 180, or split in two at the
meridian as RFC 7946 section 3.1.9 asks: the centre of an area is the centroid of its
longitudes and latitudes (:func:`polygon_center`), which for such an area lies on the
far side of the Earth, and the output files draw areas in [-180, 180]. Give such an
area as two ``[[areas]]``, one on each side of the meridian.

The sample spacing ``grid_km`` (default a third of the narrowest swath of the satellites
whose sensor the area accepts) must not give an area more than
:data:`MAX_AREA_SAMPLES` samples (estimated from the area's size).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon, shape
from shapely.validation import explain_validity

from jaxspline.base.elements import geodetic_to_ecef, unit_vectors
from jaxspline.readers.fields import (
    check_float,
    field_number,
    field_pair,
    field_str,
    field_table,
    field_tables,
    read_text,
    read_tick,
)
from jaxspline.readers.ranges import MAX_NAME_CHARS, bounds

__all__ = [
    "AREA_KEYS",
    "GRID_PER_SWATH",
    "MAX_AREA_SAMPLES",
    "MAX_RADIUS_DEG",
    "AreaSpec",
    "parse_areas",
    "polygon_center",
    "read_geojson",
    "read_samples",
]

#: Keys of an ``[[areas]]`` table.
AREA_KEYS = frozenset(
    "name geojson lonlat_deg samples_csv priority sensor window_s grid_km min_coverage".split()
)
#: Keys of earlier versions, refused with what replaced them.
RETIRED_KEYS = {
    "swath_km": "the strips are as wide as the imaging satellite's field of view (fov_deg, "
    "or its swath_km)",
    "max_length_km": "a strip lasts the satellite's strip_duration_s",
    "objective": "every area is planned by the unique coverage of its samples",
}
#: Most samples one area may have (a finer ``grid_km`` is refused).
MAX_AREA_SAMPLES = 200_000
#: Default sample spacing as a share of the narrowest swath (3 samples across a strip).
GRID_PER_SWATH = 1.0 / 3.0
MAX_RADIUS_DEG = 10.0  # largest central angle from an area's centre to a vertex [deg]
_KM_PER_DEG = 111.195  # great-circle km per degree (mean Earth radius)
_MERIDIAN = (
    "; an area across the antimeridian (180 deg) is not supported: give it as two areas, "
    "one on each side"
)
_SAMPLE_COLUMNS = ("lon_deg", "lat_deg", "weight")


@dataclasses.dataclass(frozen=True)
class AreaSpec:
    """An ``[[areas]]`` table, read and checked (:func:`parse_areas`).

    Attributes:
      name: label (unique among the areas).
      polygon: shapely Polygon or MultiPolygon, coordinates (lon, lat) [deg], or None
        (samples given without a polygon).
      value: priority of the whole area (> 0).
      sensor: required sensor type ("" = any).
      t_lo, t_hi: imaging window of its strips [s from the epoch] (-inf/+inf: free).
      grid: sample spacing [m] (0 with samples given).
      samples: float [N, 3] ``(lon [deg], lat [deg], weight)`` given, or [0, 3].
      min_share: least covered share (NaN: none).
      field: label of the table in error messages (``areas[0]``).
    """

    name: str
    polygon: object
    value: float
    sensor: str = ""
    t_lo: float = -math.inf
    t_hi: float = math.inf
    grid: float = 0.0
    samples: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))
    min_share: float = math.nan
    field: str = "areas[0]"


def _polygonal(geom, where: str):
    if isinstance(geom, Polygon | MultiPolygon):
        return geom
    raise ValueError(f"{where}: a {geom.geom_type} is not an area (Polygon or MultiPolygon)")


_POSITION_DEPTH = {"Polygon": 3, "MultiPolygon": 4}  # list levels down to a position


def _is_number(x) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _positions(node, depth: int, where: str) -> None:
    """Check that ``node`` is ``depth`` levels of lists ending in positions of 2 or 3
    numbers (``[lon, lat]`` or ``[lon, lat, height]``); ValueError naming the first bad one."""
    if depth == 1:
        if not (isinstance(node, list) and len(node) in (2, 3) and all(map(_is_number, node))):
            raise ValueError(f"{where}: a position must be 2 or 3 numbers [lon, lat], got {node!r}")
        return
    if not isinstance(node, list):
        raise ValueError(f"{where}: must be a list, got {node!r}")
    for i, x in enumerate(node):
        _positions(x, depth - 1, f"{where}[{i}]")


def _shape(geometry, where: str):
    """The shapely geometry of a GeoJSON geometry object whose positions are numbers."""
    if not isinstance(geometry, dict):
        raise ValueError(f"{where}: must be a GeoJSON geometry object, got {geometry!r}")
    kind = geometry.get("type")
    if kind not in _POSITION_DEPTH:  # GeoJSON types are case-sensitive (RFC 7946)
        raise ValueError(f"{where}: type {kind!r} is not an area (Polygon or MultiPolygon)")
    _positions(geometry.get("coordinates"), _POSITION_DEPTH[kind], f"{where} coordinates")
    return _polygonal(shape(geometry), where)


def _feature_geometry(f, where: str):
    if not isinstance(f, dict) or f.get("type") != "Feature":
        got = f.get("type") if isinstance(f, dict) else f
        raise ValueError(f"{where}: must be a GeoJSON Feature, got {got!r}")
    if f.get("geometry") is None:
        raise ValueError(f"{where}: the Feature has no geometry (null)")
    return _shape(f["geometry"], f"{where} geometry")


def _geojson_geometry(doc, label: str = "GeoJSON"):
    """The union of the polygons of a GeoJSON document (shapely, lon/lat degrees);
    :func:`jaxspline.readers.fields.read_tick` on every feature."""
    if not isinstance(doc, dict):
        raise ValueError(f"must be a GeoJSON object, got {type(doc).__name__}")
    kind = doc.get("type")
    try:
        if kind == "FeatureCollection":
            feats = doc.get("features")
            if not isinstance(feats, list) or not feats:
                raise ValueError("a FeatureCollection needs a non-empty 'features' list")
            parts = []
            for i, f in enumerate(feats):
                read_tick(label, i + 1, len(feats))
                parts.append(_feature_geometry(f, f"features[{i}]"))
            geom = shapely.union_all(parts)
        elif kind == "Feature":
            geom = _feature_geometry(doc, "Feature")
        else:
            geom = _shape(doc, "geometry")
    except (AttributeError, TypeError, IndexError, KeyError, shapely.errors.ShapelyError) as exc:
        raise ValueError(f"not a valid GeoJSON {kind or 'object'}: {exc}") from None
    return geom


def _finite_number(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"numbers must be finite, got {text[:24]}{'...' * (len(text) > 24)}")
    return value


def _no_constant(name: str):
    raise ValueError(f"numbers must be finite, got {name}")


def read_geojson(path):
    """The area of a GeoJSON file: its Polygon / MultiPolygon, Feature or FeatureCollection.

    The polygons of a FeatureCollection are united; other geometry types, members of a
    FeatureCollection that are not Features, and numbers that are not finite (``NaN``,
    ``Infinity``, ``1e999``) are errors. UTF-8 text; a byte-order mark is accepted.

    Args:
      path: str or Path.
    Returns:
      shapely Polygon or MultiPolygon, coordinates (lon, lat) [deg], finite.
    Raises:
      FileNotFoundError: the file is missing.
      ValueError: not JSON, or not a polygonal GeoJSON document (naming the file).
    """
    path = Path(path)
    try:
        text = read_text(path, lambda line: f"{path.name}: line {line}")
    except FileNotFoundError:
        raise FileNotFoundError(f"GeoJSON file not found: {path}") from None
    try:
        doc = json.loads(
            text,
            parse_float=_finite_number,
            parse_int=_finite_number,  # 400-digit integers too (float() would overflow)
            parse_constant=_no_constant,
        )
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path.name}: invalid JSON: {exc}") from None
    except ValueError as exc:
        raise ValueError(f"{path.name}: invalid GeoJSON: {exc}") from None
    except RecursionError:
        raise ValueError(f"{path.name}: invalid GeoJSON: nested too deeply") from None
    try:
        return _geojson_geometry(doc, path.name)
    except ValueError as exc:
        raise ValueError(f"{path.name}: {exc}") from None


def polygon_center(geom) -> np.ndarray:
    """Unit vector of the centre of an area: its (lon, lat) centroid on the ellipsoid.

    Args:
      geom: shapely Polygon or MultiPolygon, coordinates (lon, lat) [deg].
    Returns:
      float [3], unit vector, Earth-fixed.
    """
    c = geom.centroid
    return unit_vectors(geodetic_to_ecef(math.radians(c.y), math.radians(c.x), 0.0))


def _check_polygon(geom, err) -> float:
    """Check an area's polygon (module docstring); return its radius [deg] about the centre."""
    xy = np.asarray(shapely.get_coordinates(geom))
    if not np.all(np.isfinite(xy)):
        bad = xy[~np.all(np.isfinite(xy), axis=1)][0]
        raise err(f"coordinates must be finite, got [{bad[0]!r}, {bad[1]!r}]")
    if not geom.is_empty and not geom.is_valid:
        raise err(f"invalid polygon: {explain_validity(geom)}")
    if geom.is_empty or geom.area <= 0.0:
        raise err("the polygon is empty (no area)")
    lon0, lat0, lon1, lat1 = geom.bounds
    if lat0 < -90.0 or lat1 > 90.0:
        raise err(f"latitudes must be within [-90, 90] deg, got [{lat0:g}, {lat1:g}]")
    if lon0 < -180.0 or lon1 > 180.0:
        raise err(f"longitudes must be within [-180, 180] deg, got [{lon0:g}, {lon1:g}]{_MERIDIAN}")
    if lon1 - lon0 > 180.0:
        raise err(
            f"longitudes span {lon1 - lon0:g} deg (from {lon0:g} to {lon1:g}), more than 180"
            + _MERIDIAN
        )
    c = polygon_center(geom)
    u = unit_vectors(geodetic_to_ecef(np.radians(xy[:, 1]), np.radians(xy[:, 0]), 0.0))
    radius = math.degrees(float(np.max(np.arccos(np.clip(u @ c, -1.0, 1.0)))))
    if radius > MAX_RADIUS_DEG:
        raise err(
            f"too large: a vertex is {radius:.3g} deg from the centre (at most {MAX_RADIUS_DEG:g})"
        )
    return radius


def _ring(ctx, field, value):
    ok = isinstance(value, list) and len(value) >= 3
    ok = ok and all(isinstance(p, list) and len(p) == 2 for p in value)
    if not ok:
        raise ctx.error(field, f"must be a list of >= 3 [lon, lat] pairs [deg], got {value!r}")
    pts = []
    for i, (lon, lat) in enumerate(value):

        def err(m, i=i):
            return ctx.error(field, f"vertex {i} {value[i]!r}: {m}")

        past = isinstance(lon, int | float) and 180.0 < abs(lon) <= 360.0  # wrapped
        lon = check_float(
            lon, lambda m, past=past: err(f"lon {m}" + _MERIDIAN * past), lo=-180.0, hi=180.0
        )
        lat = check_float(lat, lambda m: err(f"lat {m}"), lo=-90.0, hi=90.0)
        pts.append((lon, lat))
    try:
        return Polygon(pts)
    except shapely.errors.ShapelyError as exc:
        raise ctx.error(field, f"not a polygon: {exc}") from None


def parse_areas(ctx, data: dict, base_dir, satellites, horizon=None) -> list[AreaSpec]:
    """The ``[[areas]]`` (alias ``[area]``) tables of a parsed scenario file, checked.

    Args:
      ctx: :class:`jaxspline.readers.fields.FieldContext` of the file.
      data: dict, the parsed scenario TOML.
      base_dir: folder that relative paths start from (None: the working directory).
      satellites: the scenario's :class:`jaxspline.readers.mission.Satellite` tuple (the
        default grid spacing comes from the narrowest swath of those whose sensor the
        area accepts).
      horizon: the scenario's duration [s]: ``window_s`` lies in ``[0, horizon]`` (None:
        the longest horizon).
    Returns:
      list of :class:`AreaSpec`, in file order.
    Raises:
      ValueError: naming the field (``areas[1].grid_km``), its TOML line and the value.
    """
    out, names = [], {}
    for i, (f, a) in enumerate(field_tables(ctx, data, "areas", "area")):
        for key, why in RETIRED_KEYS.items():
            if isinstance(a, dict) and key in a:
                raise ctx.error(f"{f}.{key}", f"is no longer read: {why}")
        a = field_table(ctx, f, a, AREA_KEYS)
        name = a.get("name", f"area_{i + 1}")
        name = field_str(ctx, f"{f}.name", name, allow_empty=False, max_chars=MAX_NAME_CHARS)
        if name in names:
            raise ctx.error(f"{f}.name", f"duplicate area name {name!r} (also {names[name]})")
        names[name] = f

        def num(key, default=None, f=f, a=a):
            return field_number(ctx, f"{f}.{key}", a.get(key, default), **bounds(f"areas[].{key}"))

        value = num("priority", 1.0)
        sensor = field_str(ctx, f"{f}.sensor", a.get("sensor", ""), max_chars=MAX_NAME_CHARS)
        t_lo, t_hi = -math.inf, math.inf
        if "window_s" in a:
            t_lo, t_hi = field_pair(ctx, f"{f}.window_s", a["window_s"],
                                    **bounds("areas[].window_s", horizon))  # fmt: skip
        min_share = num("min_coverage") if "min_coverage" in a else math.nan
        if "samples_csv" in a:
            samples = _area_samples(ctx, f, a, base_dir)
            geom = _area_polygon(ctx, f, a, base_dir)[0] if _has_polygon(a) else None
            grid = 0.0
        else:
            geom, radius = _area_polygon(ctx, f, a, base_dir)
            samples, grid = np.zeros((0, 3)), _area_grid(ctx, f, a, radius, sensor, satellites)
        out.append(AreaSpec(name, geom, value, sensor, t_lo, t_hi, grid, samples, min_share, f))
    return out


def _has_polygon(a) -> bool:
    return "geojson" in a or "lonlat_deg" in a


def _area_samples(ctx, f, a, base_dir) -> np.ndarray:
    """The samples of ``samples_csv`` (:func:`read_samples`), errors naming the field."""
    key = f"{f}.samples_csv"
    path = Path(field_str(ctx, key, a["samples_csv"], allow_empty=False))
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    try:
        return read_samples(path)
    except (OSError, ValueError) as exc:
        raise ctx.error(key, str(exc)) from None


def read_samples(path) -> np.ndarray:
    """An area's samples from a CSV file with columns ``lon_deg``, ``lat_deg``, ``weight``.

    Args:
      path: str or Path of the file.
    Returns:
      float [N, 3] ``(lon [deg], lat [deg], weight)``.
    Raises:
      ValueError: a missing column, a row that is not three finite numbers, a longitude
        or latitude out of range, a negative weight, weights summing to more than 1, or
        no rows (the message names the file, the row and the value).
      OSError: the file cannot be read.
    """
    import csv

    path = Path(path)
    text = read_text(path)
    rows = list(csv.DictReader(text.splitlines()))
    head = rows[0].keys() if rows else next(csv.reader(text.splitlines()), [])
    missing = [c for c in _SAMPLE_COLUMNS if c not in head]
    if missing:
        raise ValueError(
            f"{path.name}: missing column {missing[0]!r} (columns: lon_deg, lat_deg, weight)"
        )
    out = np.empty((len(rows), 3))
    for i, row in enumerate(rows):
        for j, c in enumerate(_SAMPLE_COLUMNS):
            out[i, j] = check_float(
                row[c],
                lambda m, i=i, c=c: ValueError(f"{path.name} row {i + 2}: {c} {m}"),
                text=True,
            )
    if out.shape[0] == 0:
        raise ValueError(f"{path.name}: no samples")
    for j, (c, lo, hi) in enumerate(
        (("lon_deg", -180, 180), ("lat_deg", -90, 90), ("weight", 0, 1))
    ):
        bad = np.flatnonzero((out[:, j] < lo) | (out[:, j] > hi))
        if bad.size:
            i = int(bad[0])
            got = float(out[i, j])
            raise ValueError(
                f"{path.name} row {i + 2}: {c} must be within [{lo}, {hi}], got {got!r}"
            )
    if out[:, 2].sum() > 1.0 + 1e-9:
        raise ValueError(f"{path.name}: the weights sum to {out[:, 2].sum():.6g}, more than 1")
    return out


def _area_grid(ctx, f, a, radius: float, sensor: str, satellites) -> float:
    """The grid spacing [m] of an area: ``grid_km`` in its range, or :data:`GRID_PER_SWATH`
    of the narrowest swath of the satellites whose sensor the area accepts; refused when
    the area would get over :data:`MAX_AREA_SAMPLES` samples."""
    if "grid_km" in a:
        grid = 1e3 * field_number(ctx, f"{f}.grid_km", a["grid_km"], **bounds("areas[].grid_km"))
        given = ""
    else:
        swaths = [(s.swath, k) for k, s in enumerate(satellites) if sensor in ("", s.sensor)]
        if not swaths:
            raise ctx.error(
                f"{f}.sensor", f"no satellite has sensor {sensor!r}: none can image the area"
            )
        swath, k = min(swaths)
        grid = swath * GRID_PER_SWATH
        given = f" ({GRID_PER_SWATH:.3g} x satellites[{k}].swath_km: grid_km not given)"
    across = 2.0 * radius * _KM_PER_DEG * 1e3  # the area's size bound [m]
    if (across / grid) ** 2 > MAX_AREA_SAMPLES:
        raise ctx.error(
            f"{f}.grid_km",
            f"{grid / 1e3:g} km{given} is too fine: the area, up to {across / 1e3:.4g} km "
            f"across, would get ~{(across / grid) ** 2:.3g} samples (at most "
            f"{MAX_AREA_SAMPLES}); give a coarser grid_km",
        )
    return grid


def _area_polygon(ctx, f, a, base_dir):
    """``(polygon, radius [deg])`` of an area table: its GeoJSON file or inline ring,
    checked (:func:`_check_polygon`); errors name ``areas[i].geojson`` / ``.lonlat_deg``."""
    if ("geojson" in a) == ("lonlat_deg" in a):
        raise ctx.error(f"{f}.geojson", "give exactly one of geojson (a file) and lonlat_deg")
    where = ""  # the GeoJSON file, named in errors about its polygon
    if "geojson" in a:
        key = f"{f}.geojson"
        path = Path(field_str(ctx, key, a["geojson"], allow_empty=False))
        if not path.is_absolute() and base_dir is not None:
            path = Path(base_dir) / path
        if not path.is_file():
            raise ctx.error(key, f"GeoJSON file not found: {path}")
        try:
            geom = read_geojson(path)
        except ValueError as exc:
            raise ctx.error(key, str(exc)) from None
        where = f"{path.name}: "
    else:
        key = f"{f}.lonlat_deg"
        geom = _ring(ctx, key, a["lonlat_deg"])
    try:
        return geom, _check_polygon(geom, lambda m: ctx.error(key, where + m))
    except shapely.errors.ShapelyError as exc:  # GEOS on a degenerate polygon
        raise ctx.error(key, f"{where}not a usable polygon: {exc}") from None
