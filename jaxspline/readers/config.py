"""The planner's settings: :class:`PlannerConfig` and its safety :class:`Margins`.

A :class:`~jaxspline.readers.mission.Scenario` carries one :class:`PlannerConfig` (the
``[planner]`` table of a scenario file). Every constructor validates eagerly and raises
``ValueError`` naming the field and the value.
"""

from __future__ import annotations

import dataclasses
import math

__all__ = [
    "DEFAULT_ROLL_STEP_DEG",
    "MAX_EXACT_OPTIONS",
    "Margins",
    "PlannerConfig",
    "positive_number",
]

DEFAULT_ROLL_STEP_DEG = 0.25  # [deg] roll grid of area strips (~3 km at 30 deg from 550 km)
# the exact search recurses once per option (Python's stack: ~1000 frames); beyond a
# few hundred options branch and bound cannot finish anyway
MAX_EXACT_OPTIONS = 500


def positive_number(name: str, value, allow_zero: bool = False) -> float:
    """``value`` as a float, checked finite and > 0 (>= 0 with ``allow_zero``).

    Args:
      name: the field, named by the error; value: what was given.
    Returns:
      float.
    Raises:
      ValueError: naming the field and the value.
    """
    v = float(value)
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be finite and {bound}, got {value!r}")
    return v


@dataclasses.dataclass(frozen=True)
class Margins:
    """Safety margins of the planner (what it keeps back from each limit).

    Attributes:
      off_nadir: observations keep off-nadir <= limit - this [rad].
      horizon: sine of the target elevation must exceed this (> 0 is the rule).
      gap: added to every required rest-to-rest slew time [s] (eigen_axis, flexible,
        roll_only).
      battery_wh: the battery level must stay >= this [Wh].
      duty: imaging seconds kept below a satellite's duty limit per orbit [s].
      shadow_guard: charging counts only if sunlit this many battery steps around
        a step (covers shadow-entry timing differences).
    """

    off_nadir: float = 0.0
    horizon: float = 0.0
    gap: float = 0.0
    battery_wh: float = 0.0
    shadow_guard: int = 0
    duty: float = 0.0


@dataclasses.dataclass(frozen=True)
class PlannerConfig:
    """Static planner settings (one frozen object instead of many keyword arguments).

    Attributes:
      time_step: action grid [s]: observation starts are multiples of it (aeossp: 5 s).
      geometry_step: ephemeris knot / visibility grid step [s]; ``time_step`` must be
        a multiple of it, so that every start is an exact ephemeris knot.
      scan_speeds: strip ground scan speeds [m/s] (one option per speed).
      sun_elevation_min: targets must see the Sun at least this high at the start
        [rad] (None: no daylight rule).
      margins: :class:`Margins`.
      exact_max_options: instances with at most this many options are solved exactly
        (branch and bound over the per-satellite timelines), at most
        :data:`MAX_EXACT_OPTIONS`.
      lagrangian_share: search share of the Lagrangian phase (none in timed runs with the worker).
      bound_worker: on a machine with at least two CPUs, iterate the bound (and repair
        its paths into plans for a time-limited LNS) in a second process (BoundWorker).
      refine_steps: optax steps of start-time refinement of per-channel satellites'
        sequences (:mod:`jaxspline.planner.refine_starts`; 0 = off).
      default_time_limit: search budget [s] when :func:`plan` gets no time limit.
      max_actions: most observations of a plan, all satellites together (None: no cap).
      area_roll_step: roll grid step of area strips [rad].
      area_pitch_step: pitch grid step of an agile satellite's area strips [rad] (their
        pitches are its multiples within the off-nadir limit); None: per satellite, the
        pitch that moves the imaged ground by one action-grid step of its ground track
        (``atan(ground speed * time_step / altitude)``), so that a strip of any row can
        start at any step of the pass.
    """

    time_step: float = 5.0
    geometry_step: float = 5.0
    scan_speeds: tuple[float, ...] = (7000.0,)
    sun_elevation_min: float | None = None
    margins: Margins = Margins()
    exact_max_options: int = 60
    lagrangian_share: float = 0.3
    bound_worker: bool = True
    refine_steps: int = 100
    default_time_limit: float = 30.0
    max_actions: int | None = None
    area_roll_step: float = math.radians(DEFAULT_ROLL_STEP_DEG)
    area_pitch_step: float | None = None

    def __post_init__(self):
        for f in ("time_step", "geometry_step", "default_time_limit"):
            positive_number(f"planner.{f}", getattr(self, f))
        ratio = self.time_step / self.geometry_step
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError(
                f"planner.time_step={self.time_step!r} must be a multiple of "
                f"planner.geometry_step={self.geometry_step!r}"
            )
        if int(self.refine_steps) < 0:
            raise ValueError(f"planner.refine_steps must be >= 0, got {self.refine_steps!r}")
        if not 0 <= int(self.exact_max_options) <= MAX_EXACT_OPTIONS:
            raise ValueError(
                f"planner.exact_max_options must be in [0, {MAX_EXACT_OPTIONS}], got "
                f"{self.exact_max_options!r}"
            )
        if not self.scan_speeds or any(not s > 0 for s in self.scan_speeds):
            raise ValueError(f"planner.scan_speeds must be > 0, got {self.scan_speeds!r}")
        if not 0.0 <= self.lagrangian_share < 1.0:
            raise ValueError(
                f"planner.lagrangian_share must be in [0, 1), got {self.lagrangian_share!r}"
            )
        if self.max_actions is not None and int(self.max_actions) < 1:
            raise ValueError(f"planner.max_actions must be >= 1, got {self.max_actions!r}")
        positive_number("planner.area_roll_step", self.area_roll_step)
        if self.area_pitch_step is not None:
            positive_number("planner.area_pitch_step", self.area_pitch_step)
