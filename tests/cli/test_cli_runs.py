"""``jaxspline plan`` as a user runs it: separate processes, repeat runs, signals.

* SIGINT / SIGTERM during the search: exit 130, the best plan so far checked and
  written whole (valid JSON, CSV rows = observations, ``report.interrupted`` named,
  no temporary file left), a line on stderr says so.
* SIGKILL during the search: no child process (the bound worker) outlives the command,
  and a rerun on the same output directory starts at once.
* exit 3 in an early stage: its remedy is enough; a run at the limit it names plans.

The processes share the run's compile cache (tests/conftest.py), so only the first one compiles.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_cli_plan import SMALL, plan_json

_TIMEOUT_S = 300


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    d = tmp_path_factory.mktemp("runs")
    scen = d / "small.toml"
    scen.write_text(SMALL, encoding="utf-8")
    e = dict(os.environ, PYTHONUNBUFFERED="1")  # the run's shared XLA cache (conftest)
    return {"scen": scen, "env": e, "dir": d}


def _cmd(scen, out, *extra):
    return [
        sys.executable,
        "-m",
        "jaxspline.cli",
        "plan",
        str(scen),
        "-o",
        str(out),
        "--no-plots",
        "--no-aem",
        *extra,
    ]


def _start_until(env, out, marker: bytes, *extra):
    """Start ``jaxspline plan`` and read its stderr until ``marker``; (process, stderr)."""
    p = subprocess.Popen(
        _cmd(env["scen"], out, *extra),
        env=env["env"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    seen = b""
    t0 = time.monotonic()
    while marker not in seen:
        chunk = os.read(p.stderr.fileno(), 4096)
        assert chunk, seen.decode(errors="replace")
        seen += chunk
        assert time.monotonic() - t0 < _TIMEOUT_S
    return p, seen


def _rows(out):
    with open(out / "plan.csv", newline="") as fh:
        return list(csv.DictReader(fh))


# SIGTERM takes the same path as SIGINT (one handler); the default run checks SIGINT
@pytest.mark.parametrize(
    "sig", [signal.SIGINT, pytest.param(signal.SIGTERM, marks=pytest.mark.slow)]
)
def test_signal_during_search_writes_the_best_plan_and_exits_130(env, sig):
    out = env["dir"] / f"sig{int(sig)}"
    # a long budget: only the signal ends the search early
    t0 = time.monotonic()
    p, seen = _start_until(env, out, b"greedy", "--time-limit", "240")  # a first plan
    time.sleep(1.0)
    p.send_signal(sig)
    stdout, stderr = p.communicate(timeout=_TIMEOUT_S)
    stderr = (seen + stderr).decode(errors="replace")
    assert p.returncode == 130, stderr
    assert "stopping the search" in stderr
    assert "interrupted" in stderr
    data = plan_json(out)
    rep = data["report"]
    assert rep["interrupted"] == sig.name
    assert rep["valid"]
    assert len(_rows(out)) == data["summary"]["observations"] > 0
    assert not [f.name for f in out.iterdir() if f.name.startswith(".")]  # no temp files
    assert time.monotonic() - t0 < 120  # well before the 240 s budget


def _stat(pid) -> list[str]:
    """Fields of ``/proc/PID/stat`` after the command name ([state, parent, ...]); [] when
    there is no such process."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return []


