"""What the planner's stages share once the problem is built: one frozen :class:`PlanContext`.

:func:`jaxspline.planner.pipeline.build_problem` (stages 1-4: orbits, windows, options,
screening) returns it; the search reads its :class:`jaxspline.search.Problem`, and the
stages after the search (:func:`jaxspline.planner.repair.repair`,
:func:`jaxspline.planner.plan_check.check_plan`,
:func:`jaxspline.planner.refine_starts.refine_starts`,
:func:`jaxspline.planner.assemble.assemble_result`) read the scenario, the scene, the
usable orbit table, the option table and the battery model from it. Nothing in it is
changed after it is built: what a later stage decides (a refined option table, options
withdrawn from the search) is returned by that stage, never written back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jaxspline.geometry.orbit import OrbitTable
from jaxspline.geometry.pointing import Scene
from jaxspline.geometry.windows import Windows
from jaxspline.planner.opportunities import Opportunities
from jaxspline.readers.mission import Scenario
from jaxspline.search import BatteryModel, Problem

__all__ = ["PlanContext"]


@dataclass(frozen=True, eq=False)
class PlanContext:
    """The scenario and everything stages 1-4 built from it (module docstring).

    Attributes:
      scenario: the planned :class:`jaxspline.readers.mission.Scenario`.
      problem: the search's :class:`jaxspline.search.Problem` (read only).
      opportunities: the :class:`jaxspline.planner.opportunities.Opportunities` (the
        problem's option ids index them).
      windows: :class:`jaxspline.geometry.windows.Windows`, every visibility window.
      scene: the multi-satellite :class:`jaxspline.geometry.pointing.Scene`.
      orbits: :class:`jaxspline.geometry.orbit.OrbitTable` on the geometry knots.
      battery: :class:`jaxspline.search.BatteryModel` with the planner's margins.
      far: float [S], the always-feasible gap of each satellite [s].
      areas: :class:`jaxspline.planner.area_options.AreaOptions` of the scenario's areas
        (their samples, groups and rows), or None.
      stereo: ``(StereoOptions, StereoMerge)`` of the scenario's stereo targets
        (:mod:`jaxspline.planner.stereo_options`: the looks, their rows in
        ``opportunities``, the products), or None.
    """

    scenario: Scenario
    problem: Problem
    opportunities: Opportunities
    windows: Windows
    scene: Scene
    orbits: OrbitTable
    battery: BatteryModel
    far: np.ndarray
    areas: object = None
    stereo: object = None

    def usable(self, sat, t) -> np.ndarray:
        """Whether the orbit table is usable for satellites ``sat`` at times ``t``.

        Args:
          sat: int [M], satellite indices.
          t: float [M], times from the epoch [s].
        Returns:
          bool [M] (:meth:`jaxspline.geometry.orbit.OrbitTable.usable`).
        """
        return self.orbits.usable(sat, t)
