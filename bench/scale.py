"""Scale section: whole ``jaxspline plan`` runs as subprocesses, peak RSS and stage times.

``python -m bench --section scale [--sizes default:20,12x12h:120,day:540] [--time-limit S]
[--max-rss-gb G]`` plans each size with

    jaxspline plan [SCENARIO] --no-aem --no-plots --time-limit S -o DIR

(``python -m jaxspline.cli``, so the checkout's package runs) under
``/usr/bin/time -v`` (its ``Maximum resident set size`` is the peak RSS), reads
``DIR/plan.json`` (stage timings, per-stage peak RSS, windows, options, near pairs,
pair-store bytes, value, bound, gap, check) and writes ``scale.json`` and ``SCALE.md``
into the output folder. Plots are skipped: they measure matplotlib, not the planner.

Sizes: ``default`` (the packaged default job, no scenario argument), ``12x12h`` (made
by ``scripts/make_scale_scenario.py --preset 12x12h`` into the work folder),
``day`` (the packaged ``jaxspline/data/constellation_day.toml``), or a path to any
scenario TOML; ``SIZE:SECONDS`` gives that size its own planning budget (the others take
``--time-limit``). A field missing from ``plan.json`` (an older or newer planner, or a
killed run) is shown as "-".

Memory guard: the child's process tree is polled every ``POLL_S``. Its proportional
set size (every process in it, from ``/proc``: pages a fork shares count once) costs a
walk of each process's page tables (~0.1 s for a 4.6 GB planner, which it also stalls),
so it is read at most once in :data:`PSS_COST_RATIO` times the last read's duration; in
between, the estimate is the last PSS plus the growth of the tree's resident set since
(cheap to read; a page that becomes resident adds at most one page to either). Above
``--max-rss-gb`` the PSS is read at once, and if it is above too, the whole process
group is killed (SIGKILL) and the run is reported as killed with the last stage it
finished. The child may overshoot by what it allocates in one poll interval.
``RLIMIT_AS`` is no use here: XLA reserves far more address space than it touches.
A wall-clock cap (``--max-wall-min``) kills a run the same way.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.markdown import cell, header, row, run_cells, section, write_result

REPO = Path(__file__).resolve().parents[1]
DAY_TOML = REPO / "jaxspline" / "data" / "constellation_day.toml"
GENERATOR = REPO / "scripts" / "make_scale_scenario.py"
SIZES = ("default", "12x12h", "day")
POLL_S = 0.1
#: A PSS read is followed by at least this many times its own duration without one
#: (the poller's page-table walks: at most ~2 % of the time; the bench's day run had
#: 0.75 CPU-s a second for its search with a read every 0.1 s).
PSS_COST_RATIO = 50.0
MAX_RSS_GB = 8.0  # default guard: a third of the shared 24 GB machine
MAX_WALL_MIN = 60.0
TIME_BIN = "/usr/bin/time"
#: Columns of the summary table of ``SCALE.md``, one run a row.
RUN_COLUMNS = (
    "size|sats|targets|limit s|exit|wall s|peak RSS MB|windows|options|near pairs|bytes/pair|"
    "store MB|Lagr. it.|worker it.|LNS it.|value|bound|bound status|gap %|valid|load|"
    "plain bound|strengthened bound|worker status|DP it/s|LNS moves/s|LNS moves/CPU-s"
).split("|")
_STAGE_LINE = re.compile(r"\[plan [^\]]*\] (\w+)\s")


# ------------------------------------------------------------------ sizes
def split_limit(token: str, time_limit: float) -> tuple[str, float]:
    """(size, planning budget [s]) of a ``--sizes`` token ``SIZE`` or ``SIZE:SECONDS``."""
    size, sep, limit = token.rpartition(":")
    if not sep or not size:
        return token, time_limit
    try:
        seconds = float(limit)
    except ValueError:
        raise SystemExit(f"--sizes: {token!r}: the budget after ':' must be seconds") from None
    if not seconds > 0:
        raise SystemExit(f"--sizes: {token!r}: the budget must be positive, got {seconds:g}")
    return size, seconds


def resolve_size(token: str, workdir: Path) -> tuple[str, Path | None]:
    """(label, scenario TOML or None for the packaged default) of a ``--sizes`` token."""
    if token == "default":
        return token, None
    if token == "day":
        return token, DAY_TOML
    if token == "12x12h":
        path = workdir / "scale_12x12h.toml"
        if not path.exists():
            cmd = [sys.executable, str(GENERATOR), "--preset", "12x12h", "--out", str(path)]
            subprocess.run(cmd, check=True, capture_output=True, text=True, env=child_env())
        return token, path
    path = Path(token)
    if path.suffix == ".toml" and path.is_file():
        return path.stem, path
    raise SystemExit(f"--sizes: unknown size {token!r} (use {', '.join(SIZES)} or a .toml file)")


def repo_relative(arg: str) -> str:
    """``arg`` relative to the repository when it is a path inside it, else unchanged."""
    path = Path(arg)
    if path.is_absolute() and path.is_relative_to(REPO):
        return str(path.relative_to(REPO))
    return arg


def child_env() -> dict:
    """The environment with this checkout first on PYTHONPATH (its jaxspline runs)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(REPO), env.get("PYTHONPATH")) if p)
    return env


