"""The plan as one self-contained web page: map, timeline, battery and headline figures.

:func:`write_plan_html` renders a plan document (the content of ``plan.json``:
:meth:`jaxspline.planner.result.PlanResult.to_dict` plus the ``"view"`` section of
:mod:`jaxspline.products.plan_view`) with Bokeh (imported lazily) and its JavaScript inlined, so
the file opens by double-click with no network. The page (models named for tests and
scripts, ``Bokeh.documents[0].get_model_by_name(name)``):

* ``header``: scenario, value, bound and gap, validity, join statistics, areas
  covered, search statistics and stage timings (each number in a cell with a
  ``data-key`` attribute);
* ``map`` (equirectangular, pan / zoom): land and coastlines from the package's
  offline land data (:func:`jaxspline.base.land.land_fraction`, contoured at land
  fraction 0.5), area polygons (``areas``), the samples of the areas
  (``area_samples_covered`` green, ``area_samples_uncovered`` red),
  strip centrelines (``strips``), ground
  tracks (``tracks``), sensor footprints of the observations (``footprints``), targets
  not imaged (``targets_not_imaged``, grey) and one glyph per observation at its
  target in the satellite's colour (``targets_imaged``); hovering a target shows its
  name, priority, satellite, start and end (UTC), off-nadir angle, maneuver time and
  slack; stereo targets marked by the product the plan collects (``stereo_targets``,
  :mod:`jaxspline.products.plan_html_stereo`);
* ``timeline``: per-satellite Gantt chart of imaging (``imaging``) and maneuvers
  (``maneuvers``), the looks of each stereo product joined (``stereo_joins``), and
  ``battery`` below (``battery-<satellite>`` lines) on the same
  time axis (a note when no satellite has a power model);
* linking: the satellite check boxes (``satellite_filter``) and the time range shown
  by the timeline (zoom or pan it) filter the map's tracks, footprints and imaged
  targets (a few lines of ``CustomJS`` set the renderers' ``BooleanFilter``); the
  battery lines of unchecked satellites are hidden; ``filter_status`` says what is
  shown; a click on an imaged target zooms the timeline to its observation
  +- :data:`PASS_PAD_S` (and so the map to that pass), on a stereo target to its
  product's looks +- the same.

A ``plan.json`` without the ``"view"`` section (older jaxspline) still gives the
header and the timeline; the map then has the coastlines only.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from jaxspline.planner.files import atomic_write_text, refuse_overwrite
from jaxspline.planner.result import PlanResult
from jaxspline.products import plan_html_columns as columns
from jaxspline.products import plan_html_stereo as stereo
from jaxspline.products.plan_html_header import header_html

__all__ = ["HTML_FILE", "plan_document", "read_plan", "write_plan_html"]

HTML_FILE = "plan.html"
LAND_COLOR = "#efeae0"  # as the PNG map (jaxspline.products.plot_plan)
COAST_COLOR = "#595959"
OCEAN_COLOR = "#f4f8fb"
NOT_IMAGED_COLOR = "#999999"
STRIP_COLOR = "#555555"
MANEUVER_COLOR = "#333333"
AREA_COLOR = "#ffd700"
COVERED_COLOR = "#2ca02c"  # coverage samples the plan covers
UNCOVERED_COLOR = "#d62728"  # coverage samples no planned strip covers
MAP_WIDTH = 1200  # [px]; the map is 2:1 (360 x 180 deg)
CONTROLS_WIDTH = 190  # [px]
TIMELINE_ROW_PX = 34
BATTERY_HEIGHT = 230
IMAGING_HEIGHT = 0.6  # Gantt bar heights (row pitch 1)
MANEUVER_HEIGHT = 0.25

# CustomJS glue: the satellite check boxes and the timeline's time range filter the map.
_FILTER_JS = """
const on = new Set(boxes.active)
const a = xr.start, b = xr.end
for (const r of filtered) {
  const d = r.data_source.data
  const n = d.sat.length
  const keep = new Array(n)
  for (let i = 0; i < n; i++) {
    keep[i] = on.has(d.sat[i]) && d.t1[i] >= a && d.t0[i] <= b
  }
  r.view.filter.booleans = keep
}
for (const r of battery) {
  r.visible = on.has(r.tags[0])
}
const iso = (t) => new Date(t).toISOString().slice(0, 19).replace("T", " ")
const names = boxes.active.map((k) => boxes.labels[k])
status.text = `map shows ${names.length} of ${boxes.labels.length} satellites ` +
  `(${names.join(", ") || "none"}), ${iso(a)} to ${iso(b)} UTC`
