"""The documentation site builds in strict mode, and its API reference is complete.

* ``mkdocs build --strict`` (the command of ``docs/development.md``) into a temporary
  folder: exit 0 and no ``WARNING`` line, so a reference to a missing name, a broken
  link or anchor, or a docstring entry that names no argument fails the suite.
* Every name of ``jaxspline.__all__`` appears in ``docs/api/*.md`` exactly once, as
  ``::: jaxspline.NAME`` (through the top-level namespace, so moving a module never
  breaks the reference), and the reference documents no other name.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

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


NAMESPACES = (
    "jaxspline",
    *(
        f"jaxspline.{n}"
        for n in (
            "kernels",
            "base",
            "geometry",
            "screen",
            "readers",
            "search",
            "sequences",
            "planner",
            "products",
        )
    ),
)


def _public() -> dict[str, str]:
    """Every explicitly re-exported name (``from x import f as f``, modules aside) of the
    namespaces: its public path -> the path where it is defined."""
    out = {}
    for ns in NAMESPACES:
        init = Path(importlib.import_module(ns).__file__)
        for node in ast.parse(init.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.ImportFrom):
                for a in node.names:
                    obj = getattr(importlib.import_module(node.module), a.name)
                    if a.asname == a.name and not inspect.ismodule(obj):
                        out[f"{ns}.{a.name}"] = f"{node.module}.{a.name}"
    return out


def test_every_public_name_is_in_the_api_reference():
    """Each public object is documented once, under one of the names users reach it by."""
    documented = _documented()
    public = _public()
    objects = public
    by_source = {}
    for path, src in objects.items():
        by_source.setdefault(src, set()).add(path)
    missing = sorted(src for src, paths in by_source.items() if not paths & set(documented))
    assert missing == [], f"public names missing from docs/api/*.md: {missing}"
    extra = sorted(set(documented) - set(objects))
    assert extra == [], f"docs/api/*.md documents names that are not re-exported: {extra}"
    repeated = sorted({n for n in documented if documented.count(n) > 1})
    assert repeated == [], f"documented more than once: {repeated}"
    twice = sorted(src for src, paths in by_source.items() if len(paths & set(documented)) > 1)
    assert twice == [], f"documented under two names: {twice}"
