"""``jaxspline plan`` end to end on a small scenario: outputs, bound and gap, overwrite rules.

The scenario (written below): 30 minutes over central Europe, a TLE eigen-axis
satellite (ascending pass near t = 1320 s) and a circular per-channel one placed over
46 N 15 E at t = 900 s, 30 random point targets and 2 strips under both tracks.

JIT compilation takes 10-25 s here (more on a busy machine), and the stages before the
search count compile time past 20 s against the time limit. So the module fixture
first runs ``--no-plots`` with a 120 s budget and an iteration cap (it compiles the
kernels and its three files are checked), then the plain command (flown joins, AEMs,
page, figures; more kernels) with 60 s and a cap. Later runs reuse the compiled
kernels with a 10 s budget.
"""

import csv
import datetime as dt
import html
import json
import os
import re
import shutil
import subprocess
import sys

import pytest

from jaxspline.cli import main
from jaxspline.cli.plan import ATTITUDE_FIGURE, OUTPUT_FILES
from jaxspline.products.aem import aem_file_name
from jaxspline.products.plan_html import HTML_FILE

EPOCH = dt.datetime(2026, 4, 14, 12, 30, tzinfo=dt.UTC)
DURATION_S = 1800.0
SMALL = f"""
[scenario]
name = "cli-small"
epoch = "{EPOCH:%Y-%m-%dT%H:%M:%SZ}"
duration_s = {DURATION_S}

[[satellites]]
name = "eo-tle"
tle = [
  "1 44622U 19066A   26103.98739708  .00000848  00000+0  11127-3 0  9997",
  "2 44622  98.0448  57.1255 0005574   1.4726 358.6503 14.82916452352865",
]
model = "eigen_axis"
rate_deg_s = 1.8
accel_deg_s2 = 0.4
settle_s = 2.0
off_nadir_max_deg = 30.0

[[satellites]]
name = "eo-agile"
over = {{ lat_deg = 46.0, lon_deg = 15.0, t_s = 900.0, descending = true }}
model = "per_channel"
rate_deg_s = [3.0, 3.0, 2.0]
accel_deg_s2 = [1.5, 1.5, 1.0]
off_nadir_max_deg = 40.0

[[targets]]
kind = "strip"
name = "strip-east"
lat_deg = 46.62
lon_deg = 14.31
azimuth_deg = 95.0
length_km = 40.0
priority = 10

[[targets]]
kind = "strip"
name = "strip-south"
lat_deg = 45.5
lon_deg = 13.0
azimuth_deg = 180.0
length_km = 30.0
priority = 8

[random_targets]
seed = 3
count = 30
lat_deg = [43.0, 49.0]
lon_deg = [11.0, 17.0]
strip_fraction = 0.0
duration_s = [10.0, 20.0]
priority = [1, 10]

[planner]
time_step_s = 10.0
geometry_step_s = 10.0
scan_speeds_km_s = [4.0, 7.0]
time_limit_s = 15.0
"""
N_TARGETS = 32
QUICK = ["--time-limit", "10", "--max-iters", "30", "--quiet"]
FIRST = ["--time-limit", "120", "--max-iters", "30", "--quiet"]  # compiles: time for it
_TIMEOUT_S = 300
AEMS = tuple(aem_file_name(n) for n in ("eo-tle", "eo-agile"))  # one file a satellite
FULL = OUTPUT_FILES + (HTML_FILE, ATTITUDE_FIGURE) + AEMS  # the default (--aem, --html)
OFF_NADIR_MAX_DEG = {"eo-tle": 30.0, "eo-agile": 40.0}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    scen = d / "small.toml"
    scen.write_text(SMALL, encoding="utf-8")
    no_plots = d / "no_plots"
    args = ["plan", str(scen), "-o", str(no_plots), "--no-plots", "--no-aem", "--no-html", *FIRST]
    code_no_plots = main(args)
    out = d / "out"
    # the default: flown joins and AEMs (their kernels compile now: time for them)
    code = main(["plan", str(scen), "-o", str(out), "--time-limit", "60", "--max-iters", "30"])
    return {"scen": scen, "out": out, "code": code, "no_plots": (code_no_plots, no_plots)}


