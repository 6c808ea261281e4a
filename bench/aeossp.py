"""aeossp_standard cases: plan each through ``jaxspline.plan``, check it, tabulate.

Run by ``python scripts/aeossp_train.py --data DIR`` (the cases are not in this
repository), which writes ``aeossp.json`` and ``AEOSSP.md`` into ``bench/results``.
Per case: :func:`jaxspline.aeossp.adapter.solve_case` (wall time around it, loading
included), then the independent checker :func:`jaxspline.aeossp.check.check_solution`:
validity, WCR, CR, TAT, PC, the number of actions, the plan's own bound on WCR (the
candidate model's Lagrangian bound, planner margins) and its status.

``certificates`` in ``aeossp.json`` (case -> WCR bound) are the HiGHS bounds of
``python scripts/aeossp_upper_bound.py --mip SECONDS CASE_DIR...`` on the candidate model
with margins looser than the rules, so they bound every valid plan; the table shows them
where present.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from bench.markdown import cell, header, row, section, write_result

#: Columns of the table of ``AEOSSP.md``, one case a row.
CASE_COLUMNS = (
    "case|valid|WCR|bound|bound status|gap|HiGHS bound|gap to it|CR|TAT s|PC Wh|actions|wall s"
).split("|")


def solve_cases(data: Path, cases, time_limit: float, seed: int, solutions, progress) -> list:
    """Plan and check every case of ``data`` (or those named); one dict per case.

    Args:
      data: folder of case folders (the benchmark's ``train`` split).
      cases: case names, or None for every folder of ``data``.
      time_limit: planning budget per case [s].
      seed: the search's seed.
      solutions: folder for the solution JSON files, or None.
      progress: print the solver's progress lines.
    """
    from jaxspline.aeossp.adapter import solve_case
    from jaxspline.aeossp.case import load_case
    from jaxspline.aeossp.check import check_solution

    names = cases or sorted(p.name for p in data.iterdir() if p.is_dir())
    rows = []
    for name in names:
        t0 = time.monotonic()
        case = load_case(data / name)
        sol, res = solve_case(case, time_limit=time_limit, progress=progress, seed=seed)
        wall = time.monotonic() - t0
        if solutions:
            Path(solutions).mkdir(parents=True, exist_ok=True)
            (Path(solutions) / f"{name}.json").write_text(json.dumps(sol))
        rep = check_solution(case, sol)
        m = rep.metrics
        rows.append(
            {
                "case": name,
                "valid": bool(rep.valid),
                "violations": len(rep.violations),
                **{k: m[k] for k in ("WCR", "CR", "TAT", "PC")},
                "actions": len(sol["actions"]),
                "wall_s": round(wall, 2),
                "bound": res.bound / (res.total_value or 1.0),
                "bound_status": str(res.stats["bound_status"]),
            }
        )
        print(case_line(rows[-1]), flush=True)
    return rows


def case_line(r: dict) -> str:
    """One progress line of a checked case."""
    return (
        f"{r['case']}: {'valid' if r['valid'] else 'INVALID'} WCR={cell(r['WCR'], '{:.4f}')} "
        f"bound={cell(r['bound'], '{:.4f}')} ({r['bound_status']}) "
        f"wall={cell(r['wall_s'], '{:.1f}')} s"
    )


def _mean(values) -> float | None:
    vals = [v for v in values if v is not None]
    return sum(vals) / len(vals) if vals else None


def _case_row(r: dict, cert: float | None) -> str:
    gap = None if r.get("bound") is None else r["bound"] - r["WCR"]
    gap_cert = None if cert is None else cert - r["WCR"]
    return row(
        [
            r["case"],
            cell(r.get("valid")),
            cell(r.get("WCR"), "{:.4f}"),
            cell(r.get("bound"), "{:.4f}"),
            cell(r.get("bound_status")),
            cell(gap, "{:.4f}"),
            cell(cert, "{:.4f}"),
            cell(gap_cert, "{:.4f}"),
            cell(r.get("CR"), "{:.4f}"),
            cell(r.get("TAT"), "{:.1f}"),
            cell(r.get("PC"), "{:.1f}"),
            cell(r.get("actions"), "{:d}"),
            cell(r.get("wall_s"), "{:.1f}"),
        ]
    )


def aeossp_table(report: dict) -> list[str]:
    """Markdown: one row per case and the means (section ``cases``)."""
    cases, certs = report.get("cases", []), report.get("certificates", {})
    body = [*header(*CASE_COLUMNS), *(_case_row(r, certs.get(r["case"])) for r in cases)]
    if cases:
        mean = {k: _mean(r.get(k) for r in cases) for k in ("WCR", "bound", "CR")}
        mean_cert = _mean(certs.get(r["case"]) for r in cases)
        valid = sum(bool(r.get("valid")) for r in cases)
        gap = None if mean["bound"] is None else mean["bound"] - mean["WCR"]
        gap_cert = None if mean_cert is None else mean_cert - mean["WCR"]
        cells = [f"{valid}/{len(cases)}", cell(mean["WCR"], "**{:.4f}**")]
        cells += [cell(mean["bound"], "{:.4f}"), "", cell(gap, "{:.4f}")]
        cells += [cell(mean_cert, "{:.4f}"), cell(gap_cert, "{:.4f}")]
        body.append(row(["**mean**", *cells, cell(mean["CR"], "{:.4f}"), "", "", "", ""]))
    lines = [
        f"\n`python scripts/aeossp_train.py --data DIR --time-limit "
        f"{report.get('time_limit_s', 60):g} --seed {report.get('seed', 0)}`: each case "
        "planned through `jaxspline.plan` (wall time includes loading), then checked by "
        "the independent checker. *bound* is the plan's own Lagrangian bound on WCR and "
        "*gap* its distance to the plan's WCR; *HiGHS bound* the offline certificate of "
        "`scripts/aeossp_upper_bound.py --mip`, which bounds every valid plan.",
        *section("cases", body),
    ]
    if report.get("note"):
        lines.append(f"\n{report['note']}")
    return lines


def write_aeossp(report: dict, out: Path) -> None:
    """Write ``aeossp.json`` and ``AEOSSP.md`` into ``out`` and print the table."""
    write_result(out, "aeossp", report, "aeossp_standard training cases", aeossp_table(report))
