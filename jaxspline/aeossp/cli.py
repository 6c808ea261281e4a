"""``jaxspline aeossp solve|check``: the aeossp_standard benchmark adapter."""

from __future__ import annotations


def register(sub) -> None:
    """Register the ``aeossp`` sub-command (placeholder until the adapter lands)."""
