"""The greedy strategy, once: decision by decision, commit the admissible candidate of
least cost, and never take a commit back.

A greedy construction is a sequence of *decisions*. Each decision offers the
candidates that are admissible given the commits made so far, with their costs; the
strategy commits the first candidate of least cost (ties go to the earlier candidate:
the order in which a problem lists its candidates is its tie-break) and goes on to the
next decision. A decision without candidates commits nothing. Decisions are read one
at a time, after the previous commit, so a decision may depend on every commit before
it (a generator that reads the problem's state is fine).

Every greedy of the package is this strategy, :func:`greedy_pass`; a problem supplies
only what its decisions are, what is admissible and what it costs:

* :func:`jaxspline.search.greedy` (multi-satellite timelines): one decision per target,
  heaviest first (:func:`jaxspline.search.lns.greedy_order`); the candidates are the
  target's options that fit (:meth:`jaxspline.search.timeline.Timeline.check`), their
  cost the timeline time they consume plus a small end-time term
  (:meth:`jaxspline.search.timeline.Timeline.insert_choices`). The LNS re-inserts the
  targets of a destroyed window with the same pass, on noisy costs.
* :func:`jaxspline.sequences.greedy_chain` (one chain over screened transitions,
  :mod:`jaxspline.sequences.sequencer`): one decision per position of the chain; the
  candidates are the feasible successors of the last option (every option at the
  start) whose route is unvisited, in ``(t_start, index)`` order, their cost minus the
  value density value / (t_end - now). The decisions end when one commits nothing.
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.base import clock

__all__ = ["first_least", "greedy_pass"]

_DEADLINE_CHECK = 64  # decisions between deadline checks


def first_least(costs) -> int:
    """Position of the first least cost: the greedy's choice among one decision's candidates.

    Args:
      costs: float costs, a list (or a numpy array for many candidates), none NaN.
    Returns:
      int, the position of the least cost (the earliest one on ties), -1 when
      ``costs`` is empty.
    """
    if type(costs) is list:  # the hot path: one target's few options
        return costs.index(min(costs)) if costs else -1
    return int(np.argmin(costs)) if np.size(costs) else -1


def greedy_pass(decisions, choices, commit, deadline: float = math.inf) -> int:
    """Run the greedy strategy (module docstring) over ``decisions``.

    Args:
      decisions: iterable of decisions, read one at a time after the previous commit.
      choices: callable ``choices(decision) -> (candidates, costs)``, the admissible
        candidates of a decision (given the commits so far) and their costs, in
        tie-break order.
      commit: callable ``commit(candidate)`` applying the chosen candidate.
      deadline: ``time.monotonic()`` value after which no further decision is taken
        (compared with :func:`jaxspline.base.clock.now` every few decisions);
        ``+inf``: every decision is taken, even after a stop request.
    Returns:
      int, the number of commits.
    """
    made = 0
    for i, d in enumerate(decisions):
        if i % _DEADLINE_CHECK == 0 and clock.now() > deadline:
            break
        cands, costs = choices(d)
        k = first_least(costs)
        if k >= 0:
            commit(cands[k])
            made += 1
    return made
