"""Solve every stereo_imaging training case through ``jaxspline stereo solve`` and check it.

Usage (from the repository root)::

    python scripts/stereo_train.py --data DIR [--time-limit 120] [--seed 0]
                                   [--out bench/results] [--solutions DIR]
                                   [--cases case_0001 ...]

``--data`` is the ``train`` folder of the public stereo_imaging benchmark (see
docs/stereo.md; this repository does not ship the cases). For each case the whole
command ``jaxspline stereo solve CASE -o SOLUTION.json --time-limit T --seed S`` runs as
a subprocess (wall time and peak RSS measured around it, :mod:`bench.stereo`), then the
independent checker ``jaxspline.stereo.check.check_solution`` checks the written
solution and ``jaxspline.stereo.bound.coverage_bound`` bounds the case's coverage.
Prints a line per case and writes ``stereo.json`` and ``STEREO.md`` (validity, coverage
and its bound, quality, valid pairs and triples, looks, the plan's value / bound / gap,
wall time, peak RSS, the means, the load average at the start and the end) into
``--out`` (default ``bench/results`` of this repository). Solutions go to
``--solutions DIR`` if given. Exit 0 when every solution is valid.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:  # bench/ is a folder of the checkout, not installed
    sys.path.insert(0, str(REPO))

from bench.stereo import solve_cases, write_stereo  # noqa: E402


def main(argv=None) -> int:
    """Command line: solve, check, write the results; exit 0 when every solution is valid."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, required=True, help="the benchmark's train folder")
    ap.add_argument("--time-limit", type=float, default=120.0, help="per case [s] (120)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "results")
    ap.add_argument("--solutions", default=None, help="directory for the solution JSON files")
    ap.add_argument("--cases", nargs="*", default=None)
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        ap.error(f"--data: no such folder: {args.data}")
    missing = [c for c in args.cases or [] if not (args.data / c).is_dir()]
    if missing:
        ap.error(f"--cases: no such case folder in {args.data}: {', '.join(missing)}")

    load_start = os.getloadavg()[0]
    rows = solve_cases(args.data, args.cases, args.time_limit, args.seed, args.solutions)
    report = {
        "time_limit_s": args.time_limit,
        "seed": args.seed,
        "cpus": os.cpu_count(),
        "load_avg": {"start": round(load_start, 2), "end": round(os.getloadavg()[0], 2)},
        "cases": rows,
    }
    write_stereo(report, args.out)
    return 0 if rows and all(r.get("valid") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
