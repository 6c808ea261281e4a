"""Bound section: DP iterations/s (numpy, JAX on the default device), plain vs strengthened bound.

``python -m bench --section bound [--bound-hours 0.5,3] [--bound-seconds 5]`` builds,
for each horizon H, the 12 x 12 h preset cut to H hours
(``scripts/make_scale_scenario.py --preset 12x12h --hours H``; the problem by
:func:`jaxspline.build_problem`) and measures, same inputs, same process:

* *numpy*: :func:`jaxspline.search.dp_paths` (forward + back-tracking) and the forward
  pass alone (:func:`jaxspline.search.dp_forward`), iterations/s over ``--bound-seconds``;
* *JAX*: :class:`jaxspline.search.dp_jax.JaxDP` on ``jax.devices()[0]`` (CPU here, a GPU
  where one is installed), compile time apart, the forward pass alone and with the
  host back-tracking, and ``DP_BATCH`` value vectors in one scan (``JaxDP.forward_many``,
  counted as that many passes); ``equal`` says its values match numpy's bit for bit;
* the bound iterated to convergence (:func:`jaxspline.search.upper_bound`, battery
  relaxed, iteration cap ``BOUND_ITERS``): plain and strengthened (``merge_repeats``),
  value, iterations, seconds;
* the strengthened relaxation's *floor* (:func:`jaxspline.search.relaxation_floor`,
  ``FW_ITERS`` Frank-Wolfe steps): a fractional plan's value, below which no bound of
  that relaxation can go.

Writes ``bound.json`` and ``BOUND.md``.
"""

from __future__ import annotations

import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench.markdown import cell, header, row, section, write_result

REPO = Path(__file__).resolve().parents[1]
GENERATOR = REPO / "scripts" / "make_scale_scenario.py"
BOUND_ITERS = 3000  # cap of the converged bound (it converges in a few hundred)
DP_BATCH = 64  # value vectors of one batched JAX forward pass
PLAN_VALUE = 1.0  # step-size target of the bound runs (any value gives a valid bound)
FW_ITERS = 200  # Frank-Wolfe steps of the floor
COLUMNS = (
    "hours|options|near pairs|blocks|numpy DP it/s|numpy fwd it/s|JAX fwd it/s|"
    f"JAX DP it/s|JAX fwd x{DP_BATCH} passes/s|JAX compile s|equal|plain bound|it|s|"
    "strengthened bound|it|s|floor|s"
).split("|")


def _rate(fn, seconds: float) -> float:
    """Calls of ``fn`` per second over at least ``seconds`` (one call at least)."""
    t0, n = time.perf_counter(), 0
    while True:
        fn()
        n += 1
        dt = time.perf_counter() - t0
        if dt >= seconds:
            return n / dt


def _problem(hours: float, workdir: Path):
    """The 12 x 12 h preset cut to ``hours``, as a search Problem (and its build time)."""
    import jax

    from jaxspline import build_problem, load_scenario

    toml = workdir / f"bound_12x12h_{hours:g}h.toml"
    if not toml.exists():
        cmd = [sys.executable, str(GENERATOR), "--preset", "12x12h", "--hours", f"{hours:g}"]
        subprocess.run([*cmd, "--out", str(toml)], check=True, capture_output=True)
    t0 = time.perf_counter()
    with jax.enable_x64(True):  # float64 like the CLI
        pb = build_problem(load_scenario(toml)).problem
    return pb, time.perf_counter() - t0


