"""The Lagrangian upper bound of a scenario, alone or with a sharded plan, on 1..N processes.

:func:`run_bound` screens the scenario like :func:`jaxspline.plan` and iterates the
Lagrangian bound of the option model (per-satellite longest paths under target prices,
battery relaxed), without searching for a plan. With a ``coordinator`` (one call per
process, on one or several hosts, the same scenario everywhere) the satellites are
sharded over the processes through ``jax.distributed`` (:mod:`jaxspline.planner.sharded`):
each process screens, stores and solves only its satellites, and all report the bound a
single process would.

With ``plan_path`` the processes also search a plan, sharded the same way
(:func:`jaxspline.planner.sharded.sharded_plan`): after the bound phase every target gets
one owner process (the process whose satellites' DP paths at the best prices take it
most often, then the one with most of its options, then the lowest index; a target its
owner leaves out goes to the next process by the same rule for a short second round);
each process searches its targets on its satellites, drops what the independent check
(:func:`jaxspline.planner.repair.drop_failing`) rejects, and the disjoint parts are
merged. Process 0 writes the merged plan (observations with satellite, target, start,
end, value), its value, the bound and the gap. Left out, unlike :func:`jaxspline.plan`:
start-time refinement, flown-join screening, the HiGHS certificate, and a search across
the shards (a target is only ever tried on the satellites of its owner, then of the next
process).
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from typing import NamedTuple

import jax
import numpy as np

from jaxspline.planner.build import build_problem
from jaxspline.planner.deadline import RunSize, StageDeadline
from jaxspline.planner.files import atomic_write_text, refuse_overwrite
from jaxspline.planner.repair import drop_failing
from jaxspline.planner.sharded import (
    jax_allgather,
    owned_satellites,
    sharded_plan,
    sharded_upper_bound,
)
from jaxspline.readers.scenario import scenario_from
from jaxspline.search import BoundStatus, Timeline, greedy

__all__ = ["SEARCH_TIME_S", "BoundRun", "run_bound"]

SEARCH_TIME_S = 30.0  # default search budget of a sharded plan after the bound phase [s]


class BoundRun(NamedTuple):
    """What one process of :func:`run_bound` reports.

    Attributes:
      scenario: the scenario's name.
      bound: the upper bound (the same in every process).
      status: the bound's :class:`jaxspline.search.BoundStatus`.
      iterations: Lagrangian iterations run.
      target: the step-size target used.
      processes: number of processes; process: this one's index.
      satellites: names of the satellites this process owns.
      near_pairs: screened pairs stored here.
      seconds: wall time after loading [s].
      value, gap, observations: the merged plan's value, its gap and number of
        observations (None without a plan).
    """

    scenario: str
    bound: float
    status: BoundStatus
    iterations: int
    target: float
    processes: int
    process: int
    satellites: list
    near_pairs: int
    seconds: float
    value: float | None = None
    gap: float | None = None
    observations: int | None = None

    def to_dict(self) -> dict:
        """The run as a JSON-ready dict (the plan's fields only when a plan was searched)."""
        out = self._asdict()
        if self.value is None:
            for key in ("value", "gap", "observations"):
                out.pop(key)
        return out


class _Processes(NamedTuple):
    index: int
    count: int
    allgather: object
    distributed: bool


def run_bound(
    scenario=None,
    *,
    time_limit: float = 60.0,
    max_iters: int | None = None,
    target: float | None = None,
    json_path=None,
    plan_path=None,
    search_time: float = SEARCH_TIME_S,
    search_iters: int | None = None,
    seed: int = 0,
    force: bool = False,
    coordinator: str | None = None,
    num_processes: int = 1,
    process_id: int = 0,
    memory=None,
    t_start: float | None = None,
) -> BoundRun:
    """Screen ``scenario`` and iterate its Lagrangian bound (module docstring).

    Args:
      scenario: scenario TOML path, a Scenario, or None (the default scenario).
      time_limit: wall-clock budget [s] of the whole call from ``t_start``: the stages
        before the iterations stop with :class:`jaxspline.planner.deadline.TimeLimitError`
        once it has passed, as :func:`jaxspline.plan`'s do (with several processes they
        run whole: no process may stop while its peers wait), the iterations at its end
        (after one at least); with ``plan_path`` the search's ``search_time`` follows.
      max_iters: cap on the iterations (None: the time limit alone).
      target: step-size target; None: the sum of each process's greedy plan values
        (the same in every process).
      json_path: process 0 writes the result (:meth:`BoundRun.to_dict`) here, atomically.
      plan_path: also search a plan (module docstring); process 0 writes it here
        (atomically). None: the bound alone.
      search_time: with ``plan_path``, the search budget after the bound phase [s].
      search_iters: with ``plan_path``, the cap of each process's search (``max_iters``
        of :func:`jaxspline.search.solve`); None: ``search_time`` alone.
      seed: with ``plan_path``, the search seed.
      force: overwrite ``json_path`` and ``plan_path``.
      coordinator: ``HOST:PORT`` of process 0 for ``jax.distributed``; None: one process.
      num_processes: number of processes (with ``coordinator``).
      process_id: this run's index among the processes.
      memory: optional :class:`jaxspline.planner.memory_guard.MemoryGuard` for the
        screening of this process's satellites (``jaxspline bound`` passes one).
      t_start: when ``time_limit`` starts [s, ``time.monotonic``] (the command passes
        its process's start); None: now.
    Returns:
      :class:`BoundRun` of this process.
    Raises:
      ValueError: bad arguments (more processes than satellites, bad limits).
      jaxspline.planner.memory_guard.MemoryLimitError: the screening would not fit ``memory``.
      jaxspline.planner.deadline.TimeLimitError: the limit ran out before the iterations.
    """
    t_start = time.monotonic() if t_start is None else t_start
    _validate(time_limit, plan_path, search_time, search_iters, num_processes, coordinator)
    for path in (json_path, plan_path):
        if path is not None and process_id == 0:
            refuse_overwrite(path, force)
    procs = _start_processes(coordinator, num_processes, process_id)
    try:
        sc = scenario_from(scenario)
        if procs.count > len(sc.satellites):
            raise ValueError(
                f"num_processes must be at most the {len(sc.satellites)} satellites (one at "
                f"least per process), got {procs.count!r}"
            )
        with jax.enable_x64(True):  # float64 through the collectives too
            search = None if plan_path is None else (search_time, search_iters, seed)
            clock = _deadline(sc, time_limit, t_start, procs)
            run, doc = _run(sc, procs, clock, max_iters, target, search, memory)
        if procs.index == 0:
            if doc is not None:
                atomic_write_text(plan_path, json.dumps(doc, indent=1) + "\n", force=force)
            if json_path is not None:
                text = json.dumps(run.to_dict(), indent=1) + "\n"
                atomic_write_text(json_path, text, force=force)
        return run
    finally:
        if procs.distributed:
            jax.distributed.shutdown()


def _validate(time_limit, plan_path, search_time, search_iters, num_processes, coordinator):
    if not (math.isfinite(time_limit) and time_limit > 0):
        raise ValueError(f"time_limit must be a number > 0, got {time_limit!r}")
    if plan_path is not None:
        if not (math.isfinite(search_time) and search_time > 0):
            raise ValueError(f"search_time must be a number > 0, got {search_time!r}")
        if search_iters is not None and not (isinstance(search_iters, int) and search_iters >= 1):
            raise ValueError(f"search_iters must be an integer >= 1, got {search_iters!r}")
    if coordinator is not None and num_processes < 1:
        raise ValueError(f"num_processes must be >= 1, got {num_processes!r}")


def _start_processes(coordinator, num_processes: int, process_id: int) -> _Processes:
    """Join the ``jax.distributed`` run (before any JAX computation), or run alone."""
    if coordinator is None:
        return _Processes(0, 1, lambda x: np.asarray(x, np.float64)[None], False)
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(coordinator, num_processes, process_id)
    return _Processes(jax.process_index(), jax.process_count(), jax_allgather, True)


def _deadline(sc, time_limit: float, t_start: float, procs: _Processes) -> StageDeadline:
    """The clock of the call: the stages before the iterations check it (one process)."""
    scale = f"{len(sc.targets)} targets, {len(sc.satellites)} satellites, {sc.duration / 3600:g} h"
    size = RunSize(len(sc.targets), len(sc.satellites), sc.duration, sc.planner.time_step, False)
    clock = StageDeadline(
        t_start, time_limit, scale, size=size, goal="the bound's iterations", flags="--time-limit"
    )
    if not procs.distributed:
        clock.check("loading", 1.0)
    return clock


def _run(sc, procs: _Processes, clock: StageDeadline, max_iters, target, search, memory=None):
    """The bound (and with ``search`` = (time, iterations, seed), the sharded plan)."""
    t0 = time.monotonic()
    owned = owned_satellites(len(sc.satellites), procs.index, procs.count)
    shard = dataclasses.replace(sc, satellites=tuple(sc.satellites[k] for k in owned))
    allgather = procs.allgather
    ctx = build_problem(
        shard,
        reduce_slack=lambda s: float(allgather(np.array([s])).min()),
        memory=memory,
        deadline=None if procs.distributed else clock,
    )
    pb = ctx.problem
    if target is None:
        tl = Timeline(pb)
        greedy(tl, math.inf)
        target = float(allgather(np.array([tl.value])).sum())
    deadline = clock.end
    n_sats = len(sc.satellites)
    merged = doc = None
    if search is None:
        res = sharded_upper_bound(pb, owned, n_sats, target, deadline, max_iters, allgather)
    else:
        merged = _sharded_plan(sc, ctx, owned, procs, target, deadline, max_iters, search)
        res = merged.bound
    run = BoundRun(
        scenario=sc.name,
        bound=res.bound,
        status=res.status,
        iterations=res.iterations,
        target=target,
        processes=procs.count,
        process=procs.index,
        satellites=[sc.satellites[k].name for k in owned],
        near_pairs=len(pb.pairs),
        seconds=round(time.monotonic() - t0, 3),
    )
    if merged is not None:
        doc = _plan_doc(sc, merged, procs.count)
        run = run._replace(
            value=doc["value"], gap=doc["gap"], observations=len(doc["observations"])
        )
    return run, doc


def _sharded_plan(sc, ctx, owned, procs, target, deadline, max_iters, search):
    """This process's part of the sharded plan (``ctx``: its shard of the scenario ``sc``),
    each part checked independently (:func:`jaxspline.planner.repair.drop_failing`)."""
    search_time, search_iters, seed = search

    def check(ids):
        return drop_failing(ctx, ids)[0]

    return sharded_plan(
        ctx.problem,
        owned,
        len(sc.satellites),
        procs.index,
        target,
        deadline,
        search_time,
        bound_iters=max_iters,
        search_iters=search_iters,
        seed=seed,
        lagrangian_share=sc.planner.lagrangian_share,
        exact_max_options=sc.planner.exact_max_options,
        check=check,
        allgather=procs.allgather,
    )


def _plan_doc(sc, mp, count: int) -> dict:
    """The ``--plan`` JSON of a :class:`jaxspline.planner.sharded.ShardedPlan`."""
    tg = sc.targets
    imaged = np.flatnonzero(mp.sat >= 0)
    imaged = imaged[np.lexsort((mp.start[imaged], mp.sat[imaged]))]  # by satellite, then start
    bound = float(mp.bound.bound)
    per_process = [
        {"satellites": [s.name for s in sc.satellites[p::count]], **st}
        for p, st in enumerate(mp.processes)
    ]
    return {
        "scenario": sc.name,
        "processes": count,
        "value": mp.value,
        "bound": bound,
        "gap": max(bound, mp.value) - mp.value,
        "bound_status": mp.bound.status,
        "bound_iterations": mp.bound.iterations,
        "per_process": per_process,
        "observations": [
            {
                "satellite": sc.satellites[mp.sat[t]].name,
                "target": str(tg.name[t]),
                "start": float(mp.start[t]),
                "end": float(mp.end[t]),
                "value": float(tg.value[t]),
                "option": int(mp.option[t]),
                "process": int(mp.owner[t]),
            }
            for t in imaged
        ],
    }
