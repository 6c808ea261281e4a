"""jaxspline: batched, differentiable attitude-maneuver kinematics and imaging planning.

The package is layered (docs/development.md, "Architecture"); imports point down only:

- :mod:`jaxspline.kernels` - per-candidate mathematics (reach, slew, flex, attitude,
  joins, retarget);
- :mod:`jaxspline.geometry` - frames, orbits, pointing, routes, visibility windows;
- :mod:`jaxspline.engine` - option tables, screening, search, refinement, checks and
  the planner (:func:`plan`);
- the product at the top: scenario files, outputs (CZML, figures), the CLI, and the
  :mod:`jaxspline.aeossp` adapter.

Every public name of the three layers is re-exported here once: ``__all__`` is the
union of the layers' ``__all__`` (each the union of its modules'), plus the
scenario loaders (:mod:`jaxspline.scenario`), the area targets and their coverage
(:mod:`jaxspline.areas`, :mod:`jaxspline.areas_io`) and the AEM writer/reader
(:mod:`jaxspline.aem`). The library never enables float64 on
import or globally: :func:`plan` runs inside ``jax.enable_x64(True)``; for the kernels,
use that context manager (or ``jax.config.update("jax_enable_x64", True)``) yourself.
"""

from jaxspline import aem, areas, areas_io, engine, geometry, kernels, scenario

__all__ = [*kernels.__all__, *geometry.__all__, *engine.__all__]
__all__ += [n for m in (scenario, areas_io, areas, aem) for n in m.__all__ if n not in __all__]

# registers PlanResult.to_html's writer (Bokeh itself is imported when a page is written)
from jaxspline import plan_html  # noqa: E402, F401
from jaxspline.aem import *  # noqa: E402, F403
from jaxspline.areas import *  # noqa: E402, F403
from jaxspline.areas_io import *  # noqa: E402, F403
from jaxspline.engine import *  # noqa: E402, F403
from jaxspline.geometry import *  # noqa: E402, F403
from jaxspline.kernels import *  # noqa: E402, F403
from jaxspline.scenario import *  # noqa: E402, F403

__version__ = "0.1.0"