def plan_json(out):
    """plan.json without what a run measures (times, memory, the clock's account)."""
    data = json.loads((out / "plan.json").read_text())
    data.pop("timings_s")
    measured = (
        "peak_rss_mb",
        "worker_dp_per_s",
        "memory_estimate_mb",
        "lns_seconds",
        "lns_cpu_seconds",
        "sweep_seconds",
        "start_sweep_seconds",
    )
    for name in measured:  # not the plan
        data["stats"].pop(name, None)
    data["report"].pop("time_limit", None)  # the clock's account of the run (elapsed, pace)
    return data


def test_max_iters_gives_the_same_plan_in_another_process(runs, tmp_path):
    """The fixture's first run again as a command, under another hash seed (no set or dict
    order can leak into the plan): plan.json is the same but for what the run measures."""
    code, first = runs["no_plots"]
    assert code == 0
    seed = "2" if os.environ.get("PYTHONHASHSEED") == "1" else "1"
    out = tmp_path / "again"
    cmd = [sys.executable, "-m", "jaxspline.cli", "plan", str(runs["scen"]), "-o", str(out)]
    cmd += ["--no-plots", "--no-aem", "--no-html", *FIRST]
    env = dict(os.environ, PYTHONHASHSEED=seed)  # the run's shared XLA cache (conftest)
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=_TIMEOUT_S)
    assert r.returncode == 0, r.stderr
    again = plan_json(out)
    assert again["summary"]["observations"] > 0
    assert again == plan_json(first)


def _snapshot(out):
    return {n: ((out / n).read_bytes(), (out / n).stat().st_mtime_ns) for n in OUTPUT_FILES}


def test_plan_writes_all_outputs(runs):
    code, out = runs["code"], runs["out"]
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(FULL)
    for name in FULL:  # no temporaries, nothing empty
        assert (out / name).stat().st_size > 0, name
    assert json.loads((out / "plan.czml").read_text())[0]["id"] == "document"


def test_plan_json_summary_bound_and_gap(runs):
    out = runs["out"]
    doc = json.loads((out / "plan.json").read_text())
    s, obs = doc["summary"], doc["observations"]
    assert s["valid"] is True
    assert doc["report"]["violations"] == [] and doc["report"]["checked"] == len(obs)
    joins = doc["report"]["joins"]  # with --aem the command checks the flown joins
    assert joins["violating"] == 0 and joins["joins"] >= len(obs)
    assert joins["refilled"] >= 0 and joins["rejected"] >= 0
    assert max(joins["max_rate_ratio"], joins["max_accel_ratio"]) < 1.0
    assert (s["satellites"], s["targets"], s["observations"]) == (2, N_TARGETS, len(obs))
    assert s["bound"] >= s["value"] > 0
    assert s["gap"] == pytest.approx(s["bound"] - s["value"], abs=1e-9)
    assert s["value"] == pytest.approx(sum(o["value"] for o in obs))
    assert s["value"] <= s["total_value"]
    assert set(doc["timings_s"]) >= {"orbits", "windows", "options", "screening", "search"}
    assert {o["satellite"] for o in obs} == {"eo-tle", "eo-agile"}  # both tracks cross targets


def test_plan_observations_in_horizon_once_each(runs):
    out = runs["out"]
    obs = json.loads((out / "plan.json").read_text())["observations"]
    assert len({o["target"] for o in obs}) == len(obs)  # each target imaged at most once
    for o in obs:
        assert 0.0 <= o["start_s"] < o["end_s"] <= DURATION_S, o
        assert o["slack_s"] >= 0.0 and o["maneuver_s"] >= 0.0, o
        start = dt.datetime.strptime(o["start_utc"], "%Y-%m-%dT%H:%M:%S.%fZ")
        offset = (start.replace(tzinfo=dt.UTC) - EPOCH).total_seconds()
        assert offset == pytest.approx(o["start_s"], abs=1e-5), o
    for sat in ("eo-tle", "eo-agile"):  # one observation at a time per satellite
        mine = sorted((o["start_s"], o["end_s"]) for o in obs if o["satellite"] == sat)
        assert all(s1 >= e0 for (_, e0), (s1, _) in zip(mine, mine[1:], strict=False))


