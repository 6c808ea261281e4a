"""``jaxspline plan``: scenario -> route options -> screening -> sequence -> refine -> validate.

Writes ``plan.json``, ``plan.csv`` and three figures (``ground_track.png``,
``attitude.png``, ``margins.png``) into the output directory; never overwrites
an existing output unless ``--force``.
"""

from __future__ import annotations

import csv
import io
import json
import time
from pathlib import Path

import numpy as np

from jaxspline._io import atomic_write_text

__all__ = ["register", "run_plan", "OUTPUT_FILES"]

OUTPUT_FILES = ("plan.json", "plan.csv", "ground_track.png", "attitude.png", "margins.png")


def register(sub) -> None:
    """Register the ``plan`` sub-command."""
    p = sub.add_parser(
        "plan",
        help="plan imaging on a scenario (default: built-in 300-target pass)",
        description=__doc__,
    )
    p.add_argument("scenario", nargs="?", help="scenario TOML (default: built-in scenario)")
    p.add_argument("-o", "--outdir", default="plan_out", help="output directory (default plan_out)")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.add_argument("--float32", action="store_true", help="compute in float32 (default float64)")
    p.add_argument("--beam-width", type=int, default=None, help="beam width (overrides scenario)")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_main)


def _main(args) -> int:
    run_plan(
        args.scenario,
        args.outdir,
        force=args.force,
        beam_width=args.beam_width,
        plots=not args.no_plots,
        progress=not args.quiet,
    )
    return 0


def _take(options, idx):
    return take_options(options, idx)


def _pair_lookup(tr, src, dst):
    """Index of each (src, dst) pair in the Transitions table (-1 if absent)."""
    src = np.atleast_1d(np.asarray(src, np.int64))
    dst = np.atleast_1d(np.asarray(dst, np.int64))
    key = np.asarray(tr.src, np.int64) * (1 << 32) + np.asarray(tr.dst, np.int64)
    if key.size == 0:
        return np.full(src.shape, -1, np.int64)
    q = src * (1 << 32) + dst
    order = np.argsort(key)
    pos = np.clip(np.searchsorted(key[order], q), 0, key.size - 1)
    return np.where(key[order][pos] == q, order[pos], -1)