def _running(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, ended and not reaped, does not)."""
    return _stat(pid)[:1] not in ([], ["Z"], ["X"])


def _children(pid: int) -> list[int]:
    """The running processes whose parent is ``pid``."""
    ids = [int(d.name) for d in Path("/proc").iterdir() if d.name.isdigit()]
    return [k for k in ids if _stat(k)[1:2] == [str(pid)] and _running(k)]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="no bound worker on one core")
def test_kill_9_during_the_search_leaves_no_process_and_the_directory_free(env):
    out = env["dir"] / "killed"
    p, seen = _start_until(env, out, b"lns", "--time-limit", "60")  # the search runs
    kids = _children(p.pid)
    try:
        assert kids, "no bound worker: nothing to check"
        p.kill()
        p.wait()
        t_end = time.monotonic() + 5.0
        while time.monotonic() < t_end and any(map(_running, kids)):
            time.sleep(0.05)
        left = [k for k in kids if _running(k)]
        assert not left, f"children of the killed run still run: {left}"
    finally:
        p.kill()
        p.wait()
        for k in kids:
            with contextlib.suppress(ProcessLookupError):
                os.kill(k, signal.SIGKILL)
    again = subprocess.run(
        _cmd(env["scen"], out, "--force", "--time-limit", "10", "--max-iters", "30", "--quiet"),
        env=env["env"],
        capture_output=True,
        timeout=_TIMEOUT_S,
    )
    assert again.returncode == 0, again.stderr.decode(errors="replace")
    assert plan_json(out)["report"]["valid"]


def test_signal_before_any_plan_leaves_nothing(env):
    out = env["dir"] / "early"
    p, _ = _start_until(env, out, b"orbits", "--time-limit", "240")  # no plan yet
    p.send_signal(signal.SIGTERM)
    _, stderr = p.communicate(timeout=_TIMEOUT_S)
    assert p.returncode == 130, stderr.decode(errors="replace")
    assert not out.exists() or not any(out.iterdir())


# a sweep of real signals over the repair and the writing (~9 CPU-s): the default run
# checks a real signal in the search above and a signal while writing in-process
# (test_cli_errors.py, tests/products/test_outputs.py)
@pytest.mark.slow
def test_signals_while_repairing_and_writing_leave_whole_files(env):
    """SIGTERM from the repair on, every 0.3 s until the process exits: whatever phase a
    signal lands in, every output that exists parses whole and no temporary file stays."""
    out = env["dir"] / "writing"
    # the search is over (an iteration cap ends it at once, not its share of the limit)
    p, _ = _start_until(env, out, b"repair", "--time-limit", "20", "--max-iters", "30")
    sent = 0
    while p.poll() is None and sent < 100:
        p.send_signal(signal.SIGTERM)
        sent += 1
        time.sleep(0.3)
    p.communicate(timeout=_TIMEOUT_S)
    assert p.returncode == 130
    assert not [f.name for f in out.iterdir() if f.name.startswith(".")] if out.exists() else True
    if (out / "plan.json").exists():  # written: all of it, whole
        data = plan_json(out)
        # named unless the first signal came after plan.json was written
        assert data["report"].get("interrupted", "SIGTERM") == "SIGTERM"
        assert len(_rows(out)) == data["summary"]["observations"]
        # an optional product is whole, or left out for the time limit and said so
        limit = json.loads((out / "plan.json").read_text())["report"].get("time_limit", {})
        skipped = {s["what"] for s in limit.get("skipped", [])}
        html, czml = out / "plan.html", out / "plan.czml"
        assert html.stat().st_size > 0 if html.exists() else "plan.html" in skipped
        assert czml.read_text().rstrip().endswith("]") if czml.exists() else "plan.czml" in skipped


_ADVICE = re.compile(r"give a time limit of (\d+) s or more")


def _run_for(env, scen, out, limit, *extra):
    """``jaxspline plan`` with ``--time-limit limit``: (exit code, stderr, wall seconds)."""
    cmd = _cmd(scen, out, "--force", "--no-html", "--quiet", "--time-limit", str(limit), *extra)
    t0 = time.monotonic()
    done = subprocess.run(cmd, env=env["env"], capture_output=True, timeout=_TIMEOUT_S)
    return done.returncode, done.stderr.decode(errors="replace"), time.monotonic() - t0


# the run at the advised limit searches until it (minutes) unless an iteration cap ends it
@pytest.mark.parametrize("capped", [True, pytest.param(False, marks=pytest.mark.slow)])
def test_the_remedy_of_an_early_stop_covers_the_whole_run(env, capped):
    """A limit that stops the run while loading: the remedy names a limit at which the run
    plans (or, once, a larger one that it then meets), and which covers the whole run:
    the stages after the one stopped (the screening, quadratic in the options' density),
    the search's share, the repair and the outputs. Capped by ``--max-iters``, the run
    at that limit does its fixed work and ends: its wall time is what the run needed."""
    base = (Path(__file__).parents[2] / "jaxspline" / "data" / "default.toml").read_text()
    text = "\n".join(line for line in base.splitlines() if not line.startswith("targets_csv"))
    text = re.sub(r"(?m)^count = \d+.*$", "count = 6000", text)  # strips on land
    scen = env["dir"] / "six_thousand.toml"
    scen.write_text(text, encoding="utf-8")
    out = env["dir"] / f"advice{int(capped)}"
    code, err, _ = _run_for(env, scen, out, 1)
    assert code == 3, err
    first = limit = int(_ADVICE.search(err).group(1))
    extra = ("--max-iters", "30") if capped else ()
    for _ in range(2):  # the advised limit, then at most one larger one it names
        code, err, wall = _run_for(env, scen, out, limit, *extra)
        if code != 3:
            break
        more = int(_ADVICE.search(err).group(1))
        assert more > limit, err
        limit = more
    assert code == 0, err
    assert plan_json(out)["report"]["valid"]
    if capped:
        assert wall <= first, f"the run took {wall:.0f} s; the first advice was {first} s"