def test_plan_csv_matches_json(runs):
    out = runs["out"]
    obs = json.loads((out / "plan.json").read_text())["observations"]
    with (out / "plan.csv").open(newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(obs) > 0
    for row, o in zip(rows, obs, strict=True):
        assert list(row) == list(o)
        for key, value in o.items():
            if isinstance(value, str):
                assert row[key] == value, key
            else:
                assert float(row[key]) == value, key


def _page_header(html_text: str) -> dict:
    """``data-key`` cells of the page's header, from the Bokeh document embedded in it."""
    blob = re.search(r'<script type="application/json"[^>]*>(.*?)</script>', html_text, re.S)
    found = []

    def walk(x):
        if isinstance(x, dict):
            if x.get("attributes", {}).get("name") == "header":
                found.append(x["attributes"]["text"])
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)

    walk(json.loads(html.unescape(blob.group(1))))  # Bokeh escapes the embedded JSON
    (text,) = found
    return dict(re.findall(r'data-key="([^"]+)">([^<]*)<', text))


def test_plan_html_numbers_equal_plan_json(runs):
    """The page of a real plan: header numbers and view data agree with plan.json."""
    out = runs["out"]
    doc = json.loads((out / "plan.json").read_text())
    cells = _page_header((out / HTML_FILE).read_text(encoding="utf-8"))
    s, joins = doc["summary"], doc["report"]["joins"]
    for key, want in [
        ("observations", s["observations"]),
        ("value", s["value"]),
        ("bound", s["bound"]),
        ("gap", s["gap"]),
        ("checked", doc["report"]["checked"]),
        ("joins", joins["joins"]),
        ("joins_rejected", joins["rejected"]),
        ("windows", doc["stats"]["windows"]),
        ("t_search", doc["timings_s"]["search"]),
    ]:
        assert float(cells[key]) == pytest.approx(want, rel=5e-3, abs=1e-12), key
    assert cells["scenario"] == "cli-small" and cells["valid"] == "valid"
    view, obs = doc["view"], doc["observations"]
    assert len(view["targets"]["name"]) == N_TARGETS
    assert len(view["strips"]) == 2 and [s_["name"] for s_ in view["satellites"]] == list(
        OFF_NADIR_MAX_DEG
    )
    off = view["observations"]["off_nadir_deg"]
    assert len(off) == len(view["observations"]["footprint"]) == len(obs) > 0
    for o, angle in zip(obs, off, strict=True):  # the planner kept every look within limits
        assert 0.0 <= angle <= OFF_NADIR_MAX_DEG[o["satellite"]] + 0.05, (o, angle)
    track = view["tracks"]
    assert track["t_s"][0] == 0.0 and track["t_s"][-1] == DURATION_S
    assert all(len(lon) == len(track["t_s"]) for lon in track["lon_deg"])


def test_plan_refuses_to_overwrite(runs, capsys):
    scen, out = runs["scen"], runs["out"]
    before = _snapshot(out)
    capsys.readouterr()
    assert main(["plan", str(scen), "-o", str(out), *QUICK]) == 2
    err = capsys.readouterr().err
    assert "plan.json" in err and "--force" in err
    assert _snapshot(out) == before  # bytes and modification times unchanged


def test_plan_force_overwrites(runs, tmp_path):
    # --force replaces the whole set: a data-only run over a full set leaves its own
    # three files, never the earlier page, figures or AEMs beside them
    out = tmp_path / "out"
    shutil.copytree(runs["out"], out)  # keeps the modification times
    before = {n: (out / n).stat().st_mtime_ns for n in FULL}
    args = ["plan", str(runs["scen"]), "-o", str(out), "--force", "--no-plots", "--no-aem"]
    assert main([*args, "--no-html", *QUICK]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUT_FILES[:3])
    for name in OUTPUT_FILES[:3]:
        assert (out / name).stat().st_mtime_ns > before[name], name
    assert json.loads((out / "plan.json").read_text())["summary"]["valid"] is True


