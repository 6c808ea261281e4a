"""Checks of a ``plan.json`` before ``jaxspline view`` draws it: every field by its path.

``plan.json`` is the document ``jaxspline plan`` writes
(:meth:`jaxspline.planner.result.PlanResult.to_dict` with the ``"view"`` section of
:func:`jaxspline.products.plan_view.view_data`). The page reads many of its fields; a
file edited by hand or by another program may hold anything, so :func:`check_plan_doc`
checks the types of what the page reads and raises ``ValueError`` naming the file and
the first bad field (``plan.json: view.targets.lon_deg[3]: must be a number or null,
got 'x'``). Numbers may be ``null`` where the plan writes ``null`` (non-finite values);
a number is finite (``plan.json`` never holds ``NaN`` or ``Infinity``), and an
observation's ``start_s <= end_s`` lie within the longest horizon
(``scenario.duration_s``'s range).
"""

from __future__ import annotations

import datetime as _dt
import math

from jaxspline.readers.ranges import RANGES

__all__ = ["check_plan_doc"]

NUM = "number"  # int or float, not bool
OPT = "number or null"
STR = "string"
BOOL = "true or false"
OPT_STR = "string or null"
UTC_FORMAT = "%Y-%m-%dT%H:%M:%S.%fZ"  # as plan.json writes instants
MAX_HORIZON_S = RANGES["scenario.duration_s"][1]  # the longest horizon [s]


def _ok(kind: str, x) -> bool:
    if kind in (NUM, OPT):
        return (x is None and kind == OPT) or (
            isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
        )
    if kind in (STR, OPT_STR):
        return isinstance(x, str) or (x is None and kind == OPT_STR)
    return isinstance(x, bool)


class _Checker:
    def __init__(self, source: str):
        self.source = source

    def fail(self, where: str, msg: str):
        raise ValueError(f"{self.source}: {where or 'the document'}: {msg}")

    def value(self, where, x, kind):
        if not _ok(kind, x):
            self.fail(where, f"must be a {kind}, got {_show(x)}")

    def table(self, where, x, fields: dict, required=()):
        """``x`` a dict; its present ``fields`` of their kind (a kind, a callable, or a
        kind for every entry of a list: ``[kind]``); ``required`` must be there."""
        if not isinstance(x, dict):
            self.fail(where, f"must be an object, got {_show(x)}")
        missing = [k for k in required if k not in x]
        if missing:
            self.fail(where, f"missing {', '.join(missing)}")
        for k, kind in fields.items():
            if k in x:
                self.field(f"{where}.{k}".lstrip("."), x[k], kind)

    def field(self, where, x, kind):
        if callable(kind):
            kind(self, where, x)
        elif isinstance(kind, list):
            self.items(where, x, kind[0])
        else:
            self.value(where, x, kind)

    def items(self, where, x, kind, n=None):
        if not isinstance(x, list):
            self.fail(where, f"must be a list, got {_show(x)}")
        if n is not None and len(x) != n:
            self.fail(where, f"must have {n} entries (one per observation), got {len(x)}")
        for i, v in enumerate(x):
            self.field(f"{where}[{i}]", v, kind)


def _show(x) -> str:
    text = repr(x)
    return text if len(text) <= 60 else text[:57] + "..."


def _nums_or_null(c, where, x):
    if x is not None:
        c.items(where, x, OPT)


def _lonlat(c, where, x):
    if x is not None:
        c.table(where, x, {"lon_deg": [OPT], "lat_deg": [OPT]}, ("lon_deg", "lat_deg"))


def _utc(c, where, x):
    c.value(where, x, STR)
    try:
        _dt.datetime.strptime(x, UTC_FORMAT)
    except ValueError:
        c.fail(where, f"must be a UTC instant like 2026-04-14T00:00:00.000000Z, got {_show(x)}")


def _positive(c, where, x):
    c.value(where, x, NUM)
    if not (math.isfinite(x) and x > 0):
        c.fail(where, f"must be a finite number > 0, got {_show(x)}")


def _observation(c, where, x):
    fields = {"satellite": STR, "target": STR, "kind": STR, "model": STR, "start_utc": _utc,
              "end_utc": _utc, "start_s": NUM, "end_s": NUM, "value": OPT, "maneuver_s": OPT,
              "slack_s": OPT, "scan_speed_m_s": OPT}  # fmt: skip
    c.table(where, x, fields, ("satellite", "target", "start_s", "end_s"))
    start, end = x["start_s"], x["end_s"]
    if not 0.0 <= start <= end <= MAX_HORIZON_S:
        c.fail(
            where,
            f"must have 0 <= start_s <= end_s <= {MAX_HORIZON_S:g} s, got start_s "
            f"{_show(start)}, end_s {_show(end)}",
        )


