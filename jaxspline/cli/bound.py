"""``jaxspline bound [SCENARIO.toml]``: the Lagrangian upper bound, on one or many processes.

Screens the scenario like ``jaxspline plan`` and iterates the Lagrangian bound of the
candidate model (per-satellite longest paths under task prices, battery relaxed),
without searching for a plan. With ``--coordinator HOST:PORT --num-processes N
--process-id I`` (one command per process, on one or several hosts, the same scenario
file everywhere) the satellites are sharded over the processes through
``jax.distributed`` (:mod:`jaxspline.search.sharded`): each process screens,
stores and solves only its satellites, and all report the bound a single process
would. Process 0 prints the result and writes ``--json``.

With ``--plan PLAN.json`` the processes also search a plan, sharded the same way
(:func:`jaxspline.search.sharded.sharded_plan`): after the bound phase every
task gets one owner process (merge rule: the process whose satellites' DP paths at
the best prices take it most often, then the one with most of its options, then the
lowest index; a task its owner leaves out goes to the next process by the same rule
for a short second round); each process searches its tasks on its satellites, drops
what the independent check (:func:`jaxspline.planning.repair.drop_failing`) rejects, and
the disjoint parts are merged. Process 0 writes the merged plan (observations with
satellite, target, start, end, value), its value, the bound and the gap. Left out,
unlike ``jaxspline plan``: start-time refinement, flown-join screening and AEM files,
figures and the web page, the HiGHS certificate, and a search across the shards (a
task is only ever tried on the satellites of its owner, then of the next process).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time

from jaxspline.planning.files import atomic_write_text

__all__ = ["SEARCH_TIME_S", "register", "run_bound"]

SEARCH_TIME_S = 30.0  # default search budget of --plan after the bound phase [s]


def register(sub) -> None:
    """Register the ``bound`` sub-command.

    Args:
      sub: the ``argparse`` sub-parsers object of the ``jaxspline`` command.
    """
    p = sub.add_parser(
        "bound",
        help="Lagrangian upper bound of a scenario, optionally sharded over processes",
        description=__doc__,
    )
    p.add_argument("scenario", nargs="?", help="scenario TOML (default: built-in scenario)")
    p.add_argument("--time-limit", type=float, default=60.0, help="iteration budget [s]")
    p.add_argument("--max-iters", type=int, default=None, help="cap on the iterations")
    p.add_argument(
        "--target",
        type=float,
        default=None,
        help="plan value for the step size (default: the greedy plans' total)",
    )
    p.add_argument("--json", default=None, help="write the result here (process 0)")
    p.add_argument(
        "--plan",
        default=None,
        metavar="PLAN.json",
        help="also search a plan, sharded like the bound, and write the merged plan here "
        "(process 0)",
    )
    p.add_argument(
        "--search-time",
        type=float,
        default=SEARCH_TIME_S,
        help=f"with --plan: search budget after the bound [s] (default {SEARCH_TIME_S:g})",
    )
    p.add_argument(
        "--search-iters",
        type=int,
        default=None,
        metavar="N",
        help="with --plan: cap each process's search at N LNS iterations (N/10 Lagrangian); "
        "with --max-iters the plan is the same on every run (default: time-bound)",
    )
    p.add_argument("--seed", type=int, default=0, help="with --plan: search seed (default 0)")
    p.add_argument("--force", action="store_true", help="overwrite --json and --plan")
    p.add_argument("--coordinator", default=None, help="HOST:PORT of process 0")
    p.add_argument("--num-processes", type=int, default=1)
    p.add_argument("--process-id", type=int, default=0)
    p.set_defaults(func=_main)


def _main(args) -> int:
    res = run_bound(
        args.scenario,
        time_limit=args.time_limit,
        max_iters=args.max_iters,
        target=args.target,
        json_path=args.json,
        plan_path=args.plan,
        search_time=args.search_time,
        search_iters=args.search_iters,
        seed=args.seed,
        force=args.force,
        coordinator=args.coordinator,
        num_processes=args.num_processes,
        process_id=args.process_id,
    )
    if res["process"] == 0:
        print(
            f"bound {res['bound']:.6g} ({res['status']}, {res['iterations']} iterations, "
            f"{res['processes']} process(es), {res['seconds']:.1f} s)",
            file=sys.stdout,
        )
        if args.plan is not None:
            print(
                f"plan {res['value']:.6g}, gap {res['gap']:.6g} ({res['observations']} "
                f"observations) -> {args.plan}",
                file=sys.stdout,
            )
    return 0


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
) -> dict:
    """Screen ``scenario`` and iterate its Lagrangian bound (module docstring).

    Args:
      scenario: scenario TOML path, a Scenario, or None (the default scenario).
      time_limit: iteration budget [s] after screening.
      max_iters: cap on the iterations (None: the time limit alone).
      target: step-size target; None: the sum of each process's greedy plan values
        (the same in every process).
      json_path: process 0 writes the result dict here (atomically).
      plan_path: also search a plan (module docstring); process 0 writes it here
        (atomically). None: the bound alone.
      search_time: with ``plan_path``, the search budget after the bound phase [s].
      search_iters: with ``plan_path``, the cap of each process's search (``max_iters``
        of :func:`jaxspline.search.solve`); None: ``search_time`` alone.
      seed: with ``plan_path``, the search seed.
      force: overwrite ``json_path`` and ``plan_path``.
      coordinator: ``HOST:PORT`` of process 0 for ``jax.distributed``; None: one process.
      num_processes, process_id: this run's place among the processes.
    Returns:
      dict: bound, status, iterations, processes, process, satellites (owned here),
      near_pairs (here), seconds; with ``plan_path`` also value, gap and observations
      (their number).
    Raises:
      ValueError: bad arguments (more processes than satellites, bad limits).
    """
    import jax
    import numpy as np

    from jaxspline.io.scenario import scenario_from
    from jaxspline.planning.files import refuse_overwrite
    from jaxspline.planning.planner import build_problem
    from jaxspline.planning.repair import drop_failing
    from jaxspline.search import Timeline, greedy
    from jaxspline.search.sharded import (
        jax_allgather,
        owned_satellites,
        sharded_plan,
        sharded_upper_bound,
    )

    if not (math.isfinite(time_limit) and time_limit > 0):
        raise ValueError(f"time_limit must be a number > 0, got {time_limit!r}")
    if plan_path is not None:
        if not (math.isfinite(search_time) and search_time > 0):
            raise ValueError(f"search_time must be a number > 0, got {search_time!r}")
        if search_iters is not None and not (isinstance(search_iters, int) and search_iters >= 1):
            raise ValueError(f"search_iters must be an integer >= 1, got {search_iters!r}")
    for path in (json_path, plan_path):
        if path is not None and process_id == 0:
            refuse_overwrite(path, force)
    if coordinator is not None:  # before any JAX computation (scenario loading included)
        if num_processes < 1:
            raise ValueError(f"num_processes must be >= 1, got {num_processes!r}")
        jax.config.update("jax_cpu_collectives_implementation", "gloo")
        jax.distributed.initialize(coordinator, num_processes, process_id)
        index, count, allgather = jax.process_index(), jax.process_count(), jax_allgather
    else:
        index, count = 0, 1

        def allgather(x):
            return np.asarray(x, np.float64)[None]

    sc = scenario_from(scenario)
    if count > len(sc.satellites):
        raise ValueError(
            f"num_processes must be at most the {len(sc.satellites)} satellites (one at "
            f"least per process), got {count!r}"
        )
    try:
        with jax.enable_x64(True):  # float64 through the collectives too
            t0 = time.monotonic()
            owned = owned_satellites(len(sc.satellites), index, count)
            shard = dataclasses.replace(sc, satellites=tuple(sc.satellites[k] for k in owned))
            prep = build_problem(
                shard, reduce_slack=lambda s: float(allgather(np.array([s])).min())
            )
            pb = prep.problem
            if target is None:
                tl = Timeline(pb)
                greedy(tl, math.inf)
                target = float(allgather(np.array([tl.W])).sum())
            deadline = time.monotonic() + time_limit
            merged = None
            if plan_path is None:
                res = sharded_upper_bound(
                    pb, owned, len(sc.satellites), target, deadline, max_iters, allgather
                )
            else:

                def check(ids):
                    scene, usable, opp = prep.scene, prep.orbits.usable, prep.opportunities
                    return drop_failing(shard, scene, usable, opp, ids, prep.battery)[0]

                merged = sharded_plan(
                    pb,
                    owned,
                    len(sc.satellites),
                    index,
                    target,
                    deadline,
                    search_time,
                    bound_iters=max_iters,
                    search_iters=search_iters,
                    seed=seed,
                    lagrangian_share=sc.planner.lagrangian_share,
                    exact_max_options=sc.planner.exact_max_options,
                    check=check,
                    allgather=allgather,
                )
                res = merged.bound
            out = {
                "scenario": sc.name,
                "bound": res.bound,
                "status": res.status,
                "iterations": res.iterations,
                "target": target,
                "processes": count,
                "process": index,
                "satellites": [sc.satellites[k].name for k in owned],
                "near_pairs": len(pb.pairs),
                "seconds": round(time.monotonic() - t0, 3),
            }
            if merged is not None:
                doc = _plan_doc(sc, merged, count)
                out.update(value=doc["value"], gap=doc["gap"])
                out["observations"] = len(doc["observations"])
                if index == 0:
                    atomic_write_text(plan_path, json.dumps(doc, indent=1) + "\n", force=force)
            if json_path is not None and index == 0:
                atomic_write_text(json_path, json.dumps(out, indent=1) + "\n", force=force)
            return out
    finally:
        if coordinator is not None:
            jax.distributed.shutdown()


def _plan_doc(sc, mp, count: int) -> dict:
    """The ``--plan`` JSON of a :class:`jaxspline.search.sharded.ShardedPlan`."""
    import numpy as np

    tg = sc.targets
    tasks = np.flatnonzero(mp.sat >= 0)
    tasks = tasks[np.lexsort((mp.start[tasks], mp.sat[tasks]))]  # by satellite, then start
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
            for t in tasks
        ],
    }
