"""The documentation site builds in strict mode, and its API reference is complete.

* ``mkdocs build --strict`` (the command of ``docs/development.md``) into a temporary
  folder: exit 0 and no ``WARNING`` line, so a reference to a missing name, a broken
  link or anchor, or a docstring entry that names no argument fails the suite.
* Every name of ``jaxspline.__all__`` appears in ``docs/api/*.md`` exactly once, as
  ``::: jaxspline.NAME`` (through the top-level namespace, so moving a module never
  breaks the reference), and the reference documents no other name.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import jaxspline

ROOT = Path(__file__).resolve().parents[2]
API = ROOT / "docs" / "api"
DIRECTIVE = re.compile(r"^::: (\S+)\s*$", re.M)
_TIMEOUT_S = 300


def _env() -> dict:
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
    return dict(os.environ, PYTHONPATH=path)


def test_docs_build_strict_without_warnings(tmp_path):
    site = tmp_path / "site"
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)]
    run = subprocess.run(
        cmd, cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=_TIMEOUT_S
    )
    log = run.stdout + run.stderr
    warnings = [line for line in log.splitlines() if "WARNING" in line]
    assert run.returncode == 0, log
    assert warnings == [], "\n".join(warnings)
    for page in ("index.html", "api/kernels/index.html", "api/planning/index.html"):
        assert (site / page).is_file(), page
    html = (site / "api" / "planning" / "index.html").read_text(encoding="utf-8")
    assert 'id="jaxspline.plan"' in html  # the reference is rendered, not just listed


def _documented() -> list[str]:
    names = []
    for page in sorted(API.glob("*.md")):
        names += DIRECTIVE.findall(page.read_text(encoding="utf-8"))
    return names


def test_every_public_name_is_in_the_api_reference():
    documented = _documented()
    public = {f"jaxspline.{n}" for n in jaxspline.__all__}
    missing = sorted(public - set(documented))
    assert missing == [], f"public names missing from docs/api/*.md: {missing}"
    extra = sorted(set(documented) - public)
    assert extra == [], f"docs/api/*.md documents names outside jaxspline.__all__: {extra}"
    repeated = sorted({n for n in documented if documented.count(n) > 1})
    assert repeated == [], f"documented more than once: {repeated}"
