"""The regional_coverage benchmark (Mtrya/astro-reason): strip observations by roll-only
SAR-like satellites over polygon regions, scored by unique area-weighted coverage of a
sample grid.

``case`` reads and validates case files and reads / writes solutions; ``adapter``
translates a case into a :class:`jaxspline.Scenario` (its regions as areas) and a plan
into a solution: the case is planned by :func:`jaxspline.plan` like any scenario with
areas; ``check`` (with ``check_geometry``) is an independent checker of every rule,
sharing no code with the solver but the case reader; ``cli`` registers ``jaxspline
regional ...``.
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
