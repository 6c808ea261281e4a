"""Plan every aeossp_standard training case through jaxspline.plan and check each plan.

Usage (from the repository root)::

    python scripts/aeossp_train.py --data DIR [--time-limit 60] [--seed 0]
                                   [--out bench/results] [--solutions DIR]
                                   [--cases case_0001 ...]

``--data`` is the ``train`` folder of the public aeossp_standard benchmark (see
docs/aeossp.md; this repository does not ship the cases). For each case:
:func:`jaxspline.aeossp.adapter.solve_case` (wall time measured around it, loading
included), then the independent checker ``jaxspline.aeossp.check.check_solution``.
Prints a line per case and writes ``aeossp.json`` and ``AEOSSP.md`` (validity, WCR, the
plan's Lagrangian bound and its status, CR, TAT, PC, actions, wall time, the means) into
``--out`` (default ``bench/results`` of this repository); the HiGHS certificates already
recorded there are kept. Solutions go to ``--solutions DIR`` if given. Exit 0 when every
plan is valid.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:  # bench/ is a folder of the checkout, not installed
    sys.path.insert(0, str(REPO))

from bench.aeossp import solve_cases, write_aeossp  # noqa: E402


def main(argv=None) -> int:
    """Command line: plan, check, write the results; exit 0 when every plan is valid."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, required=True, help="the benchmark's train folder")
    ap.add_argument("--time-limit", type=float, default=60.0, help="per case [s] (60)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "results")
    ap.add_argument("--solutions", default=None, help="directory for the solution JSON files")
    ap.add_argument("--cases", nargs="*", default=None)
    ap.add_argument("--quiet", action="store_true", help="no solver progress lines")
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        ap.error(f"--data: no such folder: {args.data}")

    rows = solve_cases(
        args.data, args.cases, args.time_limit, args.seed, args.solutions, not args.quiet
    )
    old = args.out / "aeossp.json"
    certs = json.loads(old.read_text()).get("certificates", {}) if old.is_file() else {}
    report = {"time_limit_s": args.time_limit, "seed": args.seed, "cases": rows}
    if certs:
        report["certificates"] = certs
    write_aeossp(report, args.out)
    return 0 if all(r["valid"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
