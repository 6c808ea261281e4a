"""The search: timelines, greedy, large-neighbourhood search, Lagrangian/DP bound, exact search.

Its input is a :class:`Problem` of plain arrays (built by :mod:`jaxspline.planner`), so
it imports nothing of the package but :mod:`jaxspline.base` and this folder. The one
objective is the weight of samples covered at least once: a point or strip target is one
sample, an area its sample grid (``cover``: which samples each area option covers).
Inside, imports point one way:
``store`` / ``battery`` / ``cover`` -> ``problem`` -> ``dp`` / ``timeline`` / ``energy`` /
``mip`` -> ``pass_dp`` / ``area_moves`` (the moves of area strips inside one pass) ->
``lns_energy`` -> ``lns`` -> ``pass_bound`` / ``lagrangian`` (the one bound: point DPs,
per-pass area DPs, prices on samples) / ``exact`` / ``sweep`` -> ``bound_worker`` (the
bound in another process; ``orphans`` ends it with its parent) / ``floor`` (how low the
relaxation's bound can go) -> ``solve`` (:func:`solve`, the stages run until a
deadline); ``memory`` (the heap trim) comes first. ``construct`` is the one greedy
strategy (``greedy_pass``), used by ``timeline``, ``lns`` and
:mod:`jaxspline.sequences.sequencer`; ``status`` (:class:`BoundStatus`) is how every
bound ended. Time and stop requests come from :mod:`jaxspline.base.clock`. The search
speaks of *targets* (what may be imaged once), *samples* (what an option covers) and
*options* (one way to image a target: satellite, start; for an area also its pointing).
"""

from jaxspline.search.battery import BatteryModel as BatteryModel
from jaxspline.search.battery import Levels as Levels
from jaxspline.search.bound_worker import BoundWorker as BoundWorker
from jaxspline.search.cover import CoverCounts as CoverCounts
from jaxspline.search.cover import CoverTable as CoverTable
from jaxspline.search.dp import DPData as DPData
from jaxspline.search.dp import NeedPrice as NeedPrice
from jaxspline.search.dp import backtrack as backtrack
from jaxspline.search.dp import dp_forward as dp_forward
from jaxspline.search.dp import dp_paths as dp_paths
from jaxspline.search.dp import dp_prepare as dp_prepare
from jaxspline.search.dp_jax import JaxDP as JaxDP
from jaxspline.search.exact import exact_search as exact_search
from jaxspline.search.floor import RelaxationFloor as RelaxationFloor
from jaxspline.search.floor import relaxation_floor as relaxation_floor
from jaxspline.search.lagrangian import BoundResult as BoundResult
from jaxspline.search.lagrangian import lagrangian as lagrangian
from jaxspline.search.lagrangian import plan_from_paths as plan_from_paths
from jaxspline.search.lagrangian import upper_bound as upper_bound
from jaxspline.search.lns import adopt as adopt
from jaxspline.search.lns import earliest_pass as earliest_pass
from jaxspline.search.lns import greedy as greedy
from jaxspline.search.lns import greedy_order as greedy_order
from jaxspline.search.lns import lns as lns
from jaxspline.search.lns_energy import EnergyRank as EnergyRank
from jaxspline.search.lns_energy import make_room as make_room
from jaxspline.search.memory import trim_heap as trim_heap
from jaxspline.search.mip import MipBound as MipBound
from jaxspline.search.mip import mip_bound as mip_bound
from jaxspline.search.problem import Problem as Problem
from jaxspline.search.solve import SearchResult as SearchResult
from jaxspline.search.solve import solve as solve
from jaxspline.search.status import BoundStatus as BoundStatus
from jaxspline.search.sweep import sweep as sweep
from jaxspline.search.sweep import sweeps as sweeps
from jaxspline.search.timeline import Timeline as Timeline
