"""jaxspline CPU benchmark: ``python -m bench [--section NAME] [--quick] [--out DIR]``.

Sections and the files each writes into ``--out`` (default ``bench/results``), every
markdown generated from the JSON beside it (``--render`` rewrites them without
measuring):

- ``bandwidth``, ``kernels``, ``threads`` -> ``report.json``, ``RESULTS.md``,
  ``throughput.png``: the batched JAX kernels against numpy running the same formula, a
  pure-Python loop and Ruckig per call, on the same inputs in one process; candidates/s
  after compilation (compile time apart), median and spread of repetitions, as
  fractions of this machine's measured streaming limit;
- ``screening`` -> ``screening.json``, ``SCREENING.md``: the screening engine end to end
  (:mod:`bench.scenarios`);
- ``scale`` (only when named) -> ``scale.json``, ``SCALE.md``: whole plans of three
  sizes (:mod:`bench.scale`);
- ``job`` (only when named) -> ``job.json``, ``JOB.md``: the default job with every
  output, from an empty compilation cache and warm (:mod:`bench.job`);
- ``coverage`` (only when named) -> ``coverage.json``, ``COVERAGE.md``: the strip
  coverage engine against numpy + shapely on a regional_coverage training case, and
  ``jaxspline plan`` on areas scenarios (coverage, bound, gap, time, peak RSS;
  ``--quick``: the areas example alone) (:mod:`bench.coverage`);
- ``bound`` (only when named) -> ``bound.json``, ``BOUND.md``: the bound's DP
  iterations/s, numpy and JAX on the default device, and the plain vs strengthened
  bound (:mod:`bench.bound`).

Without ``--section`` the first four run.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def _parse(argv):
    p = argparse.ArgumentParser(
        prog="python -m bench",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", default="bench/results", help="output folder (default bench/results)")
    p.add_argument("--quick", action="store_true", help="small batches only (smoke test, ~1 min)")
    p.add_argument("--max-batch", type=float, default=1e8, help="largest batch (default 1e8)")
    p.add_argument("--reps", type=int, default=5, help="repetitions per measurement (default 5)")
    p.add_argument("--float32", action="store_true", help="float32 only (default: both)")
    p.add_argument(
        "--section",
        action="append",
        choices=[
            "bandwidth",
            "kernels",
            "threads",
            "screening",
            "scale",
            "job",
            "coverage",
            "bound",
        ],
        help="run only these sections (repeatable; scale, job, coverage and bound run only when "
        "named)",
    )
    p.add_argument(
        "--only",
        action="append",
        metavar="KERNEL",
        help="benchmark only these kernels, e.g. is_reachable (repeatable)",
    )
    p.add_argument(
        "--routes",
        action="append",
        type=int,
        help="screening section: route counts (repeatable; default 1000 2000 5000 10000)",
    )
    p.add_argument(
        "--modes",
        action="append",
        choices=("all", "feasible", "top_k"),
        help="screening section: comparison modes (repeatable; default all three)",
    )
    p.add_argument(
        "--sizes",
        default="default:20,12x12h:120,day:540",
        help="scale section: comma-separated sizes, default / 12x12h / day or a scenario "
        "TOML, each optionally SIZE:SECONDS for its own planning budget (default "
        "default:20,12x12h:120,day:540)",
    )
    p.add_argument(
        "--time-limit",
        type=float,
        default=60.0,
        help="scale section: planning budget [s] of a size given without one",
    )
    p.add_argument(
        "--max-rss-gb",
        type=float,
        default=8.0,
        help="scale, job and coverage sections: kill a plan whose process tree exceeds "
        "this RSS (default 8)",
    )
    p.add_argument(
        "--max-wall-min",
        type=float,
        default=60.0,
        help="scale, job and coverage sections: kill a plan running longer than this "
        "(default 60 min)",
    )
    p.add_argument(
        "--scale-dir", help="scale section: keep scenarios and plans here (default: a temp dir)"
    )
    p.add_argument(
        "--bound-hours",
        default="0.5,3",
        help="bound section: comma-separated horizons [h] of the 12x12h preset (default 0.5,3)",
    )
    p.add_argument(
        "--bound-seconds",
        type=float,
        default=5.0,
        help="bound section: seconds per iterations/s measurement (default 5)",
    )
    p.add_argument(
        "--job-runs", type=int, default=2, help="job section: runs, the first cold (default 2)"
    )
    p.add_argument(
        "--job-max-iters",
        type=int,
        default=200,
        help="job section: the plan's --max-iters (default 200; 0: the time limit alone)",
    )
    p.add_argument(
        "--render",
        action="store_true",
        help="measure nothing: rewrite every markdown of --out from its JSON",
    )
    p.add_argument("--child", help=argparse.SUPPRESS)  # internal: run one measurement, print JSON
    return p.parse_args(argv)


def _jax_setup(x64: bool):
    import jax

    jax.config.update("jax_enable_x64", x64)
    return jax


# ------------------------------------------------------------------ streaming limit
def measure_bandwidth(reps: int, nbytes: int = 1 << 30) -> dict:
    """Memory read bandwidth: a jitted sum over ``nbytes`` of float64 (GB/s)."""
    jax = _jax_setup(True)
    import jax.numpy as jnp

    from bench.timing import time_jax

    x = jnp.ones(nbytes // 8, dtype=jnp.float64)
    t = time_jax(jax.jit(jnp.sum), (x,), n=nbytes, reps=reps)
    return {
        "bytes": nbytes,
        "GBps": t.rate / 1e9,
        "GBps_lo": t.rate_spread[0] / 1e9,
        "GBps_hi": t.rate_spread[1] / 1e9,
        "compile_s": t.compile_s,
    }


# ------------------------------------------------------------------ kernels
# Batches above CHUNK are streamed the way the screening engine does it: calls of CHUNK
# candidates cycling over a materialized pool of POOL candidates (8 chunks, ~335 MB of
# float64 inputs: far beyond any cache, so every pass streams from memory). Chunked
# outputs (<= 8 MB) are reused by the allocator instead of being page-faulted anew.
CHUNK = 1 << 20
POOL = 8 * CHUNK


def _batch_sizes(max_batch: float, quick: bool) -> list[int]:
    top = 1e5 if quick else max_batch
    return [int(10**e) for e in range(3, 9) if 10**e <= top]


def bench_kernel(w, dtype: str, sizes: list[int], reps: int, do_baselines: bool) -> dict:
    """Throughput of one workload over batch sizes, plus baselines at the largest numpy size."""
    jax = _jax_setup(dtype == "float64")
    import jax.numpy as jnp

    from bench.timing import time_call, time_jax

    npdt = np.float64 if dtype == "float64" else np.float32
    fn = jax.jit(jax.vmap(w.jax_kernel))
    rows = []
    for n in sizes:
        if n > w.max_batch:
            break
        if n <= CHUNK:  # one call on a materialized batch
            inp = w.make_inputs(n, 0)
            args = tuple(jnp.asarray(inp[k].astype(npdt)) for k in w.args)
            t = time_jax(fn, args, n=n, reps=reps)
        else:  # stream n // CHUNK calls over the pool's chunks
            inp = w.make_inputs(POOL, 0)
            chunks = [
                tuple(jnp.asarray(inp[k][i * CHUNK : (i + 1) * CHUNK].astype(npdt)) for k in w.args)
                for i in range(POOL // CHUNK)
            ]
            calls = n // CHUNK
            compile_s = time_jax(fn, chunks[0], n=CHUNK, reps=1).compile_s

            def stream(chunks=chunks, calls=calls):
                for i in range(calls):
                    last = fn(*chunks[i % len(chunks)])
                return last

            t = time_call(stream, n=calls * CHUNK, reps=max(1, reps // 2))
            t = type(t)(t.n, t.median_s, t.min_s, t.max_s, t.reps, compile_s)
            args = chunks
        rows.append({"n": int(t.n), **t.to_dict()})
        del args, inp  # free the pool before the next size
    out = {"workload": w.name, "dtype": dtype, "jax": rows}
    if not do_baselines:
        return out
    # baselines on the same inputs (numpy at 1e6, Python/Ruckig on subsamples)
    n_np = int(min(10**6, w.max_batch))
    inp = w.make_inputs(n_np, 0)
    arrs = [inp[k].astype(npdt) for k in w.args]
    jargs = tuple(jnp.asarray(a) for a in arrs)
    jax_out = np.asarray(jax.tree_util.tree_leaves(fn(*jargs))[0])
    if w.numpy_fn is not None:
        t = time_call(lambda: w.numpy_fn(*arrs), n=n_np, reps=reps)
        ref = np.asarray(w.numpy_fn(*arrs))
        ref = ref[0] if ref.ndim > 1 else ref
        out["numpy"] = {**t.to_dict(), "agree": _agree(jax_out, ref)}
    for key, f in w.extra.items():
        t = time_call(lambda f=f: f(*arrs), n=n_np, reps=reps)
        ref = np.asarray(f(*arrs))
        ref = ref[0] if ref.ndim > 1 else ref
        out[key] = {**t.to_dict(), "agree": _agree(jax_out, ref)}
    # numpy again on the streamed pool (memory-bound, like the JAX streaming rows); JAX's
    # figure at the same regime is its largest streamed batch over these very inputs
    big = [r for r in out["jax"] if r["n"] > CHUNK]
    if w.numpy_fn is not None and big:
        pool = w.make_inputs(POOL, 0)
        parr = [pool[k].astype(npdt) for k in w.args]
        t = time_call(lambda: w.numpy_fn(*parr), n=POOL, reps=max(1, reps // 2))
        out["numpy_streamed"] = {**t.to_dict(), "jax_rate": big[-1]["rate"]}
        del pool, parr
    for key, f, m in (("python", w.python_fn, 20000), ("ruckig", w.ruckig_fn, 2000)):
        if f is None:
            continue
        sub = [a[:m].astype(np.float64).tolist() for a in arrs]
        t0 = time.perf_counter()
        vals = [f(*c) for c in zip(*sub, strict=True)]
        dt = time.perf_counter() - t0
        out[key] = {
            "n": m,
            "median_s": dt,
            "rate": m / dt,
            "agree": _agree(jax_out[:m], np.asarray(vals, dtype=jax_out.dtype)),
        }
    return out


def _agree(a, b) -> dict:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype == bool or b.dtype == bool:
        mism = int(np.sum(a.astype(bool) != b.astype(bool)))
        return {"n": int(a.size), "mismatches": mism}
    fin = np.isfinite(a) & np.isfinite(b)
    dev = (
        float(np.max(np.abs(a[fin] - b[fin]) / np.maximum(1.0, np.abs(b[fin]))))
        if fin.any()
        else 0.0
    )
    return {
        "n": int(a.size),
        "max_rel_dev": dev,
        "inf_mismatches": int(np.sum(np.isfinite(a) != np.isfinite(b))),
    }


def _child(spec: str) -> None:
    """Run one measurement described by JSON ``spec`` and print a JSON line (subprocess use)."""
    s = json.loads(spec)
    if s.get("kind") == "screening_speed":
        from bench.scenarios import screening_compare

        res = screening_compare(s["routes"], s["reps"], s["modes"])
        print("RESULT " + json.dumps(res))
        return
    if s.get("kind") == "screening_rss":
        from bench.scenarios import screening_rss

        print("RESULT " + json.dumps(screening_rss(s["routes"], s["path"], s["mode"])))
        return
    if s.get("kind") == "screening_stream":
        from bench.scenarios import screening_stream

        print("RESULT " + json.dumps(screening_stream(s["routes"], s["search"])))
        return
    from bench.cases import workloads

    w = {w.name: w for w in workloads()}[s["workload"]]
    if s.get("devices", 1) > 1:  # shard the candidate axis over forced host devices
        jax = _jax_setup(s["dtype"] == "float64")
        import jax.numpy as jnp
        from jax.sharding import Mesh, NamedSharding, PartitionSpec

        from bench.timing import time_jax

        mesh = Mesh(np.array(jax.devices()), ("c",))
        sh = NamedSharding(mesh, PartitionSpec("c"))
        inp = w.make_inputs(s["n"], 0)
        args = tuple(jax.device_put(jnp.asarray(inp[k]), sh) for k in w.args)
        t = time_jax(jax.jit(jax.vmap(w.jax_kernel)), args, n=s["n"], reps=s["reps"])
        res = {"n": s["n"], "devices": len(jax.devices()), **t.to_dict()}
    else:
        res = bench_kernel(w, s["dtype"], [s["n"]], s["reps"], False)["jax"][0]
    print("RESULT " + json.dumps(res))


def _run_child(spec: dict, env_extra: dict | None = None, prefix: list[str] | None = None) -> dict:
    env = dict(os.environ, **(env_extra or {}))
    cmd = (prefix or []) + [sys.executable, "-m", "bench", "--child", json.dumps(spec)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    return json.loads(next(ln for ln in out.splitlines() if ln.startswith("RESULT "))[7:])


def bench_threads(reps: int, n: int) -> dict:
    """Membership throughput pinned to 1 core (taskset) vs both cores; 1 vs 2 forced devices."""
    spec = {"workload": "is_reachable", "dtype": "float64", "n": n, "reps": reps}
    res = {"n": n}
    try:
        res["1_core"] = _run_child(spec, prefix=["taskset", "-c", "0"])
    except (OSError, subprocess.CalledProcessError) as exc:
        res["1_core"] = {"error": str(exc)}
    res["2_cores"] = _run_child(spec)
    res["2_devices"] = _run_child(
        dict(spec, devices=2), {"XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    )
    return res


# ------------------------------------------------------------------ end-to-end screening
#: Route counts of the screening section (synthetic single pass, see bench.scenarios).
SCREEN_ROUTES = [1000, 2000, 5000, 10000]
#: Largest route count run with every row returned (10,000 routes: 3e8 rows, 15 GB).
FULL_MAX_ROUTES = 5000
#: Largest route count for the host path (it holds every feasible row, 11 GB at 10,000
#: routes, and ~2x that with feasible_only: masked parts plus their concatenation).
HOST_MAX_ROUTES = 5000


def bench_screening(route_counts: list[int], reps: int, only_modes=None) -> dict:
    """End-to-end screening: host vs fused path vs ceiling, peak RSS, screen + search.

    Speed: one subprocess per route count, interleaved repetitions of both paths and
    the ceiling in every mode (``bench.scenarios.screening_compare``). Memory: one
    subprocess per (routes, path, mode), ``VmHWM`` of one call
    (``bench.scenarios.screening_rss``). Streaming: one subprocess per (routes,
    search), the screen's chunks consumed by the search as they come
    (``bench.scenarios.screening_stream``). ``only_modes``: the comparison modes to run
    (None: every mode of ``bench.scenarios.MODES``).
    """
    from bench.scenarios import MODES

    speed, rss, stream = [], [], []
    for r in route_counts:
        modes = list(MODES) if r <= FULL_MAX_ROUTES else ["feasible", "top_k"]
        modes = [m for m in modes if only_modes is None or m in only_modes]
        if r <= HOST_MAX_ROUTES:
            spec = {"kind": "screening_speed", "routes": r, "reps": reps, "modes": modes}
            speed.append(_run_child(spec))
            for m in speed[-1]["modes"]:
                print(
                    f"  screening {r} routes, {m['mode']}: {m['n_screened']:.3g} candidates, "
                    f"fused {m['rate']['fused']:.3g}/s, host {m['rate']['host']:.3g}/s "
                    f"(fused/host {m['fused_over_host']:.2f}x), ceiling "
                    f"{m['rate']['ceiling']:.3g}/s, identical {m['identical_to_host']}",
                    flush=True,
                )
        for mode in modes:
            for path in ("host", "fused"):
                if path == "host" and r > HOST_MAX_ROUTES:
                    continue
                spec = {"kind": "screening_rss", "routes": r, "path": path, "mode": mode}
                rss.append(_child_or_error(spec, {"routes": r, "path": path, "mode": mode}))
                print(f"  rss {rss[-1]}", flush=True)
        for search in ("greedy", "beam"):
            spec = {"kind": "screening_stream", "routes": r, "search": search}
            stream.append(_child_or_error(spec, {"routes": r, "search": search}))
            print(f"  stream {stream[-1]}", flush=True)
    return {"speed": speed, "rss": rss, "stream": stream}


def _child_or_error(spec: dict, tag: dict) -> dict:
    try:
        return _run_child(spec)
    except subprocess.CalledProcessError as exc:
        return {**tag, "error": (exc.stderr or str(exc))[-300:]}


# ------------------------------------------------------------------ driver
#: Sections with files of their own (``scale.json`` / ``SCALE.md``, ...); the others
#: share ``report.json`` / ``RESULTS.md``.
OWN_FILES = ("screening", "scale", "job", "coverage", "bound")


def _write(report: dict, sections: set, out: Path) -> None:
    """Write each measured section's files: the common ones and those of its own."""
    from bench.bound import write_bound
    from bench.coverage import write_coverage
    from bench.job import write_job
    from bench.report import write_outputs, write_screening
    from bench.scale import write_scale

    common = {k: v for k, v in report.items() if k not in OWN_FILES}
    meta = {k: report[k] for k in ("machine", "args", "total_s")}
    writers = {
        "screening": write_screening,
        "scale": write_scale,
        "job": write_job,
        "coverage": write_coverage,
        "bound": write_bound,
    }
    for name in OWN_FILES:
        if name in sections:
            writers[name]({**meta, name: report[name]}, out)
    if sections - set(OWN_FILES):
        write_outputs(common, out)


