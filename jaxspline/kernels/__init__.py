"""Kernels: the per-candidate mathematics of the papers, one candidate each, batched once.

``limits`` (parameter bundles), ``reach`` (per-channel reachable sets, SPEC §1),
``reach_durations`` (feasible durations, minimum transfer time and peak acceleration),
``slew`` (eigen-axis slew profiles, SPEC §2), ``flex`` (flexible-mode residual),
``attitude`` (quaternions, MRPs), ``joins`` (degree-7 joins, spatial maneuvers),
``join_check`` (their sampled limit check), ``channel_join`` (peaks of the
channel-wise degree-7 join),
``retarget_channel`` / ``retarget`` (minimum-peak control: one channel, 3-D).
Private helpers: ``_safe`` (numerical guards), ``_validate`` (eager input checks),
``_batch`` (batching, padding, chunks).

Layer 0: imports nothing of the package outside this folder.
"""

from jaxspline.kernels import (
    attitude,
    channel_join,
    flex,
    join_check,
    joins,
    limits,
    reach,
    reach_durations,
    retarget,
    retarget_channel,
    slew,
)
from jaxspline.kernels.attitude import *  # noqa: F403
from jaxspline.kernels.channel_join import *  # noqa: F403
from jaxspline.kernels.flex import *  # noqa: F403
from jaxspline.kernels.join_check import *  # noqa: F403
from jaxspline.kernels.joins import *  # noqa: F403
from jaxspline.kernels.limits import *  # noqa: F403
from jaxspline.kernels.reach import *  # noqa: F403
from jaxspline.kernels.reach_durations import *  # noqa: F403
from jaxspline.kernels.retarget import *  # noqa: F403
from jaxspline.kernels.retarget_channel import *  # noqa: F403
from jaxspline.kernels.slew import *  # noqa: F403

_MODULES = (
    limits,
    reach,
    reach_durations,
    slew,
    flex,
    attitude,
    joins,
    join_check,
    channel_join,
    retarget_channel,
    retarget,
)
__all__ = [name for m in _MODULES for name in m.__all__]
