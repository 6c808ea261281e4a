"""The sharded bound and plan against one process (references: upper_bound, solve,
the independent plan check on the whole scenario).

* in one process: two shards of the satellites in two threads, the all-gather a
  barrier between them (the protocol alone);
* for real: ``jaxspline bound --plan`` as two processes under ``jax.distributed``
  (gloo on the CPU, localhost) against the same command as one process and against
  the threads.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import jax
import numpy as np
import pytest

from jaxspline.planner.build import build_problem
from jaxspline.planner.plan_check import check_plan
from jaxspline.planner.repair import drop_failing
from jaxspline.planner.sharded import (
    owned_satellites,
    restrict_targets,
    sharded_plan,
    sharded_upper_bound,
    target_owners,
)
from jaxspline.readers.scenario import load_scenario
from jaxspline.search import solve, upper_bound

sys.path.insert(0, str(Path(__file__).parents[1] / "cli"))
from test_cli_plan import SMALL  # noqa: E402

PLAN_VALUE = 100.0
ITERS = 40  # bound iterations
SEARCH_ITERS = 300  # LNS iterations of each search
MIN_RATIO = 0.9  # merged plan value / one process's, at least


@pytest.fixture(scope="module")
def scenario_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("sharded") / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def built(scenario_file):
    """The whole scenario's PlanContext and one (satellites, shard scenario, PlanContext) a
    process."""
    sc = load_scenario(scenario_file)
    full = build_problem(sc)
    count = len(sc.satellites)
    shards = []
    for i in range(count):
        owned = owned_satellites(count, i, count)
        shard = dataclasses.replace(sc, satellites=tuple(sc.satellites[k] for k in owned))
        prep = build_problem(shard, reduce_slack=lambda s, w=full.problem.near_slack: w)
        shards.append((owned, shard, prep))
    return sc, full, shards


class _Exchange:
    """All-gather between threads: every party posts, waits, reads all posts."""

    def __init__(self, parties):
        self.barrier = threading.Barrier(parties)
        self.posts = [None] * parties

    def allgather(self, i):
        def gather(x):
            self.posts[i] = np.asarray(x, np.float64).copy()
            self.barrier.wait()
            out = np.stack(self.posts)
            self.barrier.wait()  # nobody overwrites a post before all have read it
            return out

        return gather


def _in_threads(count, run):
    """``run(i, allgather)`` in ``count`` threads sharing one exchange; their results."""
    ex = _Exchange(count)
    results = [None] * count
    errors = []

    def body(i):
        try:
            results[i] = run(i, ex.allgather(i))
        except BaseException as e:  # noqa: BLE001 - re-raised in the test's thread
            errors.append(e)
            ex.barrier.abort()

    threads = [threading.Thread(target=body, args=(i,)) for i in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    if errors:
        raise errors[0]
    return results


def test_threads_sharded_bound_equals_one_process(built):
    sc, full, shards = built
    ref = upper_bound(full.problem, PLAN_VALUE, math.inf, max_iters=ITERS, energy=False)
    count = len(shards)
    assert sum(len(prep.problem.pairs) for _, _, prep in shards) == len(full.problem.pairs)

    def run(i, allgather):
        owned, _, prep = shards[i]
        return sharded_upper_bound(
            prep.problem, owned, count, PLAN_VALUE, math.inf, ITERS, allgather=allgather
        )

    for r in _in_threads(count, run):
        assert r.bound == ref.bound  # bit for bit
        assert r.iterations == ref.iterations == ITERS


def test_task_owners_hand_table():
    takes = [[1, 0, 0, 1, 0], [0, 1, 0, 1, 0], [0, 1, 0, 0, 0]]
    options = [[1, 5, 2, 3, 0], [9, 2, 7, 4, 0], [0, 3, 7, 9, 0]]
    # target 0: the only taker; 1: two takers, more options; 2: nobody takes it, most
    # options tie (1, 2): lowest index; 3: two takers, more options; 4: no option: 0
    assert target_owners(takes, options).tolist() == [0, 2, 1, 1, 0]
    with pytest.raises(ValueError, match="takes"):
        target_owners([[1, 0]], [[1, 0, 0]])


def test_restrict_tasks_keeps_options_pairs_and_plans(built):
    sc, full, _ = built
    pb = full.problem
    n_t = pb.n_targets
    caps = dict(max_iters=SEARCH_ITERS, exact_max_options=sc.planner.exact_max_options)
    ref = solve(pb, math.inf, **caps)
    every, ids = restrict_targets(pb, np.ones(n_t, bool))
    assert ids.tolist() == list(range(pb.n_options))
    assert solve(every, math.inf, **caps).timeline.assigned == ref.timeline.assigned
    keep = np.arange(n_t) % 2 == 0
    sub, ids = restrict_targets(pb, keep)
    assert sub.n_options == sum(len(pb.target_options[t]) for t in np.flatnonzero(keep))
    for name in (
        "option_target",
        "option_sat",
        "option_start",
        "option_end",
        "option_first",
        "option_start_los",
        "option_end_los",
    ):
        assert getattr(sub, name) == [getattr(pb, name)[c] for c in ids], name
    same = np.equal.outer(sub.option_sat, sub.option_sat)
    for i, j in zip(*np.nonzero(same), strict=True):  # brute force over the kept pairs
        assert sub.pairs.lookup(i, j) == pb.pairs.lookup(ids[i], ids[j])
    plan = solve(sub, math.inf, **caps).timeline
    assert plan.value > 0 and all(keep[t] for t, c in enumerate(plan.assigned) if c >= 0)
    with pytest.raises(ValueError, match="keep"):
        restrict_targets(pb, keep[:-1])


@pytest.fixture(scope="module")
def thread_plans(built):
    """sharded_plan in two threads, each process's part checked as the CLI does."""
    sc, _, shards = built
    pc = sc.planner

    def run(i, allgather):
        owned, _, prep = shards[i]

        def check(ids):
            with jax.enable_x64(True):  # the context is per thread
                return drop_failing(prep, ids)[0]

        return sharded_plan(
            prep.problem,
            owned,
            len(sc.satellites),
            i,
            PLAN_VALUE,
            math.inf,
            math.inf,
            bound_iters=ITERS,
            search_iters=SEARCH_ITERS,
            lagrangian_share=pc.lagrangian_share,
            exact_max_options=pc.exact_max_options,
            check=check,
            allgather=allgather,
        )

    return _in_threads(len(shards), run)


