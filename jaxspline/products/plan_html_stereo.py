"""Stereo targets on the plan page (:mod:`jaxspline.products.plan_html`): marks and joins.

From the view's ``stereo`` section (:func:`jaxspline.products.plan_view.view_data`: per
stereo target its position, product and the product's looks as observation indices):

* on the map, ``stereo_targets``: one marker per stereo target, drawn under the
  observation glyphs and larger (it rings the glyphs of its looks in the satellites'
  colours), by what the plan collects there: a triangle for a pair
  (:data:`PAIR_COLOR`), a diamond for a triple (:data:`TRI_COLOR`), an inverted
  triangle for none (:data:`NO_PRODUCT_COLOR`); hovering shows the product, its
  quality, convergence and overlap, and the number of looks; a click zooms the timeline
  to the product's looks (+- the page's pass pad);
* on the timeline, ``stereo_joins``: the looks of one product joined by segments, each
  from one look to the next in time (a pair: one segment, a triple: two), from bar
  midpoint to bar midpoint a little above the bars (across satellites' rows too), in the
  product's colour; ``stereo_looks``: a marker on each joined look's bar, with the
  product on hover;
* legends: ``stereo_legend`` on the map (one entry per product kind present),
  ``stereo_join_legend`` above the timeline.

Everything is drawn only when the view has a ``stereo`` section; a look index outside
the observations is skipped (a hand-edited ``plan.json`` never breaks the page).
"""

from __future__ import annotations

import html

import numpy as np

__all__ = [
    "JOIN_OFFSET",
    "NO_PRODUCT_COLOR",
    "PAIR_COLOR",
    "TRI_COLOR",
    "add_stereo_joins",
    "add_stereo_targets",
    "join_columns",
    "stereo_columns",
    "stereo_summary",
]

PAIR_COLOR = "#009e73"  # bluish green (Okabe-Ito): no satellite colour is near it
TRI_COLOR = "#e6ab02"  # dark gold
NO_PRODUCT_COLOR = "#999999"  # as targets not imaged
MARKERS = {"pair": "triangle", "tri": "diamond", None: "inverted_triangle"}
LABELS = {"pair": "stereo pair", "tri": "stereo triple", None: "stereo: no product"}
COLORS = {"pair": PAIR_COLOR, "tri": TRI_COLOR, None: NO_PRODUCT_COLOR}
SIZES = {"pair": 16, "tri": 16, None: 9}  # map marker sizes [px]
JOIN_OFFSET = 0.42  # joins run this far above a row's centre (bars are 0.6 high)
LEGEND_PX = 28  # the timeline grows by this when it carries the join legend


def _entries(doc) -> list[dict]:
    """The view's stereo entries (objects only: a hand-edited file never breaks the page)."""
    entries = (doc.get("view") or {}).get("stereo") or []
    return [e for e in entries if isinstance(e, dict)] if isinstance(entries, list) else []


def _looks(entry, n_obs: int) -> list[int]:
    """The entry's look indices that name an observation (time order as the view gives)."""
    out = []
    for i in entry.get("looks") or []:
        if isinstance(i, int) and not isinstance(i, bool) and 0 <= i < n_obs:
            out.append(i)
    return out