def run_plan(
    scenario_path=None,
    outdir="plan_out",
    *,
    force: bool = False,
    beam_width: int | None = None,
    plots: bool = True,
    progress: bool = True,
    scenario=None,
) -> dict:
    """Run the whole planning job; returns the summary dict written to ``plan.json``.

    ``scenario`` (a Scenario) overrides ``scenario_path``; with neither, the built-in
    default scenario is used. Raises FileExistsError naming an existing output file
    unless ``force``; ValueError on a bad scenario.
    """
    import jax.numpy as jnp

    from jaxspline import reach
    from jaxspline import refine as refine_mod
    from jaxspline import screen as screen_mod
    from jaxspline import sequence as seq_mod
    from jaxspline import validate as val_mod
    from jaxspline.limits import AxisLimits
    from jaxspline.routes import (
        STRIP,
        exact_states,
        tabulate_route_model,
    )
    from jaxspline.scenario import default_scenario, load_scenario

    out = Path(outdir)
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"output path exists and is not a directory: {out}")
    names = OUTPUT_FILES if plots else OUTPUT_FILES[:2]
    if not force:
        for n in names:
            if (out / n).exists():
                raise FileExistsError(f"{out / n} exists (use --force to overwrite)")
    if beam_width is not None and beam_width < 1:
        raise ValueError(f"--beam-width must be >= 1, got {beam_width}")

    timings: dict[str, float] = {}
    tic = time.perf_counter()

    def lap(name):
        nonlocal tic
        now = time.perf_counter()
        timings[name] = round(now - tic, 3)
        tic = now

    if scenario is None:
        scenario = default_scenario() if scenario_path is None else load_scenario(scenario_path)
    sc = scenario
    pl = sc.planner
    width = beam_width if beam_width is not None else pl.beam_width
    dtype = jnp.result_type(float)
    lap("scenario")

    routes = sc.route_set()
    lap("windows")
    opts_all, info_all = sc.route_options(routes, progress=progress)
    keep = np.flatnonzero(np.asarray(opts_all.scan_ok))
    options = _take(opts_all, keep)
    info = type(info_all)(*(np.asarray(x)[keep] for x in info_all))
    lap("options")

    limits = AxisLimits(jnp.asarray(sc.limits.rate, dtype), jnp.asarray(sc.limits.accel, dtype))
    n_opt = int(keep.size)
    if n_opt:
        tr = screen_mod.screen_transitions(options, limits, max_gap=pl.max_gap, progress=progress)
    else:
        tr = screen_mod._empty(dtype)
    lap("screen")

    g_plan = seq_mod.greedy(options, tr) if n_opt else seq_mod.Plan(np.zeros(0, np.int64), 0.0)
    b_plan = seq_mod.beam_search(options, tr, width=width) if n_opt else g_plan
    plan = b_plan if b_plan.value >= g_plan.value else g_plan
    lap("sequence")

    idx = np.asarray(plan.options, np.int64)
    chosen_routes = np.asarray(options.route)[idx]
    speed = info.speed[idx]
    lo_all, hi_all = np.asarray(routes.t0_min), np.asarray(routes.t0_max)
    windows = (lo_all[chosen_routes], hi_all[chosen_routes])
    t_before = np.asarray(options.t_start)[idx]
    pairs = _pair_lookup(tr, idx[:-1], idx[1:]) if idx.size > 1 else np.zeros(0, np.int64)
    margin_before = (
        np.where(pairs >= 0, np.asarray(tr.margin, np.float64)[pairs], np.nan)
        if pairs.size
        else np.zeros(0)
    )
    refined = None
    margin_after = None
    if pl.refine_steps > 0 and idx.size >= 2:
        # a tabulated (Catmull-Rom in t0) copy of the pointing law keeps the optimizer's
        # compiled graph small; the refined start times are re-evaluated exactly below
        model = tabulate_route_model(routes, chosen_routes, speed)
        refined = refine_mod.refine_plan(
            plan,
            options,
            model,
            limits,
            steps=pl.refine_steps,
            learning_rate=pl.refine_learning_rate,
        )
    lap("refine")

    steps_plan = _take(options, idx)
    rep_plan = val_mod.validate_plan(steps_plan, limits, windows=windows)
    use_refined = False
    report, steps, margins = rep_plan, steps_plan, margin_before
    if refined is not None:
        t1, sa, sr, ea, er = exact_states(routes, chosen_routes, refined.t0, speed)
        steps_ref = type(options)(
            route=chosen_routes,
            t_start=np.asarray(refined.t0, np.float64),
            t_end=t1,
            start_angle=sa,
            start_rate=sr,
            end_angle=ea,
            end_rate=er,
            value=np.asarray(options.value)[idx],
            scan_ok=np.ones(idx.size, bool),
        )
        steps_ref = type(options)(
            *(
                np.asarray(x).astype(np.asarray(y).dtype)
                for x, y in zip(steps_ref, steps_plan, strict=True)
            )
        )
        rep_ref = val_mod.validate_plan(steps_ref, limits, windows=windows)
        margin_after = np.asarray(
            reach.reach_margin(
                ea[:-1],
                er[:-1],
                sa[1:],
                sr[1:],
                (np.asarray(refined.t0)[1:] - t1[:-1])[:, None],
                limits,
            )
        ).min(axis=1)
        if rep_ref.ok and margin_after.min() >= margin_before.min():
            use_refined = True
            report, steps, margins = rep_ref, steps_ref, margin_after
    lap("validate")

    # ---------------------------------------------------------------- outputs
    out.mkdir(parents=True, exist_ok=True)
    n_routes = int(sc.routes.kind.size)
    visible = int(np.sum(np.isfinite(np.asarray(routes.t0_min))))
    kind_names = np.where(np.asarray(routes.kind) == STRIP, "strip", "point")
    ts, te = np.asarray(steps.t_start, np.float64), np.asarray(steps.t_end, np.float64)
    rows = []
    for k in range(idx.size):
        r = int(chosen_routes[k])
        row = {
            "step": k + 1,
            "route": r,
            "kind": str(kind_names[r]),
            "lat_deg": float(np.degrees(routes.lat[r])),
            "lon_deg": float(np.degrees(routes.lon[r])),
            "azimuth_deg": float(np.degrees(routes.azimuth[r]))
            if kind_names[r] == "strip"
            else None,
            "scan_speed_m_s": float(speed[k]) if kind_names[r] == "strip" else None,
            "value": float(np.asarray(steps.value)[k]),
            "t_start_s": float(ts[k]),
            "t_end_s": float(te[k]),
            "t_start_grid_s": float(t_before[k]),
            "window_s": [float(windows[0][k]), float(windows[1][k])],
            "transfer_T_s": float(ts[k] - te[k - 1]) if k else None,
            "transfer_margin_deg": float(np.degrees(margins[k - 1])) if k else None,
        }
        for part in ("start", "end"):
            a = np.degrees(np.asarray(getattr(steps, f"{part}_angle"), np.float64)[k])
            w = np.degrees(np.asarray(getattr(steps, f"{part}_rate"), np.float64)[k])
            for c, ch in enumerate(("roll", "pitch", "yaw")):
                row[f"{part}_{ch}_deg"] = float(a[c])
                row[f"{part}_{ch}_rate_deg_s"] = float(w[c])
        rows.append(row)
    n_feas = int(np.sum(np.asarray(tr.feasible)))
    summary = {
        "scenario": {
            "name": sc.name,
            "epoch": sc.epoch,
            "duration_s": sc.duration,
            "routes": n_routes,
            "routes_visible": visible,
            "off_nadir_max_deg": float(np.degrees(sc.max_off_nadir)),
            "rate_limit_deg_s": np.degrees(np.asarray(sc.limits.rate)).tolist(),
            "accel_limit_deg_s2": np.degrees(np.asarray(sc.limits.accel)).tolist(),
            "dtype": str(np.dtype(dtype)),
        },
        "stats": {
            "options": int(np.asarray(opts_all.route).size),
            "options_scan_ok": n_opt,
            "candidates_screened": int(tr.n_screened),
            "candidates_feasible": n_feas,
            "feasible_fraction": n_feas / max(int(tr.n_screened), 1),
            "plan_value_greedy": float(g_plan.value),
            "plan_value_beam": float(b_plan.value),
            "beam_width": int(width),
            "plan_value": float(plan.value),
            "plan_steps": int(idx.size),
            "refined": bool(use_refined),
            "min_margin_before_deg": float(np.degrees(margin_before.min())) if pairs.size else None,
            "min_margin_after_deg": (
                float(np.degrees(margin_after.min())) if margin_after is not None else None
            ),
            "plan_margins_from": "refined" if use_refined else "grid",
            "valid": bool(report.ok),
            "violations": list(report.violations),
            "peak_rate_deg_s": np.degrees(np.asarray(report.peak_rate)).tolist(),
            "peak_accel_deg_s2": np.degrees(np.asarray(report.peak_accel)).tolist(),
        },
        "timings_s": timings,
        "plan": rows,
    }
    buf = io.StringIO()
    fields = list(rows[0].keys()) if rows else ["step"]
    w = csv.DictWriter(buf, fieldnames=fields)
    w.writeheader()
    for row in rows:
        w.writerow(
            {
                k: ("" if v is None else v if not isinstance(v, list) else " ".join(map(str, v)))
                for k, v in row.items()
            }
        )
    atomic_write_text(out / "plan.csv", buf.getvalue())
    if plots:
        _plots(
            out,
            sc,
            routes,
            options,
            tr,
            steps,
            speed,
            idx,
            margin_before,
            margin_after,
            limits,
            summary,
        )
    lap("outputs")
    summary["timings_s"] = timings
    atomic_write_text(out / "plan.json", json.dumps(summary, indent=2) + "\n")
    _print_summary(summary, out)
    return summary


