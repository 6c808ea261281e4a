"""Columns of the plan page (:mod:`jaxspline.products.plan_html`): plan.json in Bokeh's shapes.

Every function reads the plan document (``plan.json``'s content, with its ``"view"``
section) and returns plain lists / arrays per glyph: satellites and colours,
observations with their hover texts, ground-track segments, sensor footprints, area
polygons, and the offline land polygons and coastlines. No Bokeh import here.
"""

from __future__ import annotations

import datetime as _dt
import functools
import html
import math

import numpy as np

from jaxspline.products.czml import SATELLITE_COLORS

__all__ = [
    "MS",
    "area_columns",
    "sample_columns",
    "coast",
    "epoch_ms",
    "fmt",
    "footprint_columns",
    "observation_columns",
    "satellites",
    "track_columns",
    "utc_text",
]

TRACK_SEGMENT = 10  # track samples per filterable map segment (5 min at 30 s)
COAST_DECIMATE = 2  # land grid cells averaged per axis for the page (0.5 deg)
MS = 1000.0  # Bokeh datetimes are milliseconds


@functools.cache
def coast():
    """Land polygons (with holes) and coastlines [deg] from the offline land grid, cached.

    Returns:
      (land_xs, land_ys, coast_xs, coast_ys): nested lists for Bokeh ``multi_polygons``
      (one polygon per row: [[exterior, hole, ...]]) and ``multi_line`` (float32).
    """
    import contourpy

    from jaxspline.base.land import land_fraction

    lat, lon, land = land_fraction()
    d = COAST_DECIMATE
    n, m = land.shape[0] // d, land.shape[1] // d
    land = land[: n * d, : m * d].reshape(n, d, m, d).mean(axis=(1, 3))
    lat = lat[: n * d].reshape(n, d).mean(axis=1)
    lon = lon[: m * d].reshape(m, d).mean(axis=1)
    # close the grid at the poles and the antimeridian so land polygons do not stop short
    lon = np.concatenate([[-180.0], lon, [180.0]])
    land = np.concatenate([land[:, -1:], land, land[:, :1]], axis=1)
    gen = contourpy.contour_generator(lon, lat, land, fill_type="OuterOffset", line_type="Separate")
    pts, offsets = gen.filled(0.5, 2.0)
    land_xs, land_ys = [], []
    for p, off in zip(pts, offsets, strict=True):
        rings = [p[i:j].astype(np.float32) for i, j in zip(off[:-1], off[1:], strict=True)]
        land_xs.append([[r[:, 0] for r in rings]])
        land_ys.append([[r[:, 1] for r in rings]])
    lines = [ln.astype(np.float32) for ln in gen.lines(0.5) if len(ln) > 1]
    return land_xs, land_ys, [ln[:, 0] for ln in lines], [ln[:, 1] for ln in lines]


def _parse_utc(text: str) -> _dt.datetime:
    return _dt.datetime.strptime(text, "%Y-%m-%dT%H:%M:%S.%fZ").replace(tzinfo=_dt.UTC)


def epoch_ms(doc) -> float:
    """Scenario epoch [ms since 1970] (Bokeh datetime) from the view or the first row."""
    view = doc.get("view") or {}
    if "epoch_utc" in view:
        return _parse_utc(view["epoch_utc"]).timestamp() * MS
    rows = doc["observations"]
    if rows:
        return (_parse_utc(rows[0]["start_utc"]).timestamp() - rows[0]["start_s"]) * MS
    return 0.0


def satellites(doc) -> list[dict]:
    view = doc.get("view") or {}
    if view.get("satellites"):
        return view["satellites"]
    names = list(dict.fromkeys(o["satellite"] for o in doc["observations"]))
    return [
        {"name": n, "model": "", "color": SATELLITE_COLORS[k % len(SATELLITE_COLORS)]}
        for k, n in enumerate(names)
    ]


def utc_text(iso: str) -> str:
    """``2026-04-14T00:03:21.123456Z`` -> ``2026-04-14 00:03:21.123``."""
    return iso[:23].replace("T", " ")


def fmt(x, spec: str = ".6g") -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return str(x).lower()
    if isinstance(x, int | float):
        return format(x, spec)
    return html.escape(str(x))


