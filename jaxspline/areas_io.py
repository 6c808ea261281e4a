"""Area target tables of scenario files: ``[[areas]]``, GeoJSON polygons, named errors.

The schema is documented with the rest of the scenario file in
:mod:`jaxspline.scenario`; :mod:`jaxspline.areas` cuts the areas read here into strip
targets. Every error is a ``ValueError`` naming the field (``areas[1].swath_km``), its
TOML line and the value; GeoJSON content errors name ``areas[i].geojson`` and what is
wrong with the file. Polygons: GeoJSON Polygon / MultiPolygon, a Feature of one, or a
FeatureCollection of them (united), or one inline ring ``lonlat_deg`` of ``[lon, lat]``
pairs [deg]; valid (no self-intersection), with area, within [-180, 180] x [-90, 90]
deg, less than 180 deg wide in longitude (antimeridian areas are not supported) and no
vertex farther than :data:`MAX_RADIUS_DEG` from the centre.
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

from jaxspline._fields import field_number, field_pair, field_str, field_table, field_tables
from jaxspline.geometry.frames import geodetic_to_ecef
from jaxspline.geometry.ground import unit_vectors

__all__ = [
    "AREA_KEYS",
    "DENSIFY_DEG",
    "MAX_RADIUS_DEG",
    "AreaSpec",
    "parse_areas",
    "polygon_center",
    "read_geojson",
]

#: Keys of an ``[[areas]]`` table.
AREA_KEYS = frozenset(
    "name geojson lonlat_deg priority swath_km max_length_km sensor window_s".split()
)
MAX_RADIUS_DEG = 10.0  # largest central angle from an area's centre to a vertex [deg]
DENSIFY_DEG = 0.05  # polygon edges are split into pieces at most this long [deg]


@dataclasses.dataclass(frozen=True)
class AreaSpec:
    """An ``[[areas]]`` table, read and checked (:func:`parse_areas`), not yet cut.

    Attributes:
      name: label (unique among the areas).
      polygon: shapely Polygon or MultiPolygon, coordinates (lon, lat) [deg].
      value: priority of the whole area (> 0).
      swath: strip width [m] (> 0).
      max_length: longest strip [m] (inf: no limit).
      sensor: required sensor type ("" = any).
      t_lo, t_hi: imaging window of every strip [s from the epoch] (-inf/+inf: free).
      field: label of the table in error messages (``areas[0]``).
    """

    name: str
    polygon: object
    value: float
    swath: float
    max_length: float = math.inf
    sensor: str = ""
    t_lo: float = -math.inf
    t_hi: float = math.inf
    field: str = "areas[0]"


def _polygonal(geom, where: str):
    if isinstance(geom, Polygon | MultiPolygon):
        return geom
    raise ValueError(f"{where}: a {geom.geom_type} is not an area (Polygon or MultiPolygon)")


def _geojson_geometry(doc):
    """The union of the polygons of a GeoJSON document (shapely, lon/lat degrees)."""
    if not isinstance(doc, dict):
        raise ValueError(f"must be a GeoJSON object, got {type(doc).__name__}")
    kind = doc.get("type")
    try:
        if kind == "FeatureCollection":
            feats = doc.get("features")
            if not isinstance(feats, list) or not feats:
                raise ValueError("a FeatureCollection needs a non-empty 'features' list")
            parts = [
                _polygonal(shape(f.get("geometry") or {}), f"features[{i}]")
                for i, f in enumerate(feats)
            ]
            return shapely.union_all(parts)
        if kind == "Feature":
            return _polygonal(shape(doc.get("geometry") or {}), "Feature geometry")
        return _polygonal(shape(doc), "geometry")
    except (AttributeError, TypeError, IndexError, KeyError, shapely.errors.ShapelyError) as exc:
        raise ValueError(f"not a valid GeoJSON {kind or 'object'}: {exc}") from None


def read_geojson(path):
    """The area of a GeoJSON file: its Polygon / MultiPolygon, Feature or FeatureCollection.

    The polygons of a FeatureCollection are united; other geometry types are errors.

    Args:
      path: str or Path.
    Returns:
      shapely Polygon or MultiPolygon, coordinates (lon, lat) [deg].
    Raises:
      FileNotFoundError: the file is missing.
      ValueError: not JSON, or not a polygonal GeoJSON document.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise FileNotFoundError(f"GeoJSON file not found: {path}") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path.name}: invalid JSON: {exc}") from None
    try:
        return _geojson_geometry(doc)
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


