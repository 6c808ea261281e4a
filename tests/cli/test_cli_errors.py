"""Every failure of the ``jaxspline`` command: one line naming its cause, a documented exit code.

* every flag of ``plan``, ``bound``, ``view``, ``aeossp solve|check`` is checked before
  any work and named in the message (exit 2, within seconds, nothing written);
* an unexpected error is one line with the exception's name and a pointer to
  ``--debug`` (exit 70); ``--debug`` prints the traceback; no other output has one;
* bad files: a directory as the scenario, TOML nested thousands deep or a number of
  thousands of digits, a malformed ``plan.json`` for ``view`` (exit 2);
* writing: a failure while writing the set is one line (exit 4), the previous set is
  kept; a signal while writing is recorded in ``plan.json``;
* the time limit: a scenario that cannot fit a tiny limit stops before the search
  with exit 3, an estimate and the remedy, and writes nothing;
* the memory: a scenario whose options would take terabytes (steps of 0.01 s, both in
  their ranges) stops before it allocates them, with exit 3, the estimate and the remedy.
"""

from __future__ import annotations

import json
import math
import os
import signal
import time
import types

import pytest

from jaxspline.cli import (
    EXIT_BAD_INPUT,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_TIME_LIMIT,
    EXIT_WRITE,
    build_parser,
    main,
)

SCENARIO = """
[scenario]
epoch = "2026-04-14T00:00:00Z"
duration_s = 600.0
[[satellites]]
altitude_km = 600.0
[[targets]]
lat_deg = 46.0
lon_deg = 15.0
"""


