"""IO: the files a user reads and writes - scenarios, targets, areas, plans, figures, pages.

Layer 6: may import everything below (``kernels`` ... ``ops``), nothing above. Readers:
``fields`` (checked TOML/CSV fields) -> ``land`` (land mask), ``targets_io`` (target
tables), ``areas_io`` (GeoJSON/TOML areas) -> ``areas`` (area targets cut into strips,
and their coverage by a plan) -> ``scenario`` (the TOML scenario reader). Writers:
``czml`` (Cesium), ``plot`` -> ``plot_plan`` / ``plot_attitude`` (PNG figures),
``plan_view`` -> ``plan_html_columns`` -> ``plan_html`` (the self-contained web page).

Decisions: ``areas`` lives here, not in ``ops``: it builds on the area reader
(``areas_io``) and is read by ``scenario`` and the writers. ``scenario`` (the TOML
reader) lives here whole: the dataclasses it fills are
:mod:`jaxspline.planning.mission`'s, which is all the planner imports. ``plan_html``
registers :meth:`PlanResult.to_html`'s writer when imported (the façade imports it).

Re-exported here (and from :mod:`jaxspline`): the public names of ``scenario``,
``areas_io`` and ``areas``; the other modules stay namespaces.
"""

from jaxspline.io import areas, areas_io, scenario

_MODULES = (scenario, areas_io, areas)
__all__ = [name for m in _MODULES for name in m.__all__]

from jaxspline.io.areas import *  # noqa: E402, F403
from jaxspline.io.areas_io import *  # noqa: E402, F403
from jaxspline.io.scenario import *  # noqa: E402, F403