"""
_ALL_JS = "boxes.active = boxes.labels.map((_, k) => k)"
# a click on an imaged target zooms the timeline (and so the map) to its pass; on a stereo
# target (its marker rings the glyphs of its looks; it wins) to its product's looks
_TAP_JS = """
let d = null, i
for (const s of [stereo, src]) {
  if (s !== null && s.selected.indices.length > 0) {
    d = s.data
    i = s.selected.indices[0]
    break
  }
}
if (d !== null && isFinite(d.t0[i]) && isFinite(d.t1[i])) {
  const [lo, hi] = xr.bounds
  xr.setv({start: Math.max(d.t0[i] - pad, lo), end: Math.min(d.t1[i] + pad, hi)})
}
"""
PASS_PAD_S = 600.0  # a click on a target shows its observation +- this in the timeline [s]


def read_plan(path) -> dict:
    """Read a ``plan.json``.

    Args:
      path: str or Path.
    Returns:
      dict, the document.
    Raises:
      FileNotFoundError: no such file.
      ValueError: not a plan document (naming the file and what is missing).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"plan file not found: {path}")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not JSON ({exc})") from None
    missing = [
        k
        for k in ("summary", "report", "observations")
        if not isinstance(doc, dict) or k not in doc
    ]
    if missing:
        raise ValueError(f"{path}: not a jaxspline plan.json (missing {', '.join(missing)})")
    return doc


def plan_document(result) -> dict:
    """The document of a plan with its ``"view"`` section (what ``plan.json`` holds).

    Args:
      result: :class:`jaxspline.planner.result.PlanResult`.
    Returns:
      dict, JSON-ready.
    """
    from jaxspline.products.plan_view import view_data

    return result.to_dict(extra={"view": view_data(result)})


def _map(doc, sats, obs):
    """The map (module docstring) and its renderers filtered by satellite and time."""
    view = doc.get("view") or {}
    fig = _world_figure()
    _add_areas(fig, doc)
    _add_area_samples(fig, view.get("areas") or [])
    _add_strips(fig, view.get("strips") or [])
    filt = _add_tracks_and_footprints(fig, doc, sats, obs)
    if view.get("targets"):
        _add_free_targets(fig, view["targets"], obs)
    stereo.add_stereo_targets(fig, doc, obs)  # under the observation glyphs, larger
    filt.append(_add_imaged_targets(fig, obs))
    return fig, filt


def _world_figure():
    """The empty world map (equirectangular, pan / zoom) with land and coastlines."""
    from bokeh.models import Range1d
    from bokeh.plotting import figure

    fig = figure(
        name="map",
        width=MAP_WIDTH,
        height=MAP_WIDTH // 2 + 40,
        x_range=Range1d(-180.0, 180.0, bounds=(-180.0, 180.0)),
        y_range=Range1d(-90.0, 90.0, bounds=(-90.0, 90.0)),
        match_aspect=True,
        tools="pan,wheel_zoom,box_zoom,reset,save",
        active_scroll="wheel_zoom",
        x_axis_label="longitude [deg]",
        y_axis_label="latitude [deg]",
        background_fill_color=OCEAN_COLOR,
        output_backend="canvas",
    )
    fig.grid.grid_line_alpha = 0.3
    land_xs, land_ys, coast_xs, coast_ys = columns.coast()
    fig.multi_polygons(xs=land_xs, ys=land_ys, fill_color=LAND_COLOR, line_color=None, name="land")
    fig.multi_line(xs=coast_xs, ys=coast_ys, line_color=COAST_COLOR, line_width=0.6, name="coast")
    return fig


def _filtered(cols) -> dict:
    """Glyph arguments of a source whose rows the page's filter shows or hides."""
    from bokeh.models import BooleanFilter, CDSView, ColumnDataSource

    src = ColumnDataSource(cols)
    return {"source": src, "view": CDSView(filter=BooleanFilter([True] * len(cols["sat"])))}