# ------------------------------------------------------------------ memory of a process tree
def _children_proc(pid: int) -> list[int]:
    out = []
    try:
        for tid in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{tid}/children") as fh:
                out += [int(x) for x in fh.read().split()]
    except OSError:
        pass
    return out


def _rss_proc(pid: int, pss: bool = True) -> int:
    """Memory of one process [bytes]: its proportional set size (shared pages split
    among the processes mapping them, so a fork's copy-on-write pages count once),
    else (or without ``pss``) its resident set; 0 once it is gone."""
    files = ((f"/proc/{pid}/smaps_rollup", "Pss:"),) if pss else ()
    for path, key in (*files, (f"/proc/{pid}/status", "VmRSS:")):
        try:
            with open(path) as fh:
                for line in fh:
                    if line.startswith(key):
                        return int(line.split()[1]) * 1024
        except OSError:
            pass
    return 0


def tree_rss_bytes(pid: int, pss: bool = True) -> int:
    """Memory of ``pid`` and all its descendants [bytes] (:func:`_rss_proc` summed; 0
    once it is gone)."""
    total, todo, seen = 0, [pid], set()
    while todo:
        p = todo.pop()
        if p in seen:
            continue
        seen.add(p)
        total += _rss_proc(p, pss)
        todo += _children_proc(p)
    return total


class _TreeMemory:
    """The guard's estimate of a process tree's PSS (module docstring)."""

    def __init__(self, pid: int):
        self.pid, self.peak, self.next = pid, 0, 0.0
        self.pss = self.rss = 0

    def read(self) -> int:
        """Read the PSS (and the resident set it goes with) now [bytes]."""
        t = time.monotonic()
        self.rss = tree_rss_bytes(self.pid, pss=False)
        self.pss = tree_rss_bytes(self.pid)
        self.next = time.monotonic() + PSS_COST_RATIO * (time.monotonic() - t)
        self.peak = max(self.peak, self.pss)
        return self.pss

    def estimate(self, limit: float) -> int:
        """The PSS now, or an upper estimate of it while that is at most ``limit``."""
        if time.monotonic() >= self.next:
            return self.read()
        guess = self.pss + max(0, tree_rss_bytes(self.pid, pss=False) - self.rss)
        return guess if guess <= limit else self.read()


# ------------------------------------------------------------------ one run
def run_guarded(cmd, log: Path, max_rss_bytes: float, max_wall_s: float, env=None) -> dict:
    """Run ``cmd`` in its own process group, output to ``log``, killed over the caps.

    Returns:
      dict: ``exit`` (code, or -signal), ``wall_s``, ``polled_peak_rss_mb``, ``killed``
      (None, or why).
    """
    t0 = time.monotonic()
    killed = None
    with open(log, "wb") as fh:
        proc = subprocess.Popen(
            cmd, stdout=fh, stderr=subprocess.STDOUT, env=env, start_new_session=True
        )
        memory = _TreeMemory(proc.pid)
        try:
            while proc.poll() is None:
                rss = memory.estimate(max_rss_bytes)
                if rss > max_rss_bytes:
                    killed = f"RSS {rss / 2**30:.3g} GB > {max_rss_bytes / 2**30:g} GB"
                elif time.monotonic() - t0 > max_wall_s:
                    killed = f"wall time > {max_wall_s:g} s"
                if killed:
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait()
                    break
                time.sleep(POLL_S)
        except BaseException:  # Ctrl-C of the bench: take the child down with it
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            raise
    return {
        "exit": proc.returncode,
        "wall_s": round(time.monotonic() - t0, 2),
        "polled_peak_rss_mb": round(memory.peak / 2**20, 1),
        "killed": killed,
    }


