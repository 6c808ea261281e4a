"""The sharded Lagrangian bound equals the single-process one (reference: upper_bound).

* in one process: two shards of the satellites in two threads, the all-gather a
  barrier between them (the protocol alone);
* for real: ``jaxspline bound`` as two processes under ``jax.distributed`` (gloo on the
  CPU, localhost) against the same command as one process.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from jaxspline.engine.planner import build_problem
from jaxspline.engine.search import upper_bound
from jaxspline.engine.search.sharded import owned_satellites, sharded_upper_bound
from jaxspline.scenario import load_scenario

sys.path.insert(0, str(Path(__file__).parents[2] / "product"))
from test_cli_plan import SMALL  # noqa: E402

TARGET = 100.0
ITERS = 40


@pytest.fixture(scope="module")
def scenario_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("sharded") / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return path


class _Exchange:
    """All-gather between threads: every party posts, waits, reads all posts."""

    def __init__(self, parties):
        self.barrier = threading.Barrier(parties)
        self.posts = [None] * parties

    def allgather(self, i):
        def gather(x):
            self.posts[i] = np.asarray(x, np.float64).copy()
            self.barrier.wait()
            out = np.stack(self.posts)
            self.barrier.wait()  # nobody overwrites a post before all have read it
            return out

        return gather


def test_threads_sharded_bound_equals_one_process(scenario_file):
    sc = load_scenario(scenario_file)
    full = build_problem(sc).problem
    ref = upper_bound(full, TARGET, math.inf, max_iters=ITERS, energy=False)
    count = len(sc.satellites)
    ex = _Exchange(count)
    shards = []
    for i in range(count):
        owned = owned_satellites(count, i, count)
        shard = dataclasses.replace(sc, satellites=tuple(sc.satellites[k] for k in owned))
        pb = build_problem(shard, reduce_slack=lambda s, w=full.near_slack: w).problem
        shards.append((owned, pb))
    assert sum(len(pb.pairs) for _, pb in shards) == len(full.pairs)
    results = [None] * count

    def run(i):
        owned, pb = shards[i]
        results[i] = sharded_upper_bound(
            pb, owned, count, TARGET, math.inf, ITERS, allgather=ex.allgather(i)
        )

    threads = [threading.Thread(target=run, args=(i,)) for i in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    for r in results:
        assert r.bound == ref.bound  # bit for bit
        assert r.iterations == ref.iterations == ITERS


def _free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def _bound_cmd(scen, out, *extra):
    return [
        sys.executable,
        "-m",
        "jaxspline.cli",
        "bound",
        str(scen),
        "--max-iters",
        str(ITERS),
        "--target",
        str(TARGET),
        "--json",
        str(out),
        *extra,
    ]


def test_two_processes_under_jax_distributed_equal_one(scenario_file, tmp_path):
    env = dict(os.environ, JAXSPLINE_CACHE_DIR=str(tmp_path / "xla"))
    one = tmp_path / "one.json"
    r = subprocess.run(
        _bound_cmd(scenario_file, one), env=env, capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr
    two = tmp_path / "two.json"
    port = _free_port()
    procs = [
        subprocess.Popen(
            _bound_cmd(
                scenario_file,
                two,
                "--coordinator",
                f"localhost:{port}",
                "--num-processes",
                "2",
                "--process-id",
                str(i),
            ),
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for i in (1, 0)
    ]
    for p in procs:
        _, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
    a, b = json.loads(one.read_text()), json.loads(two.read_text())
    assert b["processes"] == 2 and a["processes"] == 1
    assert b["bound"] == a["bound"] and b["iterations"] == a["iterations"] == ITERS
    assert b["satellites"] == [load_scenario(scenario_file).satellites[0].name]
    assert 0 < b["near_pairs"] < a["near_pairs"]  # process 0 stores its shard only
