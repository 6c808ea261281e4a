"""``python -m bench --section coverage``: strip coverage on a training case, and plans of areas.

The case is taken the way the planner takes it: its :class:`Scenario`
(:func:`jaxspline.regional.adapter.case_scenario`: one area per region on the case's own
samples), the planner's orbit table (:func:`jaxspline.geometry.windows.orbit_scene`) and
its Earth-fixed tracks on the mesh ``k * geometry_step``, the case's
``coverage_sample_step_s`` (:func:`jaxspline.planner.area_options.earth_fixed_tracks`).

Candidates: every pass of every satellite near a region (sub-satellite point within the
sensor's reach of a region's bounding circle), rolls on a grid over the sensor band on both
sides, starts every 10 s from one longest strip before the pass to its end, every allowed
duration (``pass_candidates``). Measured in one run:

* the JAX engine (:func:`jaxspline.screen.coverage.coverage_slices`) on the whole set:
  candidates/s after compilation (compile apart), in a subprocess that also reports the
  peak RSS of loading the case, the tracks and the table;
* the numpy + shapely baseline (:mod:`bench.coverage_baseline`, its own edge points and
  point-in-polygon test) on a random subsample of the same candidates and the same
  tracks: candidates/s, and the covered sets compared with the engine's (asserted
  identical);
* the engine on that subsample alone (no sharing between candidates);
* memory: bytes per candidate and per covered sample of the slice form and of the CSR;
* plans (``plan_runs``): ``jaxspline plan`` as a subprocess under ``/usr/bin/time -v``
  (:func:`bench.scale.run_plan`) on the packaged areas example with its own time limit
  and outputs (as a user runs it), and on a training case written as a scenario file
  (``scripts/scenario_toml.py``) with a 120 s limit, ``--no-aem --no-plots --no-html``;
  from ``plan.json``: value, bound, gap, every area's covered share, wall time; peak RSS
  from ``time -v``. ``--quick`` plans the areas example alone.

Writes ``coverage.json`` and ``COVERAGE.md`` into the output folder.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path
from typing import NamedTuple

import numpy as np

from bench.markdown import cell, header, row, run_cells, section

REPO = Path(__file__).resolve().parents[1]
DEFAULT_CASE = "/work/shared/data/regional_coverage/train/case_0001"
#: The packaged areas example (planned with its own time limit and outputs).
AREAS_EXAMPLE = REPO / "jaxspline" / "data" / "areas_example.toml"
#: The training case planned as a scenario file, and its time limit [s].
PLAN_CASE = "/work/shared/data/regional_coverage/train/case_0002"
PLAN_CASE_LIMIT_S = 120.0
SCENARIO_TOML = REPO / "scripts" / "scenario_toml.py"
ROLL_STEP_DEG = 0.5
START_EVERY_S = 10.0
SUBSAMPLE = 400
REACH_MARGIN_DEG = 0.5


class Setup(NamedTuple):
    """A training case as the planner sees it (:func:`jaxspline.regional.adapter.case_scenario`).

    Attributes:
      name: the case's id.
      pos, vel: float64 [S, K, 3], Earth-fixed states on the mesh ``k * step``, k = 0..K-1
        (:func:`jaxspline.planner.area_options.earth_fixed_tracks`) [m], [m/s].
      lon, lat: float64 [N], the areas' samples, area by area [deg].
      region: int64 [N], the area of each sample.
      fov_deg, min_edge_deg, max_edge_deg: float64 [S], field of view and edge band [deg].
      min_duration_s, max_duration_s: float64 [S], shortest and longest strip [s].
      step: ephemeris mesh step [s] (the case's ``coverage_sample_step_s``).
      time_step: action grid step [s].
    """

    name: str
    pos: np.ndarray
    vel: np.ndarray
    lon: np.ndarray
    lat: np.ndarray
    region: np.ndarray
    fov_deg: np.ndarray
    min_edge_deg: np.ndarray
    max_edge_deg: np.ndarray
    min_duration_s: np.ndarray
    max_duration_s: np.ndarray
    step: float
    time_step: float


def _region_circles(su: Setup):
    cen, rad = [], []
    for r in range(int(su.region.max()) + 1):
        m = su.region == r
        la, lo = np.radians(su.lat[m]), np.radians(su.lon[m])
        v = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1)
        c = v.mean(0) / np.linalg.norm(v.mean(0))
        cen.append(c)
        rad.append(np.degrees(np.arccos(np.clip(v @ c, -1, 1)).max()))
    return np.array(cen), np.array(rad)


def _windows(pos, max_edge_deg, cen, rad):
    """Mesh intervals where a satellite (positions ``pos`` [K, 3]) can reach a region's
    bounding circle."""
    u = pos / np.linalg.norm(pos, axis=-1, keepdims=True)
    h = np.linalg.norm(pos, axis=-1) / 6378137.0
    edge = np.radians(max_edge_deg)
    reach = np.degrees(np.arcsin(np.clip(h * np.sin(edge), -1, 1))) - max_edge_deg
    d = np.degrees(np.arccos(np.clip(u @ cen.T, -1, 1)))
    idx = np.flatnonzero((d - rad[None] < reach[:, None] + REACH_MARGIN_DEG).any(1))
    if idx.size == 0:
        return []
    br = np.flatnonzero(np.diff(idx) > 1)
    return list(zip(np.r_[idx[0], idx[br + 1]], np.r_[idx[br], idx[-1]], strict=True))


def pass_candidates(su: Setup, roll_step_deg=ROLL_STEP_DEG, start_every_s=START_EVERY_S):
    """Candidate strips of every pass near a region (see the module docstring).

    Args:
      su: the case's :class:`Setup`.
      roll_step_deg: roll grid step [deg].
      start_every_s: start spacing [s] (a multiple of the action grid).
    Returns:
      jaxspline.screen.coverage.Candidates (roll-only: no pitch).
    """
    from jaxspline.screen.coverage import Candidates

    step = su.step
    ks, kd = int(round(start_every_s / step)), int(round(su.time_step / step))
    cen, rad = _region_circles(su)
    n_mesh = su.pos.shape[1]
    rows = []
    for s in range(su.pos.shape[0]):
        fov = su.fov_deg[s]
        lo, hi = su.min_edge_deg[s] + fov / 2, su.max_edge_deg[s] - fov / 2
        rolls = np.arange(np.ceil(lo / roll_step_deg) * roll_step_deg, hi + 1e-9, roll_step_deg)
        n_lo = int(round(su.min_duration_s[s] / step)) + 1
        n_hi = int(round(su.max_duration_s[s] / step)) + 1
        ns = np.arange(n_lo, n_hi + 1, kd)
        for a, b in _windows(su.pos[s], su.max_edge_deg[s], cen, rad):
            k0s = np.arange(max(0, (a - n_hi) // ks * ks), b + 1, ks)
            r, k0, n = np.meshgrid(np.r_[-rolls, rolls], k0s, ns, indexing="ij")
            ok = k0 + n - 1 < n_mesh
            rows.append(np.stack([np.full(ok.sum(), s), k0[ok], n[ok], r[ok]], -1))
    a = np.concatenate(rows)
    return Candidates(
        a[:, 0].astype(np.int32), a[:, 1].astype(np.int32), a[:, 2].astype(np.int32), a[:, 3]
    )


def _setup(case_dir) -> tuple[Setup, float]:
    """The case's :class:`Setup` through the planner's own path, and the seconds its
    tracks took (orbit table and Earth-fixed rotation)."""
    from jaxspline.geometry.windows import orbit_scene
    from jaxspline.planner.area_options import earth_fixed_tracks
    from jaxspline.regional.adapter import case_scenario

    sc = case_scenario(case_dir)
    t0 = time.perf_counter()
    table, scene = orbit_scene(sc)
    pos, vel, _ = earth_fixed_tracks(sc, table, scene)
    tracks_s = time.perf_counter() - t0
    smp = [a.samples for a in sc.areas]
    sats = sc.satellites
    deg = np.degrees
    su = Setup(
        name=sc.name,
        pos=pos,
        vel=vel,
        lon=np.concatenate([x[:, 0] for x in smp]),
        lat=np.concatenate([x[:, 1] for x in smp]),
        region=np.repeat(np.arange(len(smp)), [x.shape[0] for x in smp]),
        fov_deg=deg([s.fov for s in sats]),
        min_edge_deg=deg([s.edge_band[0] for s in sats]),
        max_edge_deg=deg([s.edge_band[1] for s in sats]),
        min_duration_s=np.array([s.strip_duration[0] for s in sats], np.float64),
        max_duration_s=np.array([s.strip_duration[1] for s in sats], np.float64),
        step=float(sc.planner.geometry_step),
        time_step=float(sc.planner.time_step),
    )
    return su, tracks_s


def _engine(su: Setup, cands):
    from jaxspline.screen.coverage import coverage_slices

    return coverage_slices(su.pos, su.vel, su.fov_deg, cands, su.lon, su.lat, su.region)


def build_child(case_dir: str, reps: int) -> dict:
    """The full table in this process: times, sizes, peak RSS (run as a subprocess)."""
    t0 = time.perf_counter()
    su, tracks_s = _setup(case_dir)
    cands = pass_candidates(su)
    t_first = time.perf_counter()
    cov = _engine(su, cands)
    first_s = time.perf_counter() - t_first
    times, cpu = [], []
    for _ in range(reps):
        t1, c1 = time.perf_counter(), time.process_time()
        cov = _engine(su, cands)
        times.append(time.perf_counter() - t1)
        cpu.append(time.process_time() - c1)
    cnt = cov.counts()
    nnz, c = int(cnt.sum()), int(cnt.size)
    csr_bytes = 8 * (c + 1) + 4 * nnz
    return {
        "case": Path(case_dir).name,
        "satellites": int(su.pos.shape[0]),
        "grid_samples": int(su.lon.size),
        "mesh_samples": int(su.pos.shape[1]),
        "candidates": c,
        "nonempty": int((cnt > 0).sum()),
        "covered_entries": nnz,
        "tracks_s": tracks_s,
        "first_call_s": first_s,
        "median_s": float(np.median(times)),
        "rate": c / float(np.median(times)),
        "cpu_s": float(np.median(cpu)),
        "rate_cpu": c / float(np.median(cpu)),
        "compile_s_est": first_s - float(np.median(times)),
        "slices_bytes": cov.nbytes,
        "slices_bytes_per_candidate": cov.nbytes / c,
        "slices_bytes_per_covered": cov.nbytes / max(nnz, 1),
        "csr_bytes": csr_bytes,
        "csr_bytes_per_candidate": csr_bytes / c,
        "csr_bytes_per_covered": csr_bytes / max(nnz, 1),
        "stats": {k: v for k, v in cov.stats.items() if not k.endswith("_s")},
        "wall_s": time.perf_counter() - t0,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }


def _baseline_compare(case_dir: str, seed: int) -> dict:
    from bench.coverage_baseline import covered_baseline, edges_np
    from jaxspline.screen.coverage import Candidates

    su, _ = _setup(case_dir)
    cands = pass_candidates(su)
    cov = _engine(su, cands)
    rng = np.random.default_rng(seed)
    pick = np.sort(rng.choice(cands.sat.size, min(SUBSAMPLE, cands.sat.size), replace=False))
    sub = Candidates(*(None if x is None else np.asarray(x)[pick] for x in cands))
    t0, c0, mismatch, nonempty = time.perf_counter(), time.process_time(), 0, 0
    refs = []
    for c in range(pick.size):
        s, k0, n, r = sub.sat[c], sub.k0[c], sub.n[c], sub.roll_deg[c]
        pos, vel = su.pos[s, k0 : k0 + n], su.vel[s, k0 : k0 + n]
        inner, outer, _ = edges_np(pos, vel, r, su.fov_deg[s])
        refs.append(covered_baseline(inner, outer, su.lon, su.lat))
    base_s, base_cpu = time.perf_counter() - t0, time.process_time() - c0
    for c, ref in zip(pick, refs, strict=True):
        got = np.sort(cov.pool[cov.lo[c] : cov.hi[c]].astype(np.int64))
        mismatch += not np.array_equal(got, ref)
        nonempty += ref.size > 0
    _engine(su, sub)  # compile the subsample's shapes
    t1, c1 = time.perf_counter(), time.process_time()
    _engine(su, sub)
    sub_s, sub_cpu = time.perf_counter() - t1, time.process_time() - c1
    return {
        "subsample": int(pick.size),
        "subsample_nonempty": int(nonempty),
        "mismatches": int(mismatch),
        "baseline_s": base_s,
        "baseline_rate": pick.size / base_s,
        "baseline_rate_cpu": pick.size / base_cpu,
        "engine_subsample_s": sub_s,
        "engine_subsample_rate": pick.size / sub_s,
        "engine_subsample_rate_cpu": pick.size / sub_cpu,
    }


def _plan_row(label: str, scenario: str, args: list[str], limit: float, wd: Path, guard) -> dict:
    """One ``jaxspline plan`` run (:func:`bench.scale.run_plan`) and its areas."""
    from bench.scale import run_plan

    print(f"coverage: planning {label} ({limit:g} s limit) ...", flush=True)
    res = run_plan(label, args, wd, guard)
    try:
        doc = json.loads((wd / f"plan_{label}" / "plan.json").read_text())
    except (OSError, ValueError):
        doc = {}
    report = doc.get("report") or {}
    keys = "area priority samples samples_covered covered_share reachable_share min_share strips"
    areas = [{k: a.get(k) for k in keys.split()} for a in report.get("areas") or []]
    prio = sum(a["priority"] or 0.0 for a in areas)
    weighted = sum((a["priority"] or 0.0) * (a["covered_share"] or 0.0) for a in areas)
    skipped = (report.get("time_limit") or {}).get("skipped") or []
    res["command"] = res["command"].replace(str(wd), "DIR")
    out = {
        "plan": label,
        "scenario": scenario,
        "time_limit_s": limit,
        **res,
        "total_value": (doc.get("summary") or {}).get("total_value"),
        "areas": areas,
        "area_coverage": weighted / prio if prio > 0 else None,
        "left_out": [x.get("what") for x in skipped],
    }
    print(
        f"  {label}: exit {out['exit']}, wall {cell(out['wall_s'], '{:.1f}')} s, peak RSS "
        f"{cell(out['peak_rss_mb'], '{:.0f}')} MB, value {cell(out.get('value'), '{:.6g}')}, "
        f"bound {cell(out.get('bound'), '{:.6g}')}, area coverage "
        f"{cell(out['area_coverage'], '{:.4f}')}",
        flush=True,
    )
    return out


def plan_runs(quick: bool = False, guard=None) -> list[dict]:
    """``jaxspline plan`` on the areas example and on a training case (module docstring).

    Args:
      quick: plan the areas example alone.
      guard: (max RSS [GB], max wall [min]) of each run (default: the scale section's).
    Returns:
      list of dict per run: :func:`bench.scale.run_plan`'s fields, ``areas`` (per area
      its ``plan.json`` report), ``area_coverage`` (the priority-weighted mean covered
      share), ``total_value`` and ``left_out`` (what the time limit left out).
    """
    from bench.scale import MAX_RSS_GB, MAX_WALL_MIN, child_env, repo_relative

    guard = guard or (MAX_RSS_GB, MAX_WALL_MIN)
    runs = []
    with tempfile.TemporaryDirectory(prefix="jaxspline_coverage_") as tmp:
        wd = Path(tmp)
        limit = float(tomllib.loads(AREAS_EXAMPLE.read_text())["planner"]["time_limit_s"])
        example = repo_relative(str(AREAS_EXAMPLE))
        args = [str(AREAS_EXAMPLE), "--time-limit", f"{limit:g}"]
        runs.append(_plan_row("areas_example", example, args, limit, wd, guard))
        if quick:
            return runs
        case = Path(PLAN_CASE).name
        cmd = [sys.executable, str(SCENARIO_TOML), PLAN_CASE, str(wd / case)]
        subprocess.run(cmd, check=True, capture_output=True, text=True, env=child_env())
        made = f"python scripts/scenario_toml.py {PLAN_CASE} DIR"
        args = [str(wd / case / "scenario.toml"), "--time-limit", f"{PLAN_CASE_LIMIT_S:g}"]
        args += ["--no-aem", "--no-plots", "--no-html"]
        runs.append(_plan_row(case, made, args, PLAN_CASE_LIMIT_S, wd, guard))
    return runs


def bench_coverage(
    case_dir: str = DEFAULT_CASE, reps: int = 3, quick: bool = False, guard=None
) -> dict:
    """The coverage section: full table in a subprocess, the baseline comparison, the plans.

    Args:
      case_dir: training case folder.
      reps: timed repetitions of the full table.
      quick: plan the areas example alone (:func:`plan_runs`).
      guard: (max RSS [GB], max wall [min]) of each plan.
    Returns:
      dict for coverage.json.
    """
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    spec = json.dumps({"case": case_dir, "reps": reps})
    cmd = [sys.executable, "-m", "bench.coverage", spec]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    full = json.loads(next(ln for ln in out.splitlines() if ln.startswith("RESULT "))[7:])
    cmp_ = _baseline_compare(case_dir, seed=0)
    if cmp_["mismatches"]:
        raise AssertionError(f"coverage: {cmp_['mismatches']} covered sets differ from shapely")
    engine_s = time.perf_counter() - t0
    res = {
        "full": full,
        "compare": cmp_,
        "ratio": full["rate"] / cmp_["baseline_rate"],
        "ratio_cpu": full["rate_cpu"] / cmp_["baseline_rate_cpu"],
        "loadavg_1min": os.getloadavg()[0],
        "loadavg_1min_start": load0,
        "cpus": os.cpu_count(),
        "engine_section_s": engine_s,
    }
    print(coverage_summary(res), flush=True)
    res["plans"] = plan_runs(quick, guard)
    res["loadavg_1min_end"] = os.getloadavg()[0]
    res["section_s"] = time.perf_counter() - t0
    return res


def coverage_summary(res: dict) -> str:
    """Markdown table of a coverage result (wall-clock and CPU-time rates)."""
    f, c = res["full"], res["compare"]
    rows = [
        "| case | sats | samples | candidates | nonempty | engine cand/s (wall / CPU) | "
        "baseline cand/s (wall / CPU) | ratio (wall / CPU) | identical | table s (wall / CPU) | "
        "compile s | bytes/cand (slices / CSR) | bytes/covered (slices / CSR) | peak RSS MB |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        f"| {f['case']} | {f['satellites']} | {f['grid_samples']} | {f['candidates']:,} | "
        f"{f['nonempty']:,} | {f['rate']:,.0f} / {f['rate_cpu']:,.0f} | "
        f"{c['baseline_rate']:,.0f} / {c['baseline_rate_cpu']:,.0f} | "
        f"{res['ratio']:,.0f}x / {res['ratio_cpu']:,.0f}x | "
        f"{c['subsample'] - c['mismatches']}/{c['subsample']} "
        f"({c['subsample_nonempty']} nonempty) | "
        f"{f['median_s']:.2f} / {f['cpu_s']:.2f} | {f['compile_s_est']:.1f} | "
        f"{f['slices_bytes_per_candidate']:.1f} / {f['csr_bytes_per_candidate']:.0f} | "
        f"{f['slices_bytes_per_covered']:.3f} / {f['csr_bytes_per_covered']:.2f} | "
        f"{f['peak_rss_mb']:.0f} |",
    ]
    note = (
        f"\nEngine on the {c['subsample']} subsampled candidates alone (no sharing between "
        f"candidates): {c['engine_subsample_rate']:,.0f} cand/s wall, "
        f"{c['engine_subsample_rate_cpu']:,.0f} CPU. Machine: {res['cpus']} CPUs, 1-min load "
        f"average {res['loadavg_1min']:.1f} (CPU-time rates are the robust figures on a shared "
        f"machine; JAX may use several threads, so CPU time can exceed wall time).\n\n"
        f"Engine counts: {json.dumps(f['stats'])}"
    )
    return "\n".join(rows) + "\n" + note


#: Title of ``COVERAGE.md``.
COVERAGE_TITLE = "Strip coverage engine vs numpy + shapely"


#: Columns of the plans table of ``COVERAGE.md``, one run a row.
PLAN_COLUMNS = (
    "plan|sats|targets|limit s|exit|wall s|peak RSS MB|load|value|total value|bound|"
    "bound status|gap|gap %|area coverage|valid|left out for the limit"
).split("|")
#: Columns of the areas table of ``COVERAGE.md``, one area of a run a row.
AREA_COLUMNS = (
    "plan|area|priority|samples|covered|covered share|reachable share|least share|strips"
).split("|")


def _plan_line(r: dict) -> str:
    state = "killed" if r.get("killed") else str(r.get("exit"))
    return row(
        [
            r["plan"],
            *run_cells(r, "satellites targets"),
            cell(r.get("time_limit_s"), "{:g}"),
            state,
            *run_cells(r, "wall_s peak_rss_mb load_avg_before"),
            cell(r.get("value"), "{:.6g}"),
            cell(r.get("total_value"), "{:.6g}"),
            cell(r.get("bound"), "{:.6g}"),
            cell(r.get("bound_status")),
            cell(r.get("gap"), "{:.4g}"),
            cell(r.get("gap_pct"), "{:.2f}"),
            cell(r.get("area_coverage"), "{:.4f}"),
            cell(r.get("valid")),
            cell(", ".join(r.get("left_out") or []) or None),
        ]
    )


def plans_table(plans: list[dict]) -> list[str]:
    """Markdown: one row per ``jaxspline plan`` run, then one per area of each run."""
    lines = [
        "\n`jaxspline plan` on areas scenarios, one subprocess each under `/usr/bin/time -v` "
        "(peak RSS of the process; wall time of the whole command). *area coverage*: the "
        "areas' covered shares weighted by their priorities (on a regional case, the "
        "benchmark's `coverage_ratio`); *gap* = bound - value, *gap %* of the bound; "
        "*load*: the machine's 1-min load average when the run started.",
        *header(*PLAN_COLUMNS),
        *(_plan_line(r) for r in plans),
        "\nPer area (`plan.json` `report.areas`): *reachable share* is what all its "
        "candidate strips cover together (no plan covers more); *least share* its "
        "minimum (- : none).",
        *header(*AREA_COLUMNS),
    ]
    for r in plans:
        for a in r.get("areas") or []:
            lines.append(
                row(
                    [
                        r["plan"],
                        cell(a.get("area")),
                        cell(a.get("priority"), "{:.4g}"),
                        cell(a.get("samples"), "{:d}"),
                        cell(a.get("samples_covered"), "{:d}"),
                        cell(a.get("covered_share"), "{:.4f}"),
                        cell(a.get("reachable_share"), "{:.4f}"),
                        cell(a.get("min_share"), "{:.4f}"),
                        cell(a.get("strips"), "{:d}"),
                    ]
                )
            )
    lines.append(
        "\nCommands: "
        + "; ".join(f"{r['plan']} = `{r.get('command', '-')}`" for r in plans)
        + (
            f" (DIR: written by `{plans[-1]['scenario']}`)"
            if any("DIR" in str(r.get("command")) for r in plans)
            else ""
        )
    )
    for r in plans:
        if r.get("exit") not in (0, None) or r.get("killed"):
            tail = (r.get("log_tail") or "").strip().splitlines()[-3:]
            lines.append(f"\n{r['plan']}: exit {r.get('exit')} {r.get('killed') or ''}: {tail}")
    return lines


def coverage_lines(report: dict) -> list[str]:
    """The body of ``COVERAGE.md`` from the section's JSON (also used by ``--render``)."""
    cov = report["coverage"]
    lines = [
        "",
        "`python -m bench --section coverage` (see bench/coverage.py for the candidate set).",
        *section("engine", ["", coverage_summary(cov)]),
    ]
    if cov.get("plans"):
        lines += section("plans", plans_table(cov["plans"]))
    if cov.get("section_s") is not None:
        lines.append(
            f"\nSection: {cov['section_s']:.0f} s wall; 1-min load average "
            f"{cell(cov.get('loadavg_1min_start'), '{:.1f}')} at its start, "
            f"{cell(cov.get('loadavg_1min_end'), '{:.1f}')} at its end "
            f"({cov.get('cpus')} CPUs)."
        )
    return lines


def write_coverage(report: dict, out: Path) -> None:
    """Write ``coverage.json`` and ``COVERAGE.md`` into ``out``."""
    from bench.markdown import write_markdown

    out.mkdir(parents=True, exist_ok=True)
    (out / "coverage.json").write_text(json.dumps(report, indent=1, default=str) + "\n")
    write_markdown(out / "COVERAGE.md", COVERAGE_TITLE, coverage_lines(report))


if __name__ == "__main__":
    import jax

    jax.config.update("jax_enable_x64", True)
    s = json.loads(sys.argv[1])
    print("RESULT " + json.dumps(build_child(s["case"], s["reps"])))
