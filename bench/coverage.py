"""``python -m bench --section coverage``: the strip-coverage engine on a training case.

Candidates: every pass of every satellite near a region (sub-satellite point within the
sensor's reach of a region's bounding circle), rolls on a grid over the sensor band on both
sides, starts every 10 s from one longest strip before the pass to its end, every allowed
duration (``pass_candidates``). Measured in one run:

* the JAX engine (:func:`jaxspline.screen.coverage.coverage_slices`) on the whole set:
  candidates/s after compilation (compile apart), in a subprocess that also reports the
  peak RSS of loading the case, the tracks and the table;
* the numpy + shapely baseline (:mod:`bench.coverage_baseline`) on a random subsample of
  the same candidates: candidates/s, and the covered sets compared with the engine's
  (asserted identical);
* the engine on that subsample alone (no sharing between candidates);
* memory: bytes per candidate and per covered sample of the slice form and of the CSR.

Writes ``coverage.json`` and ``COVERAGE.md`` into the output folder.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

DEFAULT_CASE = "/work/shared/data/regional_coverage/train/case_0001"
ROLL_STEP_DEG = 0.5
START_EVERY_S = 10.0
SUBSAMPLE = 400
REACH_MARGIN_DEG = 0.5


def _region_circles(case):
    g = case.grid
    cen, rad = [], []
    for r in range(len(case.regions)):
        m = g.region == r
        la, lo = np.radians(g.lat_deg[m]), np.radians(g.lon_deg[m])
        v = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1)
        c = v.mean(0) / np.linalg.norm(v.mean(0))
        cen.append(c)
        rad.append(np.degrees(np.arccos(np.clip(v @ c, -1, 1)).max()))
    return np.array(cen), np.array(rad)


def _windows(tr, s, sensor, cen, rad):
    """Mesh intervals where satellite s can reach a region's bounding circle."""
    u = tr.pos[s] / np.linalg.norm(tr.pos[s], axis=-1, keepdims=True)
    h = np.linalg.norm(tr.pos[s], axis=-1) / 6378137.0
    edge = np.radians(sensor.max_edge_deg)
    reach = np.degrees(np.arcsin(np.clip(h * np.sin(edge), -1, 1))) - sensor.max_edge_deg
    d = np.degrees(np.arccos(np.clip(u @ cen.T, -1, 1)))
    idx = np.flatnonzero((d - rad[None] < reach[:, None] + REACH_MARGIN_DEG).any(1))
    if idx.size == 0:
        return []
    br = np.flatnonzero(np.diff(idx) > 1)
    return list(zip(np.r_[idx[0], idx[br + 1]], np.r_[idx[br], idx[-1]], strict=True))


