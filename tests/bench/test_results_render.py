"""bench/results: every markdown is what the bench renders from the JSON beside it.

The documentation includes these files instead of copying their numbers, so a
hand-edited table (or a JSON changed without rendering) would put figures in the docs
that no measurement gave. Also: the tables tolerate the fields a run may lack.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # bench/ is a folder of the checkout, not installed
    sys.path.insert(0, str(ROOT))

from bench import aeossp, job, render  # noqa: E402

RESULTS = ROOT / "bench" / "results"


def test_stored_markdown_is_rendered_from_its_json(tmp_path):
    stored = [name for name in render.RENDERERS if (RESULTS / name).is_file()]
    assert "scale.json" in stored and "report.json" in stored
    for name in stored:
        shutil.copy(RESULTS / name, tmp_path / name)
    written = render.render_all(tmp_path)
    assert len(written) == len(stored)
    for path in written:
        ours = (RESULTS / path.name).read_text(encoding="utf-8")
        assert path.read_text(encoding="utf-8") == ours, (
            f"{path.name}: run python -m bench --render"
        )


def test_tables_show_missing_fields_as_dashes():
    runs = [
        {"run": "first (empty cache)", "exit": 0, "wall_s": 60.0, "joins": {"joins": 5}},
        {"run": "warm 1", "exit": -9, "killed": "RSS", "wall_s": 3.0},
    ]
    text = "\n".join(job.job_table({"runs": runs, "cpus": 2}))
    assert "| first (empty cache) | 0 | 60.0 | - |" in text
    assert "| warm 1 | killed | 3.0 |" in text
    assert "| first (empty cache) | 5 | - |" in text  # the joins table
    assert "<!-- --8<-- [start:runs] -->" in text and "<!-- --8<-- [end:stages] -->" in text
    case = {"case": "c1", "valid": True, "WCR": 0.5, "bound": 0.6, "bound_status": "time"}
    text = "\n".join(aeossp.aeossp_table({"cases": [case], "certificates": {"c1": 0.55}}))
    assert "| c1 | yes | 0.5000 | 0.6000 | time | 0.1000 | 0.5500 | 0.0500 | - |" in text
    assert "| **mean** | 1/1 | **0.5000** |" in text


def test_coverage_plan_rows_show_missing_fields_as_dashes():
    from bench import coverage

    plans = [
        {
            "plan": "areas_example",
            "exit": 0,
            "wall_s": 26.3,
            "peak_rss_mb": 625.0,
            "value": 53.7778,
            "total_value": 56.0,
            "bound": 56.0,
            "gap": 2.2222,
            "gap_pct": 3.968,
            "area_coverage": 0.9444,
            "areas": [{"area": "karst", "samples": 45, "covered_share": 1.0, "strips": 2}],
            "left_out": ["AEM files"],
            "command": "jaxspline plan x.toml",
        },
        {"plan": "case_0002", "exit": -9, "killed": "RSS", "wall_s": 3.0, "command": "c"},
    ]
    text = "\n".join(coverage.plans_table(plans))
    assert "| areas_example | - | - | - | 0 | 26.3 | 625 | - | 53.7778 | 56 | 56 |" in text
    assert "| 0.9444 | - | AEM files |" in text
    assert "| case_0002 | - | - | - | killed | 3.0 | - |" in text
    assert "| areas_example | karst | - | 45 | - | 1.0000 | - | - | 2 |" in text
    assert "case_0002: exit -9 RSS" in text