def _plots(out, sc, routes, options, tr, steps, speed, idx, m_before, m_after, limits, summary):
    import jax.numpy as jnp

    from jaxspline import plot, reach
    from jaxspline.frames import ecef_to_geodetic, teme_to_ecef
    from jaxspline.orbit import orbit_position
    from jaxspline.routes import _great_circle_end, sample_scans

    # ground track
    t = np.linspace(0.0, sc.duration, 241)
    r = orbit_position(sc.orbit, jnp.asarray(t))
    lat, lon, _ = ecef_to_geodetic(teme_to_ecef(r, sc.gmst0 + 7.292115146706979e-5 * t))
    rl, ro = np.asarray(routes.lat), np.asarray(routes.lon)
    el, eo, _ = _great_circle_end(rl, ro, np.asarray(routes.azimuth), np.asarray(routes.length))
    strip = np.asarray(routes.kind) == 1
    el, eo = np.where(strip, el, rl), np.where(strip, eo, ro)
    visible = np.zeros(rl.size, bool)
    visible[np.asarray(options.route)] = True
    chosen = np.asarray(options.route)[idx]
    st = summary["stats"]
    plot.plot_ground_track(
        out / "ground_track.png",
        np.asarray(lat),
        np.asarray(lon),
        rl,
        ro,
        np.asarray(routes.kind),
        el,
        eo,
        chosen,
        title=f"{sc.name}: {chosen.size} of {rl.size} routes, value {st['plan_value']:g}",
        visible=visible,
        track_t=t,
    )
    # attitude over the plan: scans from the pointing law, maneuvers from Theorem 1
    ts, te = np.asarray(steps.t_start, np.float64), np.asarray(steps.t_end, np.float64)
    tt, ang, rat, acc = [], [], [], []
    nan3 = np.full((1, 3), np.nan)
    ns = 25
    frac = np.linspace(0.0, 1.0, ns)
    t_scan = ts[:, None] + (te - ts)[:, None] * frac[None, :]
    a_s, w_s, e_s, _ = sample_scans(
        routes, np.repeat(chosen, ns), np.repeat(ts, ns), np.repeat(speed, ns), t_scan.ravel()
    )
    a_s, w_s, e_s = (x.reshape(idx.size, ns, 3) for x in (a_s, w_s, e_s))
    for k in range(idx.size):
        tt.append(t_scan[k])
        ang.append(a_s[k])
        rat.append(w_s[k])
        acc.append(e_s[k])
        if k + 1 < idx.size:
            T = ts[k + 1] - te[k]
            tau = np.linspace(0.0, T, 120)
            ea, er = np.asarray(steps.end_angle)[k], np.asarray(steps.end_rate)[k]
            sa, sr = np.asarray(steps.start_angle)[k + 1], np.asarray(steps.start_rate)[k + 1]
            f, fd, fdd = reach.transfer(ea, er, sa, sr, T, limits, tau[:, None])
            f, fd, fdd = (np.asarray(x, np.float64) for x in (f, fd, fdd))
            bad = ~np.isfinite(f)
            f, fd, fdd = (np.where(bad, np.nan, x) for x in (f, fd, fdd))
            tt.append(np.concatenate([[np.nan], te[k] + tau[1:-1], [np.nan]]))
            ang.append(np.concatenate([nan3, f[1:-1], nan3]))
            rat.append(np.concatenate([nan3, fd[1:-1], nan3]))
            acc.append(np.concatenate([nan3, fdd[1:-1], nan3]))
    if tt:
        tcat = np.concatenate(tt)
        plot.plot_attitude(
            out / "attitude.png",
            tcat,
            np.concatenate(ang),
            np.concatenate(rat),
            np.concatenate(acc),
            np.asarray(limits.rate),
            np.asarray(limits.accel),
            list(zip(ts, te, strict=True)),
            title=f"{sc.name}: attitude per channel (green: imaging; red dashed: limits)",
        )
    else:
        plot.plot_attitude(
            out / "attitude.png",
            np.zeros(1),
            np.zeros((1, 3)),
            np.zeros((1, 3)),
            np.zeros((1, 3)),
            np.asarray(limits.rate),
            np.asarray(limits.accel),
            [],
        )
    feas = np.asarray(tr.feasible, bool)
    plot.plot_margins(
        out / "margins.png",
        np.asarray(tr.margin)[feas],
        m_before,
        m_after,
        title=f"{sc.name}: margins of {int(feas.sum())} feasible of {int(tr.n_screened)} screened",
    )


