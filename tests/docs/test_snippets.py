"""The Python examples of ``README.md`` and ``docs/*.md`` run as written.

Every fenced ``python`` block runs; the blocks of one page run in order, in one
namespace of its own, with a working folder of its own: a temporary directory holding
links to the clone's ``scripts/``, ``bench/`` and ``jaxspline/`` (the examples use paths
relative to the repository root and write their outputs where they run). All pages run
in one fresh process (one JAX import and one set of compiled kernels for all of them),
the pages that leave JAX's float64 switch alone first, so each of them runs with JAX's
default as a reader's fresh session would. A block is
skipped only when an HTML comment ``<!-- skip-test: REASON -->`` stands right above its
fence (with a reason); the README's library examples are never skipped. Shell, TOML and
other blocks are not run. A failure names the page and the line of the block.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
FENCE = re.compile(r"^(`{3,}|~{3,})\s*([\w+-]*)")
SKIP = re.compile(r"^<!--\s*skip-test:\s*(?P<reason>.*?)\s*-->$")
LINKED = ("scripts", "bench", "jaxspline")
_TIMEOUT_S = 300

# runs each page's blocks in its folder and one namespace, each block compiled under
# "page:line"; a page's failure (its traceback) is recorded and the next page runs
DRIVER = """
import json, os, sys, traceback
cache = os.environ.get("JAXSPLINE_CACHE_DIR", "").strip()
if cache.lower() not in ("", "off", "0", "none"):  # the run's XLA cache (tests/conftest.py)
    import jax
    jax.config.update("jax_compilation_cache_dir", cache)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
pages = json.load(open(sys.argv[1], encoding="utf-8"))
result = {}
for page in pages:
    os.chdir(page["cwd"])
    ns = {"__name__": "__main__"}
    try:
        for b in page["blocks"]:
            print(f"--- {b['page']}:{b['line']}", flush=True)
            exec(compile(b["code"], f"{b['page']}:{b['line']}", "exec"), ns)
        result[page["page"]] = ""
    except BaseException:
        result[page["page"]] = traceback.format_exc()
json.dump(result, open(sys.argv[2], "w", encoding="utf-8"))
"""
X64_SWITCH = "jax_enable_x64"


def blocks_of(page: Path, root: Path = ROOT) -> list[dict]:
    """Fenced blocks of ``page``: language, first code line, code, skip reason or None."""
    lines = page.read_text(encoding="utf-8").splitlines()
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, lang = m.group(1), m.group(2).lower()
        prev = next((ln.strip() for ln in reversed(lines[:i]) if ln.strip()), "")
        skip = SKIP.match(prev)
        j = i + 1
        while j < len(lines) and not lines[j].startswith(fence):
            j += 1
        out.append(
            {
                "page": str(page.relative_to(root)),
                "line": i + 2,
                "lang": lang,
                "code": "\n".join(lines[i + 1 : j]) + "\n",
                "skip": skip.group("reason") if skip else None,
            }
        )
        i = j + 1
    return out


def _python(page: Path) -> list[dict]:
    return [b for b in blocks_of(page) if b["lang"] in ("python", "py")]


RUN = [p for p in PAGES if any(b["skip"] is None for b in _python(p))]


def test_skipped_blocks_give_a_reason_and_library_examples_run():
    blocks = [b for p in PAGES for b in _python(p)]
    assert blocks, "no python blocks found"
    assert all(b["skip"] != "" for b in blocks), "a skip-test comment needs a reason"
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index("## Library example") : readme.index("## Scenario files")]
    lib = [b for b in _python(ROOT / "README.md") if f"```python\n{b['code']}" in section]
    assert lib and all(b["skip"] is None for b in lib)


def test_block_parser_reads_fences_and_skip_markers(tmp_path):
    page = tmp_path / "p.md"
    page.write_text(
        "# t\n\n```python\nx = 1\n```\n\n<!-- skip-test: slow -->\n```python\ny = 2\n```\n"
        "\n```bash\nls\n```\n````python\nz = '```'\n````\n",
        encoding="utf-8",
    )
    got = [(b["lang"], b["line"], b["code"], b["skip"]) for b in blocks_of(page, tmp_path)]
    assert got == [
        ("python", 4, "x = 1\n", None),
        ("python", 9, "y = 2\n", "slow"),
        ("bash", 13, "ls\n", None),
        ("python", 16, "z = '```'\n", None),
    ]


@pytest.fixture(scope="module")
def page_runs(tmp_path_factory):
    """Run every page's blocks in one process: {page: traceback or ""}, the process's output."""
    tmp = tmp_path_factory.mktemp("pages")
    order = sorted(RUN, key=lambda p: X64_SWITCH in p.read_text(encoding="utf-8"))
    pages = []
    for k, page in enumerate(order):
        work = tmp / f"work{k}"
        work.mkdir()
        for name in LINKED:
            (work / name).symlink_to(ROOT / name, target_is_directory=True)
        blocks = [b for b in _python(page) if b["skip"] is None]
        pages.append({"page": str(page.relative_to(ROOT)), "cwd": str(work), "blocks": blocks})
    spec, result = tmp / "pages.json", tmp / "result.json"
    spec.write_text(json.dumps(pages), encoding="utf-8")
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
    env = dict(os.environ, PYTHONPATH=path, MPLBACKEND="Agg")
    run = subprocess.run(
        [sys.executable, "-c", DRIVER, str(spec), str(result)],
        cwd=tmp,
        env=env,
        capture_output=True,
        text=True,
        timeout=_TIMEOUT_S,
    )
    output = f"{run.stdout[-4000:]}\n{run.stderr[-4000:]}"
    assert run.returncode == 0 and result.exists(), output
    return json.loads(result.read_text(encoding="utf-8")), output


@pytest.mark.parametrize("page", RUN, ids=[str(p.relative_to(ROOT)) for p in RUN])
def test_python_blocks_run(page, page_runs):
    failures, output = page_runs
    name = str(page.relative_to(ROOT))
    assert name in failures, output
    assert failures[name] == "", failures[name]
