"""End-to-end screening workload: the default scenario's geometry with N routes.

Builds route options from the orbit/pointing geometry (timed apart: it is the
geometry stage, not screening), then screens ALL candidate transitions with
``screen_transitions`` — first call compiles, the following calls are timed.
"""

from __future__ import annotations

import statistics
import time


def screening_case(n_routes: int, reps: int = 2) -> dict:
    """Screen every transition of the default scenario with ``n_routes`` random routes."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    jax.config.update("jax_enable_x64", True)
    from jaxspline.limits import AxisLimits
    from jaxspline.scenario import default_scenario
    from jaxspline.screen import screen_transitions

    sc = default_scenario(count=n_routes)
    pl = sc.planner
    t0 = time.perf_counter()
    routes = sc.route_set()
    opts, _ = sc.route_options(routes)
    geometry_s = time.perf_counter() - t0
    keep = np.flatnonzero(np.asarray(opts.scan_ok))
    opts = type(opts)(*(jnp.asarray(np.asarray(x)[keep]) for x in opts))
    limits = AxisLimits(jnp.asarray(sc.limits.rate), jnp.asarray(sc.limits.accel))

    def run():
        return screen_transitions(opts, limits, max_gap=pl.max_gap, progress=False)

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
        "routes": n_routes,
        "options": int(keep.size),
        "n_screened": int(tr.n_screened),
        "n_feasible": int(np.sum(tr.feasible)),
        "median_s": med,
        "min_s": min(times),
        "max_s": max(times),
        "compile_s": max(first_s - med, 0.0),
        "geometry_s": geometry_s,
        "max_gap_s": pl.max_gap,
    }
