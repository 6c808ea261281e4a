"""jaxspline: batched, differentiable attitude-maneuver kinematics and imaging planning.

The folders, in the order the code stands on them (``tests/test_layout.py`` checks that
every import points up this list, never down):

- :mod:`jaxspline.kernels` - the closed-form mathematics of one maneuver (reach sets,
  slews, flexible modes, attitude, degree-7 joins, retargeting), batched once;
- :mod:`jaxspline.geometry` - frames, orbits, pointing laws, routes, visibility windows;
- :mod:`jaxspline.screen` - the engine: option tables, the maneuver models
  (``screen.models``) and the bulk screening of transitions;

then the path a plan's data takes:

- :mod:`jaxspline.readers` - scenario, target and area files in, mission types out;
- :mod:`jaxspline.search` - timelines, greedy, LNS, the Lagrangian bound, ``solve``;
- :mod:`jaxspline.sequences` - the route-sequence toolkit (greedy / beam / exact over a
  fixed list of routes, step check, optax refinement), which the planner also uses;
- :mod:`jaxspline.planner` - :func:`plan`: options, screening, search, repair, check,
  the :class:`PlanResult`;
- :mod:`jaxspline.products` - plan files, CZML, attitude history and AEM, figures, the
  web page;
- :mod:`jaxspline.cli` - the ``jaxspline`` command (parse and print);
- :mod:`jaxspline.aeossp` - the aeossp_standard benchmark adapter;
- :mod:`jaxspline.regional` - the regional_coverage benchmark adapter (area coverage);
- :mod:`jaxspline.stereo` - the stereo_imaging benchmark adapter (its case files and
  independent checker).

This namespace holds the entry points and the headline types and kernels; everything
else lives in the folders' namespaces (``jaxspline.geometry.gmst``). The library never
enables float64 on import or globally: :func:`plan` runs inside
``jax.enable_x64(True)``; for the kernels, use that context manager (or
``jax.config.update("jax_enable_x64", True)``) yourself.
"""

# ruff: noqa: I001  (grouped by subject, not sorted)
# first: a Ctrl-C during the imports below ends the command with one line (cli.startup)
import jaxspline.cli.startup  # noqa: F401  (installs the command's start-up handlers)

# the planner: entry points and the result
from jaxspline.planner.pipeline import plan as plan
from jaxspline.planner.pipeline import build_problem as build_problem
from jaxspline.planner.result import PlanResult as PlanResult
from jaxspline.planner.result import Observations as Observations

# scenario files and mission types
from jaxspline.readers.mission import Scenario as Scenario
from jaxspline.readers.mission import Satellite as Satellite
from jaxspline.readers.mission import Targets as Targets
from jaxspline.readers.mission import Area as Area
from jaxspline.readers.mission import Power as Power
from jaxspline.readers.mission import FlexMode as FlexMode
from jaxspline.readers.mission import Margins as Margins
from jaxspline.readers.mission import PlannerConfig as PlannerConfig
from jaxspline.readers.mission import make_targets as make_targets
from jaxspline.readers.scenario import load_scenario as load_scenario
from jaxspline.readers.scenario import parse_scenario as parse_scenario
from jaxspline.readers.scenario import default_scenario as default_scenario
from jaxspline.readers.scenario import DEFAULT_SCENARIO_PATH as DEFAULT_SCENARIO_PATH
from jaxspline.readers.targets import load_targets_csv as load_targets_csv

# kernels: limits and the headline kernels of the papers
from jaxspline.kernels.limits import AxisLimits as AxisLimits
from jaxspline.kernels.reach import is_reachable as is_reachable
from jaxspline.kernels.reach import reach_margin as reach_margin
from jaxspline.kernels.reach import envelopes as envelopes
from jaxspline.kernels.reach import rate_interval as rate_interval
from jaxspline.kernels.reach import angle_interval as angle_interval
from jaxspline.kernels.reach_durations import feasible_durations as feasible_durations
from jaxspline.kernels.reach_durations import min_peak_accel as min_peak_accel
from jaxspline.kernels.reach_durations import min_transfer_time as min_transfer_time
from jaxspline.kernels.slew import SlewProfile as SlewProfile
from jaxspline.kernels.slew import slew_profile as slew_profile
from jaxspline.kernels.slew import slew_profile_time as slew_profile_time
from jaxspline.kernels.slew import profile_state as profile_state
from jaxspline.kernels.slew import bang_bang_time as bang_bang_time
from jaxspline.kernels.slew import bang_coast_bang_time as bang_coast_bang_time
from jaxspline.kernels.slew import scurve_time as scurve_time
from jaxspline.kernels.flex import settling_time as settling_time
from jaxspline.kernels.flex import tau_for_tolerance as tau_for_tolerance
from jaxspline.kernels.flex import residual_amplitude as residual_amplitude
from jaxspline.kernels.flex import flexible_body_rate as flexible_body_rate
from jaxspline.kernels.attitude import quat_multiply as quat_multiply
from jaxspline.kernels.attitude import quat_rotate as quat_rotate
from jaxspline.kernels.attitude import quat_to_dcm as quat_to_dcm
from jaxspline.kernels.attitude import dcm_to_quat as dcm_to_quat
from jaxspline.kernels.attitude import quat_to_mrp as quat_to_mrp
from jaxspline.kernels.attitude import mrp_to_quat as mrp_to_quat
from jaxspline.kernels.joins import join7_coeffs as join7_coeffs
from jaxspline.kernels.joins import attitude_spline as attitude_spline
from jaxspline.kernels.joins import maneuver_plan as maneuver_plan
from jaxspline.kernels.joins import maneuver_eval as maneuver_eval
from jaxspline.kernels.join_check import maneuver_check as maneuver_check
from jaxspline.kernels.retarget import min_peak_retarget as min_peak_retarget

# the screening engine and the maneuver models
from jaxspline.screen.pairs import screen_transitions as screen_transitions
from jaxspline.screen.pairs import screen_pairs as screen_pairs
from jaxspline.screen.pairs import screen_chunks as screen_chunks
from jaxspline.screen.transitions import Transitions as Transitions
from jaxspline.screen.options import RouteOptions as RouteOptions
from jaxspline.screen.options import build_route_options as build_route_options
from jaxspline.screen.models import ManeuverModel as ManeuverModel
from jaxspline.screen.models import maneuver_model as maneuver_model
from jaxspline.screen.models import register_model as register_model
from jaxspline.screen.models import PerChannel as PerChannel
from jaxspline.screen.models import EigenAxis as EigenAxis
from jaxspline.screen.models import Flexible as Flexible

# products: the page, the attitude history, CCSDS AEM files
from jaxspline.products.plan_html import write_plan_html as write_plan_html
from jaxspline.products.attitude_history import attitude_history as attitude_history
from jaxspline.products.aem import read_aem as read_aem
from jaxspline.products.aem import write_aems as write_aems

# the namespaces
from jaxspline import geometry as geometry
from jaxspline import kernels as kernels
from jaxspline import planner as planner
from jaxspline import products as products
from jaxspline import readers as readers
from jaxspline import screen as screen
from jaxspline import search as search
from jaxspline import sequences as sequences

__version__ = "0.1.0"
