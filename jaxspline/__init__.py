"""jaxspline: batched, differentiable attitude-maneuver kinematics and imaging planning.

The package is layered (docs/development.md, "Architecture"); folders follow the
pipeline and imports point down only (tests/test_layout.py):

- :mod:`jaxspline.kernels` - per-candidate mathematics (reach, slew, flex, attitude,
  joins, retarget);
- :mod:`jaxspline.geometry` - frames, orbits, pointing, routes, visibility windows;
- :mod:`jaxspline.screen` - the option table and the bulk screening of transitions;
- :mod:`jaxspline.search` - timelines, greedy/LNS, Lagrangian bound, exact search;
- :mod:`jaxspline.planning` - mission types, opportunities, sequencing, refinement,
  checks, flown joins and the planner (:func:`plan`);
- :mod:`jaxspline.ops` - the attitude history of a plan and its AEM files;
- :mod:`jaxspline.io` - scenario, target and area files; CZML, figures, the web page;
- :mod:`jaxspline.cli` - the ``jaxspline`` command;
- :mod:`jaxspline.aeossp` - the aeossp_standard adapter, on top.

This ``__init__`` is the façade: every public name of the layers is re-exported here
once. ``__all__`` is the union of the re-exporting layers' ``__all__`` (each the union of
its modules'): kernels, geometry, screen, planning, ops, then the names of
:mod:`jaxspline.io` (scenario loaders, area targets and their coverage) not already in.
The library never enables float64 on import or globally: :func:`plan` runs inside
``jax.enable_x64(True)``; for the kernels, use that context manager (or
``jax.config.update("jax_enable_x64", True)``) yourself.
"""

from jaxspline import geometry, io, kernels, ops, planning, screen

__all__ = [*kernels.__all__, *geometry.__all__, *screen.__all__, *planning.__all__]
__all__ += [*ops.__all__]
__all__ += [n for n in io.__all__ if n not in __all__]

# registers PlanResult.to_html's writer (Bokeh itself is imported when a page is written)
from jaxspline.geometry import *  # noqa: E402, F403
from jaxspline.io import *  # noqa: E402, F403
from jaxspline.io import plan_html  # noqa: E402, F401
from jaxspline.kernels import *  # noqa: E402, F403
from jaxspline.ops import *  # noqa: E402, F403
from jaxspline.planning import *  # noqa: E402, F403
from jaxspline.screen import *  # noqa: E402, F403

__version__ = "0.1.0"