def _add_areas(fig, doc) -> None:
    """The area polygons, with their priority and covered fraction on hover."""
    from bokeh.models import ColumnDataSource, HoverTool

    areas = columns.area_columns(doc)
    if not areas["name"]:
        return
    ra = fig.multi_polygons(
        xs="xs",
        ys="ys",
        source=ColumnDataSource(areas),
        fill_color=AREA_COLOR,
        fill_alpha=0.25,
        line_color=AREA_COLOR,
        line_width=1.5,
        name="areas",
    )
    fig.add_tools(
        HoverTool(
            renderers=[ra],
            tooltips=[("area", "@name"), ("priority", "@priority"), ("covered", "@covered")],
        )
    )


def _add_area_samples(fig, areas) -> None:
    """The samples of the areas: covered samples in
    :data:`COVERED_COLOR`, uncovered ones in :data:`UNCOVERED_COLOR` (hover: the area)."""
    from bokeh.models import ColumnDataSource, HoverTool

    for covered, color in ((1, COVERED_COLOR), (0, UNCOVERED_COLOR)):
        cols = columns.sample_columns(areas, covered)
        if not cols["x"]:
            continue
        r = fig.scatter(
            x="x",
            y="y",
            source=ColumnDataSource(cols),
            size=4,
            color=color,
            alpha=0.8,
            name=f"area_samples_{'covered' if covered else 'uncovered'}",
        )
        what = "covered" if covered else "not covered"
        fig.add_tools(HoverTool(renderers=[r], tooltips=[("area", "@area"), ("sample", what)]))


def _add_strips(fig, strips) -> None:
    """The centrelines of the strip targets."""
    if not strips:
        return
    fig.multi_line(
        xs=[np.asarray(s["lon_deg"], np.float64) for s in strips],
        ys=[np.asarray(s["lat_deg"], np.float64) for s in strips],
        line_color=STRIP_COLOR,
        line_width=1.5,
        line_alpha=0.7,
        name="strips",
    )


def _add_tracks_and_footprints(fig, doc, sats, obs) -> list:
    """The ground tracks and the observations' footprints (filtered renderers)."""
    filt = []
    tracks = columns.track_columns(doc, sats)
    if tracks["sat"]:
        rt = fig.multi_line(
            xs="xs",
            ys="ys",
            line_color="color",
            line_width=1.2,
            line_alpha=0.8,
            name="tracks",
            **_filtered(tracks),
        )
        filt.append(rt)
    fp = columns.footprint_columns(doc, obs)
    if fp["xs"]:
        rf = fig.patches(
            xs="xs",
            ys="ys",
            fill_color="color",
            fill_alpha=0.35,
            line_color="color",
            line_width=1.0,
            name="footprints",
            **_filtered(fp),
        )
        filt.append(rf)
    return filt


def _add_free_targets(fig, tg, obs) -> None:
    """The targets no observation images (grey), with their name and priority on hover."""
    from bokeh.models import ColumnDataSource, HoverTool

    imaged = set(obs["target"])
    free = [i for i, n in enumerate(tg["name"]) if n not in imaged]
    rn = fig.scatter(
        x="x",
        y="y",
        source=ColumnDataSource(
            {
                "x": np.asarray([tg["lon_deg"][i] for i in free], np.float64),
                "y": np.asarray([tg["lat_deg"][i] for i in free], np.float64),
                "target": [tg["name"][i] for i in free],
                "kind": [tg["kind"][i] for i in free],
                "priority": np.asarray([tg["value"][i] for i in free], np.float64),
            }
        ),
        size=4,
        color=NOT_IMAGED_COLOR,
        alpha=0.8,
        name="targets_not_imaged",
    )
    fig.add_tools(
        HoverTool(
            renderers=[rn],
            tooltips=[
                ("target", "@target (@kind)"),
                ("priority", "@priority{0.[000]}"),
                ("imaged", "no"),
            ],
        )
    )


def _add_imaged_targets(fig, obs):
    """One glyph per observation at its target in the satellite's colour (filtered),
    who images it when on hover. Returns the renderer."""
    from bokeh.models import HoverTool

    ri = fig.scatter(
        x="x",
        y="y",
        size=8,
        fill_color="color",
        line_color="black",
        line_width=0.6,
        name="targets_imaged",
        **_filtered(obs),
    )
    fig.add_tools(
        HoverTool(
            renderers=[ri],
            tooltips=[
                ("target", "@target (@kind)"),
                ("priority", "@priority{0.[000]}"),
                ("satellite", "@satellite (@model)"),
                ("start", "@start UTC"),
                ("end", "@end UTC"),
                ("off-nadir", "@off_nadir{0.00} deg"),
                ("maneuver", "@maneuver{0.000} s"),
                ("slack", "@slack{0.000} s"),
            ],
        )
    )
    return ri


