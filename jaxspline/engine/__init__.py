"""Engine: option tables, screening, maneuver models, search, refinement, checks, the planner.

``mission`` (the scenario's types) and ``options`` (the option table) in;
``opportunities`` -> ``screen`` / ``screen_sequences`` / ``models`` (and ``join_screen``
for flown joins) -> ``sequence`` and ``search/``
(greedy, Lagrangian/DP bound, exact, LNS, battery) -> ``refine`` /
``refine_starts`` -> ``steps_check`` / ``plan_check`` (independent re-checks);
``planner.plan`` runs the pipeline and returns a ``result.PlanResult``. The
engine never imports the product layer.

Re-exported here (and from :mod:`jaxspline`): the public modules in ``_MODULES``.
The planner's internal stages (``opportunities``, ``models``, ``join_screen``,
``screen_models``, ``screen_fused``, ``screen_host``, ``refine_starts``, ``plan_check``)
and ``search`` (whose ``greedy`` is not the sequencer's) stay namespaces:
``jaxspline.engine.search.solve``.
"""

from jaxspline.engine import (
    attitude_history,
    mission,
    options,
    plan_joins,
    planner,
    refine,
    result,
    screen,
    screen_sequences,
    sequence,
    steps_check,
)

_MODULES = (
    mission,
    options,
    screen,
    screen_sequences,
    sequence,
    refine,
    steps_check,
    planner,
    result,
    plan_joins,
    attitude_history,
)
__all__ = [name for m in _MODULES for name in m.__all__]

from jaxspline.engine.attitude_history import *  # noqa: E402, F403
from jaxspline.engine.mission import *  # noqa: E402, F403
from jaxspline.engine.options import *  # noqa: E402, F403
from jaxspline.engine.plan_joins import *  # noqa: E402, F403
from jaxspline.engine.planner import *  # noqa: E402, F403
from jaxspline.engine.refine import *  # noqa: E402, F403
from jaxspline.engine.result import *  # noqa: E402, F403
from jaxspline.engine.screen import *  # noqa: E402, F403
from jaxspline.engine.screen_sequences import *  # noqa: E402, F403
from jaxspline.engine.sequence import *  # noqa: E402, F403
from jaxspline.engine.steps_check import *  # noqa: E402, F403
