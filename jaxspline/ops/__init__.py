"""Ops: what flies - the attitude history of a plan and its CCSDS AEM files.

Layer 5: may import ``kernels`` through ``planning``, nothing above. ``attitude_history``
samples a plan's attitude (observation laws, holds, the flown joins of
:mod:`jaxspline.planning.joins`); ``aem`` writes and reads it as one CCSDS Attitude
Ephemeris Message per satellite.

Decision: the attitude laws, flown joins and join screen sit in ``planning`` (the planner
screens with them), so only the products built on a finished plan live here.

Re-exported here (and from :mod:`jaxspline`): the public names of both modules.
"""

from jaxspline.ops import aem, attitude_history

_MODULES = (attitude_history, aem)
__all__ = [name for m in _MODULES for name in m.__all__]

from jaxspline.ops.aem import *  # noqa: E402, F403
from jaxspline.ops.attitude_history import *  # noqa: E402, F403