def _timeline(doc, sats, obs):
    """The Gantt chart and the battery figure below it, on one time axis.

    Returns ``(gantt, battery figure or note, x_range, battery lines)``.
    """
    from bokeh.models import Div, Range1d

    view = doc.get("view") or {}
    epoch = columns.epoch_ms(doc)
    duration = view.get("duration_s") or max([o["end_s"] for o in doc["observations"]] or [1.0])
    end = epoch + columns.MS * duration
    x_range = Range1d(epoch, end, bounds=(epoch, end), min_interval=10.0 * columns.MS)
    gantt = _gantt(doc, sats, obs, x_range)
    bat = view.get("battery") or {}
    if not bat:
        note = "<i>battery: no satellite of this plan has a power model</i>"
        return gantt, Div(text=note, name="battery"), x_range, []
    batt, lines = _battery(bat, sats, epoch, x_range)
    return gantt, batt, x_range, lines


def _gantt(doc, sats, obs, x_range):
    """Per-satellite rows of imaging bars and the maneuvers before them."""
    from bokeh.models import ColumnDataSource, FactorRange, HoverTool
    from bokeh.plotting import figure

    gantt = figure(
        name="timeline",
        width=MAP_WIDTH + CONTROLS_WIDTH,
        height=70 + TIMELINE_ROW_PX * max(len(sats), 1),
        x_range=x_range,
        y_range=FactorRange(*reversed([s["name"] for s in sats])),
        x_axis_type="datetime",
        tools="xpan,xwheel_zoom,xbox_zoom,reset,save",
        active_scroll="xwheel_zoom",
        title="timeline (zoom or pan to filter the map by time; UTC)",
        output_backend="canvas",
    )
    gantt.xgrid.grid_line_alpha = 0.3
    src = ColumnDataSource(obs)
    rm = gantt.hbar(
        y="satellite",
        left="m0",
        right="t0",
        height=MANEUVER_HEIGHT,
        color=MANEUVER_COLOR,
        source=src,
        name="maneuvers",
    )
    ri = gantt.hbar(
        y="satellite",
        left="t0",
        right="t1",
        height=IMAGING_HEIGHT,
        color="color",
        source=src,
        name="imaging",
    )
    stereo.add_stereo_joins(gantt, doc, obs)  # a product's looks joined, over the bars
    gantt.add_tools(
        HoverTool(
            renderers=[ri, rm],
            tooltips=[
                ("target", "@target (@kind)"),
                ("satellite", "@satellite"),
                ("start", "@start UTC"),
                ("end", "@end UTC"),
                ("maneuver", "@maneuver{0.000} s"),
                ("slack", "@slack{0.000} s"),
            ],
        )
    )
    return gantt


def _battery(bat, sats, epoch, x_range):
    """The battery level [Wh] of every powered satellite: ``(figure, lines)``."""
    from bokeh.models import HoverTool
    from bokeh.plotting import figure

    index = {s["name"]: k for k, s in enumerate(sats)}
    batt = figure(
        name="battery",
        width=MAP_WIDTH + CONTROLS_WIDTH,
        height=BATTERY_HEIGHT,
        x_range=x_range,
        x_axis_type="datetime",
        tools="xpan,xwheel_zoom,xbox_zoom,reset,save",
        active_scroll="xwheel_zoom",
        title="battery [Wh]",
        y_axis_label="Wh",
        output_backend="canvas",
    )
    batt.xgrid.grid_line_alpha = 0.3
    lines = []
    for name, b in bat.items():
        k = index.get(name, 0)
        t = epoch + columns.MS * np.asarray(b["t_s"], np.float64)
        lv = np.array([np.nan if v is None else v for v in b["level_wh"]], np.float64)
        r = batt.line(
            x=t,
            y=lv,
            color=sats[k]["color"] if k < len(sats) else "black",
            line_width=1.5,
            legend_label=name,
            name=f"battery-{name}",
            tags=[k],
        )
        lines.append(r)
    batt.legend.location = "top_left"
    batt.legend.click_policy = "hide"
    batt.add_tools(
        HoverTool(
            renderers=lines,
            tooltips=[("battery", "$name"), ("time", "$x{%F %T} UTC"), ("level", "$y{0.0} Wh")],
            formatters={"$x": "datetime"},
            mode="vline",
        )
    )
    return batt, lines


