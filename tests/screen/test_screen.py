"""Tests of the bulk screening engine against brute-force numpy references.

The exact-T reference here is the SPEC section 1 envelope formula written in
plain numpy, one candidate at a time, independent of :mod:`jaxspline.kernels.reach`.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import jax
import numpy as np
import pytest

from jaxspline.kernels.limits import AxisLimits
from jaxspline.screen import fused as screen_fused
from jaxspline.screen import pairs as screen
from jaxspline.screen import transitions
from jaxspline.screen.options import RouteOptions, take_options
from jaxspline.sequences.route_screen import screen_sequences

# ----------------------------------------------------------------------------
# numpy references and synthetic instances
# ----------------------------------------------------------------------------


def _hi_lo(a1, b1, b2, T, b, d, xp):
    ya = (b1 + b2 + d * T) / 2
    yc = (b1 + b2 - d * T) / 2
    hi2 = a1 - (b1 - b2) ** 2 / (4 * d) + T * (b1 + b2) / 2 + d * T**2 / 4
    hi3 = a1 - ((b - b1) ** 2 + (b - b2) ** 2) / (2 * d) + b * T
    lo2 = a1 + (b1 - b2) ** 2 / (4 * d) + T * (b1 + b2) / 2 - d * T**2 / 4
    lo3 = a1 + ((b + b1) ** 2 + (b + b2) ** 2) / (2 * d) - b * T
    return xp.where(ya <= b, hi2, hi3), xp.where(yc >= -b, lo2, lo3)


def ref_reachable(a1, b1, a2, b2, T, b, d, tol=0.0):
    """numpy reference of exact-T membership (SPEC section 1), elementwise."""
    a1, b1, a2, b2, T, b, d = np.broadcast_arrays(*map(np.asarray, (a1, b1, a2, b2, T, b, d)))
    rate_ok = (np.abs(b1) <= b) & (np.abs(b2) <= b) & (np.abs(b1 - b2) <= d * T + tol) & (T > 0)
    with np.errstate(all="ignore"):
        hi, lo = _hi_lo(a1, b1, b2, T, b, d, np)
    return rate_ok & (lo - tol <= a2) & (a2 <= hi + tol)


@pytest.fixture
def reach_kernels():
    """The kernels the engine screens with (``jaxspline.kernels``: reach, reach_durations)."""
    from jaxspline import kernels

    return kernels


def synthetic_options(
    rng,
    n_routes=6,
    per_route=3,
    c=2,
    horizon=400.0,
    dur=(5.0, 20.0),
    dtype=np.float64,
    rate=0.05,
    spread=0.4,
    window=15.0,
):
    """Random RouteOptions: each route has ``per_route`` start options on a window grid."""
    rows = []
    centers = np.sort(rng.uniform(0, horizon, n_routes))
    for r in range(n_routes):
        base = rng.uniform(-spread, spread, c)
        slope = rng.uniform(-0.005, 0.005, c)
        d = rng.uniform(*dur)
        srate = rng.uniform(-0.5 * rate, 0.5 * rate, c)
        for t0 in centers[r] + np.linspace(-window, window, per_route):
            a0 = base + slope * (t0 - centers[r])
            rows.append((r, t0, t0 + d, a0, srate, a0 + srate * d, srate, rng.uniform(1, 10)))
    route, ts, te, sa, sr, ea, er, val = zip(*rows, strict=True)
    n = len(route)
    return RouteOptions(
        route=np.asarray(route, np.int32),
        t_start=np.asarray(ts, dtype),
        t_end=np.asarray(te, dtype),
        start_angle=np.asarray(sa, dtype),
        start_rate=np.asarray(sr, dtype),
        end_angle=np.asarray(ea, dtype),
        end_rate=np.asarray(er, dtype),
        value=np.asarray(val, dtype),
        scan_ok=np.ones(n, bool),
    )


LIMITS = AxisLimits(rate=np.array([0.05, 0.06]), accel=np.array([0.004, 0.005]))


def brute_candidates(opt, max_gap=None):
    n = len(opt.route)
    out = []
    for i in range(n):
        for j in range(n):
            if opt.route[i] == opt.route[j] or not (opt.scan_ok[i] and opt.scan_ok[j]):
                continue
            T = float(opt.t_start[j]) - float(opt.t_end[i])
            if T <= 0 or (max_gap is not None and T > max_gap):
                continue
            out.append((i, j))
    return set(out)


def brute_feasible(opt, limits, i, j):
    T = float(opt.t_start[j]) - float(opt.t_end[i])
    return bool(
        np.all(
            ref_reachable(
                opt.end_angle[i],
                opt.end_rate[i],
                opt.start_angle[j],
                opt.start_rate[j],
                T,
                np.asarray(limits.rate),
                np.asarray(limits.accel),
            )
        )
    )


# ----------------------------------------------------------------------------
# tests
# ----------------------------------------------------------------------------


def test_candidates_and_verdicts_match_brute_force(reach_kernels):
    rng = np.random.default_rng(0)
    agree = total = 0
    for seed in range(4):
        rng = np.random.default_rng(seed)
        opt = synthetic_options(rng, n_routes=8, per_route=3, horizon=300.0)
        opt = opt._replace(scan_ok=rng.uniform(size=len(opt.route)) > 0.1)
        tr = screen.screen_transitions(opt, LIMITS, progress=False, chunk_size=64)
        pairs = list(zip(tr.src.tolist(), tr.dst.tolist(), strict=True))
        assert set(pairs) == brute_candidates(opt)
        assert len(pairs) == len(set(pairs)) == tr.n_screened
        np.testing.assert_allclose(tr.T, opt.t_start[tr.dst] - opt.t_end[tr.src], rtol=1e-15)
        for k, (i, j) in enumerate(pairs):
            total += 1
            agree += bool(tr.feasible[k]) == brute_feasible(opt, LIMITS, i, j)
        assert tr.feasible.any() and (~tr.feasible).any()
        # margin sign and effort agree with the verdict
        assert np.all(tr.margin[tr.feasible] >= -1e-9)
        assert np.all(tr.margin[~tr.feasible] <= 1e-9)
        assert np.all(tr.effort[tr.feasible] <= 1 + 1e-6)
        assert np.all(tr.effort[~tr.feasible] >= 1 - 1e-6)
        assert np.all(tr.t_min[tr.feasible] <= tr.T[tr.feasible] * (1 + 1e-9))
    assert agree == total, f"{total - agree} of {total} verdicts differ from the numpy reference"


def test_chunking_max_gap_and_order_invariance(reach_kernels):
    rng = np.random.default_rng(7)
    opt = synthetic_options(rng, n_routes=10, per_route=4, horizon=400.0)
    full = screen.screen_transitions(opt, LIMITS, progress=False)
    small = screen.screen_transitions(opt, LIMITS, progress=False, chunk_size=16)
    for f in ("src", "dst", "T", "feasible", "margin", "effort", "t_min"):
        np.testing.assert_array_equal(getattr(full, f), getattr(small, f))
    gap = screen.screen_transitions(opt, LIMITS, progress=False, max_gap=60.0, chunk_size=32)
    assert set(zip(gap.src.tolist(), gap.dst.tolist(), strict=True)) == brute_candidates(opt, 60.0)
    assert np.all(gap.T <= 60.0)
    # permuting the option table permutes indices, not verdicts
    perm = rng.permutation(len(opt.route))
    inv = np.argsort(perm)
    opt_p = take_options(opt, perm)
    tp = screen.screen_transitions(opt_p, LIMITS, progress=False)
    a = dict(
        zip(
            zip(full.src.tolist(), full.dst.tolist(), strict=True),
            full.feasible.tolist(),
            strict=True,
        )
    )
    pairs_p = zip(perm[tp.src].tolist(), perm[tp.dst].tolist(), strict=True)
    b = dict(zip(pairs_p, tp.feasible.tolist(), strict=True))
    assert a == b and inv.size == perm.size
    # multi-process split: the parts of two processes add up to the whole
    halves = [
        screen.screen_transitions(
            opt, LIMITS, progress=False, chunk_size=16, process_index=k, process_count=2
        )
        for k in (0, 1)
    ]
    assert sum(h.n_screened for h in halves) == full.n_screened
    both = sorted(
        (s_, d_) for h in halves for s_, d_ in zip(h.src.tolist(), h.dst.tolist(), strict=True)
    )
    assert both == sorted(zip(full.src.tolist(), full.dst.tolist(), strict=True))
    only = screen.screen_transitions(opt, LIMITS, progress=False, feasible_only=True)
    assert only.feasible.all() and only.src.size == full.feasible.sum()
    assert only.n_screened == full.n_screened


def test_float32_follows_input_dtype(reach_kernels):
    rng = np.random.default_rng(3)
    opt64 = synthetic_options(rng, n_routes=8, per_route=3)
    opt32 = RouteOptions(
        *(a.astype(np.float32) if a is not None and a.dtype == np.float64 else a for a in opt64)
    )
    t64 = screen.screen_transitions(opt64, LIMITS, progress=False)
    t32 = screen.screen_transitions(opt32, LIMITS, progress=False)
    assert t32.margin.dtype == np.float32 and t64.margin.dtype == np.float64
    np.testing.assert_array_equal(t32.src, t64.src)
    clear = np.abs(t64.margin) > 1e-4
    np.testing.assert_array_equal(t32.feasible[clear], t64.feasible[clear])
    np.testing.assert_allclose(t32.margin[clear], t64.margin[clear], rtol=1e-3, atol=1e-4)


def test_screen_sequences_planted(reach_kernels):
    rng = np.random.default_rng(11)
    opt = synthetic_options(rng, n_routes=8, per_route=3, horizon=600.0)
    tr = screen.screen_transitions(opt, LIMITS, progress=False)
    f_ok = np.flatnonzero(tr.feasible)
    f_bad = np.flatnonzero(~tr.feasible)
    i, j = tr.src[f_ok[0]], tr.dst[f_ok[0]]
    bi, bj = tr.src[f_bad[0]], tr.dst[f_bad[0]]
    same_route = np.flatnonzero(opt.route == opt.route[i])
    other = same_route[same_route != i][0]
    seqs = np.array(
        [
            [i, j, -1],  # feasible
            [bi, bj, -1],  # infeasible transition -> fails at position 1
            [j, i, -1],  # T <= 0 -> position 1
            [i, -1, -1],  # single option
            [-1, -1, -1],  # empty
            [i, j, other],  # repeated route at position 2 (and/or T <= 0)
        ]
    )
    feas, first, value = screen_sequences(opt, seqs, LIMITS)
    np.testing.assert_array_equal(feas, [True, False, False, True, True, False])
    np.testing.assert_array_equal(first, [-1, 1, 1, -1, -1, 2])
    np.testing.assert_allclose(value[0], opt.value[i] + opt.value[j])
    assert value[4] == 0
    opt2 = opt._replace(scan_ok=np.where(np.arange(len(opt.route)) == j, False, True))
    feas, first, _ = screen_sequences(opt2, seqs[:1], LIMITS)
    assert not feas[0] and first[0] == 1
    # batch of random sequences vs a per-row reference built from brute_feasible
    n = len(opt.route)
    rows = np.sort(rng.integers(0, n, size=(40, 4)), axis=1)
    feas, first, _ = screen_sequences(opt, rows, LIMITS)
    for r, row in enumerate(rows):
        ref = -1
        for p in range(len(row)):
            if opt.route[row[p]] in opt.route[row[:p]] or (
                p > 0
                and not (
                    opt.t_start[row[p]] > opt.t_end[row[p - 1]]
                    and brute_feasible(opt, LIMITS, row[p - 1], row[p])
                )
            ):
                ref = p
                break
        assert first[r] == ref and feas[r] == (ref < 0)


def test_value_errors(reach_kernels):
    rng = np.random.default_rng(1)
    opt = synthetic_options(rng, n_routes=3, per_route=2)
    with pytest.raises(ValueError, match="max_gap"):
        screen.screen_transitions(opt, LIMITS, max_gap=-1.0, progress=False)
    with pytest.raises(ValueError, match="limits.rate"):
        screen.screen_transitions(opt, AxisLimits(rate=np.array([0.05, -1.0]), accel=0.01))
    with pytest.raises(ValueError, match="one per channel"):
        screen.screen_transitions(opt, AxisLimits(rate=np.ones(3), accel=0.01), progress=False)
    with pytest.raises(ValueError, match="t_end"):
        bad = opt._replace(t_end=opt.t_start - 1.0)
        screen.screen_transitions(bad, LIMITS, progress=False)
    with pytest.raises(ValueError, match="start_rate"):
        screen.screen_transitions(opt._replace(start_rate=opt.start_rate[:, :1]), LIMITS)
    with pytest.raises(ValueError, match="padding"):
        screen_sequences(opt, np.array([[0, -1, 1]]), LIMITS)
    with pytest.raises(ValueError, match="sequences"):
        screen_sequences(opt, np.array([[0, 99]]), LIMITS)


def test_empty_and_no_candidates(reach_kernels):
    rng = np.random.default_rng(2)
    opt = synthetic_options(rng, n_routes=1, per_route=3)
    tr = screen.screen_transitions(opt, LIMITS, progress=False)
    assert tr.src.size == 0 and tr.n_screened == 0


_SHARD_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import jax
    jax.config.update("jax_enable_x64", True)
    import numpy as np
    sys.path.insert(0, {tests!r})
    import test_screen as ts
    from jaxspline.screen import pairs as screen
    opt = ts.synthetic_options(np.random.default_rng(5), n_routes=12, per_route=4)
    tr = screen.screen_transitions(opt, ts.LIMITS, progress=False, chunk_size=64)
    print(json.dumps({{"ndev": jax.local_device_count(),
                      "src": tr.src.tolist(), "dst": tr.dst.tolist(),
                      "feasible": tr.feasible.tolist(), "margin": tr.margin.tolist(),
                      "effort": tr.effort.tolist()}}))
    """
)


