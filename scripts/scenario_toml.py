"""Write a benchmark case as a scenario file of ``jaxspline plan`` (TOML plus sample files).

``python scripts/scenario_toml.py CASE_DIR OUT_DIR [--points N] [--model NAME]``

A regional_coverage case becomes the scenario its adapter plans
(:func:`jaxspline.regional.adapter.case_scenario`): every satellite with its TLE, agility,
sensor (field of view, edge band, strip durations), battery and duty; every region an
area on the case's own sample grid (``<region>.csv``: ``lon_deg, lat_deg, weight``) with
its priority and least coverage; the planner's action grid, ephemeris step, action cap
and margins. So ``jaxspline plan OUT_DIR/scenario.toml`` plans the same problem as
``jaxspline regional solve CASE_DIR``.

``--points N`` adds N random point targets (``[random_targets]``, seed 0, priorities
1-10) over the regions' bounding box, and scales the regions' priorities so that they
are worth together about as much as all the points; ``--model`` sets every satellite's
maneuver model (``roll_only`` satellites image area strips only: a mixed campaign needs
a model that tracks points, e.g.
``eigen_axis``; ``--pitch-step`` then sets the pitch grid of their area strips). Refuses
to overwrite an existing scenario file.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

POINT_PRIORITY = (1, 10)  # [low, high] integer priorities of the added point targets
POINT_SHARE = 1.0  # the regions together are worth about this share of the added points


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    return repr(float(v)) if isinstance(v, float) else str(v)


def _table(name: str, fields: dict, array: bool = False) -> str:
    head = f"[[{name}]]" if array else f"[{name}]"
    return "\n".join([head, *(f"{k} = {_toml_value(v)}" for k, v in fields.items())]) + "\n"


def _satellite(s, model: str) -> dict:
    deg = math.degrees
    out = {"name": s.name, "tle": list(s.orbit), "model": model}
    out["rate_deg_s"] = float(deg(float(np.max(s.limits.rate))))
    out["accel_deg_s2"] = float(deg(float(np.max(s.limits.accel))))
    out["off_nadir_max_deg"] = deg(s.off_nadir_max)
    out["sensor"] = s.sensor
    out["settle_s"] = float(s.settle)
    out["fov_deg"] = deg(s.fov)
    out["edge_off_nadir_deg"] = [deg(s.edge_band[0]), deg(s.edge_band[1])]
    out["strip_duration_s"] = [float(x) for x in s.strip_duration]
    if s.duty is not None:
        out["duty_s_per_orbit"] = float(s.duty)
    if s.power is not None:
        p = s.power
        out["power"] = {
            "capacity_wh": p.capacity_wh,
            "initial_wh": p.initial_wh,
            "idle_w": p.idle_w,
            "imaging_w": p.imaging_w,
            "slew_w": p.slew_w,
            "charge_w": p.charge_w,
        }
    return out


def write_scenario(sc, out: Path, points: int, model: str | None, pitch_step=None) -> Path:
    """Write ``sc`` (satellites with TLEs, areas with samples) under ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    path = out / "scenario.toml"
    if path.exists():
        raise SystemExit(f"{path}: exists (remove it first)")
    pc, m = sc.planner, sc.planner.margins
    parts = [
        _table(
            "scenario",
            {
                "name": sc.name,
                "epoch": sc.epoch.strftime("%Y-%m-%dT%H:%M:%SZ"),
                "duration_s": float(sc.duration),
            },
        ),  # fmt: skip
    ]
    parts += [_table("satellites", _satellite(s, model or s.model), True) for s in sc.satellites]
    lons, lats = [], []
    scale = POINT_SHARE * points * sum(POINT_PRIORITY) / 2.0 if points else 1.0
    for a in sc.areas:
        csv = out / f"{a.name}.csv"
        np.savetxt(csv, a.samples, delimiter=",", header="lon_deg,lat_deg,weight", comments="",
                   fmt=["%.9f", "%.9f", "%.12g"])  # fmt: skip
        lons += [a.samples[:, 0].min(), a.samples[:, 0].max()]
        lats += [a.samples[:, 1].min(), a.samples[:, 1].max()]
        fields = {"name": a.name, "samples_csv": csv.name,
                  "priority": float(sc.targets.value[a.target]) * scale,
                  "window_s": [0.0, float(sc.duration)]}  # fmt: skip
        if not math.isnan(a.min_share):
            fields["min_coverage"] = float(a.min_share)
        parts.append(_table("areas", fields, True))
    if points:
        parts.append(_table("random_targets", {
            "seed": 0, "count": points, "lat_deg": [min(lats), max(lats)],
            "lon_deg": [min(lons), max(lons)], "strip_fraction": 0.0,
            "priority": list(POINT_PRIORITY)}))  # fmt: skip
    planner = {"time_step_s": pc.time_step, "geometry_step_s": pc.geometry_step,
               "gap_margin_s": m.gap, "battery_margin_wh": m.battery_wh,
               "shadow_guard_steps": m.shadow_guard, "duty_margin_s": m.duty,
               "exact_max_options": pc.exact_max_options,
               "time_limit_s": pc.default_time_limit}  # fmt: skip
    if pc.max_actions is not None:
        planner["max_actions"] = int(pc.max_actions)
    if pitch_step is not None:
        planner["area_pitch_step_deg"] = float(pitch_step)
    parts.append(_table("planner", planner))
    path.write_text("\n".join(parts), encoding="utf-8")
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case_dir")
    ap.add_argument("out_dir")
    ap.add_argument("--points", type=int, default=0, help="random point targets to add")
    ap.add_argument("--model", default=None, help="maneuver model of every satellite")
    ap.add_argument("--pitch-step", type=float, default=None,
                    help="pitch grid of agile satellites' area strips [deg]")  # fmt: skip
    args = ap.parse_args(argv)
    from jaxspline.regional.adapter import case_scenario

    sc = case_scenario(args.case_dir)
    path = write_scenario(sc, Path(args.out_dir), args.points, args.model, args.pitch_step)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