def time_v_peak_mb(path: Path) -> float | None:
    """``Maximum resident set size`` [MB] from a ``/usr/bin/time -v -o`` file."""
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return None
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", text)
    return round(int(m.group(1)) / 1024, 1) if m else None


def made_by(scenario: Path | None) -> str | None:
    """The generator command in a generated scenario's header comment, if any."""
    if scenario is None:
        return None
    try:
        with open(scenario, encoding="utf-8") as fh:
            head = "".join(fh.readline() for _ in range(3))
    except OSError:
        return None
    m = re.search(r"^#\s+(python scripts/make_scale_scenario\.py .*)$", head, re.M)
    return m.group(1) if m else None


def _last_stage(log: Path) -> str | None:
    """The last stage the planner reported on stderr (``[plan NAME] stage ...``)."""
    try:
        text = log.read_text(errors="replace")
    except OSError:
        return None
    stages = _STAGE_LINE.findall(text.replace("\r", "\n"))
    return stages[-1] if stages else None


def _get(d, *paths, default=None):
    """The first present value among dotted ``paths`` of nested dict ``d``."""
    for path in paths:
        x = d
        for key in path.split("."):
            if not isinstance(x, dict) or key not in x:
                break
            x = x[key]
        else:
            if x is not None:
                return x
    return default


def _per_second(doc, count: str, seconds: str):
    """``count / seconds`` of two dotted fields of ``doc``, None when either is missing."""
    n, secs = _get(doc, count), _get(doc, seconds)
    return round(n / secs, 1) if n is not None and secs else None


def parse_plan_json(path: Path) -> dict:
    """The scale figures of one ``plan.json``; every field may be None (missing)."""
    try:
        doc = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    near = _get(doc, "stats.near_pairs")
    store = _get(doc, "stats.pair_store_bytes", "stats.store_bytes")
    per_pair = _get(doc, "stats.pair_bytes", "stats.bytes_per_pair")
    if per_pair is None and store is not None and near:
        per_pair = round(store / near, 2)
    value, bound = _get(doc, "summary.value"), _get(doc, "summary.bound")
    gap = _get(doc, "summary.gap")
    gap_pct = None
    if gap is not None and bound:
        gap_pct = round(100.0 * gap / bound, 3)
    return {
        "scenario_name": _get(doc, "summary.scenario"),
        "satellites": _get(doc, "summary.satellites"),
        "targets": _get(doc, "summary.targets"),
        "observations": _get(doc, "summary.observations"),
        "windows": _get(doc, "stats.windows"),
        "options": _get(doc, "stats.options"),
        "near_pairs": near,
        "store_bytes": store,
        "bytes_per_pair": per_pair,
        "value": value,
        "bound": bound,
        "gap": gap,
        "gap_pct": gap_pct,
        "bound_status": _get(doc, "stats.bound_status"),
        "lagrangian_iterations": _get(doc, "stats.lagrangian_iterations"),
        "worker_iterations": _get(doc, "stats.worker_iterations"),
        "lns_iterations": _get(doc, "stats.lns_iterations"),
        "plain_bound": _get(doc, "stats.lagrangian_bound"),
        "strengthened_bound": _get(doc, "stats.worker_bound"),
        "worker_status": _get(doc, "stats.worker_status"),
        "dp_per_s": _get(doc, "stats.worker_dp_per_s"),
        "lns_moves_per_s": _per_second(doc, "stats.lns_iterations", "stats.lns_seconds"),
        "lns_moves_per_cpu_s": _per_second(doc, "stats.lns_iterations", "stats.lns_cpu_seconds"),
        "valid": _get(doc, "summary.valid", "report.valid"),
        "dropped": _get(doc, "report.dropped", default={}),
        "repair_rounds": _get(doc, "report.repair_rounds"),
        "joins": _get(doc, "report.joins", default={}),
        "timings_s": _get(doc, "timings_s", default={}),
        "stage_peak_rss_mb": _get(doc, "stats.peak_rss_mb", default={}),
    }


