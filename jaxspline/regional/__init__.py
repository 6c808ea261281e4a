"""The regional_coverage benchmark (Mtrya/astro-reason): strip observations by roll-only
SAR-like satellites over polygon regions, scored by unique area-weighted coverage of a
sample grid.

``case`` reads and validates case files and reads / writes solutions; ``check`` (with
``check_geometry``) is an independent checker of every rule, sharing no code with the
solver but the case reader; ``solve`` plans a case with the coverage machinery of the
layers below (:mod:`jaxspline.geometry.coverage_tracks`, :mod:`jaxspline.screen.coverage`,
:mod:`jaxspline.planner.coverage_candidates`, ``jaxspline.search.coverage_*``); ``cli``
registers ``jaxspline regional ...``.
"""

from .case import Case as Case
from .case import Grid as Grid
from .case import Region as Region
from .case import Satellite as Satellite
from .case import format_time as format_time
from .case import load_case as load_case
from .case import load_solution as load_solution
from .case import parse_time as parse_time
from .check import CheckReport as CheckReport
from .check import Violation as Violation
from .check import check_solution as check_solution
from .check import format_report as format_report
