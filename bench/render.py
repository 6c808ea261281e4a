"""``python -m bench --render [--out DIR]``: rewrite every result markdown from its JSON.

Measures nothing: for each JSON file the bench writes (``report.json``,
``scale.json``, ``screening.json``, ``job.json``, ``aeossp.json``, ``coverage.json``,
``bound.json``, ``stereo.json``) present in the output folder, the markdown beside it
is generated again by the same code that wrote it after the measurement. Run it after
changing how a table is written.
"""

from __future__ import annotations

import json
from pathlib import Path


def _report(d: dict) -> tuple[str, list[str]]:
    from bench.report import results_lines

    return "Kernel benchmark", results_lines(d)


def _scale(d: dict) -> tuple[str, list[str]]:
    from bench.scale import scale_table

    return "Scale runs", scale_table(d["scale"])


def _screening(d: dict) -> tuple[str, list[str]]:
    from bench.report import screening_table

    return "Screening engine", screening_table(d["screening"])


def _job(d: dict) -> tuple[str, list[str]]:
    from bench.job import job_table

    return "The default job", job_table(d["job"])


def _coverage(d: dict) -> tuple[str, list[str]]:
    from bench.coverage import COVERAGE_TITLE, coverage_lines

    return COVERAGE_TITLE, coverage_lines(d)


def _aeossp(d: dict) -> tuple[str, list[str]]:
    from bench.aeossp import aeossp_table

    return "aeossp_standard training cases", aeossp_table(d)


def _stereo(d: dict) -> tuple[str, list[str]]:
    from bench.stereo import stereo_table

    return "stereo_imaging training cases", stereo_table(d)


def _bound(d: dict) -> tuple[str, list[str]]:
    from bench.bound import bound_table

    return "Bound: DP speed and strength", bound_table(d["bound"])


#: JSON file -> (markdown file, the function giving its title and lines).
RENDERERS = {
    "report.json": ("RESULTS.md", _report),
    "scale.json": ("SCALE.md", _scale),
    "screening.json": ("SCREENING.md", _screening),
    "job.json": ("JOB.md", _job),
    "aeossp.json": ("AEOSSP.md", _aeossp),
    "coverage.json": ("COVERAGE.md", _coverage),
    "bound.json": ("BOUND.md", _bound),
    "stereo.json": ("STEREO.md", _stereo),
}


def render_all(out: Path) -> list[Path]:
    """Rewrite the markdown of every result JSON in ``out``; the files written."""
    from bench.markdown import write_markdown

    written = []
    for name, (md, render) in RENDERERS.items():
        path = out / name
        if not path.is_file():
            continue
        title, lines = render(json.loads(path.read_text(encoding="utf-8")))
        write_markdown(out / md, title, lines)
        written.append(out / md)
    print("rendered " + ", ".join(str(p) for p in written))
    return written
