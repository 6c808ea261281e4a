"""The search: timelines, greedy, large-neighbourhood search, Lagrangian/DP bound, exact search.

Its input is a :class:`Problem` of plain arrays (built by :mod:`jaxspline.planner`), so
it imports nothing of the package outside this folder. Inside, imports point one way:
``store`` / ``battery`` -> ``problem`` -> ``dp`` / ``timeline`` / ``energy`` / ``mip`` ->
``lns_energy`` -> ``lns`` -> ``lagrangian`` / ``exact`` / ``sweep`` -> ``bound_worker`` /
``floor`` (how low the relaxation's bound can go) ->
``solve``
(:func:`solve`, the stages run until a deadline); ``memory`` (the heap trim) comes
first. ``clock`` is the search's one time
source; ``construct`` is the one greedy strategy (``greedy_pass``), used by ``timeline``,
``lns`` and :mod:`jaxspline.sequences.sequencer`; ``status`` (:class:`BoundStatus`) is how
every bound ended. The search speaks of *targets* (what may be imaged once) and
*options* (one way to image a target: satellite, start).

The ``coverage_*`` modules are the unique-coverage search (strips that cover samples,
each sample counted once): ``coverage_rules`` -> ``coverage_problem`` ->
``coverage_state`` -> ``coverage_passdp`` / ``coverage_passmoves`` -> ``coverage_search``
(CELF greedy + LNS) and ``coverage_bound`` (Lagrangian bound), on the roll-only rules
of the regional_coverage benchmark (:mod:`jaxspline.regional` is their adapter).
Imported by module (``jaxspline.search.coverage_search``), not re-exported here.
"""

from jaxspline.search import clock as clock
from jaxspline.search.battery import BatteryModel as BatteryModel
from jaxspline.search.battery import Levels as Levels
from jaxspline.search.bound_worker import BoundWorker as BoundWorker
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
