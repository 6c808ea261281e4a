"""``jaxspline stereo check``: exit codes (0 valid, 1 invalid, 2 bad input) and one-line
errors naming the file and the field; the checker's modules stay independent."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from _ref_stereo import DATA, EXAMPLE

from jaxspline.cli import main

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")
CASE = str(DATA / "case_0001")


def _write(tmp_path, name, data):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return str(path)


def test_check_exit_codes_and_report(tmp_path, capsys):
    out = tmp_path / "report.json"
    assert main(["stereo", "check", CASE, str(EXAMPLE), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    for key in ("valid: yes", "coverage_ratio: 0.007634", "normalized_quality", "rugged_060"):
        assert key in text
    report = json.loads(out.read_text())
    assert report["valid"] is True and report["num_covered"] == 1
    actions = json.loads(EXAMPLE.read_text())["actions"]
    actions[1]["start_time"], actions[1]["end_time"] = (
        actions[0]["start_time"],
        actions[0]["end_time"],
    )
    bad = _write(tmp_path, "bad.json", {"actions": actions})
    assert main(["stereo", "check", CASE, bad]) == 1
    assert "overlap actions[1]" in capsys.readouterr().out


@pytest.mark.parametrize(
    "content, message",
    [
        ("{", "bad.json: not valid JSON"),
        (
            {"actions": [{"type": "observation", "satellite_id": "s"}]},
            "bad.json: actions[0].target_id: missing field",
        ),
        (
            {
                "actions": [
                    {
                        "type": "observation",
                        "satellite_id": "s",
                        "target_id": "t",
                        "start_time": "2026-04-21T03:52:18",
                        "end_time": "x",
                    }
                ]
            },
            "bad.json: actions[0].start_time: needs Z",
        ),
        ({"plan": []}, "bad.json: actions: expected a list, got NoneType"),
    ],
)
def test_a_malformed_solution_is_one_line_and_exit_2(tmp_path, capsys, content, message):
    bad = _write(tmp_path, "bad.json", content)
    assert main(["stereo", "check", CASE, bad]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err


def test_bad_paths_are_exit_2(tmp_path, capsys):
    assert main(["stereo", "check", str(tmp_path / "nocase"), str(EXAMPLE)]) == 2
    assert "CASE_DIR: not found" in capsys.readouterr().err
    assert main(["stereo", "check", CASE, str(tmp_path / "none.json")]) == 2
    assert "SOLUTION: not found" in capsys.readouterr().err
    assert (
        main(["stereo", "check", CASE, str(EXAMPLE), "--json", str(tmp_path / "no" / "r.json")])
        == 2
    )
    assert "--json" in capsys.readouterr().err


def test_a_bad_case_field_is_named(tmp_path, capsys):
    import shutil

    case = tmp_path / "case"
    shutil.copytree(DATA / "case_0001", case)
    text = (case / "targets.yaml").read_text().replace("scene_type: rugged", "scene_type: rocky", 1)
    (case / "targets.yaml").write_text(text)
    assert main(["stereo", "check", str(case), str(EXAMPLE)]) == 2
    assert "targets.yaml: [" in capsys.readouterr().err


def test_the_command_runs_as_a_process():
    run = subprocess.run(
        [sys.executable, "-m", "jaxspline.cli", "stereo", "check", CASE, str(EXAMPLE)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert "valid: yes" in run.stdout


# ----------------------------------------------------------------------------- layout

CHECKER = ("check", "check_geometry", "check_products")
ALLOWED = {
    "jaxspline.stereo.case",
    "jaxspline.stereo.check_geometry",
    "jaxspline.stereo.check_products",
    "jaxspline.aeossp.check_frames",
}


@pytest.mark.parametrize("name", CHECKER)
def test_checker_is_independent(name):
    """The checker shares no code with a solver: the case reader, its own modules and the
    aeossp checker's frame models only (lazy imports included)."""
    import ast
    from pathlib import Path

    import jaxspline.stereo as pkg

    path = Path(pkg.__file__).parent / f"{name}.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("jaxspline"):
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("jaxspline"))
    assert found <= ALLOWED, found - ALLOWED


@pytest.mark.parametrize(
    "name", ("case", "case_fields", "check", "check_geometry", "check_products", "bound", "cli")
)
def test_public_names_are_documented_and_listed(name):
    import importlib
    import inspect

    mod = importlib.import_module(f"jaxspline.stereo.{name}")
    assert mod.__doc__
    for attr in mod.__all__:
        obj = getattr(mod, attr)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            assert obj.__doc__, f"{name}.{attr} has no docstring"
    own = [
        a
        for a, o in vars(mod).items()
        if not a.startswith("_")
        and (inspect.isfunction(o) or inspect.isclass(o))
        and o.__module__ == mod.__name__
    ]
    assert set(own) <= set(mod.__all__), set(own) - set(mod.__all__)
