"""How a bound computation ended: one :class:`BoundStatus` for every bound of the search.

The Lagrangian bound (:func:`jaxspline.search.lagrangian`, :func:`jaxspline.search.upper_bound`,
the bound worker, the sharded bound of :mod:`jaxspline.planner.sharded`) and the HiGHS
certificate (:func:`jaxspline.search.mip_bound`) report their status as a member of
:class:`BoundStatus`. It is a :class:`enum.StrEnum`: a member equals, prints, formats and
serializes (JSON) as its plain string value, so reports read ``"optimal"``, ``"converged"``
or ``"time"``.
"""

from __future__ import annotations

import enum

__all__ = ["BoundStatus"]


class BoundStatus(enum.StrEnum):
    """Why a bound computation stopped.

    Attributes:
      OPTIMAL: ``"optimal"``, the bound is met by a plan (the gap is closed), or the
        solver proved optimality.
      CONVERGED: ``"converged"``, the subgradient iteration stopped on its own (zero
        subgradient, or the step fell below its floor).
      TIME: ``"time"``, stopped by the deadline or the iteration cap (or, for HiGHS,
        its time limit) before either of the above.
    """

    OPTIMAL = "optimal"
    CONVERGED = "converged"
    TIME = "time"