def _plan_page(doc):
    """The Bokeh layout of a plan document (module docstring).

    Args:
      doc: dict, the content of ``plan.json`` (:func:`plan_document`).
    Returns:
      a Bokeh layout model.
    """
    from bokeh.layouts import column, row
    from bokeh.models import Button, CheckboxGroup, CustomJS, Div

    sats = columns.satellites(doc)
    obs = columns.observation_columns(doc, sats)
    fmap, filt = _map(doc, sats, obs)
    gantt, batt, x_range, lines = _timeline(doc, sats, obs)
    legend = "".join(
        f'<div><span style="display:inline-block;width:12px;height:12px;background:'
        f'{html.escape(s["color"])};margin-right:6px"></span>{html.escape(s["name"])}'
        + (f" <small>({html.escape(s['model'])})</small>" if s.get("model") else "")
        + "</div>"
        for s in sats
    )
    boxes = CheckboxGroup(
        labels=[s["name"] for s in sats], active=list(range(len(sats))), name="satellite_filter"
    )
    show_all = Button(label="all satellites", width=CONTROLS_WIDTH - 20, name="all_satellites")
    status = Div(text="", width=MAP_WIDTH + CONTROLS_WIDTH, name="filter_status")
    _add_tap(fmap, filt, x_range)
    args = {"boxes": boxes, "xr": x_range, "filtered": filt, "battery": lines, "status": status}
    cb = CustomJS(args=args, code=_FILTER_JS)
    boxes.js_on_change("active", cb)
    x_range.js_on_change("start", cb)
    x_range.js_on_change("end", cb)
    show_all.js_on_event("button_click", CustomJS(args={"boxes": boxes}, code=_ALL_JS))
    n_obs, n_tg = len(obs["sat"]), len((doc.get("view") or {}).get("targets", {}).get("name", []))
    n_free = max(n_tg - len(set(obs["target"])), 0)  # a stereo target may have several looks
    key = Div(
        text=(
            "<b>satellites</b> (check to show on the map)"
            f'<div style="font-size:12px">{legend}</div>'
            f'<p style="font-size:12px;width:{CONTROLS_WIDTH - 16}px">{n_obs} observations; '
            f"{n_free} targets not imaged (grey). Hover a target for who "
            "images it when, click it to zoom the timeline to its pass; wheel / box zoom "
            "the map; zoom or pan the timeline to filter the map by time.</p>"
            + stereo.stereo_summary(doc)
        ),
        width=CONTROLS_WIDTH,
    )
    controls = column(key, boxes, show_all, width=CONTROLS_WIDTH)
    header = Div(text=header_html(doc), width=MAP_WIDTH + CONTROLS_WIDTH, name="header")
    status.text = (
        f"map shows all {len(sats)} satellites over the whole horizon "
        "(zoom the timeline or uncheck satellites to filter)"
    )
    return column(header, row(controls, fmap), status, gantt, batt)


def _add_tap(fmap, filt, x_range) -> None:
    """A click on an imaged target zooms the timeline to its pass, on a stereo target to
    its product's looks."""
    from bokeh.models import CustomJS, TapTool

    imaged = next(r for r in filt if r.name == "targets_imaged")
    marks = fmap.select_one({"name": "stereo_targets"})
    tap = TapTool(renderers=[imaged] + ([marks] if marks else []), behavior="select")
    fmap.add_tools(tap)
    tap.callback = CustomJS(
        args={"src": imaged.data_source, "stereo": marks.data_source if marks else None,
              "xr": x_range, "pad": PASS_PAD_S * columns.MS},
        code=_TAP_JS,
    )  # fmt: skip


def write_plan_html(doc, path, *, force: bool = False) -> Path:
    """Write the page of a plan as one self-contained HTML file (atomic).

    Args:
      doc: dict, a plan document (:func:`plan_document`, or ``plan.json`` read with
        :func:`read_plan`); a :class:`PlanResult` is converted with :func:`plan_document`.
      path: output file.
      force: overwrite an existing file (otherwise ``FileExistsError``, file untouched).
    Returns:
      ``Path(path)``.
    """
    from bokeh.embed import file_html
    from bokeh.resources import INLINE

    refuse_overwrite(path, force)
    if isinstance(doc, PlanResult):
        doc = plan_document(doc)
    title = f"jaxspline plan: {doc['summary'].get('scenario', '')}"
    text = file_html(_plan_page(doc), INLINE, title=title)
    return atomic_write_text(path, text, force=force)