def _fmt(x) -> str:
    return "n/a" if x is None else f"{x:.4f}"


def _print_summary(s: dict, out: Path) -> None:
    st, sc, tm = s["stats"], s["scenario"], s["timings_s"]
    lines = [
        f"scenario            {sc['name']} ({sc['epoch']}, {sc['duration_s']:g} s, {sc['dtype']})",
        f"routes              {sc['routes']} ({sc['routes_visible']} with a visibility window)",
        f"route options       {st['options']} ({st['options_scan_ok']} scan-feasible)",
        f"candidates screened {st['candidates_screened']}",
        f"feasible            {st['candidates_feasible']} ({100 * st['feasible_fraction']:.2f} %)",
        f"plan value          {st['plan_value']:g} (greedy {st['plan_value_greedy']:g}, "
        f"beam[{st['beam_width']}] {st['plan_value_beam']:g}), {st['plan_steps']} routes",
        f"refined             {st['refined']}; min transition margin "
        f"{_fmt(st['min_margin_before_deg'])} -> {_fmt(st['min_margin_after_deg'])} deg",
        f"valid               {st['valid']} ({len(st['violations'])} violations)",
        "wall time [s]       " + ", ".join(f"{k} {v:.2f}" for k, v in tm.items()),
        f"outputs             {out}/ ({', '.join(OUTPUT_FILES)})",
    ]
    print("\n".join(lines))