def _tracks(c, where, x):
    c.table(where, x, {"step_s": OPT, "t_s": [OPT], "lon_deg": [_nums_or_null],
                       "lat_deg": [_nums_or_null]})  # fmt: skip


def _targets(c, where, x):
    cols = {"name": [STR], "kind": [STR], "lon_deg": [OPT], "lat_deg": [OPT], "value": [OPT]}
    c.table(where, x, cols)
    n = {len(x[k]) for k in cols if k in x}
    if len(n) > 1:
        c.fail(where, f"the columns must have one length, got lengths {sorted(n)}")


def _satellite(c, where, x):
    c.table(where, x, {"name": STR, "model": STR, "color": STR, "swath_m": OPT}, ("name",))


def _strip(c, where, x):
    c.table(where, x, {"target": NUM, "lon_deg": [OPT], "lat_deg": [OPT]})


def _area(c, where, x):
    c.table(where, x, {"name": STR, "value": OPT, "geometry": _geometry})


def _geometry(c, where, x):
    if x is None:  # an area given by its samples alone
        return
    c.table(where, x, {"type": STR, "coordinates": lambda c, w, v: c.items(w, v, _anything)})


def _anything(c, where, x):
    pass


def _battery(c, where, x):
    if not isinstance(x, dict):
        c.fail(where, f"must be an object, got {_show(x)}")
    for name, b in x.items():
        c.table(f"{where}.{name}", b, {"t_s": [OPT], "level_wh": [OPT]}, ("t_s", "level_wh"))


def _view(c, where, x):
    fields = {
        "version": NUM,
        "epoch_utc": _utc,
        "duration_s": _positive,
        "satellites": [_satellite],
        "tracks": _tracks,
        "targets": _targets,
        "strips": [_strip],
        "observations": lambda c, w, v: c.table(
            w, v, {"off_nadir_deg": [OPT], "footprint": [_lonlat]}
        ),
        "areas": [_area],
        "battery": _battery,
    }
    c.table(where, x, fields)


def _report(c, where, x):
    c.table(
        where,
        x,
        {
            "valid": BOOL,
            "checked": OPT,
            "dropped": lambda c, w, v: c.table(w, v, dict.fromkeys(v, OPT)),
            "joins": lambda c, w, v: c.table(w, v, dict.fromkeys(v, OPT)),
            "areas": [lambda c, w, v: c.table(w, v, {"area": STR, "covered_share": OPT})],
            "stereo": [lambda c, w, v: c.table(w, v, {"target": STR, "quality": OPT})],
            "min_battery_wh": lambda c, w, v: (
                c.table(w, v, dict.fromkeys(v, OPT)) if isinstance(v, dict) else c.value(w, v, OPT)
            ),
        },
    )


def check_plan_doc(doc, source: str) -> dict:
    """Check the fields of a plan document that ``jaxspline view`` reads.

    Args:
      doc: the parsed JSON.
      source: the file's name in error messages.
    Returns:
      dict, ``doc``.
    Raises:
      ValueError: ``source: field.path: what is wrong``.
    """
    c = _Checker(source)
    summary = {"scenario": STR, "satellites": OPT, "targets": OPT, "observations": OPT,
               "value": OPT, "total_value": OPT, "bound": OPT, "gap": OPT,
               "bound_converged": BOOL, "valid": BOOL}  # fmt: skip
    top = {
        "summary": lambda c, w, v: c.table(w, v, summary),
        "report": _report,
        "stats": lambda c, w, v: c.table(w, v, {}),
        "timings_s": lambda c, w, v: c.table(w, v, dict.fromkeys(v, OPT)),
        "observations": [_observation],
        "view": _view,
    }
    c.table("", doc, top, ("summary", "report", "observations"))
    view = doc.get("view")
    if isinstance(view, dict) and "observations" in view:
        n = len(doc["observations"])
        for key in ("off_nadir_deg", "footprint"):
            if key in view["observations"]:
                c.items(f"view.observations.{key}", view["observations"][key], _anything, n)
    return doc
