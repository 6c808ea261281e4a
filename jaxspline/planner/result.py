"""What :func:`jaxspline.plan` returns: the per-satellite timelines, value, bound and report.

A :class:`PlanResult` is plain data (numpy arrays and dicts) plus writers for JSON and
CSV. Times are seconds from the scenario epoch; ISO-8601 UTC strings are added in the
written files.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from typing import NamedTuple

import numpy as np

from jaxspline.planner.files import atomic_write_text
from jaxspline.readers.mission import KIND_NAMES, Scenario

__all__ = ["Observations", "PlanResult"]


class Observations(NamedTuple):
    """K planned observations, numpy arrays [K] sorted by (satellite, start).

    Attributes:
      sat: satellite index into ``scenario.satellites``.
      target: target index into ``scenario.targets``.
      start, end: imaging interval [s from the epoch].
      maneuver: duration [s] of the maneuver that ends at ``start`` (from the previous
        observation's end, or from the initial attitude for a satellite's first one):
        the time the satellite's model requires, at most the available gap.
      slack: available gap minus required maneuver time [s] (>= 0 in a valid plan).
      value: the target's value; for an area strip, the area's value it adds to the
        strips before it (in time order), so the values sum to the plan's.
      speed: ground scan speed of a strip [m/s] (0 for points).
      roll: the roll an area strip holds [rad] (NaN for point and strip targets).
      pitch: the pitch an area strip holds [rad] (NaN for point and strip targets).
    """

    sat: np.ndarray
    target: np.ndarray
    start: np.ndarray
    end: np.ndarray
    maneuver: np.ndarray
    slack: np.ndarray
    value: np.ndarray
    speed: np.ndarray
    roll: np.ndarray
    pitch: np.ndarray

    def __len__(self) -> int:
        return int(self.sat.shape[0])


@dataclasses.dataclass(frozen=True)
class PlanResult:
    """The outcome of :func:`jaxspline.plan`.

    Attributes:
      scenario: the planned :class:`jaxspline.readers.mission.Scenario`.
      observations: :class:`Observations`.
      value: total value of the plan (each target counted once, an area by the share
        of its samples covered).
      bound: an upper bound of the best plan's value (Lagrangian / exact DP; the
        battery is relaxed), so ``gap = bound - value`` certifies how far the plan can
        be from the optimum of the option model.
      gap: ``bound - value`` (>= 0).
      bound_converged: True when the bound's subgradient iteration stopped by
        convergence (not by the time limit).
      report: independent re-check of the plan: ``{"valid": bool, "checked": int,
        "violations": [str, ...], "min_slack_s": float, "min_battery_wh": float}``;
        with areas also ``"areas"``, one dict per area
        (:func:`jaxspline.planner.assemble.area_report`).
      stats: counts (windows, options, near pairs, search iterations, ...).
      timings: wall time per stage [s].
      battery: per satellite name, ``(t [s], level [Wh])`` of the planned battery
        profile (satellites without power model are absent).
      areas: per area of the scenario its samples and which the plan covers
        (:func:`jaxspline.planner.area_report.area_samples`; empty without areas).
      footprints: per observation the ground ring an area strip sweeps, ``(lon, lat)``
        [deg], None for other targets (:func:`jaxspline.planner.area_report.strip_footprints`;
        empty without areas).
    """

    scenario: Scenario
    observations: Observations
    value: float
    bound: float
    gap: float
    bound_converged: bool
    report: dict
    stats: dict
    timings: dict
    battery: dict = dataclasses.field(default_factory=dict)
    areas: list = dataclasses.field(default_factory=list)
    footprints: list = dataclasses.field(default_factory=list)

    @property
    def total_value(self) -> float:
        """Sum of all targets' values (the value of imaging everything once)."""
        return float(np.sum(self.scenario.targets.value))

    def timeline(self, sat: int | str) -> Observations:
        """The observations of one satellite, in time order.

        Args:
          sat: satellite index or name.
        Returns:
          Observations of that satellite.
        Raises:
          ValueError: unknown satellite name.
        """
        if isinstance(sat, str):
            names = [s.name for s in self.scenario.satellites]
            if sat not in names:
                raise ValueError(f"sat: unknown satellite {sat!r}; known: {names}")
            sat = names.index(sat)
        m = self.observations.sat == int(sat)
        return Observations(*(x[m] for x in self.observations))

    def rows(self) -> list[dict]:
        """One dict per observation (names, ISO times, seconds, maneuver, slack, value).

        Returns:
          list of dict, JSON-ready.
        """
        sc = self.scenario
        o = self.observations
        out = []
        for i in range(len(o)):
            k, r = int(o.sat[i]), int(o.target[i])
            sat = sc.satellites[k]
            out.append(
                {
                    "satellite": sat.name,
                    "target": str(sc.targets.name[r]),
                    "kind": KIND_NAMES[int(sc.targets.kind[r])],
                    "start_utc": _iso(sc.at(o.start[i])),
                    "end_utc": _iso(sc.at(o.end[i])),
                    "start_s": float(o.start[i]),
                    "end_s": float(o.end[i]),
                    "maneuver_s": float(o.maneuver[i]),
                    "slack_s": float(o.slack[i]),
                    "model": sat.model,
                    "value": float(o.value[i]),
                    "scan_speed_m_s": float(o.speed[i]),
                }
            )
        if sc.areas or sc.stereo:  # a held look's roll and pitch, an area's covered share
            self._area_columns(out)
        return out

    def _area_columns(self, rows: list[dict]) -> None:
        """Add ``roll_deg`` and ``pitch_deg`` (the pointing offset an area strip or a look
        of a stereo target holds, "" for other targets) and ``area_covered_share`` (the
        strip's area's covered share, ``report["areas"]``) to each row of :meth:`rows`."""
        share = {a["area"]: a["covered_share"] for a in self.report.get("areas", [])}
        o = self.observations
        for row, roll, pitch in zip(rows, o.roll, o.pitch, strict=True):
            area, held = row["kind"] == "area", row["kind"] in ("area", "stereo")
            row["roll_deg"] = round(math.degrees(float(roll)), 6) if held else ""
            row["pitch_deg"] = round(math.degrees(float(pitch)), 6) if held else ""
            row["area_covered_share"] = round(share[row["target"]], 6) if area else ""

    def summary(self) -> dict:
        """Headline figures (JSON-ready).

        Returns:
          dict.
        """
        return {
            "scenario": self.scenario.name,
            "satellites": len(self.scenario.satellites),
            "targets": len(self.scenario.targets),
            "observations": len(self.observations),
            "value": self.value,
            "total_value": self.total_value,
            "bound": self.bound,
            "gap": self.gap,
            "bound_converged": self.bound_converged,
            "valid": bool(self.report.get("valid", False)),
        }

    def to_dict(self, *, extra: dict | None = None) -> dict:
        """The plan document: summary, report, stats, timings and the observations.

        Args:
          extra: further top-level sections (JSON-ready), e.g. ``{"view": ...}`` from
            :func:`jaxspline.products.plan_view.view_data`; they may not replace a section.
        Returns:
          dict, JSON-ready (numpy scalars converted, non-finite floats None).
        Raises:
          ValueError: an ``extra`` key names a built-in section.
        """
        doc = {
            "summary": self.summary(),
            "report": self.report,
            "stats": self.stats,
            "timings_s": self.timings,
            "observations": self.rows(),
        }
        clash = sorted(set(extra or {}) & set(doc))
        if clash:
            raise ValueError(f"extra: sections {clash} are built in")
        return _clean({**doc, **(extra or {})})

    def to_json(self, path, *, force: bool = False, extra: dict | None = None):
        """Write :meth:`to_dict` as JSON (atomic).

        Args:
          path: str or Path.
          force: overwrite an existing file.
          extra: further top-level sections (see :meth:`to_dict`).
        Raises:
          FileExistsError: the file exists and ``force`` is false.
        """
        text = _dumps(self.to_dict(extra=extra)) + "\n"
        return atomic_write_text(path, text, force=force)

    def to_csv(self, path, *, force: bool = False):
        """Write one CSV row per observation (atomic).

        Args:
          path: str or Path.
          force: overwrite an existing file.
        Raises:
          FileExistsError: the file exists and ``force`` is false.
        """
        rows = self.rows()
        buf = io.StringIO()
        fields = list(rows[0]) if rows else ["satellite", "target", "start_utc", "end_utc"]
        w = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        return atomic_write_text(path, buf.getvalue(), force=force)


def _iso(when) -> str:
    return when.strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def _dumps(x, level: int = 0) -> str:
    """``json.dumps(x, indent=2)``, but with a list of plain values on one line.

    A ground track or a battery curve then takes one line, not one per number.
    """
    nested = isinstance(x, dict) or (
        isinstance(x, list) and any(isinstance(v, dict | list) for v in x)
    )
    if not x or not nested:
        return json.dumps(x)
    pad, end = "  " * (level + 1), "  " * level
    if isinstance(x, dict):
        items = [f"{pad}{json.dumps(str(k))}: {_dumps(v, level + 1)}" for k, v in x.items()]
        return "{\n" + ",\n".join(items) + "\n" + end + "}"
    return "[\n" + ",\n".join(pad + _dumps(v, level + 1) for v in x) + "\n" + end + "]"


def _clean(x):
    """JSON-safe copy: numpy scalars to Python, non-finite floats to None."""
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_clean(v) for v in x]
    if isinstance(x, np.ndarray):
        return _clean(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
