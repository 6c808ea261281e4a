"""Screen: the option table and the bulk screening of transitions between options.

Layer 2 (``kernels`` <- ``geometry`` <- ``screen``): may import the kernels and the
geometry, nothing above. Inside, imports point one way:

``options`` (the option table the screen reads) -> ``slew_table`` (rest-to-rest time
tables) -> ``pair_models`` (a maneuver model as a pair kernel) ->
``transitions`` (the :class:`Transitions` table, candidate runs, device mesh, top-k merge,
chunk collection) -> ``fused`` / ``host`` (the two screening paths) -> ``pairs`` (the
entry points :func:`screen_transitions`, :func:`screen_chunks`, :func:`screen_pairs`,
which dispatch to the paths) -> ``sequences`` (whole sequences), ``stream`` (the
sequencer's source-ordered view of a screen) and ``maneuvers`` (the
:class:`~jaxspline.screen.maneuvers.ManeuverModel` protocol and the built-in models:
required times of pairs, first observations, far gaps; one file per model).

Decisions: the helpers the fused and host paths share used to live in the entry-point
module, which imported the paths back (an import circle): they moved down into
``transitions`` with public names. The maneuver models sit above the entry points for the same
reason (the per-channel model screens pairs). ``options`` lives here, not with
the planner, because the screen reads it and the planner sits above.

Re-exported here (and from :mod:`jaxspline`): the public names of ``options``,
``transitions``, ``pairs``, ``sequences`` and ``maneuvers``; the other modules stay
namespaces.
"""

from jaxspline.screen import maneuvers, options, pairs, sequences, transitions

_MODULES = (options, transitions, pairs, sequences, maneuvers)
__all__ = [name for m in _MODULES for name in m.__all__]

from jaxspline.screen.maneuvers import *  # noqa: E402, F403
from jaxspline.screen.options import *  # noqa: E402, F403
from jaxspline.screen.pairs import *  # noqa: E402, F403
from jaxspline.screen.sequences import *  # noqa: E402, F403
from jaxspline.screen.transitions import *  # noqa: E402, F403
