"""bench.scale: the RSS guard kills a growing child, plan.json parsing tolerates gaps."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # bench/ is a folder of the checkout, not installed
    sys.path.insert(0, str(ROOT))

from bench import scale  # noqa: E402

GROW = (  # a child that grows by 20 MB every 20 ms up to 1.5 GB, then sleeps
    "import time\nb = []\n"
    'for _ in range(75):\n    b.append(b"\\x01" * (20 << 20)); time.sleep(0.02)\n'
    "time.sleep(30)\n"
)


def test_guard_kills_a_child_over_the_rss_limit(tmp_path):
    limit = 200 * 2**20
    res = scale.run_guarded(
        [sys.executable, "-c", GROW], tmp_path / "log", max_rss_bytes=limit, max_wall_s=60.0
    )
    assert res["killed"] and res["killed"].startswith("RSS")
    assert res["exit"] == -9  # SIGKILL
    assert 200 < res["polled_peak_rss_mb"] < 1000  # stopped long before 1.5 GB
    assert res["wall_s"] < 20


def test_guard_wall_cap_and_normal_exit(tmp_path):
    res = scale.run_guarded(
        [sys.executable, "-c", "import time; time.sleep(30)"],
        tmp_path / "a",
        max_rss_bytes=2**40,
        max_wall_s=0.5,
    )
    assert res["killed"].startswith("wall time") and res["wall_s"] < 10
    ok = scale.run_guarded([sys.executable, "-c", "print('hi')"], tmp_path / "b", 2**40, 60.0)
    assert ok == {**ok, "exit": 0, "killed": None}
    assert (tmp_path / "b").read_text().strip() == "hi"


def test_guard_reads_the_costly_pss_rarely_and_at_once_past_the_limit(monkeypatch):
    # a fake tree: PSS reads take 10 ms; the resident set is PSS + 1 GB of shared pages
    state = {"pss": 1 << 30, "reads": 0}

    def fake(pid, pss=True):
        if pss:
            state["reads"] += 1
            time.sleep(0.01)
            return state["pss"]
        return state["pss"] + (1 << 30)

    monkeypatch.setattr(scale, "tree_rss_bytes", fake)
    mem, limit = scale._TreeMemory(1), 3 << 30
    t0 = time.monotonic()
    while time.monotonic() - t0 < 1.0:
        assert mem.estimate(limit) == 1 << 30  # no growth: the last PSS
    # one read every >= 0.5 s (50 x 10 ms), not one a poll
    assert 2 <= state["reads"] <= 3
    state["pss"] = 2 << 30  # grows by 1 GB: the estimate follows the resident set
    reads = state["reads"]
    assert mem.estimate(limit) == 2 << 30 and state["reads"] == reads
    state["pss"] = 4 << 30  # past the limit: read at once
    assert mem.estimate(limit) == 4 << 30 and state["reads"] == reads + 1
    assert mem.peak == 4 << 30


def test_tree_rss_counts_descendants_and_is_zero_when_gone():
    import os
    import subprocess

    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(5)"])
    try:
        assert scale.tree_rss_bytes(os.getpid()) > scale.tree_rss_bytes(child.pid) > 0
    finally:
        child.kill()
        child.wait()
    assert scale.tree_rss_bytes(child.pid) == 0


def test_plan_json_fields_and_missing_ones(tmp_path):
    full = {
        "summary": {"scenario": "x", "satellites": 2, "targets": 9, "value": 90.0,
                    "bound": 100.0, "gap": 10.0, "valid": True},
        "stats": {"windows": 5, "options": 40, "near_pairs": 1000, "store_bytes": 8000,
                  "peak_rss_mb": {"orbits": 200.0, "search": 300.0}},
        "timings_s": {"orbits": 0.5, "search": 2.0},
    }  # fmt: skip
    (tmp_path / "full.json").write_text(json.dumps(full))
    (tmp_path / "bare.json").write_text(json.dumps({"summary": {"value": 1.0}}))
    got = scale.parse_plan_json(tmp_path / "full.json")
    assert got["bytes_per_pair"] == 8.0  # from store_bytes / near_pairs
    assert got["gap_pct"] == 10.0 and got["valid"] is True
    bare = scale.parse_plan_json(tmp_path / "bare.json")
    assert bare["options"] is None and bare["timings_s"] == {}
    assert scale.parse_plan_json(tmp_path / "missing.json") == {}
    runs = [
        {"size": "full", "exit": 0, "wall_s": 4.0, "peak_rss_mb": 310.0, **got},
        {"size": "bare", "exit": 1, "wall_s": 1.0, "peak_rss_mb": None, **bare},
        {"size": "dead", "exit": -9, "wall_s": 1.0, "peak_rss_mb": 9e3, "killed": "RSS"},
    ]
    text = "\n".join(scale.scale_table({"runs": runs, "time_limit_s": 5, "max_rss_gb": 8}))
    row = "| full | 2 | 9 | 5 | 0 | 4.0 | 310 | 5 | 40 | 1000 | 8.00 | 0.0 | - | - | - | 90 | 100 |"
    assert row in text
    assert "| bare | - | - | 5 | 1 |" in text and "| dead | - | - | 5 | killed |" in text
    assert "| full | 0.50 / 200 | 2.00 / 300 |" in text
    assert "dead: killed, RSS" in text


def test_made_by_reads_the_generator_command(tmp_path):
    toml = tmp_path / "t.toml"
    toml.write_text(
        "# Scale scenario 't'\n#   python scripts/make_scale_scenario.py --out t.toml\n"
    )
    assert scale.made_by(toml) == "python scripts/make_scale_scenario.py --out t.toml"
    assert scale.made_by(None) is None and scale.made_by(tmp_path / "none.toml") is None


def test_size_tokens_take_their_own_budget():
    assert scale.split_limit("day:540", 60.0) == ("day", 540.0)
    assert scale.split_limit("default", 60.0) == ("default", 60.0)
    assert scale.split_limit("/tmp/x.toml:7.5", 60.0) == ("/tmp/x.toml", 7.5)
    for bad in ("day:soon", "day:0"):
        try:
            scale.split_limit(bad, 60.0)
        except SystemExit as e:
            assert bad in str(e)
        else:
            raise AssertionError(bad)
