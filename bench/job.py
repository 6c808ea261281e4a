"""Job section: the default job, ``jaxspline plan --max-iters N -o DIR``, as a user runs it.

``python -m bench --section job [--job-runs R] [--job-max-iters N] [--max-rss-gb G]
[--max-wall-min M]`` plans the packaged default scenario R times (default 2) with every
output (figures, ``plan.html``, the AEM files: the command's defaults) as a subprocess
under ``/usr/bin/time -v``. The first run starts from an empty compilation cache (a
fresh clone: every XLA program compiled), the others load the programs it stored.
``--max-iters N`` (default ``JOB_MAX_ITERS``) caps the search, so the plan is the same on
every machine and under any load and only the times measure the machine; with
``--job-max-iters 0`` the runs are the README's time-limited command verbatim, whose
plan depends on what the machine gets done in the budget (compilation included).
Each run's ``plan.json`` gives the stage times, the per-stage peak RSS, the plan
(observations, value, bound, gap, check), the repair loop (dropped per reason, rounds)
and the flown joins (count, re-timed, rejected, refilled, worst ratios to the limits).
Writes ``job.json`` and ``JOB.md``.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from bench.markdown import cell, header, row, run_cells, section, write_result
from bench.scale import MAX_RSS_GB, MAX_WALL_MIN, child_env, run_plan, stage_table

#: Runs of the section by default: one from an empty cache, one warm.
JOB_RUNS = 2
#: The search's iteration cap of the runs by default (the reproducible plan).
JOB_MAX_ITERS = 200
#: Columns of the summary table of ``JOB.md``, one run a row.
JOB_COLUMNS = (
    "run|exit|wall s|peak RSS MB|load|windows|options|near pairs|observations|value|bound|"
    "bound status|gap %|valid|dropped check / battery / joins|repair rounds|LNS it.|"
    "worker it."
).split("|")
#: Columns of the flown-joins table of ``JOB.md``.
JOIN_COLUMNS = (
    "run|joins|re-timed|rejected|refilled|violating|worst rate ratio|worst accel ratio|"
    "worst jerk ratio"
).split("|")


def bench_job(
    runs: int = JOB_RUNS,
    max_iters: int = JOB_MAX_ITERS,
    max_rss_gb: float = MAX_RSS_GB,
    max_wall_min: float = MAX_WALL_MIN,
    workdir: str | None = None,
) -> dict:
    """Plan the default job ``runs`` times, the first from an empty compilation cache.

    ``max_iters`` > 0 caps the search (``--max-iters``); 0 leaves the time limit alone.
    """
    if runs < 1:
        raise SystemExit(f"--job-runs: must be >= 1, got {runs}")
    tmp = tempfile.TemporaryDirectory(prefix="jaxspline_job_") if workdir is None else None
    wd = Path(tmp.name if tmp else workdir)
    wd.mkdir(parents=True, exist_ok=True)
    env = dict(child_env(), JAXSPLINE_CACHE_DIR=str(wd / "xla"))  # empty at the first run
    args = ["--max-iters", str(max_iters)] if max_iters > 0 else []
    out = []
    try:
        for i in range(runs):
            label = "first (empty cache)" if i == 0 else f"warm {i}"
            print(f"job: {label} ...", flush=True)
            r = run_plan(f"job{i}", args, wd, (max_rss_gb, max_wall_min), env=env)
            out.append({"run": label, **r})
            print(f"  exit {r['exit']}, wall {r['wall_s']} s, value {r.get('value')}", flush=True)
    finally:
        if tmp is not None:
            tmp.cleanup()
    return {"runs": out, "cpus": os.cpu_count(), "max_rss_gb": max_rss_gb}


def _summary_row(r: dict) -> str:
    dropped = r.get("dropped") or {}
    drops = " / ".join(cell(dropped.get(k), "{:d}") for k in ("check", "battery", "joins"))
    return row(
        [
            r["run"],
            "killed" if r.get("killed") else str(r.get("exit")),
            *run_cells(r, "wall_s peak_rss_mb load_avg_before windows options near_pairs"),
            *run_cells(r, "observations value bound bound_status gap_pct valid"),
            drops,
            *run_cells(r, "repair_rounds lns_iterations worker_iterations"),
        ]
    )


def _joins_row(r: dict) -> str:
    j = r.get("joins") or {}
    counts = [cell(j.get(k), "{:d}") for k in ("joins", "retimed", "rejected", "refilled")]
    ratios = [cell(j.get(f"max_{k}_ratio"), "{:.3f}") for k in ("rate", "accel", "jerk")]
    return row([r["run"], *counts, cell(j.get("violating"), "{:d}"), *ratios])


def job_table(report: dict) -> list[str]:
    """Markdown of the section: the runs, their flown joins, their stages."""
    runs = report.get("runs", [])
    cmd = runs[0].get("command", "jaxspline plan") if runs else "jaxspline plan"
    return [
        f"\n`{cmd} -o DIR` (the packaged default scenario, every output), one subprocess "
        f"a run on a machine with {report.get('cpus', '-')} CPUs; the first run from an "
        "empty compilation cache, the others warm. With `--max-iters` the plan is the same "
        "on every machine; only the times depend on it. *load* is the load average when the "
        "run started; *dropped* counts the observations the repair loop removed per reason.",
        *section("runs", [*header(*JOB_COLUMNS), *(_summary_row(r) for r in runs)]),
        "\nFlown joins (degree-7 attitude joins between consecutive observations): "
        "re-timed, rejected (the later observation dropped), refilled (observations the "
        "refill added back); worst ratios of the sampled peaks to the satellite's limits.",
        *section("joins", [*header(*JOIN_COLUMNS), *(_joins_row(r) for r in runs)]),
        "\nPer stage: wall s / process peak RSS MB at the stage's end (plan.json); "
        "*other* = wall time outside the stages (start-up, loading, compilation cache, "
        "figures, page, writing).",
        *section("stages", stage_table(runs, "run")),
    ]


def write_job(report: dict, out: Path) -> None:
    """Write ``job.json`` and ``JOB.md`` into ``out`` and print the tables."""
    write_result(out, "job", report, "The default job", job_table(report["job"]))
