"""Run the aeossp_standard solver on every training case and check each plan.

Usage::

    nice python scripts/aeossp_train.py [--data DIR] [--time-limit 60] [--seed 0]
                                        [--out aeossp_train.md] [--cases case_0001 ...]

For each case: ``solve_case`` (wall time measured around it, loading included),
then the independent checker ``jaxspline.aeossp.check.check_solution``. Prints
per-case validity, WCR, CR, TAT, PC and wall time, and writes a markdown table
(with the mean WCR) to ``--out``. Solutions go to ``--solutions DIR`` if given.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

DEFAULT_DATA = "/work/shared/data/aeossp_standard/train"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=DEFAULT_DATA)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="aeossp_train.md")
    ap.add_argument("--solutions", default=None, help="directory for the solution JSON files")
    ap.add_argument("--cases", nargs="*", default=None)
    ap.add_argument("--quiet", action="store_true", help="no solver progress lines")
    ap.add_argument("--thin", type=int, default=None, help="keep every n-th start")
    ap.add_argument("--off-nadir-margin", type=float, default=None, help="[deg]")
    ap.add_argument("--gap-margin", type=float, default=None, help="[s]")
    ap.add_argument("--dp-share", type=float, default=None, help="search share of the DP phase")
    args = ap.parse_args(argv)

    import jax

    jax.config.update("jax_enable_x64", True)
    from jaxspline.aeossp.case import load_case
    from jaxspline.aeossp.check import check_solution
    from jaxspline.aeossp.solve import Margins, solve_case

    kw = {}
    if args.thin is not None:
        kw["thin"] = args.thin
    if args.dp_share is not None:
        kw["dp_share"] = args.dp_share
    mk = {}
    if args.off_nadir_margin is not None:
        mk["off_nadir_deg"] = args.off_nadir_margin
    if args.gap_margin is not None:
        mk["gap_s"] = args.gap_margin
    if mk:
        kw["margins"] = Margins(**mk)

    data = Path(args.data)
    cases = args.cases or sorted(p.name for p in data.iterdir() if p.is_dir())
    rows = []
    for name in cases:
        t0 = time.monotonic()
        sol, st = solve_case(
            data / name,
            time_limit=args.time_limit,
            progress=not args.quiet,
            seed=args.seed,
            return_stats=True,
            **kw,
        )
        wall = time.monotonic() - t0
        if args.solutions:
            Path(args.solutions).mkdir(parents=True, exist_ok=True)
            (Path(args.solutions) / f"{name}.json").write_text(json.dumps(sol))
        rep = check_solution(load_case(data / name), sol)
        m = rep.metrics
        row = (
            name,
            "valid" if rep.valid else f"INVALID ({len(rep.violations)})",
            m["WCR"],
            m["CR"],
            m["TAT"],
            m["PC"],
            len(sol["actions"]),
            wall,
        )
        rows.append(row)
        tat = float("nan") if row[4] is None else row[4]
        print(
            f"{name}: {row[1]} WCR={row[2]:.4f} CR={row[3]:.4f} TAT={tat:.1f}s "
            f"PC={row[5]:.1f}Wh actions={row[6]} wall={wall:.1f}s "
            f"greedy={st['greedy_wcr']:.4f} lagrangian_UB={st['lagrangian_ub_wcr']:.4f}",
            flush=True,
        )
    n = max(1, len(rows))
    mean_wcr = sum(r[2] for r in rows) / n
    mean_cr = sum(r[3] for r in rows) / n
    n_valid = sum(1 for r in rows if r[1] == "valid")
    lines = [
        f"# aeossp_standard train: time limit {args.time_limit:g} s, seed {args.seed}",
        "",
        "| case | validity | WCR | CR | TAT [s] | PC [Wh] | actions | wall [s] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        tat = "n/a" if r[4] is None else f"{r[4]:.1f}"
        cells = [r[0], r[1], f"{r[2]:.4f}", f"{r[3]:.4f}", tat, f"{r[5]:.1f}", str(r[6])]
        lines.append("| " + " | ".join(cells) + f" | {r[7]:.1f} |")
    lines.append(
        f"| **mean** | {n_valid}/{len(rows)} valid | **{mean_wcr:.4f}** | {mean_cr:.4f} | | | | |"
    )
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(text)
    print(text)
    return 0 if n_valid == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
