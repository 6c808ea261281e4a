"""``jaxspline plan`` (and ``demo``): the main job on a scenario. Filled in by the engine work."""

from __future__ import annotations


def register(sub) -> None:
    """Register the ``plan`` sub-command (placeholder until the planner lands)."""
