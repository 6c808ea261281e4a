"""The header of the plan page (:mod:`jaxspline.products.plan_html`): the plan in figures.

:func:`header_html` reads the plan document (``plan.json``'s content) and returns one
HTML fragment: scenario, value, bound and gap, validity, join statistics, areas
covered, search statistics and stage timings, one line each, every number in a cell
with a ``data-key`` attribute (for tests and scripts). No Bokeh import here.
"""

from __future__ import annotations

import html

from jaxspline.products import plan_html_columns as columns
from jaxspline.search import BoundStatus

__all__ = ["header_html"]

_STYLE = (
    "<style>.hdr{font:13px/1.5 sans-serif} .hdr .v{font-weight:600}"
    " .hdr .ok{color:#2ca02c;font-weight:700} .hdr .bad{color:#d62728;font-weight:700}"
    " .hdr h2{margin:0 0 4px 0;font-size:18px}</style>"
)
_COUNTS = ("windows", "options", "near_pairs", "lagrangian_iterations", "lns_iterations")


def _cell(key, value, spec=".6g") -> str:
    """One number of the header, formatted, in a span with ``data-key="key"``."""
    return f'<span class="v" data-key="{key}">{columns.fmt(value, spec)}</span>'


def _scenario_line(doc) -> str:
    s, view = doc["summary"], doc.get("view") or {}
    when = ""
    if "epoch_utc" in view:
        when = (
            f", {_cell('duration_h', view['duration_s'] / 3600.0, '.4g')} h from "
            f"{html.escape(columns.utc_text(view['epoch_utc'])[:16])} UTC"
        )
    return (
        f"<b>scenario</b> {_cell('scenario', s['scenario'])}: "
        f"{_cell('satellites', s['satellites'])} satellites, "
        f"{_cell('targets', s['targets'])} targets{when}"
    )


def _value_lines(doc) -> list[str]:
    """The plan's value of the total, and the bound and gap."""
    s, st = doc["summary"], doc.get("stats") or {}
    bound = s.get("bound") or 0.0
    gap_pct = 100.0 * s["gap"] / bound if bound and s.get("gap") is not None else None
    total = s.get("total_value") or 0.0
    status = BoundStatus.CONVERGED if s.get("bound_converged") else "-"
    return [
        f"<b>plan</b> {_cell('observations', s['observations'])} observations, value "
        f"{_cell('value', s['value'])} of {_cell('total_value', total)}"
        + (f" ({100.0 * s['value'] / total:.1f} %)" if total else ""),
        f"<b>bound</b> {_cell('bound', s['bound'])} "
        f"({html.escape(str(st.get('bound_status', status)))}); "
        f"<b>gap</b> {_cell('gap', s['gap'])}"
        + (
            f" ({_cell('gap_percent', gap_pct, '.3g')} % of the bound)"
            if gap_pct is not None
            else ""
        ),
    ]


def _check_line(doc) -> str:
    """Validity, checked observations, violations, dropped ones, least slack and battery."""
    s, rep = doc["summary"], doc["report"]
    valid = bool(s.get("valid"))
    low = rep.get("min_battery_wh")  # per powered satellite (older files: one number)
    low = low if isinstance(low, dict) else ({} if low is None else {"all": low})
    battery = ", ".join(
        f"{html.escape(k)} {_cell('min_battery_wh.' + k, v, '.5g')}" for k, v in low.items()
    )
    dropped = ", ".join(f"{n} {html.escape(k)}" for k, n in (rep.get("dropped") or {}).items())
    return (
        f'<b>check</b> <span class="{"ok" if valid else "bad"}" data-key="valid">'
        f"{'valid' if valid else 'INVALID'}</span>: {_cell('checked', rep.get('checked'))} "
        f"checked, {_cell('violations', len(rep.get('violations') or []))} violations"
        + (f", dropped {dropped}" if dropped else "")
        + f"; min slack {_cell('min_slack_s', rep.get('min_slack_s'), '.4g')} s"
        + (f"; min battery {battery} Wh" if battery else "")
    )


def _joins_line(rep) -> str:
    j = rep.get("joins")
    if not j:
        return "<b>joins</b> not checked (planned with --no-aem)"
    return (
        f"<b>joins</b> {_cell('joins', j.get('joins'))} degree-7 joins, "
        f"{_cell('joins_retimed', j.get('retimed'))} re-timed, "
        f"{_cell('joins_rejected', j.get('rejected'))} rejected; peak ratios rate "
        f"{_cell('max_rate_ratio', j.get('max_rate_ratio'), '.3f')}, accel "
        f"{_cell('max_accel_ratio', j.get('max_accel_ratio'), '.3f')}, jerk "
        f"{_cell('max_jerk_ratio', j.get('max_jerk_ratio'), '.3f')}"
    )


def _area_lines(rep) -> list[str]:
    return [
        f"<b>area</b> {html.escape(str(a.get('area')))}: "
        f"{a.get('strips')} strips planned, "
        f"{columns.fmt(100.0 * (a.get('covered_share') or 0.0), '.1f')} % covered"
        f" (within reach {columns.fmt(100.0 * (a.get('reachable_share') or 0.0), '.1f')} %)"
        for a in rep.get("areas") or []
    ]


def _effort_lines(doc) -> list[str]:
    """The search's counts and the stage timings, when the document has them."""
    st, tim = doc.get("stats") or {}, doc.get("timings_s") or {}
    lines = []
    counts = [(k, st[k]) for k in _COUNTS if isinstance(st.get(k), int | float)]
    if counts:
        lines.append(
            "<b>search</b> " + ", ".join(f"{k.replace('_', ' ')} {_cell(k, v)}" for k, v in counts)
        )
    if tim:
        lines.append(
            "<b>wall time [s]</b> "
            + ", ".join(f"{html.escape(k)} {_cell('t_' + k, v, '.3g')}" for k, v in tim.items())
            + f"; total {_cell('t_total', sum(v for v in tim.values() if v), '.3g')}"
        )
    return lines


def header_html(doc) -> str:
    """The page's header: a title and one line per topic (module docstring).

    Args:
      doc: dict, a plan document (the content of ``plan.json``).
    Returns:
      str, an HTML fragment with its own ``<style>``.
    """
    rep = doc["report"]
    lines = [_scenario_line(doc), *_value_lines(doc), _check_line(doc), _joins_line(rep)]
    lines += _area_lines(rep) + _effort_lines(doc)
    title = f"<h2>jaxspline plan: {html.escape(str(doc['summary']['scenario']))}</h2>"
    return _STYLE + '<div class="hdr">' + title + "<br>".join(lines) + "</div>"