def run_plan(label, args: list[str], workdir: Path, guard: tuple[float, float], env=None) -> dict:
    """``jaxspline plan ARGS -o WORKDIR/plan_LABEL`` in a guarded subprocess; its figures.

    Args:
      label: names the run's folder, log and ``/usr/bin/time`` file in ``workdir``.
      args: the command's arguments after ``plan`` (scenario and flags, no ``-o``).
      workdir: folder of the run's files.
      guard: (max RSS [GB], max wall [min]) of :func:`run_guarded`.
      env: the child's environment (default: this checkout first on PYTHONPATH).
    Returns:
      dict: the command, load average before, :func:`run_guarded`'s fields, the peak RSS
      [MB] and its source, the last stage reported, :func:`parse_plan_json`'s fields and
      ``other_s`` (wall time outside the stages).
    """
    outdir = workdir / f"plan_{label}"
    if outdir.exists():
        shutil.rmtree(outdir)
    plan = [sys.executable, "-m", "jaxspline.cli", "plan", *args, "-o", str(outdir)]
    time_file = workdir / f"time_{label}.txt"
    has_time = Path(TIME_BIN).is_file()
    cmd = ([TIME_BIN, "-v", "-o", str(time_file)] if has_time else []) + plan
    log = workdir / f"plan_{label}.log"
    load = os.getloadavg()[0]
    max_rss_gb, max_wall_min = guard
    res = run_guarded(cmd, log, max_rss_gb * 2**30, 60.0 * max_wall_min, env=env or child_env())
    peak = time_v_peak_mb(time_file) if has_time and not res["killed"] else None
    out = {
        "command": " ".join(["jaxspline", "plan", *map(repo_relative, args)]),
        "load_avg_before": round(load, 2),
        **res,
        "peak_rss_mb": peak if peak is not None else res["polled_peak_rss_mb"],
        "peak_rss_source": "time -v" if peak is not None else "polled",
        "last_stage": _last_stage(log),
        **parse_plan_json(outdir / "plan.json"),
    }
    stages = sum(out["timings_s"].values()) if out.get("timings_s") else None
    out["other_s"] = round(res["wall_s"] - stages, 2) if stages is not None else None
    if res["exit"] != 0:
        try:
            out["log_tail"] = log.read_text(errors="replace").replace("\r", "\n")[-1500:]
        except OSError:
            pass
    return out


def run_size(label, scenario, time_limit, max_rss_gb, max_wall_min, workdir: Path) -> dict:
    """Plan one size in a subprocess (plots and AEM files off) and collect its figures."""
    args = [str(scenario)] if scenario is not None else []
    args += ["--no-aem", "--no-plots", "--time-limit", f"{time_limit:g}"]
    # one folder, log and time file a run (a size may run at several limits)
    res = run_plan(f"{label}_{time_limit:g}s", args, workdir, (max_rss_gb, max_wall_min))
    return {
        "size": label,
        "scenario": repo_relative(str(scenario)) if scenario is not None else "(packaged default)",
        "made_by": made_by(scenario),
        "time_limit_s": time_limit,
        **res,
    }


def bench_scale(
    sizes: list[str],
    time_limit: float,
    max_rss_gb: float = MAX_RSS_GB,
    max_wall_min: float = MAX_WALL_MIN,
    workdir: str | None = None,
) -> dict:
    """Run every size in turn (one subprocess each); the section's report."""
    tmp = None
    if workdir is None:
        tmp = tempfile.TemporaryDirectory(prefix="jaxspline_scale_")
        wd = Path(tmp.name)
    else:
        wd = Path(workdir)
        wd.mkdir(parents=True, exist_ok=True)
    runs = []
    try:
        for token in sizes:
            size, limit = split_limit(token, time_limit)
            label, scenario = resolve_size(size, wd)
            print(f"scale: planning {label} ({limit:g} s limit) ...", flush=True)
            r = run_size(label, scenario, limit, max_rss_gb, max_wall_min, wd)
            runs.append(r)
            print("  " + summary_line(r), flush=True)
    finally:
        if tmp is not None:
            tmp.cleanup()
    return {
        "sizes": sizes,
        "time_limit_s": time_limit,
        "max_rss_gb": max_rss_gb,
        "workdir": None if tmp else str(wd),
        "runs": runs,
    }


