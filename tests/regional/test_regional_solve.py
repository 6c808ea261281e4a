"""``jaxspline regional solve`` and ``jaxspline aeossp solve`` as a user runs them: real
processes (``python -m jaxspline.cli``), their exit codes, files and messages.

* a solve writes a solution that the benchmark's independent checker finds valid;
* SIGTERM during the search: exit 130, the best solution so far written whole and valid,
  a line on stderr says so;
* an existing output without ``--force`` is refused before any work (exit 2, seconds);
* a case whose TLE epochs lie a year from the horizon is refused naming
  ``satellites.yaml`` and the ages (the TLE lines edited here, checksums recomputed).

The processes share the run's compile cache (tests/conftest.py).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

DATA = Path("/work/shared/data/regional_coverage/train")
AEOSSP = Path("/work/shared/data/aeossp_standard/train")
CASE = "case_0004"
_TIMEOUT_S = 300
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")


def _env():
    return dict(os.environ, PYTHONUNBUFFERED="1")


def _cli(*argv, timeout=_TIMEOUT_S):
    t0 = time.monotonic()
    p = subprocess.run(
        [sys.executable, "-m", "jaxspline.cli", *argv],
        env=_env(),
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return p, time.monotonic() - t0


def _check(case_dir, solution_path):
    """The benchmark checker's report of a written solution (in this process)."""
    from jaxspline.regional.case import load_case, load_solution
    from jaxspline.regional.check import check_solution

    return check_solution(load_case(case_dir), load_solution(solution_path))


def _checksum(line: str) -> int:
    """TLE checksum: the digits of columns 1-68 summed, each '-' counting 1, modulo 10."""
    return sum(int(c) if c.isdigit() else c == "-" for c in line[:68]) % 10


def _shift_epochs(case_dir: Path, days: float) -> None:
    """Move every TLE epoch of the case's satellites.yaml by ``days`` (line 1, columns
    19-32, ``YYDDD.DDDDDDDD``), with its checksum, and the ``tle_epoch`` field if any."""
    path = case_dir / "satellites.yaml"
    doc = yaml.safe_load(path.read_text())
    sats = doc["satellites"] if isinstance(doc, dict) else doc
    for s in sats:
        line = s["tle_line1"]
        yy, doy = int(line[18:20]), float(line[20:32])
        doy += days
        while doy >= 366.0:  # the years about the cases (2024-2027) have 365 or 366 days
            yy, doy = yy + 1, doy - 365.0
        while doy < 1.0:
            yy, doy = yy - 1, doy + 365.0
        new = f"{line[:18]}{yy:02d}{doy:012.8f}{line[32:68]}"
        s["tle_line1"] = new + str(_checksum(new))
        assert len(s["tle_line1"]) == 69
        if "tle_epoch" in s:
            s.pop("tle_epoch")
    path.write_text(yaml.safe_dump(doc, sort_keys=False))


# ---------------------------------------------------------------- refused before work
def test_an_existing_output_is_refused_before_any_work(tmp_path):
    sol = tmp_path / "s.json"
    sol.write_text("previous")
    p, seconds = _cli("regional", "solve", str(DATA / CASE), "-o", str(sol), "--time-limit", "30")
    assert p.returncode == 2, p.stderr
    assert "-o/--output" in p.stderr and str(sol) in p.stderr and "--force" in p.stderr
    assert "Traceback" not in p.stderr and sol.read_text() == "previous"
    assert seconds < 30.0  # no planning: an import and a check
    assert sorted(x.name for x in tmp_path.iterdir()) == ["s.json"]


def test_tles_a_year_from_the_horizon_are_refused_naming_the_file(tmp_path):
    case = tmp_path / CASE
    shutil.copytree(DATA / CASE, case)
    _shift_epochs(case, 365.0)
    from jaxspline.regional.case import load_case

    load_case(case)  # the edited TLEs are well formed: only their age is wrong
    sol = tmp_path / "s.json"
    p, seconds = _cli("regional", "solve", str(case), "-o", str(sol), "--time-limit", "30")
    assert p.returncode == 2, p.stderr
    err = p.stderr
    assert str(case / "satellites.yaml") in err and "days from the horizon" in err, err
    age = float(err.split(" days from the horizon")[0].rsplit(" ", 1)[1])
    assert 360.0 < age < 372.0  # a year, plus up to the case's 3 days
    assert "Traceback" not in err and not sol.exists() and seconds < 60.0


@pytest.mark.skipif(not AEOSSP.is_dir(), reason="aeossp cases not available")
def test_aeossp_solve_refuses_an_existing_output_and_old_tles(tmp_path):
    case = tmp_path / "case_0001"
    shutil.copytree(AEOSSP / "case_0001", case)
    sol = tmp_path / "s.json"
    sol.write_text("previous")
    p, seconds = _cli("aeossp", "solve", str(case), "-o", str(sol))
    assert p.returncode == 2 and "-o/--output" in p.stderr and sol.read_text() == "previous"
    assert seconds < 30.0
    _shift_epochs(case, -365.0)
    new = tmp_path / "new.json"
    p, _ = _cli("aeossp", "solve", str(case), "-o", str(new), "--time-limit", "30")
    assert p.returncode == 2, p.stderr
    assert str(case / "satellites.yaml") in p.stderr and "days from the horizon" in p.stderr
    assert not new.exists()


# ---------------------------------------------------------------- planning runs
def test_sigterm_during_the_search_writes_the_best_solution_and_exits_130(tmp_path):
    sol = tmp_path / "s.json"
    cmd = [sys.executable, "-m", "jaxspline.cli", "regional", "solve", str(DATA / CASE)]
    p = subprocess.Popen(
        [*cmd, "-o", str(sol), "--time-limit", "240"],
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    seen, t0 = b"", time.monotonic()
    try:
        while b"greedy" not in seen:  # a first plan exists
            chunk = os.read(p.stderr.fileno(), 4096)
            assert chunk, seen.decode(errors="replace")
            seen += chunk
            assert time.monotonic() - t0 < _TIMEOUT_S
        time.sleep(1.0)
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=_TIMEOUT_S)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    err = (seen + err).decode(errors="replace")
    assert p.returncode == 130, err
    assert "SIGTERM" in err and str(sol) in err and "best plan found so far" in err
    assert time.monotonic() - t0 < 120.0  # long before the 240 s limit
    doc = json.loads(sol.read_text())
    assert doc["actions"]
    rep = _check(DATA / CASE, sol)
    assert rep.valid, rep.violations[:5]
    assert "valid" in out.decode(errors="replace").lower()  # the check's report printed
    assert not [f.name for f in tmp_path.iterdir() if f.name != "s.json"]  # no temp file


@pytest.mark.slow
def test_solve_writes_a_valid_solution(tmp_path):
    sol = tmp_path / "s.json"
    p, seconds = _cli(
        "regional", "solve", str(DATA / CASE), "-o", str(sol), "--time-limit", "40", "--json",
        str(tmp_path / "report.json"),
    )  # fmt: skip
    assert p.returncode == 0, p.stderr
    assert seconds < 40.0 + 15.0  # the limit bounds the whole command (shared cores: slack)
    assert "coverage_ratio" in p.stdout
    rep = _check(DATA / CASE, sol)
    assert rep.valid and rep.coverage_ratio > 0.5
    written = json.loads((tmp_path / "report.json").read_text())
    assert written["valid"] is True
    # the same file through the check command
    p, _ = _cli("regional", "check", str(DATA / CASE), str(sol))
    assert p.returncode == 0, p.stdout + p.stderr
