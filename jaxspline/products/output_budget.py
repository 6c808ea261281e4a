"""What the outputs of ``jaxspline plan`` cost, and which of them still fit in its time limit.

``plan.json`` and ``plan.csv`` are always written: they are the plan. The other files
are optional products; :func:`output_seconds` estimates each from the scenario's size
(CPU seconds per item, measured on a 2-core machine on the default job: 6 satellites,
6 h, 1,700 targets, about 500 observations, 12,960 attitude states: 0.5 s for
``plan.json``/``plan.csv``, 1.1 s ``plan.czml``, 1.6 s the page, 13.6 s the attitude
history and AEM files, 5.4 s the figures with attitude.png; on the 12 x 12 h preset,
5,000 targets and 3,490 observations: 1.3 s the plan files, 4.4 s ``plan.czml``,
3.2 s the page; on the constellation day, 24 satellites, 24 h, 20,000 targets and
11,945 observations: 4.3 s, 16.4 s and 6.3 s), so the planner can keep their time out
of the search
(:attr:`jaxspline.planner.deadline.StageDeadline.after_s`, :data:`RESERVE_FACTOR`
times the estimate). When the time left is short all the same (a loaded machine, a
search that was given its minimum share), :func:`jaxspline.products.outputs.write_plan_outputs`
writes them in the order of :data:`PRODUCTS` as long as each one's estimate, at the
call's pace, fits before the limit, and records each one left out with the way to get
it (:data:`REMEDIES`) in ``plan.json``'s ``report["time_limit"]["skipped"]``.
"""

from __future__ import annotations

__all__ = [
    "AEM_S_PER_STATE",
    "ATTITUDE_PLOT_S_PER_STATE",
    "CZML_S_PER_SAT_HOUR",
    "CZML_S_PER_TARGET",
    "PAGE_FIXED_S",
    "PAGE_S_PER_TARGET",
    "PLAN_FILES_FIXED_S",
    "PLAN_FILES_S_PER_TARGET",
    "PLOTS_FIXED_S",
    "PLOTS_S_PER_SAT_HOUR",
    "PRODUCTS",
    "REMEDIES",
    "RESERVE_FACTOR",
    "output_seconds",
]

#: The optional products, in the order they are written when time is short: the
#: cheap viewers first, then the attitude files, then the figures (the page shows
#: the map, timeline and battery already).
PRODUCTS = ("plan.html", "plan.czml", "AEM files", "figures")
REMEDIES = {
    "plan.html": "run `jaxspline view plan.json` to build it",
    "plan.czml": "give a longer --time-limit",
    "AEM files": "give a longer --time-limit (or a coarser --aem-step)",
    "figures": "give a longer --time-limit",
}

PLAN_FILES_FIXED_S = 0.5  # plan.json (with its view section) and plan.csv [s]
PLAN_FILES_S_PER_TARGET = 2e-4  # ... per target [s]
PAGE_FIXED_S = 2.2  # plan.html [s]
PAGE_S_PER_TARGET = 2e-4  # ... per target [s]
CZML_S_PER_TARGET = 1.5e-4  # plan.czml, per target [s]
CZML_S_PER_SAT_HOUR = 0.026  # ... per satellite and hour of the horizon [s]
AEM_S_PER_STATE = 1.1e-3  # attitude history and its AEM files, per attitude state [s]
PLOTS_FIXED_S = 3.0  # the PNG figures (matplotlib, the world map) [s]
PLOTS_S_PER_SAT_HOUR = 0.02  # ... per satellite and hour [s]
ATTITUDE_PLOT_S_PER_STATE = 1.7e-4  # attitude.png, per attitude state [s]
#: What the search keeps free for the outputs, as a multiple of their estimate: the
#: estimates cover each product's measured CPU seconds (by 0-20 %), the factor what a
#: run adds to them (a product's first call on a new size, a slower disk). Whether
#: each product is written is still decided on its own estimate against the time
#: really left.
RESERVE_FACTOR = 1.3


def output_seconds(sc, *, plots: bool, html: bool, aem: bool, aem_step: float) -> dict:
    """Estimated CPU seconds of each output of a plan of ``sc`` (module docstring).

    Args:
      sc: the Scenario.
      plots: the PNG figures are asked for.
      html: plan.html is asked for.
      aem: the AEM files (and attitude.png with ``plots``) are asked for.
      aem_step: AEM sample step [s].
    Returns:
      dict: ``"plan files"`` (always) and each asked product of :data:`PRODUCTS` -> [s].
    """
    n_sat = len(sc.satellites)
    targets = len(sc.targets)
    sat_hours = n_sat * sc.duration / 3600.0
    states = n_sat * sc.duration / aem_step if aem else 0.0
    cost = {
        "plan files": PLAN_FILES_FIXED_S + PLAN_FILES_S_PER_TARGET * targets,
        "plan.czml": CZML_S_PER_TARGET * targets + CZML_S_PER_SAT_HOUR * sat_hours,
    }
    if html:
        cost["plan.html"] = PAGE_FIXED_S + PAGE_S_PER_TARGET * targets
    if aem:
        cost["AEM files"] = AEM_S_PER_STATE * states
    if plots:
        figures = PLOTS_FIXED_S + PLOTS_S_PER_SAT_HOUR * sat_hours
        cost["figures"] = figures + ATTITUDE_PLOT_S_PER_STATE * states
    return cost