def _run_sharded(ndev: int) -> dict:
    env = dict(os.environ)
    env["XLA_FLAGS"] = f"{env['XLA_FLAGS']} --xla_force_host_platform_device_count={ndev}"
    env["JAX_PLATFORMS"] = "cpu"
    script = _SHARD_SCRIPT.format(tests=os.path.dirname(__file__))
    out = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_sharded_over_four_devices_equals_single_device():
    four = _run_sharded(4)
    assert four["ndev"] == 4
    # the one-device reference runs here (this process has one CPU device)
    assert jax.local_device_count() == 1
    opt = synthetic_options(np.random.default_rng(5), n_routes=12, per_route=4)
    tr = screen.screen_transitions(opt, LIMITS, progress=False, chunk_size=64)
    one = {k: np.asarray(getattr(tr, k)).tolist() for k in ("src", "dst", "feasible")}
    one.update(margin=np.asarray(tr.margin), effort=np.asarray(tr.effort))
    for k in ("src", "dst", "feasible"):
        assert four[k] == one[k]
    np.testing.assert_allclose(four["margin"], one["margin"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(four["effort"], one["effort"], rtol=1e-12)


def test_chunk_program_agrees_with_public_reach_functions(reach_kernels):
    """The engine's jit(vmap) chunk equals the public (vectorized) reach functions per channel."""
    rng = np.random.default_rng(9)
    opt = synthetic_options(rng, n_routes=6, per_route=3)
    tr = screen.screen_transitions(opt, LIMITS, progress=False)
    i, j = tr.src, tr.dst
    args = (opt.end_angle[i], opt.end_rate[i], opt.start_angle[j], opt.start_rate[j], tr.T[:, None])
    lim = AxisLimits(LIMITS.rate[None, :], LIMITS.accel[None, :])
    margin = np.asarray(reach_kernels.reach_margin(*args, lim)).min(axis=1)
    ok = np.asarray(reach_kernels.is_reachable(*args, lim)).all(axis=1)
    eff = (np.asarray(reach_kernels.min_peak_accel(*args, lim.rate)) / lim.accel).max(axis=1)
    np.testing.assert_array_equal(tr.feasible, ok)
    np.testing.assert_allclose(tr.margin, margin, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(tr.effort, eff, rtol=1e-12)
    # one candidate at a time through the scalar kernel
    k = int(np.argmax(tr.feasible))
    one = [
        float(
            reach_kernels.reach_margin_kernel(
                *(np.asarray(a)[k].reshape(-1)[c] for a in args[:4]),
                tr.T[k],
                LIMITS.rate[c],
                LIMITS.accel[c],
            )
        )
        for c in range(2)
    ]
    assert min(one) == pytest.approx(tr.margin[k], rel=1e-12, abs=1e-15)


def test_tiny_chunks_empty_runs_and_screen_pairs(reach_kernels):
    """Chunk edges inside runs, sources with empty runs, nothing feasible, pairs path."""
    rng = np.random.default_rng(13)
    opt = synthetic_options(rng, n_routes=7, per_route=3, horizon=250.0)
    # a small max_gap leaves many sources with an empty destination run
    full = screen.screen_transitions(opt, LIMITS, progress=False, max_gap=25.0)
    ref = brute_candidates(opt, 25.0)
    assert set(zip(full.src.tolist(), full.dst.tolist(), strict=True)) == ref
    assert 0 < full.n_screened < len(brute_candidates(opt))
    for cs in (1, 5):
        part = screen.screen_transitions(opt, LIMITS, progress=False, max_gap=25.0, chunk_size=cs)
        for f in ("src", "dst", "T", "feasible"):
            np.testing.assert_array_equal(getattr(part, f), getattr(full, f))
        for f in ("margin", "effort", "t_min"):  # tiny programs compile unvectorized: 1 ulp
            np.testing.assert_allclose(getattr(part, f), getattr(full, f), rtol=1e-14, atol=1e-17)
        assert part.n_screened == full.n_screened
    # the pairs entry point (T formed on the device path) gives the same columns
    pairs = screen.screen_pairs(opt, LIMITS, full.src, full.dst)
    for f in ("T", "feasible", "margin", "effort", "t_min"):
        np.testing.assert_array_equal(getattr(pairs, f), getattr(full, f))
    # nothing feasible under tiny limits: feasible_only gives typed empty columns
    tiny = AxisLimits(rate=np.array([1e-6, 1e-6]), accel=np.array([1e-6, 1e-6]))
    none = screen.screen_transitions(opt, tiny, progress=False, feasible_only=True)
    assert none.src.size == 0 and none.n_screened == len(brute_candidates(opt))
    assert none.src.dtype == np.int64 and none.margin.dtype == np.float64


def test_prefaulted_columns_are_plain_writable_arrays():
    """Large result columns come from one pre-populated mapping; they behave like np.empty."""
    for n, dt in ((3_000_000, np.float64), (2_500_000, np.int64), (20_000_000, bool), (10, float)):
        a = transitions._prefaulted(n, dt)
        assert a.shape == (n,) and a.dtype == np.dtype(dt) and a.flags.writeable
        a[:] = 1
        a[-1] = 0
        assert a[:-1].all() and not a[-1] and a[: n // 2].base is not None


_DIST_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import jax
    jax.config.update("jax_enable_x64", True)
    jax.distributed.initialize(
        coordinator_address="127.0.0.1:{port}", num_processes=2, process_id=int(sys.argv[1])
    )
    import numpy as np
    sys.path.insert(0, {tests!r})
    import test_screen as ts
    from jaxspline.screen import pairs as screen
    opt = ts.synthetic_options(np.random.default_rng(5), n_routes=12, per_route=4)
    # process_index / process_count come from jax.distributed
    tr = screen.screen_transitions(opt, ts.LIMITS, progress=False, chunk_size=64)
    print(json.dumps({{"index": jax.process_index(), "count": jax.process_count(),
                      "src": tr.src.tolist(), "dst": tr.dst.tolist(),
                      "feasible": tr.feasible.tolist(), "margin": tr.margin.tolist()}}))
    jax.distributed.shutdown()
    """
)


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_two_distributed_processes_split_the_candidates():
    """Two local CPU processes under jax.distributed: the union of parts is the whole."""
    env = dict(os.environ, JAX_PLATFORMS="cpu")
    script = _DIST_SCRIPT.format(port=_free_port(), tests=os.path.dirname(__file__))
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", script, str(k)],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for k in (0, 1)
    ]
    parts = []
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err[-3000:]
        parts.append(json.loads(out.strip().splitlines()[-1]))
    assert sorted((q["index"], q["count"]) for q in parts) == [(0, 2), (1, 2)]
    assert all(q["src"] for q in parts)  # both processes screened something
    opt = synthetic_options(np.random.default_rng(5), n_routes=12, per_route=4)
    whole = screen.screen_transitions(opt, LIMITS, progress=False, chunk_size=64)
    ref = {
        (s, d): (f, m)
        for s, d, f, m in zip(
            whole.src.tolist(), whole.dst.tolist(), whole.feasible.tolist(),
            whole.margin.tolist(), strict=True,
        )
    }  # fmt: skip
    got = {}
    for q in parts:
        for s, d, f, m in zip(q["src"], q["dst"], q["feasible"], q["margin"], strict=True):
            assert (s, d) not in got  # no candidate screened twice
            got[(s, d)] = (f, m)
    assert got.keys() == ref.keys()
    for key, (f, m) in ref.items():
        assert got[key][0] == f and got[key][1] == pytest.approx(m, rel=1e-12, abs=1e-15)


# ----------------------------------------------------------------------------
# fused path (pairs generated and compacted on the device) vs the host path
# ----------------------------------------------------------------------------

_COLS = ("src", "dst", "T", "feasible", "margin", "effort", "t_min")


def _fused_and_host(opt, limits=LIMITS, **kw):
    args = dict(max_gap=None, chunk_size=2**18, progress=False, feasible_only=False, pi=0, pc=1)
    args.update(kw)
    order = ("max_gap", "chunk_size", "progress", "feasible_only", "pi", "pc")
    a = [args[k] for k in order]
    return (
        screen_fused.screen_transitions_fused(opt, limits, *a),
        screen._screen_transitions_host(opt, limits, *a),
    )


def _assert_same(f, h, rtol=1e-12):
    assert f.n_screened == h.n_screened
    for k in ("src", "dst", "T", "feasible"):
        np.testing.assert_array_equal(getattr(f, k), getattr(h, k), err_msg=k)
        assert getattr(f, k).dtype == getattr(h, k).dtype
    for k in ("margin", "effort", "t_min"):
        np.testing.assert_allclose(getattr(f, k), getattr(h, k), rtol=rtol, atol=1e-15, err_msg=k)


@pytest.mark.parametrize(
    "kw",
    [
        {},
        # each option alone is slow: the default run checks them together
        pytest.param({"max_gap": 100.0}, marks=pytest.mark.slow),
        pytest.param({"feasible_only": True}, marks=pytest.mark.slow),
        {"max_gap": 100.0, "feasible_only": True, "chunk_size": 100},
        {"chunk_size": 1},
        {"chunk_size": 700},
    ],
)
def test_fused_path_equals_host_path_and_brute_force(kw):
    """Thousands of random candidates: fused == host path (feasibility bit-identical,
    margins to 1e-12) == numpy brute force, incl. max_gap, feasible_only, scan_ok and
    same-route exclusion, chunk edges inside runs."""
    rng = np.random.default_rng(21)
    opt = synthetic_options(rng, n_routes=30, per_route=4, horizon=500.0, spread=0.8)
    opt = opt._replace(scan_ok=rng.uniform(size=len(opt.route)) > 0.1)
    if kw.get("chunk_size") == 1:  # one candidate per program: a smaller table
        opt = take_options(opt, np.arange(40))
    f, h = _fused_and_host(opt, **kw)
    _assert_same(f, h)
    ref = brute_candidates(opt, kw.get("max_gap"))
    assert f.n_screened == len(ref) > (100 if kw.get("chunk_size") == 1 else 1500)
    pairs = list(zip(f.src.tolist(), f.dst.tolist(), strict=True))
    verdict = {p: brute_feasible(opt, LIMITS, *p) for p in ref}
    if kw.get("feasible_only"):
        assert f.feasible.all() and set(pairs) == {p for p, v in verdict.items() if v}
    else:
        assert set(pairs) == ref and len(pairs) == len(ref)
        assert [verdict[p] for p in pairs] == f.feasible.tolist()
        assert 0 < f.feasible.sum() < f.feasible.size


def test_fused_path_float32_and_process_split():
    rng = np.random.default_rng(22)
    opt64 = synthetic_options(rng, n_routes=25, per_route=4, horizon=400.0, spread=0.8)
    opt32 = RouteOptions(
        *(a.astype(np.float32) if a is not None and a.dtype == np.float64 else a for a in opt64)
    )
    # float32: the fused path against the float32 host path (T is formed in float64 and
    # cast by both, so it is bit-identical; the kernels' float32 rounding may differ in
    # the last ulp between the two programs' vectorizations)
    f, h = _fused_and_host(opt32, chunk_size=512)
    assert f.margin.dtype == np.float32 and f.src.size > 2000
    for k in ("src", "dst", "T"):
        np.testing.assert_array_equal(getattr(f, k), getattr(h, k))
    clear = np.abs(h.margin) > 1e-5
    np.testing.assert_array_equal(f.feasible[clear], h.feasible[clear])
    np.testing.assert_allclose(f.margin, h.margin, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(f.effort, h.effort, rtol=1e-5)
    # multi-process split: chunk k to process k % P; the parts add up to the whole,
    # in order, and each part equals the host path's part where chunks coincide
    whole = screen.screen_transitions(opt64, LIMITS, progress=False)
    for pc in (2, 3):
        parts = [
            screen.screen_transitions(
                opt64, LIMITS, progress=False, chunk_size=256, process_index=i, process_count=pc
            )
            for i in range(pc)
        ]
        assert sum(q.n_screened for q in parts) == whole.n_screened
        got = {}
        for q in parts:
            for row in zip(*(getattr(q, k).tolist() for k in _COLS), strict=True):
                assert row[:2] not in got
                got[row[:2]] = row
        cols = (getattr(whole, k).tolist() for k in _COLS)
        ref = {row[:2]: row for row in zip(*cols, strict=True)}
        assert got.keys() == ref.keys()
        assert all(got[p][3] == ref[p][3] for p in ref)
        np.testing.assert_allclose(
            [got[p][4] for p in ref], [ref[p][4] for p in ref], rtol=1e-12, atol=1e-15
        )


def test_x64_off_falls_back_to_the_host_path():
    import jax

    rng = np.random.default_rng(23)
    opt = synthetic_options(rng, n_routes=6, per_route=3, dtype=np.float32)
    with jax.enable_x64(False):
        tr = screen.screen_transitions(opt, LIMITS, progress=False)
    ref = screen._screen_transitions_host(opt, LIMITS, None, 2**18, False, False, 0, 1)
    np.testing.assert_array_equal(tr.src, ref.src)
    np.testing.assert_array_equal(tr.feasible, ref.feasible)


def test_sink_lazy_columns_and_list_fallback_agree():
    """The fused path's feasible_only sink writes kept rows in place into lazily
    reserved columns; without the reservation it keeps copies and concatenates."""
    rng = np.random.default_rng(24)
    chunks = [
        [
            rng.integers(0, 9, n),
            rng.integers(0, 9, n),
            rng.normal(size=n),
            rng.uniform(size=n) > 0.5,
        ]
        + [rng.normal(size=n) for _ in range(3)]
        for n in (5, 0, 7)
    ]
    lazy = transitions._Sink(12, np.float64, True, lazy=True)
    plain = transitions._Sink(12, np.float64, True)
    for c in chunks:
        lazy.add_rows(c)
        plain.add_rows(c)
    a, b = lazy.result(12), plain.result(12)
    assert lazy.cols is not None and plain.cols is None
    for x, y in zip(a[:7], b[:7], strict=True):
        np.testing.assert_array_equal(x, y)
        assert x.size == 12 and x.dtype == y.dtype


# k = 3 over one row is (1, 512)'s selection with (3, 32)'s k: a slow variant
@pytest.mark.parametrize(
    "k, chunk",
    [(1, 512), pytest.param(3, 512, marks=pytest.mark.slow), (3, 32), (1000, 512)],
)
def test_top_k_keeps_the_best_feasible_successors(k, chunk):
    """top_k equals, per source, the k largest margins among the full screen's feasible rows."""
    import jax

    opt = synthetic_options(np.random.default_rng(11), n_routes=40, per_route=5, horizon=900.0)
    full = screen.screen_transitions(opt, LIMITS, progress=False, chunk_size=512)
    # chunk 32: rows of at most 32 slots; most sources' runs (median ~90) span rows to merge
    with jax.enable_x64(False):  # the host fallback takes the same selection
        host = screen.screen_transitions(
            opt._replace(**{f: np.asarray(getattr(opt, f), np.float32) for f in
                            ("t_start", "t_end", "start_angle", "start_rate", "end_angle",
                             "end_rate", "value")}),
            LIMITS, progress=False, top_k=k,
        )  # fmt: skip
    best = screen.screen_transitions(opt, LIMITS, progress=False, chunk_size=chunk, top_k=k)
    assert best.n_screened == full.n_screened and best.feasible.all()
    want = {}
    for s_, m in zip(full.src[full.feasible], full.margin[full.feasible], strict=True):
        want.setdefault(int(s_), []).append(float(m))
    got = {}
    for s_, m in zip(best.src, best.margin, strict=True):
        got.setdefault(int(s_), []).append(float(m))
    assert got.keys() == want.keys()
    for s_, ms in want.items():
        assert got[s_] == sorted(ms, reverse=True)[:k], s_  # decreasing margins, k of them
    assert set(host.src.tolist()) <= set(want) and all(
        np.sum(host.src == s_) == min(k, len(ms)) for s_, ms in want.items()
    )
    # rows of a source stay together, sources in t_start order
    starts = np.asarray(opt.t_start)[best.src]
    assert np.all(np.diff(starts) >= 0)
    with pytest.raises(ValueError, match="top_k"):
        screen.screen_transitions(opt, LIMITS, progress=False, top_k=0)


@pytest.mark.parametrize("k", [1, 5, 16, 40, 64])
def test_row_top_k_matches_a_stable_sort(k):
    """Per-row selection equals numpy's stable descending sort (ties: lower column first),
    with picks past the row's last finite score marked not real (never duplicated)."""
    import jax

    from jaxspline.screen.fused import _row_top_k

    rng = np.random.default_rng(k)
    score = np.round(rng.normal(size=(300, 64)), 1)  # many exact ties
    score[rng.random(score.shape) < 0.6] = -np.inf
    score[:5] = -np.inf  # rows with nothing feasible
    col, real = (np.asarray(x) for x in _row_top_k(jax.numpy.asarray(score), k))
    kk = min(k, 64)
    want = np.argsort(-score, axis=1, kind="stable")[:, :kk]
    n_finite = np.isfinite(score).sum(axis=1)
    for r in range(score.shape[0]):
        m = min(kk, n_finite[r])
        assert real[r].sum() == m
        got, ref = col[r][real[r]].tolist(), want[r, :m].tolist()
        if kk == score.shape[1]:  # the whole row: a set, in column order
            got, ref = sorted(got), sorted(ref)
        assert got == ref


# both orders over rows of 32 slots (the merge across rows); one order each for k = 1 and
# for k past every source's count (the other pairs are slow variants)
@pytest.mark.parametrize(
    "k, chunk, by",
    [
        (4, 32, "value"),
        (4, 32, "density"),
        (1, 512, "value"),
        (1000, 512, "density"),
        pytest.param(1, 512, "density", marks=pytest.mark.slow),
        pytest.param(1000, 512, "value", marks=pytest.mark.slow),
    ],
)
def test_top_k_by_value_keeps_the_most_valuable_feasible_successors(k, chunk, by):
    """top_k_by="value" / "density": per source, the k feasible successors j of largest
    value[j] / value[j] per second (t_end[j] - t_end[i]) (ties: earlier destination), on
    the fused path and on the host fallback (x64 off)."""
    import jax

    rng = np.random.default_rng(5)
    opt = synthetic_options(rng, n_routes=40, per_route=5, horizon=900.0)
    opt = opt._replace(value=np.round(rng.uniform(1, 5, len(opt.route))))  # many ties

    def expected(full):
        ts, te, val = (np.asarray(x, np.float64) for x in (opt.t_start, opt.t_end, opt.value))
        out = {}
        for s_ in np.unique(full.src):
            d = full.dst[full.src == s_]
            score = val[d] if by == "value" else val[d] / (te[d] - te[s_])
            out[int(s_)] = d[np.lexsort((d, ts[d], -score))][:k].tolist()  # score desc, time
        return out

    def kept(best):
        return {int(s_): best.dst[best.src == s_].tolist() for s_ in np.unique(best.src)}

    full = screen.screen_transitions(opt, LIMITS, progress=False, feasible_only=True)
    best = screen.screen_transitions(
        opt, LIMITS, progress=False, chunk_size=chunk, top_k=k, top_k_by=by
    )
    assert kept(best) == expected(full) and best.feasible.all()
    with jax.enable_x64(False):  # the host fallback screens in float32: compare with that
        full32 = screen.screen_transitions(opt, LIMITS, progress=False, feasible_only=True)
        host = screen.screen_transitions(opt, LIMITS, progress=False, top_k=k, top_k_by=by)
    assert kept(host) == expected(full32)
    with pytest.raises(ValueError, match="top_k_by"):
        screen.screen_transitions(opt, LIMITS, progress=False, top_k=2, top_k_by="cost")