@pytest.fixture
def scen(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    return path


def _run(capsys, argv):
    capsys.readouterr()
    t0 = time.monotonic()
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.err, time.monotonic() - t0


# (extra arguments of the command, the flag its message must name)
PLAN_FLAGS = [
    (["--time-limit", "0"], "--time-limit: must be > 0"),
    (["--time-limit", "-3"], "--time-limit: must be > 0"),
    (["--time-limit", "nan"], "--time-limit: must be a finite"),
    (["--time-limit", "inf"], "--time-limit: must be a finite"),
    (["--time-limit", "1e12"], "--time-limit: must be <="),
    (["--seed", "-1"], "--seed: must be within"),
    (["--seed", str(2**40)], "--seed: must be within"),
    (["--max-iters", "0"], "--max-iters: must be within"),
    (["--certify", "-1"], "--certify: must be >= 0"),
    (["--certify", "nan"], "--certify: must be a finite"),
    (["--aem-step", "0"], "--aem-step: must be > 0, got 0"),
    (["--aem-step", "1e-9"], "--aem-step: must be >="),
    (["--aem-step", "1e9"], "--aem-step: must be <="),
    (["--aem-step", "0.01"], "--aem-step: 0.01 s over the 600 s horizon"),
    (
        ["--aem-step", "86400"],
        "--aem-step: 86400 s is longer than the 600 s horizon; use at most 600",
    ),
    (["--max-memory", "0"], "--max-memory: must be a finite number > 0"),
    (["--max-memory", "nan"], "--max-memory: must be a finite number > 0"),
    (["--max-memory", "0.01"], "--max-memory: must be within [0.25, 65536] GB"),
    (["-o", ""], "-o/--outdir: must not be empty"),
    (["-o", " "], "-o/--outdir: must not be empty"),
]


@pytest.mark.parametrize(("extra", "msg"), PLAN_FLAGS, ids=[" ".join(e) for e, _ in PLAN_FLAGS])
def test_plan_flags_are_checked_before_any_work(tmp_path, scen, capsys, extra, msg):
    out = tmp_path / "out"
    argv = ["plan", str(scen), "-o", str(out), "--quiet", *extra]
    code, err, seconds = _run(capsys, argv)
    assert code == EXIT_BAD_INPUT, err
    assert err.startswith("jaxspline: error: ") and msg in err, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists() and sorted(os.listdir(tmp_path)) == ["s.toml"]
    assert seconds < 10.0  # nothing planned (typically well under a second)


def test_plan_refuses_a_directory_as_scenario_and_the_working_directory(
    tmp_path, capsys, monkeypatch
):
    code, err, _ = _run(capsys, ["plan", str(tmp_path), "-o", str(tmp_path / "o")])
    assert code == EXIT_BAD_INPUT and "is a directory" in err, err
    monkeypatch.chdir(tmp_path)
    code, err, _ = _run(capsys, ["plan", "-o", "."])
    assert code == EXIT_BAD_INPUT and "working directory" in err, err


BOUND_FLAGS = [
    (["--time-limit", "0"], "--time-limit: must be > 0"),
    (["--max-iters", "0"], "--max-iters: must be within"),
    (["--target", "-1"], "--target: must be a finite number > 0"),
    (["--json", ""], "--json: must not be empty"),
    (["--plan", "PLACEHOLDER_DIR"], "--plan: "),
    (["--plan", "p.json", "--search-time", "0"], "--search-time: must be > 0"),
    (["--plan", "p.json", "--search-iters", "0"], "--search-iters: must be within"),
    (["--search-time", "5"], "--search-time / --search-iters: only with --plan"),
    (["--num-processes", "0"], "--num-processes: must be within"),
    (["--num-processes", "2"], "--num-processes: more than one process needs --coordinator"),
    (["--process-id", "3"], "--process-id: must be within [0, 0]"),
    (["--coordinator", "nohostport"], "--coordinator: must be HOST:PORT"),
    (["--coordinator", "h:70000"], "--coordinator: must be HOST:PORT"),
    (["--json", "a.json", "--plan", "a.json"], "--json and --plan: must be two files"),
]


@pytest.mark.parametrize(("extra", "msg"), BOUND_FLAGS, ids=[" ".join(e) for e, _ in BOUND_FLAGS])
def test_bound_flags_are_checked_before_any_work(tmp_path, scen, capsys, extra, msg):
    extra = [str(tmp_path) if e == "PLACEHOLDER_DIR" else e for e in extra]
    code, err, seconds = _run(capsys, ["bound", str(scen), *extra])
    assert code == EXIT_BAD_INPUT and msg in err, err
    assert "Traceback" not in err and seconds < 10.0


def test_view_and_aeossp_flags(tmp_path, capsys):
    plan = tmp_path / "plan.json"
    plan.write_text("{}")
    cases = [
        (["view", str(plan), "-o", ""], "-o/--output: must not be empty"),
        (["view", str(plan), "-o", str(tmp_path)], "is a directory"),
        (["view", str(tmp_path)], "PLAN: "),
        (["aeossp", "solve", str(tmp_path / "none"), "-o", "s.json"], "CASE_DIR: not found"),
        (["aeossp", "solve", str(tmp_path), "-o", ""], "-o/--output: must not be empty"),
        (["aeossp", "solve", str(tmp_path), "-o", "s.json", "--time-limit", "0"], "--time-limit"),
        (["aeossp", "solve", str(tmp_path), "-o", "s.json", "--seed", "-2"], "--seed"),
        (["aeossp", "check", str(plan), str(plan)], "CASE_DIR: "),
        (["aeossp", "check", str(tmp_path), str(tmp_path / "x")], "SOLUTION: not found"),
    ]
    for argv, msg in cases:
        code, err, _ = _run(capsys, argv)
        assert code == EXIT_BAD_INPUT and msg in err, (argv, err)
        assert "Traceback" not in err


def test_every_subcommand_takes_debug():
    parser = build_parser()
    for argv in (["--debug", "view", "p.json"], ["view", "p.json", "--debug"],
                 ["aeossp", "check", "c", "s", "--debug"], ["bound", "--debug"]):  # fmt: skip
        assert parser.parse_args(argv).debug is True
    assert parser.parse_args(["view", "p.json"]).debug is False


UNPARSABLE = [  # (command line, the one line argparse's error becomes)
    ("plan --time-limit abc", "jaxspline plan: error: --time-limit: 'abc' is not a number"),
    ("plan --max-iters 1.5", "jaxspline plan: error: --max-iters: '1.5' is not an integer"),
    ("plan --aem-step", "jaxspline plan: error: --aem-step: expected one argument"),
    ("bound --search-iters 2e3", "jaxspline bound: error: --search-iters: '2e3' is not an integer"),
    ("bound --target x", "jaxspline bound: error: --target: 'x' is not a number"),
    ("view p.json -o", "jaxspline view: error: -o/--output: expected one argument"),
    (
        "aeossp solve c -o s.json --time-limit 1m",
        "jaxspline aeossp solve: error: --time-limit: '1m' is not a number",
    ),
    (
        "aeossp check",
        "jaxspline aeossp check: error: the following arguments are required: case_dir, solution",
    ),
    (
        "regional solve c -o s.json --seed -",
        "jaxspline regional solve: error: --seed: '-' is not an integer",
    ),
    ("plan --bogus", "jaxspline: error: unrecognized arguments: --bogus"),
]


@pytest.mark.parametrize(("argv", "line"), UNPARSABLE, ids=[a for a, _ in UNPARSABLE])
def test_a_flag_argparse_cannot_parse_is_one_line_with_exit_2(capsys, argv, line):
    with pytest.raises(SystemExit) as exc:
        main(argv.split())
    assert exc.value.code == EXIT_BAD_INPUT
    assert capsys.readouterr().err == line + "\n"


def test_an_unexpected_error_is_one_line_and_debug_shows_the_traceback(monkeypatch, capsys):
    def boom(args):
        raise KeyError("surprise")

    def patched(command=None):
        parser = build_parser(command)
        sub = next(a for a in parser._actions if isinstance(a.choices, dict))
        sub.choices["view"].set_defaults(func=boom)
        return parser

    monkeypatch.setattr("jaxspline.cli.build_parser", patched)
    code, err, _ = _run(capsys, ["view", "plan.json"])
    assert code == EXIT_INTERNAL
    assert err.startswith("jaxspline: internal error: KeyError: 'surprise'")
    assert "--debug" in err and "Traceback" not in err and err.count("\n") == 1
    code, err, _ = _run(capsys, ["--debug", "view", "plan.json"])
    assert code == EXIT_INTERNAL and "Traceback (most recent call last)" in err


def _obs(start, end):
    return {"satellite": "s", "target": "t", "start_s": start, "end_s": end}


def test_deep_toml_and_bad_plan_json_are_named(tmp_path, capsys):
    deep = tmp_path / "deep.toml"
    deep.write_text("x = " + "[" * 3000 + "]" * 3000 + "\n")
    code, err, _ = _run(capsys, ["plan", str(deep), "-o", str(tmp_path / "o")])
    assert code == EXIT_BAD_INPUT and "deep.toml: invalid TOML" in err, err
    # an integer of 5,000 digits: Python's int() refuses it inside the TOML / JSON parser
    digits = "9" * 5000
    deep.write_text(f"[scenario]\nduration_s = {digits}\n")
    code, err, _ = _run(capsys, ["plan", str(deep), "-o", str(tmp_path / "o")])
    assert code == EXIT_BAD_INPUT and "deep.toml: invalid TOML" in err, err
    (tmp_path / "long.json").write_text(f'{{"summary": {digits}}}')
    code, err, _ = _run(capsys, ["view", str(tmp_path / "long.json"), "--force"])
    assert code == EXIT_BAD_INPUT and "long.json: not JSON" in err, err
    for doc, field in [
        ({"summary": {}, "report": {}, "observations": 3}, "observations: must be a list"),
        ({"summary": {}, "report": {}, "observations": [], "view": "x"}, "view: must be"),
        ({"summary": None, "report": {}, "observations": []}, "summary: must be an object"),
        (
            {"summary": {}, "report": {}, "observations": [], "view": {"targets": None}},
            "view.targets: must be an object",
        ),  # fmt: skip
        ([1, 2], "the document: must be an object"),
        # numbers a plan never writes: NaN (plan.json writes null), times past any horizon
        ({"summary": {"value": math.nan}, "report": {}, "observations": []}, "summary.value"),
        ({"summary": {}, "report": {}, "observations": [_obs(1e308, 1e308)]}, "observations[0]"),
        ({"summary": {}, "report": {}, "observations": [_obs(3000.0, 10.0)]}, "start_s <= end_s"),
        ({"summary": {}, "report": {}, "observations": [_obs(-5e6, 10.0)]}, "observations[0]"),
    ]:
        plan = tmp_path / "plan.json"
        plan.write_text(json.dumps(doc))
        code, err, _ = _run(capsys, ["view", str(plan), "--force"])
        assert code == EXIT_BAD_INPUT and field in err, (doc, err)
        assert "Traceback" not in err


def test_the_time_limit_stops_a_scenario_too_big_for_it(tmp_path, capsys):
    big = SCENARIO.replace(
        "[[targets]]\nlat_deg = 46.0\nlon_deg = 15.0\n",
        "[random_targets]\ncount = 20000\n",
    )
    scen = tmp_path / "big.toml"
    scen.write_text(big, encoding="utf-8")
    out = tmp_path / "out"
    argv = ["plan", str(scen), "-o", str(out), "--time-limit", "0.05", "--quiet"]
    code, err, seconds = _run(capsys, argv)
    assert code == EXIT_TIME_LIMIT, err
    assert err.startswith("jaxspline: time limit: time limit of 0.05 s reached before the search")
    assert "give a time limit of" in err and "--time-limit" in err, err
    assert not out.exists() and sorted(os.listdir(tmp_path)) == ["big.toml"]
    assert seconds < 60.0


@pytest.mark.parametrize("command", ["plan", "bound"])
def test_a_scenario_too_big_for_the_memory_stops_before_it_allocates(tmp_path, capsys, command):
    big = SCENARIO.replace("duration_s = 600.0", "duration_s = 7200.0").replace(
        "[[targets]]\nlat_deg = 46.0\nlon_deg = 15.0\n",
        "[random_targets]\ncount = 40\nseed = 3\nlat_deg = [40.0, 50.0]\n"
        "[planner]\ntime_step_s = 0.01\ngeometry_step_s = 0.01\n",
    )
    scen = tmp_path / "big.toml"
    scen.write_text(big, encoding="utf-8")
    out = tmp_path / "out"
    argv = [command, str(scen), "--time-limit", "60"]
    argv += ["-o", str(out), "--quiet"] if command == "plan" else []
    code, err, seconds = _run(capsys, argv)
    assert code == EXIT_TIME_LIMIT, err
    assert err.startswith("jaxspline: memory limit: stage 'options' would need ~"), err
    assert "planner.time_step_s = 0.01, planner.geometry_step_s = 0.01" in err, err
    assert "GB are available" in err and "raise planner.time_step_s to >= " in err, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists() and sorted(os.listdir(tmp_path)) == ["big.toml"]
    assert seconds < 30.0  # orbits and windows only (a few seconds)


@pytest.mark.parametrize(
    ("extra", "msg"),
    [
        (["--time-limit", "0.05"], "time limit: time limit of 0.05 s reached while reading"),
        (["--max-memory", "0.25"], "memory limit: stage 'loading' would need ~"),
    ],
    ids=["time", "memory"],
)
def test_a_long_targets_csv_is_stopped_while_it_is_read(tmp_path, capsys, extra, msg):
    rows = "".join(f"t{i},{40 + i % 10},{10 + i % 7},1\n" for i in range(25_000))
    (tmp_path / "t.csv").write_text("name,lat_deg,lon_deg,priority\n" + rows, encoding="utf-8")
    scen = tmp_path / "csv.toml"
    head = 'targets_csv = "t.csv"\n'
    scen.write_text(head + SCENARIO.split("[[targets]]")[0], encoding="utf-8")
    out = tmp_path / "out"
    code, err, seconds = _run(capsys, ["plan", str(scen), "-o", str(out), "--quiet", *extra])
    assert code == EXIT_TIME_LIMIT, err
    assert err.startswith(f"jaxspline: {msg}") and "% of t.csv read" in err, err
    assert err.count("\n") == 1 and not out.exists()
    assert seconds < 20.0  # stopped at its first or second block of 10,000 rows


def test_stage_deadline_estimate_and_compile_time(monkeypatch):
    from jaxspline.planner import deadline as dl

    clock = {"now": 100.0, "compiled": 0.0}
    monkeypatch.setattr(dl.time, "monotonic", lambda: clock["now"])
    monkeypatch.setattr(dl, "compile_seconds", lambda: clock["compiled"])
    d = dl.StageDeadline(100.0, 10.0, "5 targets")
    clock["now"] = 109.0
    d.check("options", 0.5, 104.0)  # within the limit
    clock.update(now=125.0, compiled=20.0)
    d.check("options", 0.5, 104.0)  # 25 s, 20 s of it compiling: 5 s of work
    clock["compiled"] = 5.0
    with pytest.raises(dl.TimeLimitError) as exc:
        d.check("options", 0.25, 105.0, "700 options")
    e = exc.value
    assert (e.stage, e.elapsed) == ("options", 25.0)
    assert e.estimate == pytest.approx(5.0 + 20.0 / 0.25 - 5.0)  # 80 s
    assert "give a time limit of 180 s" in str(e) and "700 options; 5 targets" in str(e)
    assert dl.suggested_limit(4.0) == 10 and dl.suggested_limit(1e6) == 2_000_000


def test_a_stage_stopped_before_its_first_share_estimates_its_work(monkeypatch):
    from jaxspline.planner import deadline as dl

    clock = {"now": 100.0}
    monkeypatch.setattr(dl.time, "monotonic", lambda: clock["now"])
    monkeypatch.setattr(dl, "compile_seconds", lambda: 0.0)
    d = dl.StageDeadline(100.0, 60.0, "50000 targets")
    monkeypatch.setattr(d, "pace", lambda: 2.0)
    clock["now"] = 161.0  # screening started at 150 s and is still at its first block
    with pytest.raises(dl.TimeLimitError) as exc:
        d.check("screening", 0.0, 150.0, "", lambda: (918_734, "options"))
    e, msg = exc.value, str(exc.value)
    each = dl.WORK_SECONDS["screening"]
    assert e.estimate == pytest.approx(50.0 + 918_734 * each * 2.0)  # 50 s + 184 s
    assert "0 % through it of 918,734 options; 50000 targets)" in msg, msg
    assert "need ~234 s or more (its work: 918,734 options at ~0.1 ms of CPU each" in msg, msg
    assert "give a time limit of 600 s or more" in msg, msg


def test_the_estimate_covers_every_stage_still_to_come(monkeypatch):
    """Given the run's size, the estimate adds the later stages' work models, the repair
    and the outputs to the running stage's rest (the numbers below by hand)."""
    from jaxspline.planner import deadline as dl

    clock = {"now": 100.0}
    monkeypatch.setattr(dl.time, "monotonic", lambda: clock["now"])
    monkeypatch.setattr(dl, "compile_seconds", lambda: 0.0)
    size = dl.RunSize(targets=50_000, satellites=12, duration_s=43_200.0, time_step_s=10.0)
    d = dl.StageDeadline(100.0, 5.0, "50000 targets", after_s=10.0, size=size)
    monkeypatch.setattr(d, "pace", lambda: 1.0)
    clock["now"] = 106.0  # the windows started at 104 s, 25 % done
    with pytest.raises(dl.TimeLimitError) as exc:
        d.check("windows", 0.25, 104.0, "", lambda: (600_000, "target-satellite pairs"))
    # windows: 6 s more (2 s for 25 %); options: 2 s + 600,000 pairs x 4,320 steps x 7e-4
    # candidates x 2e-5 s = 38.288 s; screening of as many options: 2 s + 1,814,400 x 1e-4 s
    # + 4 x 150 s x 1,814,400^2 / (12 x 43,200 s) pairs x 1.5e-7 s = 754.976 s; repair:
    # 6 s + min(25,000, 1,814,400, 17,280) observations x 3e-3 s = 57.84 s; outputs 10 s
    later = 38.288 + 754.976 + 57.84 + 10.0
    assert exc.value.estimate == pytest.approx(6.0 + 6.0 + later)
    msg = str(exc.value)
    assert "the whole run needs ~873 s or more (~12 s until the search, then ~861 s" in msg, msg
    assert "give a time limit of 1800 s or more" in msg, msg
    # the options' own count, once known, replaces the prior (here 7x fewer candidates)
    clock["now"] = 120.0
    with pytest.raises(dl.TimeLimitError) as exc:
        d.check("options", 0.0, 110.0, "", lambda: (259_200, "candidate options"))
    options = 2.0 + 259_200 * 2e-5  # 7.184 s, 10 s of it spent
    screening = 2.0 + 259_200 * 1e-4 + 600.0 * 259_200**2 / (12 * 43_200) * 1.5e-7
    repair = 6.0 + 17_280 * 3e-3
    assert exc.value.estimate == pytest.approx(20.0 + screening + repair + 10.0)
    assert options < 10.0  # the running stage is past its model: none of it left


def test_the_start_up_handlers_belong_to_the_command_only():
    from jaxspline.cli.startup import runs_the_command

    assert runs_the_command(["python", "-m", "jaxspline.cli", "plan"])
    assert runs_the_command(["python3", "-m", "jaxspline.aeossp", "solve"])
    assert runs_the_command(["/usr/bin/python3", "/venv/bin/jaxspline", "plan"])
    assert not runs_the_command(["python", "-m", "pytest", "tests"])
    assert not runs_the_command(["python", "script.py", "-m", "jaxspline"])
    assert not runs_the_command(["python", "-c", "import jaxspline"])


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_a_signal_while_the_command_imports_is_one_line_and_exit_130(sig):
    import subprocess
    import sys

    # the command's process, stopped by a signal as soon as `import jaxspline` is done
    # (the imports take 2-8 s before main() installs its own handlers)
    code = (
        "import sys, os, signal, time; sys.orig_argv[1:] = ['-m', 'jaxspline.cli', 'plan']; "
        "signal.signal(signal.SIGINT, signal.default_int_handler); "  # as a shell starts it
        f"import jaxspline; os.kill(os.getpid(), signal.{sig}); time.sleep(30); print('alive')"
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    p = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env
    )
    assert p.returncode == EXIT_INTERRUPTED, (p.returncode, p.stderr)
    assert p.stderr == f"jaxspline: interrupted ({sig}) while starting: nothing was done\n"
    assert p.stdout == ""


class _FakeResult:
    """Enough of a PlanResult for the write phase: a report and plan.json."""

    def __init__(self):
        self.report = {"valid": True}

    def to_json(self, path, *, force=False, extra=None):
        doc = {"report": self.report, **(extra or {})}
        path.write_text(json.dumps(doc), encoding="utf-8")


def test_a_signal_while_writing_is_recorded_in_plan_json(tmp_path, monkeypatch):
    from jaxspline.cli import plan as plan_cli
    from jaxspline.products import outputs
    from jaxspline.products.outputs import OutputSet

    def write(result, folder, **kw):
        result.to_json(folder / "plan.json", extra={"view": {"v": 1}})
        os.kill(os.getpid(), signal.SIGINT)  # held by the write phase until the set is whole
        (folder / "plan.csv").write_text("rows")

    monkeypatch.setattr(outputs, "write_plan_outputs", write)
    result = _FakeResult()
    with OutputSet(tmp_path / "out") as s:
        plan_cli._write(result, s, plots=False, aem=False, aem_step=10.0, html=False)
    doc = json.loads((tmp_path / "out" / "plan.json").read_text())
    assert doc["report"]["interrupted"] == "SIGINT" and doc["view"] == {"v": 1}
    assert sorted(os.listdir(tmp_path / "out")) == ["plan.csv", "plan.json"]


def test_a_write_error_is_one_line_with_exit_4_and_keeps_the_previous_set(
    tmp_path, monkeypatch, capsys
):
    from jaxspline.cli import plan as plan_cli
    from jaxspline.products import outputs

    out = tmp_path / "out"
    out.mkdir()
    (out / "plan.json").write_text("previous")
    fake = types.SimpleNamespace(report={"valid": True}, timings={})

    def fake_plan(*args, **kw):
        return fake

    def write(result, folder, **kw):
        (folder / "plan.json").write_text("half")
        raise outputs.OutputError("cannot write the outputs: No space left on device")

    monkeypatch.setattr(plan_cli, "_plan", fake_plan)
    monkeypatch.setattr(outputs, "write_plan_outputs", write)
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO, encoding="utf-8")
    code, err, _ = _run(capsys, ["plan", str(scen), "-o", str(out), "--force", "--no-aem"])
    assert code == EXIT_WRITE, err
    assert err == "jaxspline: cannot write: cannot write the outputs: No space left on device\n"
    assert (out / "plan.json").read_text() == "previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "s.toml"]