def _check_polygon(geom, err):
    if not geom.is_empty and not geom.is_valid:
        raise err(f"invalid polygon: {explain_validity(geom)}")
    if geom.is_empty or geom.area <= 0.0:
        raise err("the polygon is empty (no area)")
    lon0, lat0, lon1, lat1 = geom.bounds
    if lon0 < -180.0 or lon1 > 180.0 or lat0 < -90.0 or lat1 > 90.0:
        raise err(
            f"coordinates must be [lon, lat] within [-180, 180] x [-90, 90] deg, got {geom.bounds}"
        )
    if lon1 - lon0 > 180.0:
        raise err("spans more than 180 deg of longitude (antimeridian areas are not supported)")
    c = polygon_center(geom)
    xy = np.asarray(shapely.get_coordinates(geom))
    u = unit_vectors(geodetic_to_ecef(np.radians(xy[:, 1]), np.radians(xy[:, 0]), 0.0))
    radius = math.degrees(float(np.max(np.arccos(np.clip(u @ c, -1.0, 1.0)))))
    if radius > MAX_RADIUS_DEG:
        raise err(
            f"too large: a vertex is {radius:.3g} deg from the centre (at most {MAX_RADIUS_DEG:g})"
        )


def _ring(ctx, field, value):
    ok = isinstance(value, list) and len(value) >= 3
    ok = ok and all(isinstance(p, list) and len(p) == 2 for p in value)
    if not ok:
        raise ctx.error(field, f"must be a list of >= 3 [lon, lat] pairs [deg], got {value!r}")
    pts = [(field_number(ctx, field, p[0]), field_number(ctx, field, p[1])) for p in value]
    return Polygon(pts)


def parse_areas(ctx, data: dict, base_dir, satellites) -> list[AreaSpec]:
    """The ``[[areas]]`` (alias ``[area]``) tables of a parsed scenario file, checked.

    Args:
      ctx: :class:`jaxspline._fields.FieldContext` of the file.
      data: dict, the parsed scenario TOML.
      base_dir: folder that relative GeoJSON paths start from (None: the working directory).
      satellites: the scenario's :class:`jaxspline.engine.mission.Satellite` tuple (the
        default swath is the narrowest of those whose sensor the area accepts).
    Returns:
      list of :class:`AreaSpec`, in file order.
    Raises:
      ValueError: naming the field (``areas[1].swath_km``), its TOML line and the value.
    """
    out, names = [], {}
    for i, (f, a) in enumerate(field_tables(ctx, data, "areas", "area")):
        a = field_table(ctx, f, a, AREA_KEYS)
        name = field_str(ctx, f"{f}.name", a.get("name", f"area_{i + 1}"), allow_empty=False)
        if name in names:
            raise ctx.error(f"{f}.name", f"duplicate area name {name!r} (also {names[name]})")
        names[name] = f
        if ("geojson" in a) == ("lonlat_deg" in a):
            raise ctx.error(f"{f}.geojson", "give exactly one of geojson (a file) and lonlat_deg")
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
        else:
            key = f"{f}.lonlat_deg"
            geom = _ring(ctx, key, a["lonlat_deg"])
        _check_polygon(geom, lambda m, key=key: ctx.error(key, m))
        value = field_number(ctx, f"{f}.priority", a.get("priority", 1.0), positive=True)
        sensor = field_str(ctx, f"{f}.sensor", a.get("sensor", ""))
        if "swath_km" in a:
            swath = 1e3 * field_number(ctx, f"{f}.swath_km", a["swath_km"], positive=True)
        else:
            swaths = [s.swath for s in satellites if sensor in ("", s.sensor)]
            if not swaths:
                raise ctx.error(
                    f"{f}.swath_km",
                    f"missing, and no satellite has sensor {sensor!r} to take it from",
                )
            swath = float(min(swaths))
        max_len = math.inf
        if "max_length_km" in a:
            max_len = 1e3 * field_number(
                ctx, f"{f}.max_length_km", a["max_length_km"], positive=True
            )
        t_lo, t_hi = -math.inf, math.inf
        if "window_s" in a:
            t_lo, t_hi = field_pair(ctx, f"{f}.window_s", a["window_s"])
        out.append(AreaSpec(name, geom, value, swath, max_len, sensor, t_lo, t_hi, f))
    return out
