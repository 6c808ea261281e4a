"""The forked bound worker against the in-process bound and the search without it.

References: :func:`upper_bound` iterated in this process (the worker must return the
same bits across the fork), :func:`solve` without the worker (the plan must not change
and the bound may only get smaller), and every plan value the search finds (a bound
below one would be wrong). The plans the worker publishes are checked by inserting them
option by option into an empty timeline (every insertion must pass its feasibility
check, battery included) and against the bound.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import pytest

from jaxspline.planner.build import build_problem
from jaxspline.readers.scenario import load_scenario
from jaxspline.search import (
    BoundWorker,
    Timeline,
    adopt,
    dp_prepare,
    greedy,
    solve,
    upper_bound,
)

sys.path.insert(0, str(Path(__file__).parents[1] / "cli"))
from test_cli_plan import SMALL  # noqa: E402

PLAN_VALUE = 100.0
CAP = 60  # worker iterations
SEARCH_ITERS = 400
TIMED_S = 3.0  # the worker converges in ~1 s here and may hand a plan over
WALK_S = 3.0  # the converged worker's own search in the walk test


@pytest.fixture(scope="module")
def problem(tmp_path_factory):
    path = tmp_path_factory.mktemp("worker") / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return build_problem(load_scenario(path)).problem


def test_worker_bound_equals_in_process_bound(problem):
    ref = upper_bound(problem, PLAN_VALUE, math.inf, CAP, energy=False)
    got = BoundWorker(problem, PLAN_VALUE, math.inf, CAP).result()
    assert got is not None
    assert got.bound == ref.bound  # bit for bit across the fork
    assert got.iterations == ref.iterations
    assert got.status == ref.status


def test_worker_with_the_parents_dp_layout_gives_the_same_bound(problem):
    ref = upper_bound(problem, PLAN_VALUE, math.inf, CAP, energy=False)
    got = BoundWorker(problem, PLAN_VALUE, math.inf, CAP, dp_prepare(problem)).result()
    assert got is not None
    assert (got.bound, got.iterations, got.status) == (ref.bound, ref.iterations, ref.status)


def test_solve_with_worker_keeps_the_plan_and_tightens_the_bound(problem):
    base = solve(problem, math.inf, seed=3, max_iters=SEARCH_ITERS)
    with_w = solve(problem, math.inf, seed=3, max_iters=SEARCH_ITERS, bound_worker=True)
    assert with_w.timeline.assigned == base.timeline.assigned
    assert "worker_bound" in with_w.stats
    assert with_w.bound <= base.bound
    assert with_w.bound == min(base.bound, with_w.stats["worker_bound"])
    assert with_w.bound >= with_w.timeline.value - 1e-9


def test_result_without_waiting_ends_the_process(problem):
    w = BoundWorker(problem, PLAN_VALUE, time.monotonic() + 600.0, None)
    t0 = time.monotonic()
    out = w.result(wait=False)
    assert time.monotonic() - t0 < 10.0
    assert out is None or out.bound >= 0.0
    assert not w.alive


def _feasible_value(pb, assigned) -> float:
    """The value of a target -> option assignment, asserting every insertion (in start
    order, into an empty timeline) passes :meth:`Timeline.check`."""
    tl = Timeline(pb)
    for c in sorted((c for c in assigned if c >= 0), key=lambda c: pb.option_start[c]):
        assert tl.check(c) is not None, f"option {c} of the published plan does not fit"
        tl.insert(c)
    return tl.value


def test_worker_publishes_feasible_plans_below_its_bound(problem):
    w = BoundWorker(problem, PLAN_VALUE, time.monotonic() + 600.0, CAP, plans=True)
    res = w.result()
    offer = w.plan(-math.inf)
    assert res is not None and offer is not None
    value, plan = offer
    targets = [problem.option_target[c] for c in plan]
    assert len(set(targets)) == len(plan)  # each target once
    assert _feasible_value(problem, plan) == value
    assert 0.0 < value <= res.bound + 1e-9
    assert w.plan(-math.inf) is None  # handed out once


def test_worker_first_builds_and_publishes_the_greedy_start_it_is_given(problem):
    # the reference: the same greedy in this process, in the reverse of the value order
    order = [t for t in range(problem.n_targets) if problem.target_options[t]][::-1]
    ref = Timeline(problem)
    greedy(ref, math.inf, order)
    few = 2  # iterations: fewer than the first repair needs, so the greedy's is the only plan
    w = BoundWorker(problem, 0.0, time.monotonic() + 600.0, few, plans=True, first=order)
    assert w.result() is not None
    value, plan = w.plan(-math.inf)
    assert sorted(plan) == sorted(ref.plan()) and value == ref.value > 0.0
    assert _feasible_value(problem, plan) == value
    # worth no more than the plan the search already has: not published
    w = BoundWorker(problem, ref.value, time.monotonic() + 600.0, few, plans=True, first=order)
    w.result()
    assert w.plan(-math.inf) is None


def test_worker_without_plans_publishes_none(problem):
    w = BoundWorker(problem, PLAN_VALUE, time.monotonic() + 600.0, 8)
    w.result()
    assert not w.plans
    assert w.plan(-math.inf) is None


def test_adopt_takes_only_a_better_plan(problem):
    ref = Timeline(problem)
    greedy(ref, math.inf)
    tl = Timeline(problem)
    assert not adopt(tl, None, None)
    assert adopt(tl, None, (ref.value, list(ref.assigned)))
    assert tl.assigned == ref.assigned and tl.value == ref.value
    assert not adopt(tl, None, (ref.value, [-1] * problem.n_targets))  # not better


def test_timed_solve_with_worker_plans_stays_valid(problem):
    res = solve(problem, time.monotonic() + TIMED_S, seed=3, bound_worker=True)
    assert res.stats["worker_plans"] >= 0
    assert res.stats["lagrangian_iterations"] == 0  # the worker stands for the phase
    assert _feasible_value(problem, res.timeline.assigned) == res.timeline.value
    assert res.bound >= res.timeline.value - 1e-9


def test_retime_moves_the_search_end_once_the_greedy_start_is_built(problem):
    # the caller's reserve re-estimated from the plan's size: a deadline an hour away
    # becomes one a second after the greedy start, for the worker as for the LNS
    asked = []

    def retime(per_sat):
        assert len(per_sat) == problem.n_sats
        asked.append(sum(per_sat))
        return time.monotonic() + 1.0

    t0 = time.monotonic()
    res = solve(problem, t0 + 3600.0, seed=3, bound_worker=True, retime=retime)
    assert len(asked) == 1 and 0 < asked[0] <= problem.n_targets
    assert time.monotonic() - t0 < 30.0
    assert res.bound >= res.timeline.value - 1e-9
    solve(problem, math.inf, seed=3, max_iters=10, retime=retime)  # capped: no clock
    assert len(asked) == 1


class _Record:
    """Stands in for the shared plan: records every publication."""

    def __init__(self):
        self.plans = []

    def publish(self, value, assigned):
        self.plans.append((value, list(assigned)))


def test_converged_worker_searches_on_and_publishes_better_feasible_plans(problem):
    # what the worker does once its bound converged: an LNS of its own from the greedy
    # start (no repaired plan yet), publishing strictly better plans, ending in time
    from jaxspline.search.bound_worker import _WALK_END_S, _Repairs

    start = Timeline(problem)
    greedy(start, math.inf)
    shared = _Record()
    deadline = time.monotonic() + WALK_S
    _Repairs(problem, shared, deadline, dp_prepare(problem)).walk()
    assert time.monotonic() <= deadline - _WALK_END_S + 1.0
    assert shared.plans, "the walk published nothing"
    values = [v for v, _ in shared.plans]
    assert values == sorted(set(values))  # each publication beats the one before
    assert values[0] >= start.value
    for value, assigned in shared.plans:
        assert _feasible_value(problem, assigned) == value


def test_searching_worker_stops_its_bound_at_its_own_step_floor(problem):
    # a worker that publishes plans converges at SEARCH_MU_MIN, then searches: its
    # bound is the in-process bound at that floor, bit for bit, reached in fewer
    # iterations than the bound alone needs
    from jaxspline.search.bound_worker import SEARCH_MU_MIN
    from jaxspline.search.status import BoundStatus

    cap = 10 * CAP
    ref = upper_bound(problem, PLAN_VALUE, math.inf, cap, energy=False, mu_min=SEARCH_MU_MIN)
    alone = upper_bound(problem, PLAN_VALUE, math.inf, cap, energy=False)
    got = BoundWorker(problem, PLAN_VALUE, time.monotonic() + 600.0, cap, plans=True).result()
    assert got is not None
    assert ref.status == alone.status == BoundStatus.CONVERGED
    assert (got.bound, got.iterations, got.status) == (ref.bound, ref.iterations, ref.status)
    assert ref.iterations < alone.iterations
    assert ref.bound >= alone.bound
