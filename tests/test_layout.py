"""The import graph points down only: kernels <- geometry <- engine <- product.

Parses every module of the package with ``ast`` (no import side effects): a
module of the kernels imports nothing above the kernels, geometry imports the
kernels at most, the engine never imports the product (top-level modules,
``aeossp``). The aeossp checker (``check``, ``check_frames``) imports nothing of
the package but the case reader: it shares no code with what it checks.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import jaxspline

ROOT = Path(jaxspline.__file__).parent
RANK = {"kernels": 0, "geometry": 1, "engine": 2}  # anything else: product (3)


def _layer(module: str) -> int:
    parts = module.split(".")
    return RANK.get(parts[1], 3) if len(parts) > 1 else 3


def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT.parent).with_suffix("")
        parts = list(rel.parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        yield ".".join(parts), path, is_pkg


def imports_of(module: str, path: Path, is_pkg: bool) -> set[str]:
    """Package modules imported by ``module`` (absolute and relative, any depth)."""
    package = module if is_pkg else module.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.add(target)
            found.update(f"{target}.{a.name}" for a in node.names)  # `from pkg import mod`
    known = {m for m, _, _ in _modules()}
    return {m for m in found if m in known and m != module}


MODULES = list(_modules())


def test_every_layer_is_a_folder():
    assert {"kernels", "geometry", "engine"} <= {p.name for p in ROOT.iterdir() if p.is_dir()}


@pytest.mark.parametrize("module,path,is_pkg", MODULES, ids=[m for m, _, _ in MODULES])
def test_imports_point_down(module, path, is_pkg):
    layer = _layer(module)
    if layer == 3:
        return  # the product may import anything
    up = sorted(m for m in imports_of(module, path, is_pkg) if _layer(m) > layer)
    assert not up, f"{module} (layer {layer}) imports from above: {up}"


@pytest.mark.parametrize("name", ["check", "check_frames"])
def test_aeossp_checker_is_independent(name):
    path = ROOT / "aeossp" / f"{name}.py"
    deps = imports_of(f"jaxspline.aeossp.{name}", path, False)
    allowed = {"jaxspline.aeossp", "jaxspline.aeossp.case", "jaxspline.aeossp.check_frames"}
    assert deps <= allowed, deps


def test_the_rule_can_fail(tmp_path):
    """The parser sees an upward import (guards the test against a vacuous pass)."""
    bad = tmp_path / "reach.py"
    bad.write_text("from jaxspline.screen.pairs import screen_pairs\nfrom .. import scenario\n")
    deps = imports_of("jaxspline.kernels.reach", bad, False)
    assert "jaxspline.screen.pairs" in deps
    assert "jaxspline.io.scenario" in deps
    assert any(_layer(m) > 0 for m in deps)