def _observations(sc, mp):
    names = [s.name for s in sc.satellites]
    return sorted(
        (names[mp.sat[t]], str(sc.targets.name[t]), mp.start[t], mp.end[t], int(mp.option[t]))
        for t in np.flatnonzero(mp.sat >= 0)
    )


def test_threads_sharded_plan_is_valid_on_the_whole_scenario(built, thread_plans):
    sc, full, _ = built
    pb = full.problem
    a, b = thread_plans
    assert _observations(sc, a) == _observations(sc, b) and a.value == b.value
    assert all(p["handed_in"] >= 0 for p in a.processes) and len(a.processes) == 2
    # every observation is an option of the single-process table, found by its index
    ids = []
    for t in np.flatnonzero(a.sat >= 0):
        c = pb.sat_lo[a.sat[t]] + int(a.option[t])
        assert (pb.option_target[c], pb.option_start[c], pb.option_end[c]) == (
            t,
            a.start[t],
            a.end[t],
        )
        ids.append(c)
    assert len({pb.option_target[c] for c in ids}) == len(ids)  # each target at most once
    assert a.value == sum(pb.target_value[pb.option_target[c]] for c in ids)
    with jax.enable_x64(True):
        bad, det = check_plan(full, ids)
    assert bad == [] and det["violations"] == []
    # the bound is the single process's; the plan within MIN_RATIO of its plan
    ref = upper_bound(pb, PLAN_VALUE, math.inf, max_iters=ITERS, energy=False)
    assert a.bound.bound == ref.bound and a.bound.iterations == ITERS
    one = solve(
        pb,
        math.inf,
        max_iters=SEARCH_ITERS,
        lagrangian_share=sc.planner.lagrangian_share,
        exact_max_options=sc.planner.exact_max_options,
    ).timeline.value
    assert MIN_RATIO * one <= a.value <= ref.bound


def _free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def _bound_cmd(scen, out, plan, *extra):
    return [
        sys.executable,
        "-m",
        "jaxspline.cli",
        "bound",
        str(scen),
        "--max-iters",
        str(ITERS),
        "--target",
        str(PLAN_VALUE),
        "--json",
        str(out),
        "--plan",
        str(plan),
        "--search-iters",
        str(SEARCH_ITERS),
        *extra,
    ]


# slow: two processes under jax.distributed are checked by default in
# tests/screen/test_screen.py, the sharded protocol by the thread tests above
@pytest.mark.slow
def test_two_processes_under_jax_distributed_equal_one(
    scenario_file, built, thread_plans, tmp_path
):
    sc, full, _ = built
    env = dict(os.environ)  # the run's shared XLA cache (conftest)
    one, plan_one = tmp_path / "one.json", tmp_path / "plan_one.json"
    r = subprocess.run(
        _bound_cmd(scenario_file, one, plan_one),
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    two, plan_two = tmp_path / "two.json", tmp_path / "plan_two.json"
    port = _free_port()
    procs = [
        subprocess.Popen(
            _bound_cmd(
                scenario_file,
                two,
                plan_two,
                "--coordinator",
                f"localhost:{port}",
                "--num-processes",
                "2",
                "--process-id",
                str(i),
            ),
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for i in (1, 0)
    ]
    for p in procs:
        _, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
    a, b = json.loads(one.read_text()), json.loads(two.read_text())
    assert b["processes"] == 2 and a["processes"] == 1
    assert b["bound"] == a["bound"] and b["iterations"] == a["iterations"] == ITERS
    assert b["satellites"] == [sc.satellites[0].name]
    assert 0 < b["near_pairs"] < a["near_pairs"]  # process 0 stores its shard only
    p1, p2 = json.loads(plan_one.read_text()), json.loads(plan_two.read_text())
    # two processes: the threads' plan, observation for observation
    obs = sorted(
        (o["satellite"], o["target"], o["start"], o["end"], o["option"]) for o in p2["observations"]
    )
    assert obs == _observations(sc, thread_plans[0])
    assert p2["value"] == thread_plans[0].value == b["value"]
    assert p2["bound"] == p1["bound"] == a["bound"] and p2["gap"] == p2["bound"] - p2["value"]
    # one process: solve on the whole problem, as checked
    assert [p["dropped"] for p in p1["per_process"]] == [0]
    one_value = solve(
        full.problem,
        math.inf,
        max_iters=SEARCH_ITERS,
        lagrangian_share=sc.planner.lagrangian_share,
        exact_max_options=sc.planner.exact_max_options,
    ).timeline.value
    assert p1["value"] == one_value
