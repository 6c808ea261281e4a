"""``jaxspline bound [SCENARIO.toml]``: the Lagrangian upper bound, on one or many processes.

Screens the scenario like ``jaxspline plan`` and iterates the Lagrangian bound of the
option model (per-satellite longest paths under target prices, battery relaxed),
without searching for a plan. ``--time-limit`` bounds the whole command, from the start
of its process, as ``jaxspline plan``'s does: the stages before the iterations stop with
exit 3, an estimate and the remedy when it runs out there (up to 20 s of compiling are
not counted: :mod:`jaxspline.planner.deadline`); the iterations stop at its end. With
``--coordinator HOST:PORT --num-processes N
--process-id I`` (one command per process, on one or several hosts, the same scenario
file everywhere) the satellites are sharded over the processes through
``jax.distributed`` (:mod:`jaxspline.planner.sharded`): each process screens,
stores and solves only its satellites, and all report the bound a single process
would. Process 0 prints the result and writes ``--json``.

With ``--plan PLAN.json`` the processes also search a plan, sharded the same way
(:func:`jaxspline.planner.sharded.sharded_plan`): after the bound phase every
target gets one owner process (merge rule: the process whose satellites' DP paths at
the best prices take it most often, then the one with most of its options, then the
lowest index; a target its owner leaves out goes to the next process by the same rule
for a short second round); each process searches its targets on its satellites, drops
what the independent check (:func:`jaxspline.planner.repair.drop_failing`) rejects, and
the disjoint parts are merged. Process 0 writes the merged plan (observations with
satellite, target, start, end, value), its value, the bound and the gap. Left out,
unlike ``jaxspline plan``: start-time refinement, flown-join screening and AEM files,
figures and the web page, the HiGHS certificate, and a search across the shards (a
target is only ever tried on the satellites of its owner, then of the next process).
"""

from __future__ import annotations

import sys

from jaxspline.cli.flags import (
    MAX_ITERS,
    MAX_PROCESSES,
    MAX_SEED,
    check_host_port,
    check_int,
    check_output_file,
    check_path,
    check_seconds,
    check_value,
)

__all__ = ["check_bound_flags", "register"]


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
    p.add_argument(
        "--time-limit",
        type=float,
        default=60.0,
        help="wall-clock budget [s] of the whole command, from its start (default 60): the "
        "stages before the iterations stop with exit 3 when it runs out there, the "
        "iterations at its end; with --plan, --search-time follows",
    )
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
        default=None,
        help="with --plan: search budget after the bound [s] (default 30)",
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


def check_bound_flags(args) -> None:
    """The flags of ``jaxspline bound``, each by its name, before any work.

    Args:
      args: the parsed ``argparse`` namespace.
    Raises:
      ValueError: naming the flag and its value.
    """
    check_path("SCENARIO", args.scenario, kind="file")
    check_seconds("--time-limit", args.time_limit)
    check_int("--max-iters", args.max_iters, 1, MAX_ITERS)
    check_value("--target", args.target)
    check_output_file("--json", args.json, force=args.force)
    check_output_file("--plan", args.plan, force=args.force)
    check_seconds("--search-time", args.search_time)
    check_int("--search-iters", args.search_iters, 1, MAX_ITERS)
    check_int("--seed", args.seed, 0, MAX_SEED)
    check_host_port("--coordinator", args.coordinator)
    check_int("--num-processes", args.num_processes, 1, MAX_PROCESSES)
    check_int("--process-id", args.process_id, 0, args.num_processes - 1)
    if args.num_processes > 1 and args.coordinator is None:
        raise ValueError("--num-processes: more than one process needs --coordinator HOST:PORT")
    if args.plan is None and (args.search_time is not None or args.search_iters is not None):
        raise ValueError("--search-time / --search-iters: only with --plan PLAN.json")
    same = args.json is not None and args.json == args.plan
    if same:
        raise ValueError(f"--json and --plan: must be two files, both are {args.json!r}")


def _main(args) -> int:
    from jaxspline.planner.bound import run_bound
    from jaxspline.planner.memory_guard import MemoryGuard

    check_bound_flags(args)

    more = {} if args.search_time is None else {"search_time": args.search_time}
    res = run_bound(
        args.scenario,
        time_limit=args.time_limit,
        max_iters=args.max_iters,
        target=args.target,
        json_path=args.json,
        plan_path=args.plan,
        search_iters=args.search_iters,
        seed=args.seed,
        force=args.force,
        coordinator=args.coordinator,
        num_processes=args.num_processes,
        process_id=args.process_id,
        memory=MemoryGuard(),
        t_start=getattr(args, "started", None),
        **more,
    )
    if res.process == 0:
        print(
            f"bound {res.bound:.6g} ({res.status}, {res.iterations} iterations, "
            f"{res.processes} process(es), {res.seconds:.1f} s)",
            file=sys.stdout,
        )
        if args.plan is not None:
            print(
                f"plan {res.value:.6g}, gap {res.gap:.6g} ({res.observations} "
                f"observations) -> {args.plan}",
                file=sys.stdout,
            )
    return 0