def test_plan_no_plots_no_aem_no_html_writes_data_files_only(runs):
    code, out = runs["no_plots"]
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUT_FILES[:3])
    assert json.loads((out / "plan.json").read_text())["summary"]["valid"] is True


@pytest.mark.parametrize(
    "old, new, field",
    [
        ("[planner]\n", "[planner]\nbeam_width = 4\n", "planner.beam_width"),
        ("[planner]\n", "[planer]\n", "planer"),
    ],
    ids=["unknown-key", "unknown-section"],
)
def test_plan_bad_scenario_names_the_key(tmp_path, capsys, old, new, field):
    assert SMALL.count(old) == 1
    text = SMALL.replace(old, new)
    line = text.splitlines().index(new.splitlines()[-1]) + 1
    bad = tmp_path / "bad.toml"
    bad.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["plan", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{field} (line {line}): unknown" in err, err
    assert not out.exists()  # nothing written


def test_plan_missing_scenario_file(tmp_path, capsys):
    missing = tmp_path / "missing.toml"
    assert main(["plan", str(missing), "-o", str(tmp_path / "out")]) == 2
    assert "scenario file not found" in capsys.readouterr().err


def test_a_full_disk_names_the_page_being_written(runs, tmp_path, monkeypatch, capsys):
    import errno

    from test_files import _FullFile

    from jaxspline.planner import files

    page = tmp_path / "page.html"
    monkeypatch.setattr(files, "open", _FullFile, raising=False)  # ENOSPC at the first write
    assert main(["view", str(runs["out"] / "plan.json"), "-o", str(page)]) == 4
    err = capsys.readouterr().err
    assert err == f"jaxspline: cannot write: {page}: {os.strerror(errno.ENOSPC)}\n", err
    assert list(tmp_path.iterdir()) == []


def test_a_real_full_disk_names_the_page_being_written(runs, tmp_path):
    from _full_disk import full_disk

    with full_disk(tmp_path) as full:
        page = full / "page.html"
        cmd = [sys.executable, "-m", "jaxspline.cli", "view", str(runs["out"] / "plan.json")]
        done = subprocess.run([*cmd, "-o", str(page)], capture_output=True, text=True, timeout=120)
        assert done.returncode == 4, done.stderr
        assert done.stderr == f"jaxspline: cannot write: {page}: No space left on device\n"


def test_compile_cache_directory_from_the_environment(monkeypatch, tmp_path):
    from jaxspline.cli import CACHE_ENV, cache_dir

    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "xla"))
    assert cache_dir() == tmp_path / "xla"
    for off in ("off", "", "OFF", "none"):
        monkeypatch.setenv(CACHE_ENV, off)
        assert cache_dir() is None
    monkeypatch.delenv(CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert cache_dir() == tmp_path / "jaxspline" / "xla"


def test_a_time_bound_run_leaves_out_what_does_not_fit_and_says_so(
    runs, tmp_path, monkeypatch, capsys
):
    """The optional outputs would take hours: a time-bound run writes the plan files
    alone, valid, records what it left out in plan.json and says so on stderr."""
    from jaxspline.products import output_budget as ob

    real = ob.output_seconds

    def slow(sc, **asked):
        return {k: v if k == "plan files" else 1e4 for k, v in real(sc, **asked).items()}

    monkeypatch.setattr(ob, "output_seconds", slow)
    out = tmp_path / "late"
    assert main(["plan", str(runs["scen"]), "-o", str(out), "--time-limit", "8", "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["plan.csv", "plan.json"]
    doc = json.loads((out / "plan.json").read_text())
    tl = doc["report"]["time_limit"]
    assert [s["what"] for s in tl["skipped"] if s["stage"] == "outputs"] == list(ob.PRODUCTS)
    assert tl["limit_s"] == 8.0 and tl["reserve_s"]["outputs"] >= 1e4
    assert doc["summary"]["valid"] is True and doc["report"]["violations"] == []
    err = capsys.readouterr().err
    assert "note: left out for the time limit: " in err
    assert "; plan.html [run `jaxspline view plan.json` to build it]; " in err
