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


HORIZON_S = 1375.0  # [s] synthetic pass: 5,000 routes give ~7.5e7 candidates at MAX_GAP
PER_ROUTE = 6  # options per route (the former single-pass scenario had 5.9)
SPREAD = (1.4, 1.4, 0.6)  # [rad] start-angle spread per channel
SCAN_RATE = 0.7  # [deg/s] largest scan rate (channels 1-2; channel 3 the same)


def synthetic_options(n_routes: int, seed: int = 0):
    """RouteOptions of ``n_routes`` routes in one ``HORIZON_S`` pass, 3 channels.

    The density of the former single-pass default scenario (29,329 options and
    7.5e7 candidates within ``MAX_GAP`` at 5,000 routes), for route counts the
    packaged scenario (~1,700 targets) cannot reach: each route has ``PER_ROUTE``
    start options 6 s apart around a random centre, 5-20 s scans, start angles
    within +-SPREAD rad per channel drifting slowly, constant scan rates within
    +-0.7 deg/s; the default scenario's per-channel limits (3, 3, 2 deg/s;
    1.5, 1.5, 1 deg/s^2). Returns (RouteOptions, AxisLimits).
    """
    import numpy as np

    from jaxspline.engine.options import RouteOptions
    from jaxspline.kernels.limits import AxisLimits

    rng = np.random.default_rng(seed)
    c = 3
    centre = rng.uniform(0, HORIZON_S, n_routes)
    base = rng.uniform(-1.0, 1.0, (n_routes, c)) * np.asarray(SPREAD)
    slope = rng.uniform(-0.005, 0.005, (n_routes, c))
    dur = rng.uniform(5.0, 20.0, n_routes)
    srate = np.deg2rad(rng.uniform(-1.0, 1.0, (n_routes, c))) * SCAN_RATE
    off = (np.arange(PER_ROUTE) - (PER_ROUTE - 1) / 2) * 6.0
    route = np.repeat(np.arange(n_routes, dtype=np.int32), PER_ROUTE)
    ts = (centre[:, None] + off).reshape(-1)
    sa = (base[:, None, :] + slope[:, None, :] * off[None, :, None]).reshape(-1, c)
    sr = np.repeat(srate, PER_ROUTE, axis=0)
    te = ts + np.repeat(dur, PER_ROUTE)
    ea = sa + sr * (te - ts)[:, None]
    opts = RouteOptions(
        route=route,
        t_start=ts,
        t_end=te,
        start_angle=sa,
        start_rate=sr,
        end_angle=ea,
        end_rate=sr.copy(),
        value=rng.uniform(1, 10, route.size),
        scan_ok=np.ones(route.size, bool),
    )
    limits = AxisLimits(rate=np.deg2rad([3.0, 3.0, 2.0]), accel=np.deg2rad([1.5, 1.5, 1.0]))
    return opts, limits
