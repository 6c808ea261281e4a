"""Checked fields of scenario files: typed readers whose errors name the field and line.

Shared by :mod:`jaxspline.readers.scenario` (satellites, planner) and
:mod:`jaxspline.readers.targets` (targets). Every reader raises ``ValueError`` as
``source: field (line N): message``; :class:`FieldContext` finds the TOML line of a
field such as ``satellites[1].rate_deg_s`` when the raw text is known.
:func:`read_text` reads every input file (TOML, CSV, GeoJSON, YAML) as UTF-8, a
byte-order mark dropped, and names the file and line of bytes that are not UTF-8.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

__all__ = [
    "REQUIRED",
    "FieldContext",
    "check_float",
    "field_bool",
    "field_int",
    "field_number",
    "field_pair",
    "field_str",
    "field_table",
    "field_tables",
    "read_text",
]

_IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


class FieldContext:
    """Error helper: names the field and, when the raw text is known, its TOML line.

    Args:
      source: name of the file (or other source) in error messages.
      text: the raw TOML text, or None when line numbers are unknown.

    Attributes:
      source: as given.
      lines: the text's lines, or None.
    """

    def __init__(self, source: str, text: str | None):
        self.source = source
        self.lines = text.splitlines() if text is not None else None

    def _find(self, pattern: re.Pattern, start: int, stop_at_header: bool) -> int | None:
        for i in range(start, len(self.lines)):
            if stop_at_header and i > start and re.match(r"^\s*\[", self.lines[i]):
                return None
            if pattern.search(self.lines[i]):
                return i
        return None

    def line_of(self, field: str) -> int | None:
        """1-based TOML line of a field, or None when unknown.

        Args:
          field: dotted field label (``table[index].key...``).
        Returns:
          int or None.
        """
        if self.lines is None:
            return None
        parts = re.findall(_IDENT + r"|\[\d+\]", field)
        if not parts:
            return None
        table = parts[0]
        index = int(parts[1][1:-1]) if len(parts) > 1 and parts[1].startswith("[") else None
        keys = [p for p in parts[1:] if not p.startswith("[")]
        if len(parts) == 1:  # a top-level key before the first header, or a table header
            top = re.compile(r"^\s*" + re.escape(table) + r"\s*=")
            for i, ln in enumerate(self.lines):
                if re.match(r"^\s*\[", ln):
                    break
                if top.search(ln):
                    return i + 1
        header = re.compile(r"^\s*\[\[?\s*" + re.escape(table) + r"\s*\]\]?\s*(#.*)?$")
        start, seen = None, -1
        for i, ln in enumerate(self.lines):
            if header.match(ln):
                seen += 1
                if index is None or seen == index:
                    start = i
                    break
        if start is None:
            return None
        if not keys:
            return start + 1
        for key in reversed(keys):  # a missing inner key: the line of its parent
            pat = re.compile(r"(^|[{,])\s*" + re.escape(key) + r"\s*=")
            found = self._find(pat, start, True)
            if found is not None:
                return found + 1
        return start + 1

    def error(self, field: str, msg: str) -> ValueError:
        """A ValueError ``source: field (line N): msg``.

        Args:
          field: dotted field label.
          msg: what is wrong.
        Returns:
          ValueError (to be raised by the caller).
        """
        line = self.line_of(field)
        where = f" (line {line})" if line is not None else ""
        return ValueError(f"{self.source}: {field}{where}: {msg}")


REQUIRED = object()


def read_text(path, where=None) -> str:
    """The text of a UTF-8 file (a leading byte-order mark dropped; line ends kept).

    Args:
      path: str or Path.
      where: callable ``where(line) -> str`` naming the place of a decoding error
        (default ``"<path>: line N"``).
    Returns:
      str.
    Raises:
      FileNotFoundError: the file is missing.
      ValueError: the bytes are not UTF-8, naming the file and the line.
    """
    data = Path(path).read_bytes()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        place = where(line) if where is not None else f"{path}: line {line}"
        raise ValueError(
            f"{place}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
            "save the file as UTF-8"
        ) from None


def check_float(
    raw, err, *, default=REQUIRED, text=False, positive=False, nonneg=False, lo=None, hi=None
):
    """``raw`` as a checked float.

    Args:
      raw: the value read (None: missing).
      err: callable ``err(msg) -> Exception`` building the error to raise.
      default: value returned when ``raw`` is None; required when not given.
      text: also parse strings.
      positive: require > 0.
      nonneg: require >= 0.
      lo: lower bound (with ``hi``: the closed interval [lo, hi]).
      hi: upper bound.
    Returns:
      float (or ``default``).
    Raises:
      Exception: ``err(msg)`` when missing, not a number, not finite or out of bounds.
    """
    if raw is None:
        if default is REQUIRED:
            raise err("missing")
        return default
    if text and isinstance(raw, str):
        try:
            v = float(raw)
        except ValueError:
            raise err(f"must be a number, got {raw!r}") from None
    elif isinstance(raw, bool) or not isinstance(raw, int | float):
        raise err(f"must be a number, got {raw!r}")
    else:
        v = float(raw)
    if not math.isfinite(v):
        raise err(f"must be finite, got {raw!r}")
    if positive and v <= 0:
        raise err(f"must be > 0, got {raw!r}")
    if nonneg and v < 0:
        raise err(f"must be >= 0, got {raw!r}")
    if lo is not None and hi is not None and not lo <= v <= hi:
        raise err(f"must be within [{lo:g}, {hi:g}], got {raw!r}")
    if hi is not None and lo is None and v > hi:
        raise err(f"must be <= {hi:g}, got {raw!r}")
    return v


def field_number(ctx, field, value, **kw) -> float:
    """``value`` as a checked float (keywords as in :func:`check_float`).

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      value: the value read.
      **kw: as in :func:`check_float`.
    Returns:
      float.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    return check_float(value, lambda m: ctx.error(field, m), **kw)


