"""Planning: the scenario's types, visibility options, sequencing, refinement, checks and
the planner.

Layer 4: may import ``kernels``, ``geometry``, ``screen`` and ``search``, nothing above.
The pipeline inside: ``mission`` (satellites, targets, settings) -> ``opportunities``
(windows to options) -> ``attitude_laws`` (attitude along an option) -> ``joins`` (the
flown degree-7 joins of a plan, :func:`plan_joins`) -> ``join_screen`` (screening with
those joins) -> ``sequence`` (greedy / beam / exact sequencer) -> ``steps_check`` ->
``refine`` -> ``refine_starts`` -> ``plan_check`` -> ``result`` -> ``repair`` ->
``assemble`` (a run's :class:`PlanResult`) -> ``planner`` (:func:`jaxspline.plan`).
``files`` holds the atomic file writes that every writer above uses (:class:`PlanResult`
writes its JSON with them).

Decisions: the attitude laws, the flown joins and the join screen live here, not in
``ops``: the planner screens transitions with the flown joins (``channel_states``,
``screen_joins``, ``join_far_gap``) and ``repair`` drops unflyable joins
(``reject_unflyable``), so they must sit at or below the planner. The scenario TOML
reader stays in :mod:`jaxspline.io.scenario`: the planner needs only the dataclasses of
``mission``. The folder is ``planning``, not ``plan``: a subpackage ``jaxspline.plan``
would shadow the function :func:`jaxspline.plan` (and its API page).

Re-exported here (and from :mod:`jaxspline`): the public names of ``mission``,
``sequence``, ``refine``, ``steps_check``, ``planner``, ``result`` and ``joins``; the other
modules stay namespaces (``jaxspline.planning.join_screen.screen_joins``).
"""

from jaxspline.planning import joins, mission, planner, refine, result, sequence, steps_check

_MODULES = (mission, sequence, refine, steps_check, planner, result, joins)
__all__ = [name for m in _MODULES for name in m.__all__]

from jaxspline.planning.joins import *  # noqa: E402, F403
from jaxspline.planning.mission import *  # noqa: E402, F403
from jaxspline.planning.planner import *  # noqa: E402, F403
from jaxspline.planning.refine import *  # noqa: E402, F403
from jaxspline.planning.result import *  # noqa: E402, F403
from jaxspline.planning.sequence import *  # noqa: E402, F403
from jaxspline.planning.steps_check import *  # noqa: E402, F403
