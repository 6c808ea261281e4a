"""The relaxation's floor against the path LP solved exactly from every enumerated sequence.

Reference: every feasible sequence of each satellite's options (subsets in start order,
transitions by the DP's rules: far gap or a screened near pair, the first option by
``option_first``) is a column of the Dantzig-Wolfe master LP, credited once per run of
one target; scipy's HiGHS solves it. The floor (a Frank-Wolfe iterate, a feasible point
of that LP) must not exceed its optimum, the optimum must not exceed any Lagrangian
bound, and the floor seeded with the best integer plan's sequences must reach that plan.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from test_timeline_battery import _problem

from jaxspline.search.floor import relaxation_floor

TOL = 1e-7


def _feasible(pb, seq) -> bool:
    """The DP's transition rules along ``seq`` (option ids in start order)."""
    if pb.option_first[seq[0]] > pb.option_start[seq[0]]:
        return False
    for i, j in itertools.pairwise(seq):
        if pb.option_end[i] + pb.far[pb.option_sat[i]] <= pb.option_start[j]:
            continue
        row = pb.pairs.row(j)
        if not any(pb.pairs.src[q] == i for q in range(row.start, row.stop)):
            return False
    return True


def _sequences(pb, k):
    """Every feasible sequence of satellite k's options, the empty one first."""
    ids = sorted(range(pb.sat_lo[k], pb.sat_hi[k]), key=lambda c: pb.option_start[c])
    out = [()]
    for n in range(1, len(ids) + 1):
        out += [s for s in itertools.combinations(ids, n) if _feasible(pb, s)]
    return out


def _runs(pb, seq, n_targets) -> np.ndarray:
    t = [pb.option_target[c] for c in seq]
    a = np.zeros(n_targets)
    for m, x in enumerate(t):
        a[x] += m == 0 or t[m - 1] != x
    return a


def _master_lp(pb, seqs):
    """max sum_t w_t min(1, cov_t) over convex combinations of each satellite's columns."""
    linprog = pytest.importorskip("scipy.optimize").linprog
    w = np.asarray(pb.target_value, float)
    nt = w.size
    cols = [(k, _runs(pb, s, nt)) for k, ss in enumerate(seqs) for s in ss]
    a = np.stack([c for _, c in cols], axis=1)
    conv = np.zeros((pb.n_sats, len(cols)))
    for j, (k, _) in enumerate(cols):
        conv[k, j] = 1.0
    a_ub = np.block([[a, -np.eye(nt)], [conv, np.zeros((pb.n_sats, nt))]])
    cost = np.r_[-(w @ a), w]  # each run credits w; s_t pays back the over-coverage
    res = linprog(cost, A_ub=a_ub, b_ub=np.ones(nt + pb.n_sats), bounds=(0, None))
    assert res.status == 0
    return -res.fun


def _best_plan(pb, seqs):
    """The best combination of one sequence per satellite (targets counted once)."""
    w = np.asarray(pb.target_value, float)
    best, arg = -1.0, None
    for combo in itertools.product(*seqs):
        v = w[sorted({pb.option_target[c] for s in combo for c in s})].sum()
        if v > best:
            best, arg = v, combo
    return best, [list(s) for s in arg]


# seeds whose path LP is fractional (LP > optimum; found by a scan of seeds 0-149), then
# two whose LP is integral
FRACTIONAL = (6, 24, 45)


@pytest.mark.parametrize("seed", [*FRACTIONAL, 0, 2])
def test_floor_is_below_the_exact_lp_and_the_bound_above(seed):
    rng = np.random.default_rng(seed)
    pb, _ = _problem(rng, int(rng.integers(18, 30)), n_sats=3, n_targets=8, far=40.0, repeats=0.5)
    seqs = [_sequences(pb, k) for k in range(pb.n_sats)]
    lp = _master_lp(pb, seqs)
    opt, paths = _best_plan(pb, seqs)
    assert (lp > opt + TOL) == (seed in FRACTIONAL)
    res = relaxation_floor(pb, opt, max_iters=200, fw_iters=60)
    assert res.floor <= lp + TOL
    assert lp <= res.bound + TOL
    assert math.isfinite(res.bound) and res.iterations > 0
    if seed in FRACTIONAL:  # the floor shows that no prices bring the bound to the optimum
        assert res.floor > opt + TOL
    seeded = relaxation_floor(pb, opt, max_iters=200, fw_iters=60, plan_paths=paths)
    assert opt - TOL <= seeded.floor <= lp + TOL


def _script():
    """scripts/relaxation_floor.py as a module."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "scripts" / "relaxation_floor.py"
    spec = importlib.util.spec_from_file_location("relaxation_floor_script", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod, path.parent / "example_scenario.toml"


def test_script_writes_floor_below_bound_and_refuses_to_overwrite(tmp_path, capsys):
    import json

    mod, example = _script()
    out = tmp_path / "floor.json"
    args = [str(example), "--max-iters", "30", "--fw-iters", "10", "--json", str(out)]
    assert mod.main(args) == 0
    r = json.loads(out.read_text())
    assert 0.0 < r["floor"] <= r["bound"] + TOL and r["bound_iterations"] <= 30
    assert "floor" in capsys.readouterr().out
    before = out.read_text()
    with pytest.raises(SystemExit):  # refused before any work, file untouched
        mod.main(args)
    assert "--json" in capsys.readouterr().err and out.read_text() == before
    for flag, bad in (("--fw-iters", "-1"), ("--time-limit", "nan")):
        with pytest.raises(SystemExit):
            mod.main([str(example), flag, bad])
        assert flag in capsys.readouterr().err
