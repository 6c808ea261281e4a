"""End-to-end screening workload: one synthetic pass of N routes.

The packaged default scenario has ~1,700 targets (2,330 options of a per-channel
satellite over six hours), too few for the 1,000-10,000-route sizes of the screening benchmark, so
the workload is a synthetic single pass at the density of the former single-pass
default scenario (:func:`synthetic_options`). ALL transitions within ``MAX_GAP``
seconds are screened by the host-generated path, the fused path and the compute
ceiling (:func:`screening_compare`; modes: every row, feasible rows only, the
``TOP_K`` best successors per option), and peak memory is taken per call in a fresh
process (:func:`screening_rss`). :func:`screening_stream` screens and searches in one
pass: the chunks of :func:`jaxspline.screen_chunks` go straight into the streaming
sequencers (``greedy`` on every feasible row, ``beam_search`` on the top-k rows), so
no result the size of the candidates is ever held.
"""

from __future__ import annotations

import statistics
import time

MAX_GAP = 120.0  # [s] longest transition screened
TOP_K = 16  # successors kept per option by the top-k screens
BEAM_WIDTH = 8  # partial plans kept per option by the streamed beam search
#: Modes of the speed comparison: name -> (feasible_only, top_k).
MODES = {"all": (False, None), "feasible": (True, None), "top_k": (True, TOP_K)}


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

    from jaxspline.kernels.limits import AxisLimits
    from jaxspline.screen.options import RouteOptions

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


def _host_top_k(opts, limits, max_gap, chunk, progress, feasible_only, pi, pc, top_k=None):
    """The host path, then the ``top_k`` selection per source on the host (the baseline)."""

    from jaxspline.screen import pairs as screen
    from jaxspline.screen import transitions

    tr = screen._screen_transitions_host(
        opts, limits, max_gap, chunk, progress, feasible_only, pi, pc
    )
    if top_k is None:
        return tr
    keep = transitions.best_per_source(tr.src, tr.margin, int(top_k))
    return screen.Transitions(*(x[keep] for x in tr[:-1]), n_screened=tr.n_screened)


def _paths():
    from jaxspline.screen import fused as screen_fused

    return {"host": _host_top_k, "fused": screen_fused.screen_transitions_fused}


def _call(f, opts, limits, mode: str):
    """One screen of ``opts`` by path function ``f`` in comparison mode ``mode``."""
    from jaxspline.screen import transitions

    feasible_only, top_k = MODES[mode]
    chunk = transitions.default_chunk_size()  # 2**18 on CPU, larger on an accelerator
    return f(opts, limits, MAX_GAP, chunk, False, feasible_only, 0, 1, top_k=top_k)


def _ceiling(opts, limits, n: int = 1 << 20):
    """The host path's chunk program over ``n`` materialized candidates (device arrays).

    The compute ceiling of the same per-candidate work with no pair generation, no
    compaction and no result copies, in the fused path's chunk (``default_chunk_size``;
    ``n`` grows to four chunks, the chunk shrinks to what the pass holds). Returns a
    function that screens them once.
    """
    import jax
    import jax.numpy as jnp
    import numpy as np

    from jaxspline.kernels.batch import ragged_positions
    from jaxspline.screen import host as screen_host
    from jaxspline.screen import transitions

    chunk = transitions.default_chunk_size()
    n = max(n, 4 * chunk)
    runs = transitions.candidate_runs(opts, MAX_GAP)
    k, p = ragged_positions(runs.counts)
    src, dst = runs.order[k[:n]], runs.order[runs.lo[k[:n]] + p[:n]]
    keep = np.asarray(opts.route)[src] != np.asarray(opts.route)[dst]
    src, dst = src[keep], dst[keep]
    sc = screen_host.Screener(opts, limits)
    T = sc.t_start[dst] - sc.t_end[src]
    chunk = min(chunk, 1 << (src.size.bit_length() - 1))  # at least one whole chunk
    chunks = [
        tuple(
            jax.device_put(jnp.asarray(a[i : i + chunk], dt), sc.cand)
            for a, dt in ((src, jnp.int32), (dst, jnp.int32), (T, sc.dtype))
        )
        for i in range(0, src.size - chunk + 1, chunk)
    ]

    def run():
        return [sc.program(sc.table, sc.params, *c) for c in chunks]

    return run, len(chunks) * chunk