def main(argv=None) -> int:
    args = _parse(argv)
    if args.child:
        _child(args.child)
        return 0
    if args.render:
        from bench.render import render_all

        render_all(Path(args.out))
        return 0
    sections = set(args.section or ["bandwidth", "kernels", "threads", "screening"])
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = {
        "machine": {
            "python": platform.python_version(),
            "cpus": os.cpu_count(),
            "platform": platform.platform(),
        },
        "args": vars(args),
    }
    import jax

    report["machine"]["jax"] = jax.__version__
    t_all = time.perf_counter()
    if "bandwidth" in sections:
        report["bandwidth"] = measure_bandwidth(args.reps, 1 << (27 if args.quick else 30))
        print(f"streaming limit: {report['bandwidth']['GBps']:.1f} GB/s (jnp.sum)", flush=True)
    if "kernels" in sections:
        from bench.cases import workloads

        sizes = _batch_sizes(args.max_batch, args.quick)
        dtypes = ["float32"] if args.float32 else ["float64", "float32"]
        report["kernels"] = []
        chosen = [w for w in workloads() if not args.only or w.name in args.only]
        if args.only and len(chosen) != len(set(args.only)):
            known = ", ".join(w.name for w in workloads())
            raise SystemExit(f"--only: unknown kernel in {args.only}; known: {known}")
        for w in chosen:
            for dt in dtypes:
                print(f"kernel {w.name} [{dt}] ...", flush=True)
                report["kernels"].append(bench_kernel(w, dt, sizes, args.reps, dt == dtypes[0]))
    if "threads" in sections:
        report["threads"] = bench_threads(args.reps, 10**5 if args.quick else 10**7)
    if "screening" in sections:
        counts = args.routes or ([300, 1000] if args.quick else SCREEN_ROUTES)
        report["screening"] = bench_screening(counts, max(3, args.reps // 2), args.modes)
    if "scale" in sections:
        from bench.scale import bench_scale

        sizes = [s.strip() for s in args.sizes.split(",") if s.strip()]
        report["scale"] = bench_scale(
            sizes, args.time_limit, args.max_rss_gb, args.max_wall_min, args.scale_dir
        )
    if "job" in sections:
        from bench.job import bench_job

        report["job"] = bench_job(
            args.job_runs, args.job_max_iters, args.max_rss_gb, args.max_wall_min
        )
    if "coverage" in sections:
        from bench.coverage import bench_coverage

        report["coverage"] = bench_coverage(
            reps=max(1, args.reps // 2),
            quick=args.quick,
            guard=(args.max_rss_gb, args.max_wall_min),
        )
    if "bound" in sections:
        from bench.bound import bench_bound

        hours = [float(h) for h in args.bound_hours.split(",") if h.strip()]
        report["bound"] = bench_bound(hours, args.bound_seconds)
    report["total_s"] = time.perf_counter() - t_all
    _write(report, sections, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