def _text(x, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def stereo_columns(doc, obs) -> dict:
    """One row per stereo target: position, marker, colour, hover texts and the time
    span of its product's looks [ms] (NaN without a product).

    Args:
      doc: the plan document; obs: the observation columns
        (:func:`jaxspline.products.plan_html_columns.observation_columns`).
    Returns:
      dict of lists / arrays (empty lists without a ``stereo`` section).
    """
    entries = _entries(doc)
    n = len(obs["sat"])
    cols = {k: [] for k in ("x", "y", "target", "product", "marker", "color", "label",
                            "size", "quality", "convergence", "overlap", "looks", "t0",
                            "t1")}  # fmt: skip
    nan = float("nan")
    for e in entries:
        kind = e.get("product") if e.get("product") in ("pair", "tri") else None
        looks = _looks(e, n) if kind else []
        cols["x"].append(nan if e.get("lon_deg") is None else float(e["lon_deg"]))
        cols["y"].append(nan if e.get("lat_deg") is None else float(e["lat_deg"]))
        cols["target"].append(str(e.get("target", "")))
        cand = e.get("candidates")
        what = {"pair": "pair", "tri": "triple"}.get(kind, "none")
        cols["product"].append(what if kind or cand is None else f"none ({cand} candidates)")
        cols["marker"].append(MARKERS[kind])
        cols["color"].append(COLORS[kind])
        cols["label"].append(LABELS[kind])
        cols["size"].append(SIZES[kind])
        cols["quality"].append(_text(e.get("quality"), ".3f"))
        cols["convergence"].append(_text(e.get("convergence_deg"), ".2f") + " deg" * bool(kind))
        cols["overlap"].append(_text(e.get("overlap"), ".3f"))
        cols["looks"].append(len(looks))
        cols["t0"].append(min((obs["t0"][i] for i in looks), default=nan))
        cols["t1"].append(max((obs["t1"][i] for i in looks), default=nan))
    for k in ("x", "y", "t0", "t1"):
        cols[k] = np.asarray(cols[k], np.float64)
    return cols


def join_columns(doc, obs) -> dict:
    """The timeline's joins: per product one segment from each look to the next in time,
    bar midpoint to bar midpoint, :data:`JOIN_OFFSET` above the rows' centres.

    Args:
      doc: the plan document; obs: the observation columns.
    Returns:
      dict of lists: ``x0``, ``x1`` [ms], ``y0``, ``y1`` (``[satellite, offset]``
      categorical coordinates), ``target``, ``product``, ``color``, ``label``.
    """
    entries = _entries(doc)
    n = len(obs["sat"])
    cols = {k: [] for k in ("x0", "x1", "y0", "y1", "target", "product", "color", "label")}
    for e in entries:
        kind = e.get("product")
        if kind not in ("pair", "tri"):
            continue
        looks = sorted(_looks(e, n), key=lambda i: obs["t0"][i])
        for a, b in zip(looks[:-1], looks[1:], strict=True):
            cols["x0"].append(0.5 * (obs["t0"][a] + obs["t1"][a]))
            cols["x1"].append(0.5 * (obs["t0"][b] + obs["t1"][b]))
            cols["y0"].append([obs["satellite"][a], JOIN_OFFSET])
            cols["y1"].append([obs["satellite"][b], JOIN_OFFSET])
            cols["target"].append(str(e.get("target", "")))
            cols["product"].append("pair" if kind == "pair" else "triple")
            cols["color"].append(COLORS[kind])
            cols["label"].append(LABELS[kind])
    return cols


def _look_marks(doc, obs) -> dict:
    """One row per joined look: its bar's midpoint a little above the bar, hover texts."""
    entries = _entries(doc)
    n = len(obs["sat"])
    cols = {k: [] for k in ("x", "y", "target", "product", "color", "start", "satellite")}
    for e in entries:
        kind = e.get("product")
        if kind not in ("pair", "tri"):
            continue
        for i in _looks(e, n):
            cols["x"].append(0.5 * (obs["t0"][i] + obs["t1"][i]))
            cols["y"].append([obs["satellite"][i], JOIN_OFFSET])
            cols["target"].append(str(e.get("target", "")))
            cols["product"].append("pair" if kind == "pair" else "triple")
            cols["color"].append(COLORS[kind])
            cols["start"].append(obs["start"][i])
            cols["satellite"].append(obs["satellite"][i])
    return cols


def stereo_summary(doc) -> str:
    """A line for the page's key (HTML), e.g. ``5 stereo targets: 3 pairs, 1 triple``;
    "" without stereo targets."""
    entries = _entries(doc)
    if not entries:
        return ""
    pairs = sum(e.get("product") == "pair" for e in entries)
    tri = sum(e.get("product") == "tri" for e in entries)
    none = len(entries) - pairs - tri
    return (
        f'<p style="font-size:12px">{len(entries)} stereo targets: '
        f"{_swatch('pair')} {pairs} pairs, {_swatch('tri')} {tri} triples, "
        f"{_swatch(None)} {none} none; a product's looks are joined in the timeline. "
        "Click a stereo target to zoom the timeline to its looks.</p>"
    )


def _swatch(kind) -> str:
    """The marker of a product kind as a coloured character (HTML)."""
    char = {"pair": "&#9650;", "tri": "&#9670;", None: "&#9660;"}[kind]
    return f'<span style="color:{html.escape(COLORS[kind])}">{char}</span>'


def add_stereo_targets(fig, doc, obs):
    """The stereo targets' markers on the map with their hover and legend (module
    docstring). Returns the renderer, or None without stereo targets."""
    from bokeh.models import ColumnDataSource, HoverTool

    cols = stereo_columns(doc, obs)
    if not cols["target"]:
        return None
    r = fig.scatter(
        x="x",
        y="y",
        source=ColumnDataSource(cols),
        marker="marker",
        size="size",
        fill_color="color",
        line_color="black",
        line_width=0.8,
        legend_field="label",
        name="stereo_targets",
    )
    fig.add_tools(
        HoverTool(
            renderers=[r],
            tooltips=[
                ("stereo target", "@target"),
                ("product", "@product"),
                ("quality", "@quality"),
                ("convergence", "@convergence"),
                ("overlap", "@overlap"),
                ("looks", "@looks"),
            ],
        )
    )
    fig.legend.name = "stereo_legend"
    fig.legend.location = "bottom_left"
    fig.legend.label_text_font_size = "11px"
    fig.legend.background_fill_alpha = 0.8
    fig.legend.click_policy = "hide"
    return r


def add_stereo_joins(gantt, doc, obs) -> bool:
    """The joins of each product's looks on the timeline (module docstring), a marker on
    each look and the legend above the chart. Returns whether anything was drawn."""
    from bokeh.models import ColumnDataSource, HoverTool, Legend

    cols = join_columns(doc, obs)
    marks = _look_marks(doc, obs)
    if not marks["x"]:
        return False
    rj = gantt.segment(
        x0="x0",
        y0="y0",
        x1="x1",
        y1="y1",
        source=ColumnDataSource(cols),
        line_color="color",
        line_width=2.5,
        line_alpha=0.9,
        name="stereo_joins",
    )
    rl = gantt.scatter(
        x="x",
        y="y",
        source=ColumnDataSource(marks),
        marker="circle",
        size=6,
        fill_color="color",
        line_color="black",
        line_width=0.5,
        name="stereo_looks",
    )
    gantt.add_tools(
        HoverTool(
            renderers=[rl],
            tooltips=[
                ("stereo look", "@target (@product)"),
                ("satellite", "@satellite"),
                ("start", "@start UTC"),
            ],  # fmt: skip
        )
    )
    items = []
    for kind in ("pair", "tri"):
        idx = [i for i, lab in enumerate(cols["label"]) if lab == LABELS[kind]]
        if idx:
            items.append((f"looks of one {LABELS[kind]}", [rj], idx[0]))
    legend = Legend(
        items=[_item(label, r, i) for label, r, i in items],
        orientation="horizontal",
        location="top_left",
        label_text_font_size="11px",
        name="stereo_join_legend",
    )
    gantt.add_layout(legend, "above")
    gantt.height += LEGEND_PX
    return True


def _item(label: str, renderers, index: int):
    from bokeh.models import LegendItem

    return LegendItem(label=label, renderers=renderers, index=index)