def test_output_file_flags_are_checked_before_any_work(tmp_path, scen, capsys):
    """Every command's output file (--json, --plan, -o) is checked before it works: its
    folder must exist, a file there must not block it, and the message names the flag."""
    (tmp_path / "f").write_text("a file")
    (tmp_path / "e.json").write_text('{"actions": []}')
    (tmp_path / "case").mkdir()
    missing, under_file = str(tmp_path / "no" / "x.json"), str(tmp_path / "f" / "x.json")
    case, sol = str(tmp_path / "case"), str(tmp_path / "e.json")
    plan = str(tmp_path / "p.json")  # a plan document view reads (its errors come first)
    (tmp_path / "p.json").write_text('{"summary": {}, "report": {}, "observations": []}')
    cases = [
        (["bound", str(scen), "--json", missing], "--json: the folder of"),
        (["bound", str(scen), "--plan", under_file], "--plan: the folder of"),
        (["bound", str(scen), "--json", sol], "--json: "),
        (["view", plan, "-o", missing], "-o/--output: the folder of"),
        (["aeossp", "solve", case, "-o", missing], "-o/--output: the folder"),
        (["aeossp", "check", case, sol, "--json", under_file], "--json: "),
        (
            ["regional", "solve", case, "-o", "s.json", "--time-limit", "inf"],
            "--time-limit: must be a finite",
        ),
        (["regional", "solve", case, "-o", "s.json", "--seed", "-1"], "--seed"),
        (["regional", "solve", case, "-o", ""], "-o/--output: must not be"),
        (["regional", "solve", case, "-o", str(tmp_path)], "-o/--output: "),
        (["regional", "solve", case, "-o", sol], "-o/--output: "),
        (["regional", "solve", str(tmp_path / "nocase"), "-o", "s.json"], "CASE_DIR: not found"),
        (["regional", "check", case, sol, "--json", ""], "--json: must"),
        (["regional", "check", case, sol, "--json", missing], "--json: "),
    ]
    for argv, msg in cases:
        code, err, seconds = _run(capsys, argv)
        assert code == EXIT_BAD_INPUT and msg in err, (argv, err)
        assert err.count("\n") == 1 and "Traceback" not in err and seconds < 10.0
    assert sorted(os.listdir(tmp_path)) == ["case", "e.json", "f", "p.json", "s.toml"]


