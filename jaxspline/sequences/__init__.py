"""The route-sequence toolkit (SPEC section 4): a fixed list of routes, sequenced.

A product of its own beside the planner: for a stream of routes (ground strips) with
their options (:class:`~jaxspline.screen.RouteOptions`), screen whole sequences
(``route_screen``), stream the screened transitions source by source (``stream``), build
sequences greedily, by beam search or exactly with a path bound (``sequencer``), check a
sequence step by step (``steps_check``) and refine its start times with optax
(``refine``). The planner reuses the last two (start-time refinement and the step check
of a plan).
"""

from jaxspline.sequences.refine import plan_costs as plan_costs
from jaxspline.sequences.refine import refine_plan as refine_plan
from jaxspline.sequences.refine import try_insert as try_insert
from jaxspline.sequences.route_screen import screen_sequences as screen_sequences
from jaxspline.sequences.sequencer import Plan as Plan
from jaxspline.sequences.sequencer import beam_search as beam_search
from jaxspline.sequences.sequencer import exact_plan as exact_plan
from jaxspline.sequences.sequencer import greedy_chain as greedy_chain
from jaxspline.sequences.sequencer import path_bound as path_bound
from jaxspline.sequences.sequencer import plan_value as plan_value
from jaxspline.sequences.steps_check import StepsReport as StepsReport
from jaxspline.sequences.steps_check import check_steps as check_steps