def pass_candidates(case, tr, roll_step_deg=ROLL_STEP_DEG, start_every_s=START_EVERY_S):
    """Candidate strips of every pass near a region (see the module docstring).

    Args:
      case: a regional Case.
      tr: its Tracks.
      roll_step_deg: roll grid step [deg].
      start_every_s: start spacing [s] (a multiple of the action grid).
    Returns:
      jaxspline.screen.coverage.Candidates.
    """
    from jaxspline.screen.coverage import Candidates

    step = case.sample_step_s
    ks, kd = int(round(start_every_s / step)), int(round(case.time_step_s / step))
    cen, rad = _region_circles(case)
    rows = []
    for s, sat in enumerate(case.satellites):
        sen = sat.sensor
        lo, hi = sen.min_edge_deg + sen.fov_deg / 2, sen.max_edge_deg - sen.fov_deg / 2
        rolls = np.arange(np.ceil(lo / roll_step_deg) * roll_step_deg, hi + 1e-9, roll_step_deg)
        n_lo = int(round(sen.min_duration_s / step)) + 1
        n_hi = int(round(sen.max_duration_s / step)) + 1
        ns = np.arange(n_lo, n_hi + 1, kd)
        for a, b in _windows(tr, s, sen, cen, rad):
            k0s = np.arange(max(0, (a - n_hi) // ks * ks), b + 1, ks)
            r, k0, n = np.meshgrid(np.r_[-rolls, rolls], k0s, ns, indexing="ij")
            ok = k0 + n - 1 < tr.n_samples
            rows.append(np.stack([np.full(ok.sum(), s), k0[ok], n[ok], r[ok]], -1))
    a = np.concatenate(rows)
    return Candidates(
        a[:, 0].astype(np.int32), a[:, 1].astype(np.int32), a[:, 2].astype(np.int32), a[:, 3]
    )


def _setup(case_dir):
    from jaxspline.geometry.coverage_tracks import build_tracks

    from jaxspline.regional.case import load_case

    case = load_case(case_dir)
    t0 = time.perf_counter()
    tr = build_tracks(case)
    return case, tr, time.perf_counter() - t0


def _engine(case, tr, cands):
    from jaxspline.screen.coverage import coverage_slices

    g = case.grid
    fov = np.array([s.sensor.fov_deg for s in case.satellites])
    return coverage_slices(tr.pos, tr.vel, fov, cands, g.lon_deg, g.lat_deg, g.region)


def build_child(case_dir: str, reps: int) -> dict:
    """The full table in this process: times, sizes, peak RSS (run as a subprocess)."""
    t0 = time.perf_counter()
    case, tr, tracks_s = _setup(case_dir)
    cands = pass_candidates(case, tr)
    t_first = time.perf_counter()
    cov = _engine(case, tr, cands)
    first_s = time.perf_counter() - t_first
    times, cpu = [], []
    for _ in range(reps):
        t1, c1 = time.perf_counter(), time.process_time()
        cov = _engine(case, tr, cands)
        times.append(time.perf_counter() - t1)
        cpu.append(time.process_time() - c1)
    cnt = cov.counts()
    nnz, c = int(cnt.sum()), int(cnt.size)
    csr_bytes = 8 * (c + 1) + 4 * nnz
    return {
        "case": Path(case_dir).name,
        "satellites": len(case.satellites),
        "grid_samples": int(case.grid.size),
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

    case, tr, _ = _setup(case_dir)
    cands = pass_candidates(case, tr)
    cov = _engine(case, tr, cands)
    rng = np.random.default_rng(seed)
    pick = np.sort(rng.choice(cands.sat.size, min(SUBSAMPLE, cands.sat.size), replace=False))
    sub = Candidates(*(np.asarray(x)[pick] for x in cands))
    g, fov = case.grid, np.array([s.sensor.fov_deg for s in case.satellites])
    t0, c0, mismatch, nonempty = time.perf_counter(), time.process_time(), 0, 0
    refs = []
    for c in range(pick.size):
        s, k0, n, r = sub.sat[c], sub.k0[c], sub.n[c], sub.roll_deg[c]
        inner, outer, _ = edges_np(tr.pos[s, k0 : k0 + n], tr.vel[s, k0 : k0 + n], r, fov[s])
        refs.append(covered_baseline(inner, outer, g.lon_deg, g.lat_deg))
    base_s, base_cpu = time.perf_counter() - t0, time.process_time() - c0
    for c, ref in zip(pick, refs, strict=True):
        got = np.sort(cov.pool[cov.lo[c] : cov.hi[c]].astype(np.int64))
        mismatch += not np.array_equal(got, ref)
        nonempty += ref.size > 0
    _engine(case, tr, sub)  # compile the subsample's shapes
    t1, c1 = time.perf_counter(), time.process_time()
    _engine(case, tr, sub)
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


def bench_coverage(case_dir: str = DEFAULT_CASE, reps: int = 3) -> dict:
    """The coverage section: full table in a subprocess, then the baseline comparison.

    Args:
      case_dir: training case folder.
      reps: timed repetitions of the full table.
    Returns:
      dict for coverage.json.
    """
    spec = json.dumps({"case": case_dir, "reps": reps})
    cmd = [sys.executable, "-m", "bench.coverage", spec]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    full = json.loads(next(ln for ln in out.splitlines() if ln.startswith("RESULT "))[7:])
    cmp_ = _baseline_compare(case_dir, seed=0)
    if cmp_["mismatches"]:
        raise AssertionError(f"coverage: {cmp_['mismatches']} covered sets differ from shapely")
    res = {
        "full": full,
        "compare": cmp_,
        "ratio": full["rate"] / cmp_["baseline_rate"],
        "ratio_cpu": full["rate_cpu"] / cmp_["baseline_rate_cpu"],
        "loadavg_1min": os.getloadavg()[0],
        "cpus": os.cpu_count(),
    }
    print(coverage_summary(res))
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


def coverage_lines(report: dict) -> list[str]:
    """The body of ``COVERAGE.md`` from the section's JSON (also used by ``--render``)."""
    return [
        "",
        "`python -m bench --section coverage` (see bench/coverage.py for the candidate set).",
        "",
        coverage_summary(report["coverage"]),
    ]


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
