"""The base layer: what every later layer may read, importing nothing but the kernels.

``elements`` holds the Earth and time (WGS84 and rotation constants, Julian dates,
GMST, geodetic positions, TLE records, circular orbit elements); ``models`` the
maneuver-model protocol and the registry that names the models (the built-in models
themselves live in :mod:`jaxspline.screen.models`); ``land`` the offline land mask;
``clock`` the process's one time source, its stop requests and signal handling. The
mission types a scenario is made of are in
:mod:`jaxspline.readers.mission`, the first layer after this one.
"""

from jaxspline.base.elements import J2_EARTH as J2_EARTH
from jaxspline.base.elements import MU_EARTH as MU_EARTH
from jaxspline.base.elements import OMEGA_EARTH as OMEGA_EARTH
from jaxspline.base.elements import R_EARTH as R_EARTH
from jaxspline.base.elements import SECONDS_PER_DAY as SECONDS_PER_DAY
from jaxspline.base.elements import WGS84_E2 as WGS84_E2
from jaxspline.base.elements import WGS84_F as WGS84_F
from jaxspline.base.elements import CircularOrbit as CircularOrbit
from jaxspline.base.elements import circular_orbit as circular_orbit
from jaxspline.base.elements import circular_orbit_over as circular_orbit_over
from jaxspline.base.elements import geodetic_to_ecef as geodetic_to_ecef
from jaxspline.base.elements import gmst as gmst
from jaxspline.base.elements import jd_split as jd_split
from jaxspline.base.elements import julian_date as julian_date
from jaxspline.base.elements import parse_tle as parse_tle
from jaxspline.base.elements import sso_inclination as sso_inclination
from jaxspline.base.elements import unit_vectors as unit_vectors
from jaxspline.base.models import BUILTIN_MODELS as BUILTIN_MODELS
from jaxspline.base.models import ManeuverModel as ManeuverModel
from jaxspline.base.models import maneuver_model as maneuver_model
from jaxspline.base.models import model_names as model_names
from jaxspline.base.models import register_model as register_model