def screening_compare(n_routes: int, reps: int = 3, modes=tuple(MODES)) -> dict:
    """Host path vs fused path vs compute ceiling, interleaved repetitions, one process.

    Synthetic pass of ``n_routes`` routes (:func:`synthetic_options`), float64,
    ``MAX_GAP``; for each mode of ``MODES`` both paths run once to compile, then
    ``reps`` rounds of (host, fused, ceiling, fused on the float32 table: reported
    apart, float64 is the default). Rates are candidates screened per second
    (median); ratios are of medians measured in the same rounds.
    """
    import jax

    with jax.enable_x64(True):
        return _screening_compare(n_routes, reps, modes)


def _fits(opts, mode: str, path: str = "host") -> dict | None:
    """None if this screen's result fits in 3/4 of MemAvailable, else why it is skipped.

    The machine is shared: a 10,000-route screen returns ~2.3e8 feasible rows (11 GB)
    even with ``feasible_only``. Upper bounds: every candidate kept (49 B each), times
    2 for the host path's ``feasible_only`` (masked parts plus their concatenation);
    the fused top-k screen keeps O(options x TOP_K) rows.
    """
    from jaxspline.screen import transitions

    feasible_only, top_k = MODES[mode]
    if top_k is not None and path == "fused":
        return None
    n = int(transitions.candidate_runs(opts, MAX_GAP).counts.sum())
    factor = 2.0 if (feasible_only and path == "host") else 1.0
    need = n * 49 * factor / 1e6
    avail = _meminfo("MemAvailable")
    if need <= 0.75 * avail:
        return None
    return {
        "skipped": f"estimated {need:.0f} MB > 3/4 of MemAvailable ({avail:.0f} MB)",
        "candidates": n,
    }


def _meminfo(key: str) -> float:
    with open("/proc/meminfo") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024 / 1e6
    return float("inf")


