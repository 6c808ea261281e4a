"""The screening engine: the option table and the bulk screening of transitions.

Inside, imports point one way: ``options`` (the option table) -> ``slew_table``
(rest-to-rest time tables) -> ``pair_models`` (a maneuver model as a pair kernel) ->
``transitions`` (the :class:`Transitions` table, candidate runs, top-k merge) -> ``fused``
/ ``host`` (the two screening paths) -> ``pairs`` (the entry points
:func:`screen_transitions`, :func:`screen_chunks`, :func:`screen_pairs`) -> ``models``
(the :class:`ManeuverModel` protocol and the built-in models, one file a model).
"""

from jaxspline.screen.coverage import Candidates as Candidates
from jaxspline.screen.coverage import CoverageSlices as CoverageSlices
from jaxspline.screen.coverage import CoverageTable as CoverageTable
from jaxspline.screen.coverage import coverage_slices as coverage_slices
from jaxspline.screen.coverage import coverage_table as coverage_table
from jaxspline.screen.coverage import covered_samples as covered_samples
from jaxspline.screen.models import EigenAxis as EigenAxis
from jaxspline.screen.models import Flexible as Flexible
from jaxspline.screen.models import PerChannel as PerChannel
from jaxspline.screen.models import RestToRest as RestToRest
from jaxspline.screen.models import RollLimits as RollLimits
from jaxspline.screen.models import RollOnly as RollOnly
from jaxspline.screen.models import RollTransition as RollTransition
from jaxspline.screen.models import roll_min_gap as roll_min_gap
from jaxspline.screen.models import roll_need as roll_need
from jaxspline.screen.models import roll_profile as roll_profile
from jaxspline.screen.models import roll_profile_kernel as roll_profile_kernel
from jaxspline.screen.models import roll_slew_time as roll_slew_time
from jaxspline.screen.models import roll_transition as roll_transition
from jaxspline.screen.models import roll_transition_kernel as roll_transition_kernel
from jaxspline.screen.options import RouteModel as RouteModel
from jaxspline.screen.options import RouteOptions as RouteOptions
from jaxspline.screen.options import build_route_options as build_route_options
from jaxspline.screen.options import options_dtype as options_dtype
from jaxspline.screen.options import take_options as take_options
from jaxspline.screen.options import validate_options as validate_options
from jaxspline.screen.pairs import screen_chunks as screen_chunks
from jaxspline.screen.pairs import screen_pairs as screen_pairs
from jaxspline.screen.pairs import screen_transitions as screen_transitions
from jaxspline.screen.transitions import Transitions as Transitions
from jaxspline.screen.transitions import best_per_source as best_per_source
from jaxspline.screen.transitions import default_chunk_size as default_chunk_size