def field_int(ctx, field, value, minimum=0) -> int:
    """``value`` as an integer >= ``minimum`` (booleans rejected).

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      value: the value read.
      minimum: smallest accepted value.
    Returns:
      int.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.error(field, f"must be an integer, got {value!r}")
    if value < minimum:
        raise ctx.error(field, f"must be >= {minimum}, got {value!r}")
    return int(value)


def field_bool(ctx, field, value) -> bool:
    """``value`` as a TOML boolean.

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      value: the value read.
    Returns:
      bool.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if not isinstance(value, bool):
        raise ctx.error(field, f"must be true or false, got {value!r}")
    return value


def field_str(ctx, field, value, allow_empty=True) -> str:
    """``value`` as a string (non-blank unless ``allow_empty``).

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      value: the value read.
      allow_empty: accept "" and blank strings.
    Returns:
      str.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if not isinstance(value, str) or (not allow_empty and not value.strip()):
        raise ctx.error(
            field, f"must be a {'' if allow_empty else 'non-empty '}string, got {value!r}"
        )
    return value


def field_pair(ctx, field, value, **kw) -> tuple[float, float]:
    """``value`` as a ``[lo, hi]`` list of checked floats with lo <= hi.

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      value: the value read.
      **kw: as in :func:`check_float`, applied to both numbers.
    Returns:
      (lo, hi) floats.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if not isinstance(value, list) or len(value) != 2:
        raise ctx.error(field, f"must be a list [lo, hi], got {value!r}")
    lo, hi = (field_number(ctx, field, v, **kw) for v in value)
    if lo > hi:
        raise ctx.error(field, f"needs lo <= hi, got {value!r}")
    return lo, hi


def field_table(ctx, field, tab, keys) -> dict:
    """``tab`` as a table whose keys are all in ``keys`` (the first unknown one is named).

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      tab: the value read.
      keys: set of allowed keys.
    Returns:
      dict, ``tab`` itself.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if not isinstance(tab, dict):
        raise ctx.error(field, f"must be a table, got {tab!r}")
    unknown = sorted(set(tab) - keys)
    if unknown:
        raise ctx.error(f"{field}.{unknown[0]}", f"unknown key (allowed: {sorted(keys)})")
    return tab


def field_tables(ctx, data, name, alias) -> list[tuple[str, dict]]:
    """(field label, table) of each entry of array ``name`` or its alias (one table or many).

    Args:
      ctx: FieldContext of the file being read.
      data: dict, the parsed TOML document (or a parent table).
      name: key of the array of tables (``[[name]]``).
      alias: key of the alternative single table (``[alias]``).
    Returns:
      list of (label, dict).
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if name in data and alias in data:
        raise ctx.error(alias, f"give either [[{name}]] or its alias [{alias}], not both")
    key = name if name in data else alias
    items = data.get(key, [])
    if isinstance(items, dict):
        return [(key, items)]
    if not isinstance(items, list):
        raise ctx.error(key, f"must be an array of tables [[{key}]], got {items!r}")
    return [(f"{key}[{i}]", it) for i, it in enumerate(items)]