def _screening_compare(n_routes, reps, modes):
    import jax
    import numpy as np

    opts, limits = synthetic_options(n_routes)
    opts32 = _as_float32(opts)
    modes = [m for m in modes if _fits(opts, m, "host") is None]
    ceiling, n_ceil = _ceiling(opts, limits)
    jax.block_until_ready(ceiling())
    out = {"routes": n_routes, "options": int(np.shape(opts.t_start)[0]), "modes": []}
    for mode in modes:
        times = {"host": [], "fused": [], "ceiling": [], "fused_float32": []}
        fused = _paths()["fused"]
        _call(fused, opts32, limits, mode)  # compile the float32 programs
        first = {}
        res = {}
        for name, f in _paths().items():
            t0 = time.perf_counter()
            res[name] = _call(f, opts, limits, mode)
            first[name] = time.perf_counter() - t0
        n = int(res["fused"].n_screened)
        n_rows = int(res["fused"].src.size)
        n_feasible = int(np.sum(res["host"].feasible)) if mode != "top_k" else None
        same = _same_rows(res["host"], res["fused"])
        del res
        for _ in range(reps):
            for name, f in _paths().items():
                t0 = time.perf_counter()
                r = _call(f, opts, limits, mode)
                times[name].append(time.perf_counter() - t0)
                del r
            t0 = time.perf_counter()
            jax.block_until_ready(ceiling())
            times["ceiling"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            r = _call(fused, opts32, limits, mode)
            times["fused_float32"].append(time.perf_counter() - t0)
            n32 = int(r.n_screened)
            del r
        med = {k: statistics.median(v) for k, v in times.items()}
        rate = {
            "host": n / med["host"],
            "fused": n / med["fused"],
            "ceiling": n_ceil / med["ceiling"],
            "fused_float32": n32 / med["fused_float32"],
        }
        out["modes"].append(
            {
                "mode": mode,
                "feasible_only": MODES[mode][0],
                "top_k": MODES[mode][1],
                "n_screened": n,
                "n_feasible": n_feasible,
                "rows": n_rows,
                "identical_to_host": same,
                "median_s": med,
                "times_s": times,
                "first_s": first,
                "rate": rate,
                "fused_over_host": med["host"] / med["fused"],
                "fused_over_ceiling": rate["fused"] / rate["ceiling"],
            }
        )
    return out


def _as_float32(opts):
    """The option table with float32 angles, rates and times (the fused path then screens
    in float32, T still formed in float64 first)."""
    import numpy as np

    f32 = ("t_start", "t_end", "start_angle", "start_rate", "end_angle", "end_rate", "value")
    return opts._replace(**{f: np.asarray(getattr(opts, f), np.float32) for f in f32})


def _same_rows(a, b) -> bool:
    """Both screens hold the same rows (as sets of (src, dst)) with identical verdicts and
    margins equal to 1e-12 rad."""
    import numpy as np

    if a.src.size != b.src.size or a.n_screened != b.n_screened:
        return False
    oa, ob = np.lexsort((a.dst, a.src)), np.lexsort((b.dst, b.src))
    if not (np.array_equal(a.src[oa], b.src[ob]) and np.array_equal(a.dst[oa], b.dst[ob])):
        return False
    if not np.array_equal(a.feasible[oa], b.feasible[ob]):
        return False
    ma, mb = a.margin[oa], b.margin[ob]
    fin = np.isfinite(ma)
    return bool(np.array_equal(fin, np.isfinite(mb)) and np.all(np.abs(ma[fin] - mb[fin]) <= 1e-12))


def _reset_peak() -> float:
    """Reset the process's peak RSS (``clear_refs`` 5); returns the current RSS in MB."""
    base = _status("VmRSS")
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
    except OSError:
        pass
    return base


def screening_rss(n_routes: int, path: str, mode: str) -> dict:
    """Peak RSS of one screening call (compile included) in a fresh process.

    Run as a subprocess per (routes, path, mode) so peaks do not mix. The peak
    (``VmHWM``) is reset after the options are built (``clear_refs`` 5), so it is the
    screening's own peak on top of the process's resident set at that point.
    """
    import jax

    with jax.enable_x64(True):
        opts, limits = synthetic_options(n_routes)
        skip = _fits(opts, mode, path)
        if skip is not None:
            return {"routes": n_routes, "path": path, "mode": mode, **skip}
        base = _reset_peak()
        t0 = time.perf_counter()
        r = _call(_paths()[path], opts, limits, mode)
        dt = time.perf_counter() - t0
    return {
        "routes": n_routes,
        "path": path,
        "mode": mode,
        "n_screened": int(r.n_screened),
        "rows": int(r.src.size),
        "result_MB": sum(a.nbytes for a in r[:7]) / 1e6,
        "rss_before_MB": base,
        "peak_MB": _status("VmHWM"),
        "seconds_incl_compile": dt,
    }


def screening_stream(n_routes: int, search: str) -> dict:
    """Screen and search in one pass, in a fresh process: time and peak RSS.

    ``search="greedy"``: every feasible row of :func:`jaxspline.screen_chunks` streams
    into :func:`jaxspline.sequences.greedy_chain`; ``"beam"``: the ``TOP_K`` feasible successors of
    largest value density per option (``top_k_by="density"``) stream into
    :func:`jaxspline.sequences.beam_search` (width ``BEAM_WIDTH``). Compile included.
    """
    import jax

    import jaxspline as js

    with jax.enable_x64(True):
        opts, limits = synthetic_options(n_routes)
        base = _reset_peak()
        counts = {"screened": 0, "rows": 0, "chunks": 0}

        def chunks():
            top_k = TOP_K if search == "beam" else None
            stream = js.screen_chunks(
                opts, limits, max_gap=MAX_GAP, top_k=top_k, top_k_by="density", progress=False
            )
            for c in stream:
                counts["screened"] += int(c.n_screened)
                counts["rows"] += int(c.src.size)
                counts["chunks"] += 1
                yield c

        t0 = time.perf_counter()
        if search == "greedy":
            plan = js.sequences.greedy_chain(opts, chunks())
        else:
            plan = js.sequences.beam_search(opts, chunks(), width=BEAM_WIDTH)
        dt = time.perf_counter() - t0
    return {
        "routes": n_routes,
        "search": search,
        "n_screened": counts["screened"],
        "rows_streamed": counts["rows"],
        "chunks": counts["chunks"],
        "plan_options": int(plan.chosen.size),
        "value": float(plan.value),
        "rss_before_MB": base,
        "peak_MB": _status("VmHWM"),
        "seconds_incl_compile": dt,
        "rate": counts["screened"] / dt,
    }


def _status(key: str) -> float:
    """A ``/proc/self/status`` memory field in MB (1e6 bytes, like ``result_MB``)."""
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024 / 1e6  # kB (KiB) -> MB
    return float("nan")
