"""Exact search for tiny instances: depth-first branch and bound over the options.

Options are decided in start order (take or skip); a take is tested with
:meth:`Timeline.check` (the maneuver from the satellite's previous observation, the
battery), so every leaf is a feasible plan imaging each task at most once. A branch
is cut when its value plus the values of the still-unimaged tasks that have options
later cannot beat the best plan found.
"""

from __future__ import annotations

from jaxspline.search import clock
from jaxspline.search.timeline import Timeline

__all__ = ["exact_search"]

_DEADLINE_CHECK = 1024  # nodes between deadline checks
_TOL = 1e-12


def exact_search(tl: Timeline, deadline: float):
    """Optimal plan of the candidate model (battery included) by branch and bound.

    Args:
      tl: Timeline, must be empty; it ends holding the best plan.
      deadline: float, ``time.monotonic()`` value at which to stop [s].
    Returns:
      ``(value, proven)``, with ``proven`` False when the deadline cut the search.
    """
    pb = tl.pb
    order = sorted(range(pb.n_options), key=lambda c: (pb.c_start[c], c))
    n = len(order)
    suffix = [set() for _ in range(n + 1)]
    for i in range(n - 1, -1, -1):
        suffix[i] = suffix[i + 1] | {pb.c_task[order[i]]}
    best = {"W": tl.W, "plan": list(tl.assigned)}
    state = {"nodes": 0, "timed_out": False}

    def dfs(i):
        state["nodes"] += 1
        if state["nodes"] % _DEADLINE_CHECK == 0 and clock.now() > deadline:
            state["timed_out"] = True
        if state["timed_out"]:
            return
        if tl.W > best["W"] + _TOL:
            best["W"], best["plan"] = tl.W, list(tl.assigned)
        if i == n:
            return
        upper = tl.W + sum(pb.weight[t] for t in suffix[i] if tl.assigned[t] < 0)
        if upper <= best["W"] + _TOL:
            return
        c = order[i]
        if tl.assigned[pb.c_task[c]] < 0 and tl.check(c) is not None:
            tl.insert(c)
            dfs(i + 1)
            tl.undo_to(len(tl.log) - 1)
        dfs(i + 1)

    dfs(0)
    tl.restore(best["plan"])
    return best["W"], not state["timed_out"]
