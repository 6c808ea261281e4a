"""jaxspline: batched, differentiable attitude-maneuver kinematics and imaging planning.

The folders, in the order the code stands on them (``tests/test_layout.py`` checks that
every import points up this list, never down); after the first two they read as the path
a plan's data takes:

- :mod:`jaxspline.kernels` - the closed-form mathematics of one maneuver (reach sets,
  slews, flexible modes, attitude, degree-7 joins, retargeting), batched once;
- :mod:`jaxspline.base` - what every later layer may read: Earth and time constants,
  orbit elements and TLEs, the maneuver-model registry, the land mask, the process clock;
- :mod:`jaxspline.readers` - scenario, target and area files in, mission types out
  (reading only: no orbits, no windows);
- :mod:`jaxspline.geometry` - frames, orbits, pointing laws, routes, visibility windows,
  area grids and passes;
- :mod:`jaxspline.screen` - the engine: option tables, the maneuver models
  (``screen.models``), the bulk screening of transitions and strip coverage;
- :mod:`jaxspline.search` - timelines, greedy, LNS, the Lagrangian bound, ``solve``;
- :mod:`jaxspline.sequences` - the route-sequence toolkit (greedy / beam / exact over a
  fixed list of routes, step check, optax refinement), which the planner also uses;
- :mod:`jaxspline.planner` - :func:`plan`: options, screening, search, repair, check,
  the :class:`PlanResult`;
- :mod:`jaxspline.products` - plan files, CZML, attitude history and AEM, figures, the
  web page;
- :mod:`jaxspline.cli` - the ``jaxspline`` command (parse and print);
- :mod:`jaxspline.aeossp` - the aeossp_standard benchmark adapter;
- :mod:`jaxspline.regional` - the regional_coverage benchmark adapter (its regions as
  areas of a scenario);
- :mod:`jaxspline.stereo` - the stereo_imaging benchmark adapter (its case files and
  independent checker).

This namespace holds the entry points and the headline types; everything else lives in
the folders' namespaces (``jaxspline.kernels.is_reachable``, ``jaxspline.base.gmst``).
The library never enables float64 on import or globally: :func:`plan` runs inside
``jax.enable_x64(True)``; for the kernels, use that context manager (or
``jax.config.update("jax_enable_x64", True)``) yourself.
"""

# ruff: noqa: I001  (grouped by subject, not sorted)
# first: a Ctrl-C during the imports below ends the command with one line (cli.startup)
from jaxspline.cli import startup as _startup  # noqa: F401  (installs the start-up handlers)

# the planner: entry points and the result
from jaxspline.planner.pipeline import plan as plan
from jaxspline.planner.build import build_problem as build_problem
from jaxspline.planner.result import PlanResult as PlanResult
from jaxspline.planner.result import Observations as Observations

# scenario files and mission types
from jaxspline.readers.mission import Scenario as Scenario
from jaxspline.readers.mission import Satellite as Satellite
from jaxspline.readers.mission import Targets as Targets
from jaxspline.readers.mission import Area as Area
from jaxspline.readers.mission import Power as Power
from jaxspline.readers.mission import FlexMode as FlexMode
from jaxspline.readers.config import Margins as Margins
from jaxspline.readers.config import PlannerConfig as PlannerConfig
from jaxspline.readers.mission import make_targets as make_targets
from jaxspline.readers.scenario import load_scenario as load_scenario
from jaxspline.readers.scenario import parse_scenario as parse_scenario
from jaxspline.readers.scenario import default_scenario as default_scenario
from jaxspline.readers.scenario import DEFAULT_SCENARIO_PATH as DEFAULT_SCENARIO_PATH
from jaxspline.readers.targets import load_targets_csv as load_targets_csv

# kernels: the limits type (the kernels themselves: jaxspline.kernels)
from jaxspline.kernels.limits import AxisLimits as AxisLimits

# the screening engine and the maneuver models
from jaxspline.screen.pairs import screen_transitions as screen_transitions
from jaxspline.screen.pairs import screen_pairs as screen_pairs
from jaxspline.screen.pairs import screen_chunks as screen_chunks
from jaxspline.screen.transitions import Transitions as Transitions
from jaxspline.screen.options import RouteOptions as RouteOptions
from jaxspline.screen.options import build_route_options as build_route_options
from jaxspline.base.models import ManeuverModel as ManeuverModel
from jaxspline.base.models import maneuver_model as maneuver_model
from jaxspline.base.models import register_model as register_model
from jaxspline.screen.models import PerChannel as PerChannel
from jaxspline.screen.models import EigenAxis as EigenAxis
from jaxspline.screen.models import Flexible as Flexible

# products: the page, the attitude history, CCSDS AEM files
from jaxspline.products.plan_html import write_plan_html as write_plan_html
from jaxspline.products.attitude_history import attitude_history as attitude_history
from jaxspline.products.aem import read_aem as read_aem
from jaxspline.products.aem import write_aems as write_aems

# the namespaces
from jaxspline import base as base
from jaxspline import geometry as geometry
from jaxspline import kernels as kernels
from jaxspline import planner as planner
from jaxspline import products as products
from jaxspline import readers as readers
from jaxspline import screen as screen
from jaxspline import search as search
from jaxspline import sequences as sequences

__version__ = "0.1.0"
