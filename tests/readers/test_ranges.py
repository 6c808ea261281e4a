"""The ranges of scenario numbers (:mod:`jaxspline.readers.ranges`) and the TLE checks.

* ``docs/scenarios.md`` states every range of :data:`RANGES` with the same numbers;
* TLE epochs: parsed from line 1 (two-digit years around 1957/2056), accepted up to
  30 days from the horizon and refused past it with the remedy; checksums and the
  catalogue number of both lines are checked;
* the exact search's option cap is enforced at read time and in ``PlannerConfig``.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from jaxspline.readers.config import MAX_EXACT_OPTIONS, PlannerConfig
from jaxspline.readers.ranges import MAX_TLE_AGE_DAYS, RANGES, bounds, range_text
from jaxspline.readers.satellites import tle_epoch
from jaxspline.readers.scenario import parse_scenario

DOCS = Path(__file__).resolve().parents[2] / "docs" / "scenarios.md"
L1 = "1 44622U 19066A   26103.98739708  .00000848  00000+0  11127-3 0  9997"
L2 = "2 44622  98.0448  57.1255 0005574   1.4726 358.6503 14.82916452352865"
TLE_EPOCH = dt.datetime(2026, 4, 13, tzinfo=dt.UTC) + dt.timedelta(days=0.98739708)


def test_the_docs_state_every_range():
    text = DOCS.read_text(encoding="utf-8")
    missing = [k for k in RANGES if f"| `{k}` | {range_text(k)} |" not in text]
    assert missing == [], missing


def test_bounds_of_times_end_at_the_horizon():
    assert bounds("targets[].window_s", 600.0) == {"lo": 0.0, "hi": 600.0}
    assert bounds("targets[].window_s")["hi"] == RANGES["scenario.duration_s"][1]
    assert bounds("satellites[].rate_deg_s") == {"lo": 0.01, "hi": 90.0}


def test_tle_epoch():
    assert abs(tle_epoch(L1) - TLE_EPOCH) < dt.timedelta(microseconds=1)
    assert tle_epoch("1 00005U 58002B   58100.5").year == 1958
    assert tle_epoch("1 00005U 58002B   56001.0").year == 2056
    with pytest.raises(ValueError, match="day of the year"):
        tle_epoch("1 00005U 58002B   26400.0")


def _doc(epoch: dt.datetime, tle=(L1, L2), duration_s=600.0, planner=None):
    return {
        "scenario": {"epoch": epoch.strftime("%Y-%m-%dT%H:%M:%SZ"), "duration_s": duration_s},
        "satellites": [{"tle": list(tle)}],
        "targets": [{"lat_deg": 46.0, "lon_deg": 15.0}],
        **({"planner": planner} if planner else {}),
    }


@pytest.mark.parametrize("days", [-MAX_TLE_AGE_DAYS + 0.5, 0.0, MAX_TLE_AGE_DAYS - 0.5])
def test_tle_within_30_days_is_accepted(days):
    epoch = TLE_EPOCH + dt.timedelta(days=days) - dt.timedelta(seconds=600 if days > 0 else 0)
    sc = parse_scenario(_doc(epoch))
    assert sc.satellites[0].orbit == (L1, L2)


@pytest.mark.parametrize("days", [-40.0, 31.0, 365.0 * 3])
def test_tle_far_from_the_horizon_is_refused(days):
    with pytest.raises(ValueError) as exc:
        parse_scenario(_doc(TLE_EPOCH + dt.timedelta(days=days)), source="s.toml")
    msg = str(exc.value)
    assert msg.startswith("s.toml: satellites[0].tle: the TLE's epoch 2026-04-13 23:41 UTC")
    assert "within 30 days" in msg and "a TLE of the scenario's dates" in msg


def test_a_long_horizon_counts_its_end():
    day = dt.timedelta(days=1)
    parse_scenario(_doc(TLE_EPOCH - 5 * day, duration_s=29 * 86400.0))  # ends 24 days after
    with pytest.raises(ValueError, match="31.0 days from the horizon"):
        parse_scenario(_doc(TLE_EPOCH + 5 * day, duration_s=26 * 86400.0))


@pytest.mark.parametrize(
    ("tle", "why"),
    [
        ((L1[:-1] + "8", L2), "line 1 checksum (column 69) is '8', the line's digits give 7"),
        ((L1, L2[:20] + "9" + L2[21:]), "line 2 checksum"),
        ((L1[:-1], L2), "line 1 must have 69 columns"),
        ((L2, L1), "line 1 must have 69 columns and start with '1 '"),
        ((L1, L2.replace("44622", "44623")), "line 2 checksum"),
        ((L1.replace("\u0020\u00200", "\x00 0", 1), L2), "control characters"),
    ],
)
def test_damaged_tles_are_refused(tle, why):
    with pytest.raises(ValueError, match="satellites\\[0\\].tle") as exc:
        parse_scenario(_doc(TLE_EPOCH, tle), source="s.toml")
    assert why in str(exc.value), str(exc.value)


def test_two_satellites_lines_are_refused():
    other = "2 44623" + L2[7:68]
    other += str(sum(int(c) if c.isdigit() else c == "-" for c in other) % 10)
    with pytest.raises(ValueError, match="two satellites"):
        parse_scenario(_doc(TLE_EPOCH, (L1, other)))


def test_exact_search_cap():
    with pytest.raises(ValueError, match=r"planner.exact_max_options: must be within \[0, 500\]"):
        parse_scenario(_doc(TLE_EPOCH, planner={"exact_max_options": 10**12}))
    with pytest.raises(ValueError, match="exact_max_options must be in"):
        PlannerConfig(exact_max_options=MAX_EXACT_OPTIONS + 1)
    assert PlannerConfig(exact_max_options=MAX_EXACT_OPTIONS).exact_max_options == 500


def test_directory_and_deep_nesting_are_named(tmp_path):
    from jaxspline.readers.scenario import load_scenario

    with pytest.raises(ValueError, match="is a directory, not a file"):
        load_scenario(tmp_path)
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 5000 + "]" * 5000)
    with pytest.raises(ValueError, match="deep.toml: invalid TOML"):
        load_scenario(deep)
