"""The repair loop after the search: per-transition verdicts and dropped <= violations.

References: the independent check (:func:`check_plan`, kernels from scratch) decides
what is valid; the situations are built by hand: a per-channel observation whose start
state moved after its pair was screened (as a refined or refilled neighbour does), and
plans with options forced in without the search's insertion test.
"""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from test_planner import _scenario

from jaxspline import build_problem
from jaxspline.planner.opportunities import Opportunities
from jaxspline.planner.plan_check import check_plan
from jaxspline.planner.repair import DROP_REASONS, repair
from jaxspline.search import solve

SMALL = dict(n_points=36, n_strips=3, off_nadir_deg=14.0, exact_max_options=0)


def _searched(seed):
    sc = _scenario(seed, **SMALL)
    prep = build_problem(sc)
    res = solve(prep.problem, math.inf, seed=seed, max_iters=200)
    return sc, prep, res.timeline


def _check(sc, prep, opp, chosen):
    assert prep.scenario is sc
    return check_plan(prep, chosen, opp)


def test_check_blames_only_the_later_observation_of_a_failing_transition():
    """One per-channel transition made unreachable: exactly its later observation fails
    (the check used to fail the satellite's whole plan)."""
    sc, prep, tl = _searched(0)
    opp = prep.opportunities
    o = opp.options
    k = next(i for i, s in enumerate(sc.satellites) if s.model == "per_channel")
    line = list(tl.lines[k])
    assert len(line) >= 4
    chosen = [c for c in tl.assigned if c >= 0]
    assert _check(sc, prep, opp, chosen)[0] == []  # the search's plan is valid
    gaps = [o.t_start[b] - o.t_end[a] for a, b in zip(line[:-1], line[1:], strict=True)]
    i = 1 + int(np.argmin(gaps[:-1]))  # a middle observation after the shortest gap
    c = line[i]
    # its start state moved by 2 rad on channel 0 (a re-timed neighbour): 2 rad cannot
    # be crossed at 1.5 deg/s within the gap, so transition i-1 -> i is unreachable
    assert gaps[i - 1] < 2.0 / sc.satellites[k].limits.rate[0]
    sa = np.array(o.start_angle)
    sa[c, 0] += 2.0
    moved = Opportunities(o._replace(start_angle=sa), opp.speed, opp.params)
    bad, det = _check(sc, prep, moved, chosen)
    assert bad == [c]
    assert det["reasons"] == {c: "maneuver"}
    assert any("no trajectory" in v or "peak" in v for v in det["violations"])
    rest = [x for x in chosen if x != c]
    assert _check(sc, prep, moved, rest)[0] == []  # dropping it is enough


def _force_infeasible(tl, rng, count):
    """Insert up to ``count`` options the search's insertion test refuses (bypassing it)."""
    pb = tl.pb
    forced = []
    free = [c for c in range(pb.n_options) if tl.assigned[pb.option_target[c]] < 0]
    rng.shuffle(free)
    for c in free:
        if len(forced) == count:
            break
        if tl.assigned[pb.option_target[c]] < 0 and tl.check(c) is None:
            tl.insert(c)
            forced.append(c)
    tl.commit()
    return forced


@pytest.mark.parametrize(
    "seed",
    [0, 2, *(pytest.param(k, marks=pytest.mark.slow) for k in (1, 3, 4))],
)
def test_repair_drops_at_most_one_observation_per_violation(seed):
    """Random small scenarios with infeasible options forced into the plan: the repaired
    plan passes the independent check, nothing is dropped without a violation, and the
    plan keeps every observation the violations did not name."""
    sc, prep, tl = _searched(seed)
    before = {c for c in tl.assigned if c >= 0}
    forced = _force_infeasible(tl, random.Random(seed), 3)
    assert forced
    opp = prep.opportunities
    plan_in = [c for c in tl.assigned if c >= 0]
    assert _check(sc, prep, opp, plan_in)[0]  # the forced plan does fail the check
    rep = repair(prep, plan_in, refine_steps=sc.planner.refine_steps if seed == 0 else 0)
    assert set(rep.dropped) == set(DROP_REASONS)
    n_dropped = sum(rep.dropped.values())
    assert 1 <= n_dropped <= rep.violations
    assert n_dropped == len(plan_in) - len(rep.chosen)
    bad, det = _check(sc, prep, rep.opp, rep.chosen)
    assert bad == [] and det["violations"] == []
    # a forced option costs itself and the observations its transitions blame
    assert len(before - set(rep.chosen)) <= 2 * len(forced)


@pytest.mark.parametrize("refined_loses_more", [True, False])
def test_the_last_refinement_stays_only_if_its_joins_lose_no_more(monkeypatch, refined_loses_more):
    """After the last refill, the refined table stays in force only if the plan it leaves
    after the join rejections is worth at least the search table's (joins faked here: on
    one table they fail the two most valuable observations, on the other the least)."""
    import jaxspline.planner.repair as rp

    sc, prep, tl = _searched(0)
    chosen = [c for c in tl.assigned if c >= 0]
    pb, opp_s = prep.problem, prep.opportunities
    opp_r = Opportunities(opp_s.options, opp_s.speed, opp_s.params)  # the "refined" table
    by_value = sorted(chosen, key=lambda c: pb.target_value[pb.option_target[c]])
    cheap, dear = by_value[:1], by_value[-2:]
    lose_r, lose_s = (dear, cheap) if refined_loses_more else (cheap, dear)

    def reject(scenario, scene, opp, plan):
        return [c for c in (lose_r if opp is opp_r else lose_s) if c in plan], {"joins": 0}

    monkeypatch.setattr(rp, "reject_unflyable", reject)
    refined = {"agile": {"kept": True}}
    opp, tail = rp._last_round(prep, chosen, opp_r, None, refined)
    keep_r = not refined_loses_more
    lost = lose_r if keep_r else lose_s
    assert (opp is opp_r) == keep_r and tail.kept == keep_r
    assert refined["agile"]["kept"] == keep_r
    assert tail.chosen == [c for c in chosen if c not in lost]
    assert tail.dropped["joins"] == len(lost) and np.flatnonzero(tail.withdrawn).tolist() == sorted(
        lost
    )
    assert tail.rounds == 2  # one round rejects, the next finds nothing more
