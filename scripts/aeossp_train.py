"""Plan every aeossp_standard training case through jaxspline.plan and check each plan.

Usage::

    python scripts/aeossp_train.py [--data DIR] [--time-limit 60] [--seed 0]
                                   [--out aeossp_train.md] [--cases case_0001 ...]

For each case: :func:`jaxspline.aeossp.adapter.solve_case` (wall time measured around
it, loading included), then the independent checker
``jaxspline.aeossp.check.check_solution``. Prints per-case validity, WCR, the plan's
Lagrangian bound (candidate model, battery relaxed) and its status, CR, TAT, PC and
wall time, and writes a markdown table (with the means) to ``--out``. Solutions go to
``--solutions DIR`` if given. The cases come from the public aeossp_standard
benchmark (see docs/aeossp.md); ``--data`` points at its ``train`` directory.
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
    args = ap.parse_args(argv)

    from jaxspline.aeossp.adapter import solve_case
    from jaxspline.aeossp.case import load_case
    from jaxspline.aeossp.check import check_solution

    data = Path(args.data)
    cases = args.cases or sorted(p.name for p in data.iterdir() if p.is_dir())
    rows = []
    for name in cases:
        t0 = time.monotonic()
        case = load_case(data / name)
        sol, res = solve_case(
            case, time_limit=args.time_limit, progress=not args.quiet, seed=args.seed
        )
        wall = time.monotonic() - t0
        if args.solutions:
            Path(args.solutions).mkdir(parents=True, exist_ok=True)
            (Path(args.solutions) / f"{name}.json").write_text(json.dumps(sol))
        rep = check_solution(case, sol)
        tw = res.total_value or 1.0
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
            res.bound / tw,
            res.stats["bound_status"],
        )
        rows.append(row)
        tat = float("nan") if row[4] is None else row[4]
        print(
            f"{name}: {row[1]} WCR={row[2]:.4f} CR={row[3]:.4f} TAT={tat:.1f}s "
            f"PC={row[5]:.1f}Wh actions={row[6]} wall={wall:.1f}s "
            f"bound={row[8]:.4f} ({row[9]}) gap={row[8] - row[2]:.4f}",
            flush=True,
        )
    n = max(1, len(rows))
    mean_wcr = sum(r[2] for r in rows) / n
    mean_cr = sum(r[3] for r in rows) / n
    n_valid = sum(1 for r in rows if r[1] == "valid")
    lines = [
        f"# aeossp_standard train: time limit {args.time_limit:g} s, seed {args.seed}",
        "",
        "| case | validity | WCR | bound | gap | CR | TAT [s] | PC [Wh] | actions | wall [s] |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        tat = "n/a" if r[4] is None else f"{r[4]:.1f}"
        cells = [r[0], r[1], f"{r[2]:.4f}", f"{r[8]:.4f} ({r[9]})", f"{r[8] - r[2]:.4f}"]
        cells += [f"{r[3]:.4f}", tat, f"{r[5]:.1f}", str(r[6])]
        lines.append("| " + " | ".join(cells) + f" | {r[7]:.1f} |")
    mean_ub = sum(r[8] for r in rows) / n
    lines.append(
        f"| **mean** | {n_valid}/{len(rows)} valid | **{mean_wcr:.4f}** | {mean_ub:.4f} | "
        f"{mean_ub - mean_wcr:.4f} | {mean_cr:.4f} | | | | |"
    )
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(text)
    print(text)
    return 0 if n_valid == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