# ------------------------------------------------------------------ report
def summary_line(r: dict) -> str:
    """One progress line of a finished run."""
    state = f"killed ({r['killed']})" if r.get("killed") else f"exit {r['exit']}"
    return (
        f"{r['size']}: {state}, wall {cell(r['wall_s'], '{:.1f}')} s, peak RSS "
        f"{cell(r['peak_rss_mb'], '{:.0f}')} MB, options {cell(r.get('options'), '{:d}')}, "
        f"pairs {cell(r.get('near_pairs'), '{:d}')}, value {cell(r.get('value'), '{:g}')}, "
        f"gap {cell(r.get('gap_pct'), '{:.2f}')} %, last stage {cell(r.get('last_stage'))}"
    )


def _run_row(r: dict, report: dict) -> str:
    """The summary table's row of one run."""
    state = "killed" if r.get("killed") else str(r.get("exit"))
    store = r.get("store_bytes")
    return row(
        [
            r["size"],
            *run_cells(r, "satellites targets"),
            cell(r.get("time_limit_s", report.get("time_limit_s")), "{:g}"),
            state,
            *run_cells(r, "wall_s peak_rss_mb windows options near_pairs bytes_per_pair"),
            cell(None if store is None else store / 1e6, "{:.1f}"),
            *run_cells(r, "lagrangian_iterations worker_iterations lns_iterations"),
            *run_cells(r, "value bound bound_status gap_pct valid load_avg_before"),
            *run_cells(r, "plain_bound strengthened_bound worker_status dp_per_s"),
            *run_cells(r, "lns_moves_per_s lns_moves_per_cpu_s"),
        ]
    )


def stage_table(runs: list[dict], label: str = "size") -> list[str]:
    """Markdown: per run, wall time / peak RSS at the end of every stage of ``plan.json``."""
    stages = []
    for r in runs:
        for k in list(r.get("timings_s") or {}) + list(r.get("stage_peak_rss_mb") or {}):
            if k not in stages:
                stages.append(k)
    lines = header(label, *stages, "other s", "last stage done")
    for r in runs:
        t, m = r.get("timings_s") or {}, r.get("stage_peak_rss_mb") or {}
        cells = [f"{cell(t.get(s), '{:.2f}')} / {cell(m.get(s), '{:.0f}')}" for s in stages]
        cells += [cell(r.get("other_s"), "{:.1f}"), cell(r.get("last_stage"))]
        lines.append(row([r[label], *cells]))
    return lines


def scale_table(report: dict) -> list[str]:
    """Markdown: one summary row per size, then per-stage wall time and peak RSS."""
    runs = report.get("runs", [])
    runs_lines = [
        "\nScale runs: `jaxspline plan --no-aem --no-plots --time-limit LIMIT`, one "
        f"subprocess each, guard {report.get('max_rss_gb', 0):g} GB RSS. *Lagr. it.* are "
        "the search's own bound iterations, *worker it.* those of the bound worker on the "
        "second CPU, *LNS it.* the search's; *load* is the machine's load average when the "
        "run started. *plain bound*: the search's own Lagrangian phase (per-satellite "
        "path relaxation), which a time-limited run with the worker leaves out (-; "
        "converged plain and strengthened bounds side by side: BOUND.md); "
        "*strengthened bound*: the worker's "
        "(a run of one target's options credited once), *worker status* whether it "
        "converged, *DP it/s* its iterations per second; *LNS moves/s* the search's LNS "
        "iterations per second of its LNS stage, wall and CPU (the planner process alone).",
        *header(*RUN_COLUMNS),
        *(_run_row(r, report) for r in runs),
    ]
    stage_lines = [
        "\nPer stage: wall s / process peak RSS MB at the stage's end (plan.json); "
        "*other* = wall time outside the stages (start-up, load, compile cache, writing).",
        *stage_table(runs),
    ]
    lines = section("runs", runs_lines) + section("stages", stage_lines)
    lines.append(
        "\nScenarios: "
        + "; ".join(  # one entry a size (a size may run at several limits)
            dict.fromkeys(
                f"{r['size']} = `{r.get('made_by') or r.get('scenario', '-')}`" for r in runs
            )
        )
    )
    for r in runs:
        if r.get("killed"):
            lines.append(
                f"\n{r['size']}: killed, {r['killed']}, after stage {cell(r.get('last_stage'))} "
                "(the next one was running)."
            )
    return lines


def write_scale(report: dict, out: Path) -> None:
    """Write ``scale.json`` and ``SCALE.md`` into ``out`` and print the tables."""
    write_result(out, "scale", report, "Scale runs", scale_table(report["scale"]))