def observation_columns(doc, sats) -> dict:
    """One row per observation: map position, times, hover texts, filter columns."""
    rows = doc["observations"]
    view = doc.get("view") or {}
    epoch = epoch_ms(doc)
    index = {s["name"]: k for k, s in enumerate(sats)}
    tg = view.get("targets")
    pos = {n: i for i, n in enumerate(tg["name"])} if tg else {}
    off = (view.get("observations") or {}).get("off_nadir_deg") or [None] * len(rows)
    r = [pos.get(o["target"]) for o in rows]
    nan = float("nan")
    return {
        "x": np.array([tg["lon_deg"][i] if i is not None else nan for i in r], np.float64),
        "y": np.array([tg["lat_deg"][i] if i is not None else nan for i in r], np.float64),
        "target": [o["target"] for o in rows],
        "kind": [o.get("kind", "") for o in rows],
        "priority": np.array([o["value"] for o in rows], np.float64),
        "satellite": [o["satellite"] for o in rows],
        "model": [o.get("model", "") for o in rows],
        "start": [utc_text(o["start_utc"]) for o in rows],
        "end": [utc_text(o["end_utc"]) for o in rows],
        "duration": np.array([o["end_s"] - o["start_s"] for o in rows], np.float64),
        "off_nadir": np.array([nan if v is None else v for v in off], np.float64),
        "maneuver": np.array([o["maneuver_s"] for o in rows], np.float64),
        "slack": np.array([o["slack_s"] for o in rows], np.float64),
        "sat": np.array([index[o["satellite"]] for o in rows], np.int32),
        "color": [sats[index[o["satellite"]]]["color"] for o in rows],
        "t0": epoch + MS * np.array([o["start_s"] for o in rows], np.float64),
        "t1": epoch + MS * np.array([o["end_s"] for o in rows], np.float64),
        "m0": epoch + MS * np.array([o["start_s"] - o["maneuver_s"] for o in rows], np.float64),
    }


def track_columns(doc, sats) -> dict:
    """Ground tracks cut into segments of TRACK_SEGMENT samples (filterable rows)."""
    tr = (doc.get("view") or {}).get("tracks")
    cols = {"xs": [], "ys": [], "sat": [], "t0": [], "t1": [], "color": [], "satellite": []}
    if not tr:
        return cols
    epoch = epoch_ms(doc)
    t = epoch + MS * np.asarray(tr["t_s"], np.float64)
    for k, s in enumerate(sats):
        lon = np.array([np.nan if v is None else v for v in tr["lon_deg"][k]], np.float64)
        lat = np.array([np.nan if v is None else v for v in tr["lat_deg"][k]], np.float64)
        for i in range(0, t.size - 1, TRACK_SEGMENT):
            j = min(i + TRACK_SEGMENT + 1, t.size)  # overlap one sample: no gaps
            x, y = lon[i:j], lat[i:j]
            jump = np.flatnonzero(np.abs(np.diff(x)) > 180.0) + 1  # antimeridian: break
            cols["xs"].append(np.insert(x, jump, np.nan))
            cols["ys"].append(np.insert(y, jump, np.nan))
            cols["sat"].append(k)
            cols["t0"].append(t[i])
            cols["t1"].append(t[j - 1])
            cols["color"].append(s["color"])
            cols["satellite"].append(s["name"])
    return cols


def footprint_columns(doc, obs) -> dict:
    from jaxspline.products.plan_view import disc

    view = doc.get("view") or {}
    fps = (view.get("observations") or {}).get("footprint") or []
    swath = {s["name"]: s.get("swath_m") for s in view.get("satellites") or []}
    xs, ys, keep = [], [], []
    for i, fp in enumerate(fps):
        if fp is not None:
            x, y = fp["lon_deg"], fp["lat_deg"]
        elif math.isfinite(obs["x"][i]) and swath.get(obs["satellite"][i]):
            x, y = disc(obs["x"][i], obs["y"][i], swath[obs["satellite"][i]] / 2.0)
        else:
            continue
        xs.append(np.asarray(x, np.float64))
        ys.append(np.asarray(y, np.float64))
        keep.append(i)
    cols = {k: [v[i] for i in keep] for k, v in obs.items() if k not in ("x", "y")}
    cols = {k: np.asarray(v) if isinstance(obs[k], np.ndarray) else v for k, v in cols.items()}
    return {"xs": xs, "ys": ys, **cols}


def sample_columns(areas, covered: int) -> dict:
    """Columns of the coverage samples (view ``areas[].samples``) whose flag is ``covered``.

    Args:
      areas: the view's ``areas`` list.
      covered: 1 for the covered samples, 0 for the others.
    Returns:
      dict of lists ``x`` (lon [deg]), ``y`` (lat [deg]), ``area`` (name).
    """
    cols = {"x": [], "y": [], "area": []}
    for area in areas:
        smp = area.get("samples")
        if not smp:
            continue
        for x, y, c in zip(smp["lon_deg"], smp["lat_deg"], smp["covered"], strict=True):
            if int(c) == covered:
                cols["x"].append(x)
                cols["y"].append(y)
                cols["area"].append(area["name"])
    return cols


def area_columns(doc) -> dict:
    view = doc.get("view") or {}
    cover = doc["report"].get("areas") or []
    cols = {"xs": [], "ys": [], "name": [], "priority": [], "covered": []}
    for a, area in enumerate(view.get("areas") or []):
        geom = area["geometry"]
        if geom is None:  # an area given by its samples alone
            continue
        polys = [geom["coordinates"]] if geom["type"] == "Polygon" else geom["coordinates"]
        cov = cover[a] if a < len(cover) else {}
        frac = cov.get("covered_share")
        for rings in polys:
            cols["xs"].append([[np.asarray([p[0] for p in ring], np.float64) for ring in rings]])
            cols["ys"].append([[np.asarray([p[1] for p in ring], np.float64) for ring in rings]])
            cols["name"].append(area["name"])
            cols["priority"].append(area["value"])
            cols["covered"].append("-" if frac is None else f"{100 * frac:.1f} %")
    return cols


# --- page -----------------------------------------------------------------------------
