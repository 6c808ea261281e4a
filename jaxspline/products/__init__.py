"""Products: what a plan becomes for people and programs.

``attitude_history`` (the flown attitude of a plan) -> ``aem`` (CCSDS attitude
ephemerides); ``czml`` (Cesium); ``plot`` -> ``plot_plan`` / ``plot_attitude`` (PNG
figures); ``plan_view`` -> ``plan_html_columns`` -> ``plan_html_header`` -> ``plan_html``
(the self-contained web page).
"""

from jaxspline.products.aem import aem_file_name as aem_file_name
from jaxspline.products.aem import read_aem as read_aem
from jaxspline.products.aem import write_aems as write_aems
from jaxspline.products.attitude_history import PHASES as PHASES
from jaxspline.products.attitude_history import AttitudeHistory as AttitudeHistory
from jaxspline.products.attitude_history import PlanAttitude as PlanAttitude
from jaxspline.products.attitude_history import attitude_history as attitude_history
from jaxspline.products.attitude_history import plan_scene as plan_scene
