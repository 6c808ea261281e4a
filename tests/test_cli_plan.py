"""``jaxspline plan`` end to end on a small scenario: outputs, refusal to overwrite, errors."""

import json

import numpy as np
import pytest

from jaxspline.cli import main
from jaxspline.cli_plan import OUTPUT_FILES

SMALL = """
[scenario]
name = "small"
epoch = "2026-06-21T10:00:00Z"
duration_s = 400.0

[satellite]
over = { lat_deg = 46.0, lon_deg = 15.0, t_s = 200.0 }
off_nadir_max_deg = 40.0
rate_deg_s = 2.0
accel_deg_s2 = 1.0

[[routes]]
kind = "strip"
lat_deg = 46.8
lon_deg = 15.6
azimuth_deg = 190.0
length_km = 30.0
priority = 9

[random_targets]
seed = 2
count = 10
lat_deg = [44.0, 48.0]
lon_deg = [13.5, 16.5]
strip_fraction = 0.0

[planner]
beam_width = 4
t0_grid = 3
scan_speeds_km_s = [6.0]
refine_steps = 20
max_gap_s = 40.0
"""


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    scen = d / "small.toml"
    scen.write_text(SMALL)
    out = d / "out"
    code = main(["plan", str(scen), "-o", str(out), "--quiet"])
    return code, scen, out


def test_plan_writes_valid_outputs(small_run):
    code, _, out = small_run
    assert code == 0
    for name in OUTPUT_FILES:
        assert (out / name).stat().st_size > 0, name
    summary = json.loads((out / "plan.json").read_text())
    st = summary["stats"]
    assert summary["scenario"]["routes"] == 11
    assert st["valid"] is True and st["violations"] == []
    assert st["plan_steps"] == len(summary["plan"]) >= 2
    assert st["plan_value"] == pytest.approx(sum(r["value"] for r in summary["plan"]))
    assert 0.0 < st["feasible_fraction"] <= 1.0
    assert st["candidates_screened"] >= st["candidates_feasible"] > 0
    assert set(summary["timings_s"]) >= {"options", "screen", "sequence", "refine", "validate"}
    steps = summary["plan"]
    ts = np.array([r["t_start_s"] for r in steps])
    te = np.array([r["t_end_s"] for r in steps])
    assert np.all(ts[1:] > te[:-1])  # time order, no overlap
    assert len({r["route"] for r in steps}) == len(steps)  # each route at most once
    for r in steps:
        lo, hi = r["window_s"]
        assert lo - 1e-6 <= r["t_start_s"] <= hi + 1e-6
    rows = (out / "plan.csv").read_text().strip().splitlines()
    assert len(rows) == 1 + len(steps)
    assert rows[0].startswith("step,route,kind")


def test_plan_refuses_to_overwrite(small_run, capsys):
    _, scen, out = small_run
    before = (out / "plan.json").read_text()
    code = main(["plan", str(scen), "-o", str(out), "--quiet", "--no-plots"])
    assert code == 2
    err = capsys.readouterr().err
    assert "plan.json" in err and "--force" in err
    assert (out / "plan.json").read_text() == before


def test_plan_force_overwrites_and_beam_width(small_run):
    _, scen, out = small_run
    code = main(
        ["plan", str(scen), "-o", str(out), "--quiet", "--no-plots", "--force", "--beam-width", "1"]
    )
    assert code == 0
    summary = json.loads((out / "plan.json").read_text())
    assert summary["stats"]["beam_width"] == 1
    assert not list(out.glob("*.tmp"))  # atomic writes leave no temporaries


def test_plan_bad_scenario_exit_code(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[satellite]\nrate_deg_s = [1, 2]\n[random_targets]\n")
    assert main(["plan", str(bad), "-o", str(tmp_path / "o")]) == 2
    assert "satellite.rate_deg_s" in capsys.readouterr().err
    assert main(["plan", str(tmp_path / "missing.toml"), "-o", str(tmp_path / "o")]) == 2
