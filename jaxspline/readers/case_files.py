"""What the benchmark adapters' case readers share: strict YAML and ISO 8601 UTC times.

The aeossp_standard and regional_coverage case files (:mod:`jaxspline.aeossp.case`,
:mod:`jaxspline.regional.case`) are YAML and JSON with ISO 8601 times; both readers refuse
a key repeated in one YAML mapping (:class:`UniqueKeyLoader`), read times with
:func:`parse_time` and write them with :func:`format_time`.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

import yaml

__all__ = ["UniqueKeyLoader", "format_time", "parse_time"]

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class UniqueKeyLoader(_Loader):
    """The safe YAML loader, refusing a key repeated in one mapping (YAML keeps the last)."""

    def construct_mapping(self, node, deep=False):
        """The mapping of ``node``; a repeated key is a ``ConstructorError`` at its mark."""
        if isinstance(node, yaml.MappingNode):
            seen = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=deep)
                try:
                    again = key in seen
                except TypeError:  # unhashable: the base class names it
                    continue
                if again:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {key!r}", key_node.start_mark
                    )
                seen.add(key)
        return super().construct_mapping(node, deep)


def parse_time(text: Any, *, where: str = "time", allow_datetime: bool = False) -> datetime:
    """Parse an ISO 8601 time (``2025-07-17T00:00:00Z``) to an aware UTC ``datetime``.

    A string must name its time zone (``Z`` or an offset, which is converted); one
    without is refused, as the zone it means is unknown. A ``datetime`` without one (a
    YAML timestamp, whose rules make it UTC) is taken as UTC.

    Args:
      text: the time string (or, with ``allow_datetime``, a ``datetime``).
      where: names the file and field in the error message.
      allow_datetime: also take a ``datetime`` as it is (naive = UTC).
    Returns:
      datetime in UTC.
    Raises:
      ValueError: not a string, not ISO 8601 or without a time zone (naming ``where``).
    """
    if allow_datetime and isinstance(text, datetime):
        value = text
    elif isinstance(text, str):
        s = text.strip()
        if s.endswith(("Z", "z")):
            s = s[:-1] + "+00:00"
        try:
            value = datetime.fromisoformat(s)
        except ValueError:
            raise ValueError(f"{where}: not an ISO 8601 time: {text!r}") from None
        if value.tzinfo is None:
            raise ValueError(
                f"{where}: {text!r} has no time zone: add Z (UTC) or an offset such as +02:00"
            )
    else:
        raise ValueError(f"{where}: expected an ISO 8601 time string, got {text!r}")
    if value.tzinfo is None:
        value = value.replace(tzinfo=UTC)
    return value.astimezone(UTC)


def format_time(value: datetime) -> str:
    """Format a datetime as ``YYYY-MM-DDTHH:MM:SSZ`` (``.ffffff`` added if it has microseconds).

    Args:
      value: aware datetime (naive = UTC).
    Returns:
      str.
    """
    if value.tzinfo is None:
        value = value.replace(tzinfo=UTC)
    value = value.astimezone(UTC)
    fmt = "%Y-%m-%dT%H:%M:%S.%fZ" if value.microsecond else "%Y-%m-%dT%H:%M:%SZ"
    return value.strftime(fmt)
