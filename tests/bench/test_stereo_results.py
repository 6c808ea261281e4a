"""bench/stereo: STEREO.md rendered from a small fake stereo.json, and the command's line.

No planning: the report is made up, the rendering and parsing are what is tested.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # bench/ is a folder of the checkout, not installed
    sys.path.insert(0, str(ROOT))

from bench import render, stereo  # noqa: E402

CASE = {
    "case": "case_0001",
    "valid": True,
    "exit": 0,
    "coverage_ratio": 0.9,
    "expected_coverage": 0.875,
    "coverage_bound": 0.95,
    "normalized_quality": 0.85,
    "quality_bound": 0.94,
    "pairs_valid": 120,
    "triples_valid": 7,
    "looks": 250,
    "value": 123.5,
    "bound": 130.25,
    "bound_status": "converged",
    "gap": 6.75,
    "wall_s": 118.04,
    "peak_rss_mb": 2048.4,
    "load_avg_before": 1.5,
}
REPORT = {
    "time_limit_s": 120.0,
    "seed": 0,
    "cpus": 2,
    "load_avg": {"start": 1.25, "end": 2.5},
    "cases": [CASE, {"case": "case_0002", "exit": -9, "killed": "wall time > 720 s"}],
}


def test_stereo_table_rows_means_and_missing_fields():
    text = "\n".join(stereo.stereo_table(REPORT))
    assert "--time-limit 120 --seed 0" in text
    assert (
        "| case_0001 | yes | 0.9000 | 0.8750 | 0.9500 | 0.0500 | 0.8500 | 0.9400 | 120 | 7 | 250 | "
        "123.5 | 130.25 | converged | 6.75 | 118.0 | 2048 | 1.50 |"
    ) in text
    assert "| case_0002 | - | - |" + " - |" * (len(stereo.CASE_COLUMNS) - 3) in text
    # means over the cases that have the field; valid counted over all cases
    mean = next(ln for ln in text.splitlines() if ln.startswith("| **mean** |"))
    assert mean.startswith(
        "| **mean** | 1/2 | **0.9000** | 0.8750 | 0.9500 | 0.0500 | **0.8500** | 0.9400 |"
    )
    assert mean.endswith("|  |  |  |  |  |  |  | 118.0 | 2048 |  |")  # wall, RSS in place
    assert mean.count("|") == len(stereo.CASE_COLUMNS) + 1
    assert "1.25 at the start, 2.50 at the end, on 2 CPUs" in text
    assert "case_0002: wall time > 720 s" in text
    assert "<!-- --8<-- [start:cases] -->" in text and "<!-- --8<-- [end:cases] -->" in text
    assert "held-out *test* cases" in text


def test_render_writes_stereo_md_from_its_json(tmp_path):
    (tmp_path / "stereo.json").write_text(json.dumps(REPORT))
    written = render.render_all(tmp_path)
    assert written == [tmp_path / "STEREO.md"]
    md = (tmp_path / "STEREO.md").read_text(encoding="utf-8")
    assert md.startswith("# stereo_imaging training cases\n")
    assert "| case_0001 | yes | 0.9000 |" in md
    stereo.write_stereo(REPORT, tmp_path / "again")  # the writer gives the same page
    assert (tmp_path / "again" / "STEREO.md").read_text(encoding="utf-8") == md


def test_parse_summary_of_the_solve_line():
    log = (
        "[plan case] search ...\n"
        "wrote /tmp/s/case_0001.json: coverage_ratio 0.93893 (bound 0.97710), quality "
        "0.91234, 261 looks; value 118.5, bound 124.75 (converged), gap 6.25 (117.3 s)\n"
        "valid: yes\n"
    )
    got = stereo.parse_summary(log)
    assert got == {
        "path": "/tmp/s/case_0001.json",
        "plan_coverage": 0.93893,
        "plan_coverage_bound": 0.9771,
        "plan_quality": 0.91234,
        "looks": 261,
        "value": 118.5,
        "bound": 124.75,
        "bound_status": "converged",
        "gap": 6.25,
        "command_s": 117.3,
    }
    assert stereo.parse_summary("no such line") == {}


def test_expected_coverage_matches_a_simulation_of_the_random_estimates():
    """The official checker's expectation, against a Monte-Carlo draw of its estimates:
    each valid pair passes when >= 80 of 100 random points fall in both strips; a triple
    when its common overlap passes with 100 points and two of its three pairs with 80."""
    from types import SimpleNamespace as NS

    import numpy as np

    def pair(t, acts, ov, failed=()):
        return NS(target_id=t, actions=acts, overlap=ov, failed=failed)

    pairs = [
        pair("a", (0, 1), 0.84),  # two pairs of target a, drawn apart
        pair("a", (2, 3), 0.86),
        pair("b", (4, 5), 0.79, ("overlap",)),  # fails exactly, passes by chance
        pair("c", (6, 7), 0.95, ("convergence",)),  # never valid
        pair("d", (8, 9), 0.83),  # the triple 8, 9, 10 of target d
        pair("d", (8, 10), 0.81),
        pair("d", (9, 10), 0.9, ("convergence",)),
    ]
    triples = [
        NS(target_id="d", actions=(10, 9, 8), common_overlap=0.82, failed=()),
        NS(target_id="c", actions=(6, 7, 11), common_overlap=0.99, failed=("anchor",)),
    ]
    rep = NS(pairs=pairs, triples=triples, num_targets=5)
    got = stereo.expected_coverage(rep, 0.8)

    rng = np.random.default_rng(7)
    n = 200_000

    def passes(share, points):
        return rng.binomial(points, share, n) >= 80 * points // 100

    a = passes(0.84, 100) | passes(0.86, 100)
    b = passes(0.79, 100)
    d_pair = passes(0.83, 100) | passes(0.81, 100)
    e1, e2 = passes(0.83, 80), passes(0.81, 80)  # the triple's third edge is invalid
    d = d_pair | (passes(0.82, 100) & e1 & e2)
    want = (a.mean() + b.mean() + d.mean()) / 5
    assert abs(got - want) < 0.004, (got, want)
    assert 0.0 < got < 3 / 5