def test_a_signal_that_a_finalizer_swallows_still_stops_the_run(tmp_path, scen, capsys):
    """Python runs a signal handler in whatever frame is running, a garbage-collector
    callback included, whose ``KeyboardInterrupt`` it prints as "ignored" and drops (a
    SIGTERM during the screening of the probe of issue 30 was lost that way, the run
    ended 0 with a traceback on stderr). The signal is remembered and raised at the next
    stage check: exit 130, no traceback, nothing written."""
    import gc

    from jaxspline.cli import EXIT_INTERRUPTED, _terminate

    fired = []

    def callback(phase, info):
        if phase == "start" and not fired and signal.getsignal(signal.SIGTERM) is _terminate:
            fired.append(phase)
            os.kill(os.getpid(), signal.SIGTERM)
            sum(range(1000))  # the handler runs here, inside the callback

    gc.callbacks.append(callback)
    try:
        argv = ["plan", str(scen), "-o", str(tmp_path / "out"), "--quiet", "--no-aem"]
        code, err, _ = _run(capsys, [*argv, "--no-plots", "--no-html", "--max-iters", "5"])
    finally:
        gc.callbacks.remove(callback)
    assert fired and code == EXIT_INTERRUPTED, (code, err)
    assert "Traceback" not in err and "ignored" not in err, err
    assert not (tmp_path / "out").exists()
