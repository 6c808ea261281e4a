"""Checked fields of scenario files: typed readers whose errors name the field and line.

Shared by :mod:`jaxspline.readers.scenario` (satellites, planner) and
:mod:`jaxspline.readers.targets` (targets). Every reader raises ``ValueError`` as
``source: field (line N): message``; :class:`FieldContext` finds the TOML line of a
field such as ``satellites[1].rate_deg_s`` when the raw text is known. Strings never
hold control characters (NUL, escape, line breaks, ...: :func:`check_text`).
:func:`read_text` reads every input file (TOML, CSV, GeoJSON, YAML) as UTF-8, a
byte-order mark dropped, and names the file and line of bytes that are not UTF-8; a
directory, a device or pipe, an unreadable file or one over :data:`MAX_FILE_BYTES` is
a ``ValueError`` naming the file. The readers of long files call :func:`read_tick` on
every CSV row or GeoJSON feature, and it ticks every :data:`READ_TICK_ROWS` of them: a
command sets :data:`READ_CLOCK` to check its time and memory limits while a file is
read.
"""

from __future__ import annotations

import math
import os
import re
import stat
import unicodedata
from collections.abc import Callable
from contextvars import ContextVar
from pathlib import Path

__all__ = [
    "MAX_FILE_BYTES",
    "READ_CLOCK",
    "READ_TICK_ROWS",
    "REQUIRED",
    "FieldContext",
    "check_float",
    "check_text",
    "field_bool",
    "field_int",
    "field_number",
    "field_pair",
    "field_str",
    "field_table",
    "field_tables",
    "read_text",
    "read_tick",
]

_IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
MAX_FILE_BYTES = 1 << 30  # largest input file read [bytes] (1 GiB: ~15 M CSV rows)
#: Rows (CSV) or features (GeoJSON) between two ticks of :func:`read_tick` (~0.7 s of
#: CSV reading).
READ_TICK_ROWS = 10_000
#: The clock of the files being read: ``clock(file, share read)``, which may raise to
#: stop the reading (None: nothing checks; ``jaxspline plan`` sets it).
READ_CLOCK: ContextVar[Callable[[str, float], None] | None] = ContextVar(
    "jaxspline_read_clock", default=None
)


def read_tick(label: str, done: int, total: int) -> None:
    """The reading clock's cadence: every :data:`READ_TICK_ROWS` rows or features
    (``done`` a multiple of it), call :data:`READ_CLOCK` (when set) with the file and
    the share of it read.

    Args:
      label: the file's name, for the clock's message.
      done: rows (CSV lines, the header included) or features read so far (>= 1).
      total: rows or features in the file.
    """
    if done % READ_TICK_ROWS:
        return
    clock = READ_CLOCK.get()
    if clock is not None:
        clock(label, min(max(done / max(total, 1), 0.0), 1.0))


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
      ValueError: the bytes are not UTF-8 (naming the file and the line), or the path
        is not a readable regular file of at most :data:`MAX_FILE_BYTES`.
    """
    data = _read_bytes(Path(path))
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        place = where(line) if where is not None else f"{path}: line {line}"
        raise ValueError(
            f"{place}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
            "save the file as UTF-8"
        ) from None


def _read_bytes(path: Path) -> bytes:
    """The bytes of a regular file; ValueError naming it when it is none or unreadable."""
    try:
        st = path.stat()
        kind = stat.S_IFMT(st.st_mode)
        data = path.read_bytes() if kind == stat.S_IFREG and st.st_size <= MAX_FILE_BYTES else None
    except FileNotFoundError:
        raise
    except (OSError, ValueError) as exc:  # permissions, a NUL in the name, a loop, ...
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ValueError(f"{os.fspath(path)!r}: cannot read: {why}") from None
    if kind == stat.S_IFDIR:
        raise ValueError(f"{path}: is a directory, not a file")
    if kind != stat.S_IFREG:
        raise ValueError(f"{path}: not a regular file (a device, pipe or socket)")
    if data is None:
        raise ValueError(
            f"{path}: {st.st_size:,} bytes, more than the {MAX_FILE_BYTES:,} "
            f"({MAX_FILE_BYTES >> 20} MiB) an input file may have"
        )
    return data


def check_text(value: str, err, max_chars: int | None = None) -> str:
    """``value`` if it holds no control character (and at most ``max_chars`` characters).

    Control characters (Unicode category Cc: NUL, escape, tab, line breaks, ...) and
    lone surrogates would be dropped or change meaning in the CSV, JSON and CCSDS
    files the plan is written to, so names and sensor types never hold them.

    Args:
      value: str.
      err: callable ``err(msg) -> Exception``.
      max_chars: longest accepted string (None: any length).
    Returns:
      str, ``value``.
    Raises:
      Exception: ``err(msg)`` naming the first bad character and its position.
    """
    # printable text (the common case) holds neither: both are Unicode "Other" categories
    for i, ch in enumerate("" if value.isprintable() else value):
        if unicodedata.category(ch) in ("Cc", "Cs"):
            raise err(f"must not contain control characters, got {ch!r} at position {i}")
    if max_chars is not None and len(value) > max_chars:
        raise err(f"must be at most {max_chars} characters, got {len(value)}")
    return value


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
        try:
            v = float(raw)
        except OverflowError:  # a TOML integer past the float range
            raise err(f"must be finite, got {raw!r}") from None
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
    if lo is not None and hi is None and v < lo:
        raise err(f"must be >= {lo:g}, got {raw!r}")
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


def field_int(ctx, field, value, minimum=0, maximum=None) -> int:
    """``value`` as an integer in ``[minimum, maximum]`` (booleans rejected).

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      value: the value read.
      minimum: smallest accepted value.
      maximum: largest accepted value (None: no upper bound).
    Returns:
      int.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.error(field, f"must be an integer, got {value!r}")
    if maximum is not None and not minimum <= value <= maximum:
        raise ctx.error(field, f"must be within [{minimum}, {maximum}], got {value!r}")
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


def field_str(ctx, field, value, allow_empty=True, max_chars=None) -> str:
    """``value`` as a string without control characters (non-blank unless ``allow_empty``).

    Args:
      ctx: FieldContext of the file being read.
      field: dotted field label used in the error (``table[index].key``).
      value: the value read.
      allow_empty: accept "" and blank strings.
      max_chars: longest accepted string (None: any length).
    Returns:
      str.
    Raises:
      ValueError: from ``ctx.error``, naming the field and its TOML line.
    """
    if not isinstance(value, str) or (not allow_empty and not value.strip()):
        raise ctx.error(
            field, f"must be a {'' if allow_empty else 'non-empty '}string, got {value!r}"
        )
    return check_text(value, lambda m: ctx.error(field, m), max_chars)


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
