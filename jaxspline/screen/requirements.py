"""Required times of given option pairs of one satellite, on the host.

:func:`pair_requirements` answers for a list of pairs what the screen answers in bulk:
the rest-to-rest models read the slew table (:mod:`jaxspline.screen.models`), the
per-channel model screens the pairs (:func:`jaxspline.screen.pairs.screen_pairs`). It
sits above both (the table module stays below the screening entry points, which
validate models with it), so no import circle forms.
"""

from __future__ import annotations

import numpy as np

from jaxspline.screen.models import REST_TO_REST, SlewTable, rest_to_rest
from jaxspline.screen.pairs import screen_pairs

__all__ = ["pair_requirements"]


def pair_requirements(sat, options, src, dst, table: SlewTable | None = None):
    """Required time t_req [P] [s] of transitions src -> dst of one satellite (inf: infeasible).

    Args:
      sat: the :class:`jaxspline.planning.mission.Satellite` (all pairs belong to it).
      options: :class:`jaxspline.screen.options.RouteOptions` (numpy fields; ``start_los`` and
        ``end_los`` needed by rest-to-rest models).
      src, dst: int [P] option indices.
      table: the satellite's :class:`SlewTable` (rest-to-rest models).
    """
    src = np.asarray(src, np.int64)
    dst = np.asarray(dst, np.int64)
    T = np.asarray(options.t_start)[dst] - np.asarray(options.t_end)[src]
    if src.size == 0:
        return np.zeros(0)
    if sat.model in REST_TO_REST:
        return rest_to_rest(table, options.end_los, src, options.start_los, dst, T)
    tr = screen_pairs(options, sat.limits, src, dst)
    return np.where(tr.feasible & (T > 0), np.minimum(tr.t_min, T), np.inf)
