"""Exact search for tiny instances: depth-first branch and bound over the options.

Options are decided in start order (take or skip); a take is tested with
:meth:`Timeline.check` (the maneuver from the satellite's previous observation, the
battery), so every leaf is a feasible plan imaging each target at most once. A branch
is cut when its value plus the values of the still-unimaged targets that have options
later cannot beat the best plan found.
"""

from __future__ import annotations

from jaxspline.base import clock
from jaxspline.search.timeline import Timeline

__all__ = ["exact_search"]

_DEADLINE_CHECK = 1024  # nodes between deadline checks
_TOL = 1e-12


def exact_search(tl: Timeline, deadline: float):
    """Optimal plan of the option model (battery included) by branch and bound.

    Args:
      tl: Timeline, must be empty; it ends holding the best plan.
      deadline: float, ``time.monotonic()`` value at which to stop [s].
    Returns:
      ``(value, proven)``, with ``proven`` False when the deadline cut the search.
    """
    pb = tl.pb
    order = sorted(range(pb.n_options), key=lambda c: (pb.option_start[c], c))
    n = len(order)
    suffix = [set() for _ in range(n + 1)]
    for i in range(n - 1, -1, -1):
        suffix[i] = suffix[i + 1] | {pb.option_target[order[i]]}
    best = {"value": tl.value, "plan": list(tl.assigned)}
    state = {"nodes": 0, "timed_out": False}

    def dfs(i):
        state["nodes"] += 1
        if state["nodes"] % _DEADLINE_CHECK == 0 and clock.now() > deadline:
            state["timed_out"] = True
        if state["timed_out"]:
            return
        if tl.value > best["value"] + _TOL:
            best["value"], best["plan"] = tl.value, list(tl.assigned)
        if i == n:
            return
        upper = tl.value + sum(pb.target_value[t] for t in suffix[i] if tl.assigned[t] < 0)
        if upper <= best["value"] + _TOL:
            return
        c = order[i]
        if tl.assigned[pb.option_target[c]] < 0 and tl.check(c) is not None:
            tl.insert(c)
            dfs(i + 1)
            tl.undo_to(len(tl.log) - 1)
        dfs(i + 1)

    dfs(0)
    tl.restore(best["plan"])
    return best["value"], not state["timed_out"]
