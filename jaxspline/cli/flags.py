"""Checks of command-line flags, run before any work: each error names its flag.

``argparse`` turns the text into a number; these checks add the ranges
(``--aem-step: must be > 0, got 0``). Every check raises ``ValueError`` (exit 2), and
returns the value so a command can check and use in one line.
"""

from __future__ import annotations

import math
import os
import re

__all__ = [
    "MAX_ITERS",
    "MAX_PROCESSES",
    "MAX_SECONDS",
    "MAX_SEED",
    "check_host_port",
    "check_int",
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
