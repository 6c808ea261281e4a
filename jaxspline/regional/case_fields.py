"""Strict field readers shared by the regional_coverage case and solution loaders.

Each reader raises ``ValueError`` naming the file and the field (``where``), e.g.
``satellites.yaml: [3].agility.max_roll_rate_deg_per_s: must be > 0, got -1``. JSON is
parsed strictly (no NaN / Infinity, no repeated keys), YAML with the safe loader refusing
repeated keys; files are UTF-8 (a byte-order mark is dropped).
"""

from __future__ import annotations

import json
import math
import os
from datetime import datetime
from pathlib import Path
from typing import Any

import yaml

from jaxspline.readers.case_files import UniqueKeyLoader
from jaxspline.readers.satellites import tle_checksum

#: TLE line length (columns 1-69, column 69 the checksum).
TLE_LINE_LENGTH = 69


def read_text(path: Path) -> str:
    """The text of a UTF-8 file (a byte-order mark dropped).

    Args:
      path: Path.
    Returns:
      str.
    Raises:
      ValueError: missing, unreadable or not UTF-8, naming the file.
    """
    if not path.is_file():
        raise ValueError(f"{path}: file not found")
    try:
        return path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not UTF-8 text (offset {exc.start})") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read: {exc}") from None


def _no_dup_pairs(pairs):
    out = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {key!r}")
        out[key] = value
    return out


def _no_constant(name):
    raise ValueError(f"{name} is not a number in strict JSON")


def read_json(path: str | os.PathLike) -> Any:
    """Parse a strict JSON file (no NaN / Infinity, no repeated keys).

    Args:
      path: file path.
    Returns:
      the parsed object.
    Raises:
      ValueError: missing file or bad JSON, naming the file.
    """
    path = Path(path)
    text = read_text(path)
    try:
        return json.loads(text, object_pairs_hook=_no_dup_pairs, parse_constant=_no_constant)
    except ValueError as exc:
        raise ValueError(f"{path}: not valid JSON: {exc}") from None
    except RecursionError:  # thousands of nested arrays or objects
        raise ValueError(f"{path}: not valid JSON here: nested too deeply") from None


def read_yaml(path: Path) -> Any:
    """Parse a YAML file with the safe loader, refusing a key repeated in one mapping.

    Args:
      path: Path.
    Returns:
      the parsed object.
    Raises:
      ValueError: missing file or bad YAML, naming the file.
    """
    text = read_text(path)
    try:
        return yaml.load(text, Loader=UniqueKeyLoader)
    except yaml.YAMLError as exc:
        raise ValueError(f"{path.name}: not valid YAML: {exc}") from None


def get_field(mapping: Any, key: str, where: str) -> Any:
    """``mapping[key]``, or a ValueError ``"{where}.{key}: missing field"``.

    Args:
      mapping: the parsed object (must be a dict).
      key: field name.
      where: file and path of ``mapping`` for the message.
    Returns:
      the value.
    """
    if not isinstance(mapping, dict):
        raise ValueError(f"{where}: expected a mapping, got {type(mapping).__name__}")
    if key not in mapping:
        raise ValueError(f"{where}.{key}: missing field")
    return mapping[key]


def number_field(mapping, key, where, *, lo=None, lo_open=False, hi=None, null=False):
    """A finite number field in [lo, hi] (lo excluded when ``lo_open``), or None if ``null``.

    Args:
      mapping: dict.
      key: field name.
      where: file and path of ``mapping`` for the message.
      lo, hi: bounds (None = unbounded); ``lo_open`` makes ``lo`` exclusive.
      null: accept ``null`` (returns None).
    Returns:
      float or None.
    Raises:
      ValueError: missing, not a number (booleans refused), not finite, out of bounds.
    """
    value = get_field(mapping, key, where)
    if value is None and null:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where}.{key}: expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{where}.{key}: must be finite, got {value!r}")
    if lo is not None and (value <= lo if lo_open else value < lo):
        raise ValueError(f"{where}.{key}: must be {'>' if lo_open else '>='} {lo:g}, got {value:g}")
    if hi is not None and value > hi:
        raise ValueError(f"{where}.{key}: must be <= {hi:g}, got {value:g}")
    return value


def string_field(mapping: Any, key: str, where: str) -> str:
    """A non-empty string field.

    Args:
      mapping: dict.
      key: field name.
      where: file and path of ``mapping`` for the message.
    Returns:
      str.
    """
    value = get_field(mapping, key, where)
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{where}.{key}: expected a non-empty string, got {value!r}")
    return value


def check_tle(l1: str, l2: str, where: str, start: datetime, end: datetime) -> None:
    """Check a TLE: line numbers, 69 columns, checksums, catalogue numbers, mean motion > 0,
    and SGP4 propagation without error at ``start`` and ``end``.

    Args:
      l1, l2: TLE lines.
      where: file and path of the satellite for the message.
      start, end: aware UTC datetimes (the horizon).
    Raises:
      ValueError: naming ``where`` and the line.
    """
    from sgp4.api import Satrec, jday

    for num, line in ((1, l1), (2, l2)):
        w = f"{where}.tle_line{num}"
        if len(line) != TLE_LINE_LENGTH or not line.startswith(f"{num} "):
            raise ValueError(f"{w}: not a {TLE_LINE_LENGTH}-column TLE line {num}: {line!r}")
        if not line[68].isdigit() or int(line[68]) != tle_checksum(line):
            raise ValueError(
                f"{w}: bad checksum (column 69 is {line[68]!r}, computed {tle_checksum(line)})"
            )
    if l1[2:7] != l2[2:7]:
        raise ValueError(f"{where}.tle_line2: catalogue number {l2[2:7]!r} != line 1 {l1[2:7]!r}")
    try:
        mean_motion = float(l2[52:63])
        sat = Satrec.twoline2rv(l1, l2)
    except ValueError as exc:
        raise ValueError(f"{where}.tle_line1/tle_line2: not a valid TLE: {exc}") from None
    if not mean_motion > 0:
        raise ValueError(f"{where}.tle_line2: mean motion must be > 0, got {mean_motion}")
    for label, t in (("horizon_start", start), ("horizon_end", end)):
        jd, fr = jday(t.year, t.month, t.day, t.hour, t.minute, t.second + t.microsecond * 1e-6)
        err = sat.sgp4(jd, fr)[0]
        if err != 0:
            raise ValueError(f"{where}.tle_line1/tle_line2: SGP4 error {err} at {label}")
