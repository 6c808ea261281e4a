"""Field readers of the stereo_imaging case files: each bad field a ``ValueError`` naming
the file and the field.

The strict JSON / YAML readers and the number, string and TLE checks are the
regional_coverage adapter's (:mod:`jaxspline.regional.case_fields`); this module adds the
stereo files' own fields and returns plain dicts, which :mod:`jaxspline.stereo.case` turns
into its types.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from typing import Any

from jaxspline.readers.case_files import parse_time
from jaxspline.regional.case_fields import (
    check_tle,
    get_field,
    number_field,
    read_yaml,
    string_field,
)

__all__ = [
    "load_mission",
    "load_satellites",
    "load_targets",
    "number",
    "text",
    "zoned_time",
]

#: Largest accepted ``max_off_nadir_deg`` and anchor limit [deg].
MAX_OFF_NADIR_DEG = 89.0
#: Accepted target heights above the ellipsoid [m] (Dead Sea shore to Everest, with room).
MIN_ELEVATION_M = -1000.0
MAX_ELEVATION_M = 9000.0
#: The keys of ``quality_model.pair_weights``.
PAIR_WEIGHTS = ("geometry", "overlap", "resolution")


def number(raw: Any, key: str, where: str, **bounds) -> float:
    """A finite number field (booleans and numeric strings refused).

    Args:
      raw: the mapping.
      key: field name.
      where: file and path of ``raw`` for the message.
      **bounds: ``lo``, ``lo_open``, ``hi`` as :func:`jaxspline.regional.case_fields.number_field`.
    Returns:
      float.
    Raises:
      ValueError: naming ``where.key`` and the value.
    """
    return number_field(raw, key, where, **bounds)


def text(raw: Any, key: str, where: str) -> str:
    """A non-empty string field.

    Args:
      raw: the mapping.
      key: field name.
      where: file and path of ``raw`` for the message.
    Returns:
      str.
    Raises:
      ValueError: naming ``where.key`` and the value.
    """
    return string_field(raw, key, where)


def zoned_time(raw: Any, key: str, where: str) -> datetime:
    """An ISO 8601 time with ``Z`` or an explicit offset (a naive time is refused).

    Args:
      raw: the mapping.
      key: field name.
      where: file and path of ``raw`` for the message.
    Returns:
      aware datetime (UTC).
    Raises:
      ValueError: missing, not a time, or without a zone (naming ``where.key``).
    """
    value = get_field(raw, key, where)
    w = f"{where}.{key}"
    if isinstance(value, datetime):  # an unquoted YAML timestamp
        if value.tzinfo is None:
            raise ValueError(f"{w}: needs Z or an explicit offset, got {value.isoformat()!r}")
        return parse_time(value, where=w, allow_datetime=True)
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{w}: expected an ISO 8601 time string, got {value!r}")
    s = value.strip()
    s = s[:-1] + "+00:00" if s.endswith(("Z", "z")) else s
    try:
        naive = datetime.fromisoformat(s).tzinfo is None
    except ValueError:
        raise ValueError(f"{w}: not an ISO 8601 time: {value!r}") from None
    if naive:
        raise ValueError(f"{w}: needs Z or an explicit offset, got {value!r}")
    return parse_time(value, where=w)


def _flag(raw: dict, key: str, where: str, default: bool) -> bool:
    value = raw.get(key, default)
    if not isinstance(value, bool):
        raise ValueError(f"{where}.{key}: expected true or false, got {value!r}")
    return value


def _thresholds(raw: Any, where: str) -> dict:
    w = f"{where}.validity_thresholds"
    vt = get_field(raw, "validity_thresholds", where)
    out = dict(
        min_overlap=number(vt, "min_overlap_fraction", w, lo=0.0, hi=1.0),
        min_convergence_deg=number(vt, "min_convergence_deg", w, lo=0.0, hi=180.0),
        max_convergence_deg=number(vt, "max_convergence_deg", w, lo=0.0, hi=180.0),
        max_pixel_scale_ratio=number(vt, "max_pixel_scale_ratio", w, lo=1.0),
        min_solar_elevation_deg=number(vt, "min_solar_elevation_deg", w, lo=-90.0, hi=90.0),
        anchor_max_off_nadir_deg=number(
            vt, "near_nadir_anchor_max_off_nadir_deg", w, lo=0.0, hi=MAX_OFF_NADIR_DEG
        ),
    )
    if out["min_convergence_deg"] > out["max_convergence_deg"]:
        raise ValueError(
            f"{w}.min_convergence_deg: {out['min_convergence_deg']:g} > "
            f"max_convergence_deg {out['max_convergence_deg']:g}"
        )
    return out


def _quality(raw: Any, where: str, scene_types: tuple) -> dict:
    w = f"{where}.quality_model"
    qm = get_field(raw, "quality_model", where)
    pw = get_field(qm, "pair_weights", w)
    weights = {k: number(pw, k, f"{w}.pair_weights", lo=0.0) for k in PAIR_WEIGHTS}
    tb = get_field(qm, "tri_stereo_bonus_by_scene", w)
    wt = f"{w}.tri_stereo_bonus_by_scene"
    bonus = {k: number(tb, k, wt, lo=0.0, hi=1.0) for k in scene_types}
    return dict(tri_bonus=bonus, **weights)


def load_mission(path: Path, scene_types: tuple) -> dict:
    """Read ``mission.yaml``.

    Args:
      path: the file.
      scene_types: the scene types whose tri-stereo bonus must be given.
    Returns:
      dict with ``start``, ``end``, ``allow_cross_satellite``, ``max_pair_separation_s``,
      ``thresholds`` (dict) and ``quality`` (dict).
    Raises:
      ValueError: naming the file and the field.
    """
    raw = read_yaml(path)
    name = path.name
    if not isinstance(raw, dict) or "mission" not in raw:
        raise ValueError(f"{name}: expected a top-level 'mission' mapping")
    m = raw["mission"]
    w = f"{name}: mission"
    if not isinstance(m, dict):
        raise ValueError(f"{w}: expected a mapping, got {type(m).__name__}")
    start, end = zoned_time(m, "horizon_start", w), zoned_time(m, "horizon_end", w)
    if not end > start:
        raise ValueError(f"{w}.horizon_end: must be after horizon_start")
    sep = 3600.0
    if "max_stereo_pair_separation_s" in m:
        sep = number(m, "max_stereo_pair_separation_s", w, lo=0.0, lo_open=True)
    return dict(
        start=start,
        end=end,
        allow_cross_satellite=_flag(m, "allow_cross_satellite_stereo", w, False),
        max_pair_separation_s=sep,
        thresholds=_thresholds(m, w),
        quality=_quality(m, w, scene_types),
    )


def _integer(raw: Any, key: str, where: str, lo: int) -> int:
    value = get_field(raw, key, where)
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise ValueError(f"{where}.{key}: expected an integer >= {lo}, got {value!r}")
    return value


def _satellite(raw: Any, where: str, start: datetime, end: datetime) -> dict:
    sid = text(raw, "id", where)
    l1, l2 = text(raw, "tle_line1", where).strip(), text(raw, "tle_line2", where).strip()
    check_tle(l1, l2, where, start, end)
    pos = dict(lo=0.0, lo_open=True)
    out = dict(
        id=sid,
        norad_id=_integer(raw, "norad_catalog_id", where, 0),
        tle1=l1,
        tle2=l2,
        ifov_deg=number(raw, "pixel_ifov_deg", where, hi=1.0, **pos),
        pixels=_integer(raw, "cross_track_pixels", where, 1),
        max_off_nadir_deg=number(raw, "max_off_nadir_deg", where, hi=MAX_OFF_NADIR_DEG, **pos),
        rate_deg_s=number(raw, "max_slew_velocity_deg_per_s", where, **pos),
        accel_deg_s2=number(raw, "max_slew_acceleration_deg_per_s2", where, **pos),
        settling_s=number(raw, "settling_time_s", where, lo=0.0),
        min_duration_s=number(raw, "min_obs_duration_s", where, **pos),
        max_duration_s=number(raw, "max_obs_duration_s", where, **pos),
    )
    if out["min_duration_s"] > out["max_duration_s"]:
        raise ValueError(
            f"{where}.min_obs_duration_s: {out['min_duration_s']:g} > "
            f"max_obs_duration_s {out['max_duration_s']:g}"
        )
    if out["pixels"] * out["ifov_deg"] >= 90.0:
        raise ValueError(f"{where}.cross_track_pixels: field of view pixels x IFOV >= 90 deg")
    return out


def _rows(path: Path, what: str) -> list:
    raw = read_yaml(path)
    if not isinstance(raw, list) or not raw:
        raise ValueError(f"{path.name}: expected a non-empty list of {what}")
    return raw


def _no_duplicates(rows: list, name: str) -> None:
    seen: dict = {}
    for i, r in enumerate(rows):
        if r["id"] in seen:
            raise ValueError(f"{name}: [{i}].id: duplicate {r['id']!r} (also [{seen[r['id']]}])")
        seen[r["id"]] = i


def load_satellites(path: Path, mission) -> list:
    """Read ``satellites.yaml``: TLE (checked, propagating over the horizon), sensor, agility.

    Args:
      path: the file.
      mission: the Mission (its ``start`` and ``end``).
    Returns:
      list of dicts with the fields of :class:`jaxspline.stereo.case.Satellite`.
    Raises:
      ValueError: naming the file, the entry and the field.
    """
    rows = [
        _satellite(r, f"{path.name}: [{i}]", mission.start, mission.end)
        for i, r in enumerate(_rows(path, "satellites"))
    ]
    _no_duplicates(rows, path.name)
    return rows


def _target(raw: Any, where: str, scene_types: tuple) -> dict:
    tid = text(raw, "id", where)
    scene = text(raw, "scene_type", where)
    if scene not in scene_types:
        raise ValueError(f"{where}.scene_type: {scene!r} is not one of {', '.join(scene_types)}")
    return dict(
        id=tid,
        lat_deg=number(raw, "latitude_deg", where, lo=-90.0, hi=90.0),
        lon_deg=number(raw, "longitude_deg", where, lo=-180.0, hi=180.0),
        aoi_radius_m=number(raw, "aoi_radius_m", where, lo=0.0, lo_open=True, hi=1e6),
        elevation_m=number(raw, "elevation_ref_m", where, lo=MIN_ELEVATION_M, hi=MAX_ELEVATION_M),
        scene_type=scene,
    )


def load_targets(path: Path, scene_types: tuple) -> list:
    """Read ``targets.yaml``.

    Args:
      path: the file.
      scene_types: the accepted scene types.
    Returns:
      list of dicts with the fields of :class:`jaxspline.stereo.case.Target`.
    Raises:
      ValueError: naming the file, the entry and the field.
    """
    rows = [
        _target(r, f"{path.name}: [{i}]", scene_types) for i, r in enumerate(_rows(path, "targets"))
    ]
    _no_duplicates(rows, path.name)
    return rows
