"""The planner: :func:`plan`, from a :class:`~jaxspline.readers.Scenario` to a checked
:class:`PlanResult`.

The stages, in the order a plan's data passes them: ``opportunities`` (visibility
windows to options) -> ``attitude_laws`` (the attitude along an option) ->
``flown_joins`` (the degree-7 joins a plan flies) -> ``join_screen`` (screening with
those joins) -> ``context`` (:class:`PlanContext`, what the stages share) -> ``pipeline``
(:func:`build_problem`, then search) -> ``repair`` (withdraw what fails, re-search) ->
``refine_starts`` -> ``plan_check`` (the independent re-check) -> ``assemble`` /
``result`` (the :class:`PlanResult`). ``sharded`` runs the plan over
several hosts; ``bound`` the bound alone; ``files`` the atomic file writes every writer
uses; ``deadline`` the clock of a call's time limit; ``budget`` its split between the
search and the stages after it; ``memory_guard`` the memory the stages before the
search may take.
"""

from jaxspline.planner.area_options import AreaOptions as AreaOptions
from jaxspline.planner.area_options import area_options as area_options
from jaxspline.planner.area_options import cover_table as cover_table
from jaxspline.planner.area_options import merge_options as merge_options
from jaxspline.planner.area_report import area_report as area_report
from jaxspline.planner.bound import SEARCH_TIME_S as SEARCH_TIME_S
from jaxspline.planner.bound import BoundRun as BoundRun
from jaxspline.planner.bound import run_bound as run_bound
from jaxspline.planner.build import build_problem as build_problem
from jaxspline.planner.context import PlanContext as PlanContext
from jaxspline.planner.deadline import COMPILE_ALLOWANCE_S as COMPILE_ALLOWANCE_S
from jaxspline.planner.deadline import StageDeadline as StageDeadline
from jaxspline.planner.deadline import TimeLimitError as TimeLimitError
from jaxspline.planner.deadline import compile_seconds as compile_seconds
from jaxspline.planner.deadline import suggested_limit as suggested_limit
from jaxspline.planner.flown_joins import DIRECT_MAX_S as DIRECT_MAX_S
from jaxspline.planner.flown_joins import JOIN_SAMPLES as JOIN_SAMPLES
from jaxspline.planner.flown_joins import RETURN_S as RETURN_S
from jaxspline.planner.flown_joins import Joins as Joins
from jaxspline.planner.flown_joins import join_limits as join_limits
from jaxspline.planner.flown_joins import join_summary as join_summary
from jaxspline.planner.flown_joins import plan_joins as plan_joins
from jaxspline.planner.flown_joins import reject_unflyable as reject_unflyable
from jaxspline.planner.memory_guard import MemoryGuard as MemoryGuard
from jaxspline.planner.memory_guard import MemoryLimitError as MemoryLimitError
from jaxspline.planner.pipeline import plan as plan
from jaxspline.planner.result import Observations as Observations
from jaxspline.planner.result import PlanResult as PlanResult
