"""End-to-end screening workload: the default scenario's geometry with N targets.

Builds the options of the default constellation restricted to its first N targets
through :func:`jaxspline.engine.planner.build_problem` (timed apart: orbits, windows and options
are the geometry stage), then screens ALL transitions of the first per-channel
satellite's options within ``MAX_GAP`` seconds with ``screen_transitions`` - the
first call compiles, the following calls are timed.
"""

from __future__ import annotations

import dataclasses
import statistics
import time

MAX_GAP = 120.0  # [s] longest transition screened


def screening_case(n_routes: int, reps: int = 2) -> dict:
    """Screen every transition of one per-channel satellite with ``n_routes`` targets."""
    import jax
    import numpy as np

    from jaxspline.engine.options import take_options
    from jaxspline.engine.planner import build_problem
    from jaxspline.engine.screen import screen_transitions
    from jaxspline.scenario import default_scenario

    sc = default_scenario()
    n = min(n_routes, len(sc.targets))
    tg = type(sc.targets)(
        **{f.name: getattr(sc.targets, f.name)[:n] for f in dataclasses.fields(sc.targets)}
    )
    sc = dataclasses.replace(sc, targets=tg)
    k = next(i for i, s in enumerate(sc.satellites) if s.model == "per_channel")
    t0 = time.perf_counter()
    prep = build_problem(sc)
    geometry_s = time.perf_counter() - t0
    o = prep.opportunities.options
    opts = take_options(o, np.flatnonzero(o.sat == k))
    limits = sc.satellites[k].limits
    with jax.enable_x64(True):

        def run():
            return screen_transitions(opts, limits, max_gap=MAX_GAP, progress=False)

        t0 = time.perf_counter()
        tr = run()
        first_s = time.perf_counter() - t0
        times = []
        for _ in range(reps):
            t0 = time.perf_counter()
            tr = run()
            times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    return {
        "routes": n,
        "options": int(np.shape(opts.t_start)[0]),
        "n_screened": int(tr.n_screened),
        "n_feasible": int(np.sum(tr.feasible)),
        "median_s": med,
        "min_s": min(times),
        "max_s": max(times),
        "compile_s": max(first_s - med, 0.0),
        "geometry_s": geometry_s,
        "max_gap_s": MAX_GAP,
    }
