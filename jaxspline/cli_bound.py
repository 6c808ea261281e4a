"""``jaxspline bound [SCENARIO.toml]``: the Lagrangian upper bound, on one or many processes.

Screens the scenario like ``jaxspline plan`` and iterates the Lagrangian bound of the
candidate model (per-satellite longest paths under task prices, battery relaxed),
without searching for a plan. With ``--coordinator HOST:PORT --num-processes N
--process-id I`` (one command per process, on one or several hosts, the same scenario
file everywhere) the satellites are sharded over the processes through
``jax.distributed`` (:mod:`jaxspline.engine.search.sharded`): each process screens,
stores and solves only its satellites, and all report the bound a single process
would. Process 0 prints the result and writes ``--json``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time

from jaxspline.engine._io import atomic_write_text

__all__ = ["register", "run_bound"]


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
    p.add_argument("--force", action="store_true", help="overwrite --json")
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
    return 0


def run_bound(
    scenario=None,
    *,
    time_limit: float = 60.0,
    max_iters: int | None = None,
    target: float | None = None,
    json_path=None,
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
      force: overwrite ``json_path``.
      coordinator: ``HOST:PORT`` of process 0 for ``jax.distributed``; None: one process.
      num_processes, process_id: this run's place among the processes.
    Returns:
      dict: bound, status, iterations, processes, process, satellites (owned here),
      near_pairs (here), seconds.
    Raises:
      ValueError: bad arguments (more processes than satellites, bad limits).
    """
    import jax
    import numpy as np

    from jaxspline.engine._io import refuse_overwrite
    from jaxspline.engine.planner import build_problem
    from jaxspline.engine.search import Timeline, greedy
    from jaxspline.engine.search.sharded import (
        jax_allgather,
        owned_satellites,
        sharded_upper_bound,
    )
    from jaxspline.scenario import scenario_from

    if not (math.isfinite(time_limit) and time_limit > 0):
        raise ValueError(f"time_limit must be a number > 0, got {time_limit!r}")
    if json_path is not None and process_id == 0:
        refuse_overwrite(json_path, force)
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
            res = sharded_upper_bound(
                pb, owned, len(sc.satellites), target, deadline, max_iters, allgather
            )
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
            if json_path is not None and index == 0:
                atomic_write_text(json_path, json.dumps(out, indent=1) + "\n", force=force)
            return out
    finally:
        if coordinator is not None:
            jax.distributed.shutdown()
