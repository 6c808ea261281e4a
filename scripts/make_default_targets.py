"""Build ``jaxspline/data/cities.csv``, the city targets of the default scenario.

Source: the named city tasks of the aeossp_standard benchmark's training cases
(``<cases>/case_*/tasks.yaml``; the ``background_*`` tasks are skipped). Rules, all
deterministic (the same input gives the same file byte for byte):

* cases in name order, tasks in file order; a city's first occurrence wins
  (duplicates by name are dropped); the first ``MAX_TARGETS`` cities are kept and
  written sorted by name;
* ``priority`` = the benchmark weight, rounded and clipped to [1, 10];
* ``duration_s`` = a quarter of the benchmark's imaging time, rounded up to a multiple
  of 5 s and clipped to [10, 30] s (the default plans on a 10 s grid over six hours);
* ``sensor`` = ``"infrared"`` for the benchmark's top-weight infrared requests (a few
  percent), else ``"visible"``;
* ``alt_m`` = the benchmark altitude [m]; latitude and longitude in degrees as given.

Usage::

    python scripts/make_default_targets.py [--cases DIR] [--out FILE]
"""

from __future__ import annotations

import argparse
import csv
import io
import math
from pathlib import Path

import yaml

from jaxspline.planner.files import atomic_write_text

REPO = Path(__file__).resolve().parents[1]
DEFAULT_CASES = REPO.parent / "shared" / "data" / "aeossp_standard" / "train"
DEFAULT_OUT = REPO / "jaxspline" / "data" / "cities.csv"
MAX_TARGETS = 1500
PRIORITY_RANGE = (1, 10)
DURATION_SCALE = 0.25  # benchmark imaging times are 20-120 s; ours 10-30 s
DURATION_STEP_S = 5
DURATION_RANGE_S = (10, 30)
INFRARED_MIN_WEIGHT = 5.0
BACKGROUND_PREFIX = "background_"
COLUMNS = ("name", "lat_deg", "lon_deg", "alt_m", "priority", "duration_s", "sensor")


def city_tasks(cases: Path) -> list[dict]:
    """The benchmark's city tasks, first occurrence per name, in case and file order."""
    files = sorted(cases.glob("case_*/tasks.yaml"))
    if not files:
        raise FileNotFoundError(f"no case_*/tasks.yaml under {cases}")
    seen: dict[str, dict] = {}
    for path in files:
        for task in yaml.safe_load(path.read_text(encoding="utf-8"))["tasks"]:
            name = str(task["name"]).strip()
            if not name.startswith(BACKGROUND_PREFIX) and name not in seen:
                seen[name] = task
    return list(seen.values())


def target_row(task: dict) -> dict:
    """One CSV row (see the module docstring for the rules) of a benchmark task."""
    weight = float(task["weight"])
    priority = min(max(round(weight), PRIORITY_RANGE[0]), PRIORITY_RANGE[1])
    steps = math.ceil(DURATION_SCALE * float(task["required_duration_s"]) / DURATION_STEP_S)
    duration = min(max(DURATION_STEP_S * steps, DURATION_RANGE_S[0]), DURATION_RANGE_S[1])
    infrared = task["required_sensor_type"] == "infrared" and weight >= INFRARED_MIN_WEIGHT
    return {
        "name": str(task["name"]).strip(),
        "lat_deg": f"{float(task['latitude_deg']):.5f}",
        "lon_deg": f"{float(task['longitude_deg']):.5f}",
        "alt_m": f"{float(task.get('altitude_m', 0.0)):g}",
        "priority": str(priority),
        "duration_s": str(duration),
        "sensor": "infrared" if infrared else "visible",
    }


def build_csv(cases: Path) -> str:
    """The CSV text of the default city targets."""
    rows = sorted((target_row(t) for t in city_tasks(cases)[:MAX_TARGETS]), key=lambda r: r["name"])
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def main(argv: list[str] | None = None) -> None:
    """Command line: write the CSV and print a summary."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=Path, default=DEFAULT_CASES, help="aeossp train/ folder")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help="CSV file to write")
    args = ap.parse_args(argv)
    text = build_csv(args.cases)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out, text)
    rows = list(csv.DictReader(io.StringIO(text)))
    ir = sum(r["sensor"] == "infrared" for r in rows)
    print(f"{args.out}: {len(rows)} city targets, {ir} infrared")


if __name__ == "__main__":
    main()
