"""Products: what a plan becomes for people and programs.

``attitude_history`` (the flown attitude of a plan) -> ``aem`` (CCSDS attitude
ephemerides); ``czml`` (Cesium); ``plot`` -> ``plot_plan`` / ``plot_attitude`` (PNG
figures); ``plan_view`` -> ``plan_html_columns`` -> ``plan_html_header`` -> ``plan_html``
(the self-contained web page); ``output_budget`` (what each costs, which still fit
in the time limit) -> ``outputs`` writes them as one set (checked before planning,
locked, published at once).
"""

from jaxspline.products.aem import aem_file_name as aem_file_name
from jaxspline.products.aem import read_aem as read_aem
from jaxspline.products.aem import write_aems as write_aems
from jaxspline.products.attitude_history import PHASES as PHASES
from jaxspline.products.attitude_history import AttitudeHistory as AttitudeHistory
from jaxspline.products.attitude_history import PlanAttitude as PlanAttitude
from jaxspline.products.attitude_history import attitude_history as attitude_history
from jaxspline.products.attitude_history import plan_scene as plan_scene
from jaxspline.products.outputs import ATTITUDE_FIGURE as ATTITUDE_FIGURE
from jaxspline.products.outputs import OUTPUT_FILES as OUTPUT_FILES
from jaxspline.products.outputs import PROBE_BYTES as PROBE_BYTES
from jaxspline.products.outputs import OutputBusyError as OutputBusyError
from jaxspline.products.outputs import OutputError as OutputError
from jaxspline.products.outputs import OutputSet as OutputSet
from jaxspline.products.outputs import is_plan_output as is_plan_output
from jaxspline.products.outputs import rewrite_plan_json as rewrite_plan_json
from jaxspline.products.outputs import write_plan_outputs as write_plan_outputs
