"""Stereo targets in scenario files: the ``[stereo]`` table and each stereo target's keys.

The schema is documented with the rest of the scenario file in
:mod:`jaxspline.readers.scenario`, the ranges of the numbers in
:mod:`jaxspline.readers.ranges`, what a request means (products, quality, value) in
:mod:`jaxspline.readers.stereo_request`. Angles are degrees in the file and radians in
the :class:`~jaxspline.readers.stereo_request.Stereo` requests they become.

* ``[stereo]`` (:func:`parse_stereo_table`): the scenario-wide rules and defaults of
  every stereo target, read into a *template* request (name ``""``, target ``-1``).
  Without the table, the defaults: the stereo_imaging benchmark's thresholds (overlap
  0.8, convergence 5-45 deg, pixel-scale ratio 1.5, looks at most an hour apart, two
  satellites may pair, a triple's anchor within 10 deg of nadir, quality weights
  0.5 / 0.35 / 0.15) and its urban scene (preferred convergence 8-18 deg).
* A target of kind ``stereo`` (:func:`target_stereo`): its own ``product``,
  ``radius_m``, preferred convergence band and ``tri_bonus`` (each defaulting to the
  table's); keys of a point or a strip (``duration_s``, ``length_km``,
  ``azimuth_deg``, ``min_duration_s``, ``desired_s``, ``tolerance_s``) are refused on it
  with the reason, and its keys on a target of another kind. In a TOML table the band
  is one key ``band_deg = [lo, hi]``; in a CSV file two columns ``band_lo_deg``,
  ``band_hi_deg``.

A preferred band must lie inside the accepted convergence (a product outside the
accepted range is no product; a band outside it would prefer what is refused).
"""

from __future__ import annotations

import dataclasses
import math

from jaxspline.readers.fields import field_bool, field_number, field_pair, field_str, field_table
from jaxspline.readers.ranges import bounds
from jaxspline.readers.stereo_request import PRODUCTS, Stereo

__all__ = [
    "CSV_STEREO_COLUMNS",
    "DEFAULT_RADIUS_M",
    "DEFAULT_TRI_BONUS",
    "STEREO_KEYS",
    "TARGET_STEREO_KEYS",
    "parse_stereo_table",
    "stereo_request",
    "stereo_template",
    "target_stereo",
]

#: Keys of the ``[stereo]`` table.
STEREO_KEYS = frozenset(
    "product radius_m min_overlap convergence_deg band_deg max_scale_ratio max_separation_s "
    "cross_satellite anchor_off_nadir_deg quality_weights tri_bonus quality_weight".split()
)
#: Keys of a ``[[targets]]`` table that only a stereo target takes.
TARGET_STEREO_KEYS = ("product", "radius_m", "band_deg", "tri_bonus")
#: CSV columns that only a stereo row takes (the band in two columns).
CSV_STEREO_COLUMNS = ("product", "radius_m", "band_lo_deg", "band_hi_deg", "tri_bonus")
#: Radius of the ground disk a stereo target asks for [m] (a city centre).
DEFAULT_RADIUS_M = 5000.0
#: Bonus of a triple over its best pair: the middle of the benchmark's scene bonuses
#: (0.05 open to 0.12 urban); 0 would value a triple as its best pair, and a third look
#: would then add nothing.
DEFAULT_TRI_BONUS = 0.1
DEFAULT_CONVERGENCE_DEG = (5.0, 45.0)
DEFAULT_BAND_DEG = (8.0, 18.0)
DEFAULT_ANCHOR_DEG = 10.0
DEFAULT_WEIGHTS = (0.5, 0.35, 0.15)
WEIGHT_SUM_TOL = 1e-6  # the quality weights sum to 1 within this
#: Keys of other kinds refused on a stereo target, with the reason.
_LOOK_TIME = "its looks last what covers the disk, within the satellites' strip_duration_s"
_TIMED = "its looks are timed by their products; use window_s"
_NOT_STEREO = {
    "duration_s": _LOOK_TIME,
    "length_km": "it is a disk of radius_m",
    "azimuth_deg": "its looks follow the ground track",
    "min_duration_s": _LOOK_TIME,
    "desired_s": _TIMED,
    "tolerance_s": _TIMED,
}


def stereo_template() -> Stereo:
    """The requests' defaults without a ``[stereo]`` table (module docstring).

    Returns:
      Stereo, name ``""`` and target ``-1``.
    """
    return Stereo(
        name="",
        target=-1,
        radius=DEFAULT_RADIUS_M,
        convergence=tuple(math.radians(x) for x in DEFAULT_CONVERGENCE_DEG),
        band=tuple(math.radians(x) for x in DEFAULT_BAND_DEG),
        anchor_off_nadir=math.radians(DEFAULT_ANCHOR_DEG),
        weights=DEFAULT_WEIGHTS,
        tri_bonus=DEFAULT_TRI_BONUS,
    )


def _deg_pair(rad: tuple) -> list[float]:
    return [math.degrees(x) for x in rad]


def _product(raw, err) -> str:
    """``raw`` (already a string) as a product name, ``err(msg)`` building the error."""
    if raw not in PRODUCTS:
        raise err(f"must be 'pair' or 'tri' (a triple preferred, a pair still counts), got {raw!r}")
    return raw


def _weights(ctx, value) -> tuple[float, float, float]:
    """``stereo.quality_weights``: three weights in range summing to 1."""
    f = "stereo.quality_weights"
    if not isinstance(value, list) or len(value) != 3:
        raise ctx.error(f, f"must be a list [geometry, overlap, resolution], got {value!r}")
    w = tuple(field_number(ctx, f, v, **bounds(f)) for v in value)
    if abs(sum(w) - 1.0) > WEIGHT_SUM_TOL:
        raise ctx.error(f, f"must sum to 1 (a quality lies in [0, 1]), got {value!r}")
    return w