def bench_one(hours: float, seconds: float, workdir: Path) -> dict:
    """All figures of one horizon (module docstring)."""
    import jax

    from jaxspline.search import dp_forward, dp_paths, dp_prepare, relaxation_floor, upper_bound
    from jaxspline.search.dp_jax import JaxDP

    pb, build_s = _problem(hours, workdir)
    d = dp_prepare(pb)
    w = 0.5 * np.asarray(pb.target_value)[np.asarray(pb.option_target)]
    out = {
        "hours": hours,
        "options": pb.n_options,
        "near_pairs": len(pb.pairs),
        "blocks": len(d.groups),
        "build_s": round(build_s, 2),
        "numpy_dp_per_s": _rate(lambda: dp_paths(pb, d, w), seconds),
        "numpy_forward_per_s": _rate(lambda: dp_forward(pb, d, w), seconds),
    }
    t0 = time.perf_counter()
    jd = JaxDP(pb, d)
    best = jd.forward(w)
    out["jax_compile_s"] = round(time.perf_counter() - t0, 2)
    out["jax_equal"] = bool(np.array_equal(best, dp_forward(pb, d, w)))
    out["jax_forward_per_s"] = _rate(lambda: jd.forward(w), seconds)
    out["jax_dp_per_s"] = _rate(lambda: jd.paths(w), seconds)
    ws = w * np.random.default_rng(0).uniform(0.5, 1.0, (DP_BATCH, w.size))
    many = jd.forward_many(ws)  # compiles
    same = all(np.array_equal(many[k], dp_forward(pb, d, ws[k])) for k in (0, DP_BATCH - 1))
    out["jax_equal"] = out["jax_equal"] and same
    out["jax_batch"] = DP_BATCH
    out["jax_batch_passes_per_s"] = DP_BATCH * _rate(lambda: jd.forward_many(ws), seconds)
    out["jax_device"] = str(jax.devices()[0])
    for key, merge in (("plain", False), ("strengthened", True)):
        t0 = time.perf_counter()
        res = upper_bound(pb, PLAN_VALUE, math.inf, BOUND_ITERS, merge_repeats=merge)
        out[key] = {
            "bound": res.bound,
            "iterations": res.iterations,
            "status": res.status.value,
            "seconds": round(time.perf_counter() - t0, 2),
        }
    fl = relaxation_floor(pb, PLAN_VALUE, math.inf, BOUND_ITERS, FW_ITERS, dp=d)
    out["floor"] = {"floor": fl.floor, "seconds": round(fl.seconds, 2)}
    return out


def bench_bound(hours: list[float], seconds: float, workdir: str | None = None) -> dict:
    """Every horizon in turn; the section's report."""
    import tempfile

    import jax

    with tempfile.TemporaryDirectory(prefix="jaxspline_bound_") as tmp:
        wd = Path(workdir or tmp)
        wd.mkdir(parents=True, exist_ok=True)
        runs = []
        for h in hours:
            print(f"bound: 12x12h cut to {h:g} h ...", flush=True)
            runs.append(bench_one(h, seconds, wd))
            print("  " + str(runs[-1]), flush=True)
    return {
        "hours": hours,
        "seconds": seconds,
        "devices": [str(x) for x in jax.devices()],
        "runs": runs,
    }


def bound_table(report: dict) -> list[str]:
    """Markdown: one row per horizon."""
    lines = [
        "\nThe 12 x 12 h preset cut to *hours* (`scripts/make_scale_scenario.py --preset "
        "12x12h --hours H`). DP it/s: forward pass + back-tracking of every satellite's "
        "path (`dp_paths`); fwd: the forward pass alone; JAX on "
        f"{', '.join(report.get('devices', [])) or '-'} (compile apart; *equal*: the same "
        f"values as numpy bit for bit; x{DP_BATCH}: that many value vectors in one scan, "
        "counted as that many passes). Bounds iterated to convergence, battery relaxed: "
        "*plain* is the per-satellite path relaxation, *strengthened* credits a run of "
        "one target's options once (`merge_repeats`); *floor*: the value of a fractional "
        f"plan of the strengthened relaxation ({FW_ITERS} Frank-Wolfe steps, "
        "`relaxation_floor`): no bound of that relaxation can go below it.",
        *header(*COLUMNS),
    ]
    for r in report.get("runs", []):
        p, s, f = r.get("plain", {}), r.get("strengthened", {}), r.get("floor", {})
        lines.append(
            row(
                [
                    cell(r.get("hours"), "{:g}"),
                    cell(r.get("options"), "{:d}"),
                    cell(r.get("near_pairs"), "{:d}"),
                    cell(r.get("blocks"), "{:d}"),
                    *(
                        cell(r.get(k), "{:.1f}")
                        for k in (
                            "numpy_dp_per_s",
                            "numpy_forward_per_s",
                            "jax_forward_per_s",
                            "jax_dp_per_s",
                            "jax_batch_passes_per_s",
                        )
                    ),
                    cell(r.get("jax_compile_s"), "{:.1f}"),
                    cell(r.get("jax_equal")),
                    cell(p.get("bound"), "{:.1f}"),
                    cell(p.get("iterations"), "{:d}"),
                    cell(p.get("seconds"), "{:.1f}"),
                    cell(s.get("bound"), "{:.1f}"),
                    cell(s.get("iterations"), "{:d}"),
                    cell(s.get("seconds"), "{:.1f}"),
                    cell(f.get("floor"), "{:.1f}"),
                    cell(f.get("seconds"), "{:.1f}"),
                ]
            )
        )
    return section("bound", lines)


def write_bound(report: dict, out: Path) -> None:
    """Write ``bound.json`` and ``BOUND.md`` into ``out``."""
    write_result(out, "bound", report, "Bound: DP speed and strength", bound_table(report["bound"]))
