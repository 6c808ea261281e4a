"""The stereo_imaging benchmark (Mtrya/astro-reason): timed push-broom observations of
ground targets with fixed steering angles, scored by the stereo pairs and tri-stereo sets
the checker finds among them.

``case`` (with ``case_fields``) reads and validates case files and reads / writes
solutions; ``check`` (with ``check_geometry`` and ``check_products``) is an independent
checker of every rule of RULES.md and of the score, sharing no code with a solver but the
case reader; ``bound`` lists, per case, the targets for which some valid pair exists when
no other look competes (an upper bound on coverage); ``cli`` registers
``jaxspline stereo ...``.
"""

from .bound import CoverageBound as CoverageBound
from .bound import coverage_bound as coverage_bound
from .case import Case as Case
from .case import Mission as Mission
from .case import Observation as Observation
from .case import Satellite as Satellite
from .case import Solution as Solution
from .case import Target as Target
from .case import format_time as format_time
from .case import load_case as load_case
from .case import load_solution as load_solution
from .case import parse_solution as parse_solution
from .case import parse_time as parse_time
from .check import CheckReport as CheckReport
from .check import Violation as Violation
from .check import check_solution as check_solution
from .check import format_report as format_report