def _inside(band: tuple, conv: tuple) -> bool:
    """``band`` [deg] within ``conv`` [deg] (rounding of a radian round trip allowed)."""
    return conv[0] - 1e-9 <= band[0] and band[1] <= conv[1] + 1e-9


def parse_stereo_table(ctx, data: dict) -> Stereo:
    """The ``[stereo]`` table of a parsed scenario (defaults without it), as a template.

    Args:
      ctx: :class:`jaxspline.readers.fields.FieldContext` of the file.
      data: dict, the parsed scenario TOML.
    Returns:
      Stereo: the template request (name ``""``, target ``-1``; radians, seconds).
    Raises:
      ValueError: naming the field (``stereo.band_deg``), its TOML line and the value.
    """
    d = stereo_template()
    tab = field_table(ctx, "stereo", data.get("stereo", {}), STEREO_KEYS)

    def num(key, default):
        return field_number(ctx, f"stereo.{key}", tab.get(key, default), **bounds(f"stereo.{key}"))

    def pair(key, default):
        raw = tab.get(key, list(default))
        return field_pair(ctx, f"stereo.{key}", raw, **bounds(f"stereo.{key}"))

    product = _product(
        field_str(ctx, "stereo.product", tab.get("product", d.product)),
        lambda m: ctx.error("stereo.product", m),
    )
    conv = pair("convergence_deg", DEFAULT_CONVERGENCE_DEG)
    band = pair("band_deg", DEFAULT_BAND_DEG)
    if not _inside(band, conv):
        raise ctx.error(
            "stereo.band_deg",
            f"the preferred band [{band[0]:g}, {band[1]:g}] deg must lie within "
            f"convergence_deg [{conv[0]:g}, {conv[1]:g}] (the accepted angles)",
        )
    return Stereo(
        name="",
        target=-1,
        radius=num("radius_m", d.radius),
        product=product,
        min_overlap=num("min_overlap", d.min_overlap),
        convergence=tuple(math.radians(x) for x in conv),
        band=tuple(math.radians(x) for x in band),
        max_scale_ratio=num("max_scale_ratio", d.max_scale_ratio),
        max_separation=num("max_separation_s", d.max_separation),
        cross_satellite=field_bool(
            ctx, "stereo.cross_satellite", tab.get("cross_satellite", d.cross_satellite)
        ),
        anchor_off_nadir=math.radians(num("anchor_off_nadir_deg", DEFAULT_ANCHOR_DEG)),
        weights=_weights(ctx, tab.get("quality_weights", list(d.weights))),
        tri_bonus=num("tri_bonus", d.tri_bonus),
        quality_weight=num("quality_weight", d.quality_weight),
    )


def target_stereo(get, err, num, kind: str, text_of, template: Stereo) -> dict | None:
    """The stereo fields of one target row (None for a target of another kind).

    Args:
      get: ``get(column) -> raw or None`` of the row (TOML: ``band_deg`` split into
        ``band_lo_deg`` and ``band_hi_deg``).
      err: ``err(column)(msg) -> ValueError`` naming the file, the field and its line.
      num: ``num(column, range_key=None, default=...) -> float`` checked against
        ``targets[].<key>`` of :data:`jaxspline.readers.ranges.RANGES`.
      kind: the row's kind (``"point"``, ``"strip"``, ``"stereo"``).
      text_of: ``text_of(column, default) -> str``, the row's checked text.
      template: the scenario's :func:`parse_stereo_table`.
    Returns:
      dict of :class:`Stereo` fields (``product``, ``radius``, ``band`` [rad],
      ``tri_bonus``), or None.
    Raises:
      ValueError: from ``err``, naming the column.
    """
    if kind != "stereo":
        for col in CSV_STEREO_COLUMNS:
            if get(col) is not None:
                raise err(col)(f"only a stereo target (kind 'stereo') takes it, not a {kind}")
        return None
    for col, why in _NOT_STEREO.items():
        if get(col) is not None:
            raise err(col)(f"a stereo target takes no {col}: {why}")
    product = _product(text_of("product", template.product), err("product"))
    radius = num("radius_m", default=template.radius)
    band_rad = template.band
    given = [get(c) is not None for c in ("band_lo_deg", "band_hi_deg")]
    if any(given) and not all(given):
        missing = "band_hi_deg" if given[0] else "band_lo_deg"
        raise err(missing)("give both band_lo_deg and band_hi_deg (the preferred band) [deg]")
    if all(given):
        band = [num("band_lo_deg", "band_deg"), num("band_hi_deg", "band_deg")]
        if band[0] > band[1]:
            raise err("band_hi_deg")(f"band needs lo <= hi, got [{band[0]:g}, {band[1]:g}]")
        conv = _deg_pair(template.convergence)
        if not _inside(band, conv):
            raise err("band_lo_deg")(
                f"the preferred band [{band[0]:g}, {band[1]:g}] deg must lie within the "
                f"[stereo] table's convergence_deg [{conv[0]:g}, {conv[1]:g}]"
            )
        band_rad = tuple(math.radians(x) for x in band)
    return {
        "product": product,
        "radius": radius,
        "band": band_rad,
        "tri_bonus": num("tri_bonus", default=template.tri_bonus),
    }


def stereo_request(template: Stereo, name: str, target: int, fields: dict) -> Stereo:
    """The request of a stereo target: the template with its name, row and own fields.

    Args:
      template: :func:`parse_stereo_table`'s; name: the target's name; target: its row
        in ``scenario.targets``; fields: :func:`target_stereo`'s.
    Returns:
      Stereo.
    """
    return dataclasses.replace(template, name=name, target=int(target), **fields)
