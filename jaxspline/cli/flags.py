"""Checks of command-line flags, run before any work: each error names its flag.

``argparse`` turns the text into a number; these checks add the ranges
(``--aem-step: must be > 0, got 0``). Every check raises ``ValueError`` (exit 2), and
returns the value so a command can check and use in one line.
"""

from __future__ import annotations

import math
import os
import re
import tempfile

__all__ = [
    "MAX_ITERS",
    "MAX_PROCESSES",
    "MAX_SECONDS",
    "MAX_SEED",
    "check_host_port",
    "check_int",
    "check_output_file",
    "check_path",
    "check_seconds",
    "check_value",
]

MAX_SECONDS = 7 * 86400.0  # a week: the longest time limit, search time or certificate [s]
MAX_ITERS = 10**9
MAX_SEED = 2**32 - 1
MAX_PROCESSES = 4096
_HOST_PORT = re.compile(r"^\[?([A-Za-z0-9_.\-:]+?)\]?:(\d{1,5})$")


def check_seconds(flag: str, value, *, zero: bool = False, hi: float = MAX_SECONDS):
    """A duration flag [s]: finite, > 0 (``zero``: >= 0) and at most ``hi``; None passes.

    Args:
      flag: the flag's name (``--time-limit``).
      value: float or None.
      zero: accept 0.
      hi: largest accepted value [s].
    Returns:
      the value.
    Raises:
      ValueError: naming the flag and the value.
    """
    if value is None:
        return None
    if not math.isfinite(value):
        raise ValueError(f"{flag}: must be a finite number of seconds, got {value!r}")
    if value < 0 or (value == 0 and not zero):
        raise ValueError(f"{flag}: must be {'>=' if zero else '>'} 0, got {value:g}")
    if value > hi:
        raise ValueError(f"{flag}: must be <= {hi:g} s, got {value:g}")
    return value


def check_value(flag: str, value):
    """A positive finite number (a plan value); None passes.

    Args:
      flag: the flag's name.
      value: float or None.
    Returns:
      the value.
    Raises:
      ValueError: naming the flag and the value.
    """
    if value is not None and not (math.isfinite(value) and value > 0):
        raise ValueError(f"{flag}: must be a finite number > 0, got {value!r}")
    return value


def check_int(flag: str, value, lo: int, hi: int):
    """An integer flag within ``[lo, hi]``; None passes.

    Args:
      flag: the flag's name.
      value: int or None.
      lo: smallest accepted value.
      hi: largest accepted value.
    Returns:
      the value.
    Raises:
      ValueError: naming the flag and the value.
    """
    if value is not None and not lo <= value <= hi:
        raise ValueError(f"{flag}: must be within [{lo}, {hi}], got {value}")
    return value


def check_path(flag: str, value, *, kind: str | None = None, exists: bool = False):
    """A path flag: not empty, no NUL, and not of the wrong kind; None passes.

    Args:
      flag: the flag's name (``-o/--output``).
      value: str or None.
      kind: ``"file"``: must not be a directory; ``"dir"``: must be one when it exists.
      exists: it must exist.
    Returns:
      the value.
    Raises:
      ValueError: naming the flag and the path.
      FileNotFoundError: ``exists`` and it does not.
    """
    if value is None:
        return None
    if not value.strip():
        raise ValueError(f"{flag}: must not be empty, got {value!r}")
    if "\x00" in value:
        raise ValueError(f"{flag}: must not contain a NUL character, got {value!r}")
    if exists and not os.path.exists(value):
        raise FileNotFoundError(f"{flag}: not found: {value}")
    if kind == "file" and os.path.isdir(value):
        raise ValueError(f"{flag}: {value} is a directory, not a file")
    if kind == "dir" and os.path.exists(value) and not os.path.isdir(value):
        raise ValueError(f"{flag}: {value} is not a directory")
    return value


def check_output_file(flag: str, value, *, force: bool = True, room: int = 0):
    """An output file flag, checked before any work: a usable path (:func:`check_path`),
    in an existing folder where a new file can be created (of ``room`` bytes, written and
    synced); an existing file only with ``force``. ``None`` and ``-`` (stdout) pass.

    Args:
      flag: the flag's name (``--json``).
      value: str or None.
      force: an existing file may be replaced.
      room: bytes the folder must take (0: an empty file).
    Returns:
      the value.
    Raises:
      ValueError: naming the flag: empty, a directory, or its folder is missing or a file.
      FileExistsError: the file exists and ``force`` is false.
      OSError: naming the flag: a new file cannot be created in the folder (read-only or
        full disk, no permission).
    """
    if value is None or value == "-":
        return value
    check_path(flag, value, kind="file")
    folder = os.path.dirname(os.path.abspath(value))
    if not os.path.isdir(folder):
        raise ValueError(f"{flag}: the folder of {value} is missing or not a directory")
    if os.path.lexists(value) and not force:
        raise FileExistsError(f"{flag}: {value} exists (use --force to overwrite)")
    try:
        fd, tmp = tempfile.mkstemp(prefix=".write-check.", dir=folder)
        try:
            block = b"\0" * min(room, 1 << 16)
            for _ in range(room // max(len(block), 1)):
                os.write(fd, block)
            if room:
                os.fsync(fd)
        finally:
            os.close(fd)
            os.unlink(tmp)
    except OSError as exc:
        what = f"{room} bytes" if room else "a file"
        raise OSError(
            f"{flag}: cannot write {what} in {folder} for {value}: {exc.strerror or exc}"
        ) from None
    return value


def check_host_port(flag: str, value):
    """``HOST:PORT`` with a port in [1, 65535]; None passes.

    Args:
      flag: the flag's name.
      value: str or None.
    Returns:
      the value.
    Raises:
      ValueError: naming the flag and the value.
    """
    if value is None:
        return None
    m = _HOST_PORT.match(value)
    if m is None or not 1 <= int(m.group(2)) <= 65535:
        raise ValueError(f"{flag}: must be HOST:PORT with a port in [1, 65535], got {value!r}")
    return value
