"""screen_sequences (fused device path) against the former host implementation and a
numpy brute force through the public :func:`jaxspline.kernels.reach.is_reachable`."""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys
import textwrap

import jax
import numpy as np
import pytest
from test_screen import LIMITS, synthetic_options

import jaxspline
from jaxspline.kernels import reach
from jaxspline.screen import pairs as screen
from jaxspline.screen.options import RouteOptions

# the module (``jaxspline.sequences.route_screen`` is the function after the re-export)
seqmod = importlib.import_module("jaxspline.sequences.route_screen")


def reference_screen_sequences(options, sequences, limits):
    """The implementation before the fused path: the module's host path (numpy checks
    and ``screen_pairs`` per transition), the one x64-off calls run."""
    return seqmod._screen_sequences_host(options, np.asarray(sequences), limits)


def brute_force(options, sequences, limits):
    """Row by row in Python; each transition's verdict from ``reach.is_reachable`` (all
    channels, T = t_start[j] - t_end[i] in float64, T <= 0 infeasible). Returns
    (feasible, first_fail, value, reason) with reason in {"", "scan", "route", "T", "reach"}."""
    ts = np.asarray(options.t_start, np.float64)
    te = np.asarray(options.t_end, np.float64)
    seq = np.asarray(sequences)
    pairs = {
        (int(a), int(b)) for row in seq for a, b in zip(row[:-1], row[1:], strict=True) if b >= 0
    }
    pairs = sorted(pairs)
    ok = {}
    if pairs:
        i, j = np.array(pairs).T
        T = ts[j] - te[i]
        lim = _per_channel(limits)
        r = np.asarray(
            reach.is_reachable(
                np.asarray(options.end_angle)[i],
                np.asarray(options.end_rate)[i],
                np.asarray(options.start_angle)[j],
                np.asarray(options.start_rate)[j],
                np.where(T > 0, T, 1.0)[:, None],
                lim,
            )
        ).all(axis=1)
        ok = {p: bool(v and t > 0) for p, v, t in zip(pairs, r, T, strict=True)}
        tpos = {p: bool(t > 0) for p, t in zip(pairs, T, strict=True)}
    feas, first, value, reason = [], [], [], []
    for row in seq:
        f, why, v = -1, "", 0.0
        for p, o in enumerate(row):
            if o < 0:
                break
            v += float(options.value[o])
            if f >= 0:
                continue
            if not options.scan_ok[o]:
                f, why = p, "scan"
            elif options.route[o] in [options.route[q] for q in row[:p]]:
                f, why = p, "route"
            elif p > 0 and not ok[(int(row[p - 1]), int(o))]:
                f, why = p, ("reach" if tpos[(int(row[p - 1]), int(o))] else "T")
        feas.append(f < 0)
        first.append(f)
        value.append(v)
        reason.append(why)
    return np.array(feas, bool), np.array(first, np.int64), np.array(value), reason


def _per_channel(limits):
    """Limits broadcasting against [M, C] arrays (one per channel on the last axis)."""
    return limits._replace(
        rate=np.asarray(limits.rate)[None, :], accel=np.asarray(limits.accel)[None, :]
    )


def _options(seed=31, dtype=np.float64):
    rng = np.random.default_rng(seed)
    opt = synthetic_options(rng, n_routes=30, per_route=4, horizon=500.0, spread=0.8, dtype=dtype)
    return opt._replace(scan_ok=rng.uniform(size=len(opt.route)) > 0.08)


def _sequences(opt, k=3000, length=8, seed=32):
    """Random time-ordered walks with random lengths, planted feasible rows (walks on
    the feasible transitions), repeated routes, scan_ok false, T <= 0, all-padding rows."""
    rng = np.random.default_rng(seed)
    n = len(opt.route)
    ts, te = np.asarray(opt.t_start, float), np.asarray(opt.t_end, float)
    order = np.argsort(ts)
    tr = screen.screen_transitions(opt, LIMITS, progress=False, feasible_only=True)
    succ = {}
    for s_, d_ in zip(tr.src.tolist(), tr.dst.tolist(), strict=True):
        succ.setdefault(s_, []).append(d_)
    seq = np.full((k, length), -1, np.int64)
    kind = rng.integers(0, 6, k)
    for r in range(k):
        m = int(rng.integers(0, length + 1))
        if kind[r] == 0 and succ:  # planted: a random walk over feasible transitions
            cur = int(rng.choice(list(succ)))
            row, routes = [cur], {int(opt.route[cur])}
            while len(row) < max(m, 2):
                nxt = [d for d in succ.get(cur, []) if int(opt.route[d]) not in routes]
                if not nxt:
                    break
                cur = int(rng.choice(nxt))
                row.append(cur)
                routes.add(int(opt.route[cur]))
        elif kind[r] == 1:  # uniform random indices (mostly T <= 0)
            row = rng.integers(0, n, m).tolist()
        else:  # time-ordered walk, next start 0-60 s after the end
            cur = int(rng.integers(0, n))
            row = [cur]
            while len(row) < m:
                at = np.searchsorted(ts[order], te[cur] + rng.uniform(-5.0, 60.0))
                cur = int(order[min(at, n - 1)])
                row.append(cur)
        row = row[:length]
        if kind[r] == 3 and len(row) >= 2:  # plant a repeated route
            p = int(rng.integers(1, len(row)))
            q = int(rng.integers(0, p))
            same = np.flatnonzero(opt.route == opt.route[row[q]])
            row[p] = int(rng.choice(same))
        if kind[r] == 4 and len(row) >= 2:  # swap neighbours: T <= 0
            p = int(rng.integers(1, len(row)))
            row[p - 1], row[p] = row[p], row[p - 1]
        seq[r, : len(row)] = row
    seq[rng.uniform(size=k) < 0.02] = -1  # all-padding rows
    return seq


def _assert_same(got, want, exact_value=False):
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
    assert got[0].dtype == bool and got[1].dtype == np.int64 and got[2].dtype == np.float64
    if exact_value:
        np.testing.assert_array_equal(got[2], want[2])
    else:  # numpy's pairwise sum (the former implementation) rounds differently
        np.testing.assert_allclose(got[2], want[2], rtol=1e-14, atol=0)


# ----------------------------------------------------------------------------
# tests
# ----------------------------------------------------------------------------


def test_equals_former_implementation_and_brute_force():
    opt = _options()
    seq = _sequences(opt)
    got = seqmod.screen_sequences(opt, seq, LIMITS)
    _assert_same(got, reference_screen_sequences(opt, seq, LIMITS))
    feas, first, value, reason = brute_force(opt, seq, LIMITS)
    _assert_same(got, (feas, first, value), exact_value=True)  # both sum left to right
    # every failure kind and enough feasible multi-option rows are exercised
    kinds = {w: reason.count(w) for w in ("", "scan", "route", "T", "reach")}
    assert min(kinds.values()) >= 50, kinds
    lengths = (seq >= 0).sum(axis=1)
    assert np.sum(feas & (lengths >= 3)) >= 100 and np.sum(lengths == 0) >= 30
    assert set(range(6)) <= set(first[~feas].tolist())


@pytest.mark.parametrize("chunk_size", [1, 50, 7 * 37])
def test_chunk_boundaries(chunk_size):
    """Chunks of 1, 7 and 37 rows (L = 8: 7 transitions per row); K not a multiple."""
    opt = _options()
    seq = _sequences(opt, k=300 if chunk_size == 1 else 1001)
    got = seqmod.screen_sequences(opt, seq, LIMITS, chunk_size=chunk_size)
    _assert_same(got, seqmod.screen_sequences(opt, seq, LIMITS))
    _assert_same(got, reference_screen_sequences(opt, seq, LIMITS))


def test_sorted_route_repeats_equal_pairwise(monkeypatch):
    """Long rows sort (route, position) per row instead of the [L, L] comparison."""
    opt = _options()
    seq = _sequences(opt, k=500, length=12)
    pairwise = seqmod.screen_sequences(opt, seq, LIMITS)
    monkeypatch.setattr(seqmod, "_PAIRWISE_MAX_L", 4)
    _assert_same(seqmod.screen_sequences(opt, seq, LIMITS), pairwise, exact_value=True)
    _assert_same(pairwise, reference_screen_sequences(opt, seq, LIMITS))


def test_short_and_empty_tables():
    opt = _options()
    bad = int(np.flatnonzero(~opt.scan_ok)[0])
    good = int(np.flatnonzero(opt.scan_ok)[0])
    one = np.array([[good], [bad], [-1]])  # L = 1: only scan_ok can fail
    got = seqmod.screen_sequences(opt, one, LIMITS)
    _assert_same(got, reference_screen_sequences(opt, one, LIMITS), exact_value=True)
    np.testing.assert_array_equal(got[1], [-1, 0, -1])
    np.testing.assert_array_equal(got[2], [opt.value[good], opt.value[bad], 0.0])
    empty = np.full((5, 6), -1)
    feas, first, value = seqmod.screen_sequences(opt, empty, LIMITS)
    assert feas.all() and (first == -1).all() and (value == 0).all()
    for shape in ((0, 4), (3, 0)):
        feas, first, value = seqmod.screen_sequences(opt, np.zeros(shape, np.int64), LIMITS)
        assert feas.shape == first.shape == value.shape == (shape[0],) and feas.all()


def test_float32_tables_and_x64_off():
    """float32 tables: T formed in float64 then cast, as the host path; x64 off runs
    the host path (same answers)."""
    opt64 = _options()
    opt32 = RouteOptions(
        *(a.astype(np.float32) if a is not None and a.dtype == np.float64 else a for a in opt64)
    )
    seq = _sequences(opt64, k=2000)
    got = seqmod.screen_sequences(opt32, seq, LIMITS)
    want = reference_screen_sequences(opt32, seq, LIMITS)
    _assert_same(got, want)
    with jax.enable_x64(False):
        off = seqmod.screen_sequences(opt32, seq, LIMITS)
        off_ref = reference_screen_sequences(opt32, seq, LIMITS)
    _assert_same(off, off_ref, exact_value=True)
    np.testing.assert_array_equal(off[1], got[1])


def test_public_names_and_value_errors():
    f = seqmod.screen_sequences
    assert jaxspline.sequences.screen_sequences is f
    assert not hasattr(jaxspline.screen, "screen_sequences")  # one home: the toolkit
    assert not hasattr(screen, "screen_sequences")
    opt = _options()
    for bad, match in (
        (np.array([[0, -1, 1]]), "row 0 has -1 padding"),
        (np.array([[0, len(opt.route)]]), "sequences must hold option indices"),
        (np.array([[0, -2]]), "sequences must hold option indices"),
        (np.array([0, 1]), r"int array \[K, L\]"),
        (np.array([[0.0, 1.0]]), r"int array \[K, L\]"),
    ):
        with pytest.raises(ValueError, match=match):
            f(opt, bad, LIMITS)
    with pytest.raises(ValueError, match="chunk_size"):
        f(opt, np.array([[0, 1]]), LIMITS, chunk_size=0)
    with pytest.raises(ValueError, match="limits"):
        f(opt, np.array([[0, 1]]), LIMITS._replace(accel=np.array([0.01, -1.0])))
    with pytest.raises(ValueError, match="t_end"):
        f(opt._replace(t_end=opt.t_start - 1.0), np.array([[0, 1]]), LIMITS)


_SHARD_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import jax
    jax.config.update("jax_enable_x64", True)
    sys.path[:0] = [{tests!r}, {screen_tests!r}]
    import test_route_screen as t
    opt = t._options()
    seq = t._sequences(opt, k=999)
    feas, first, value = t.seqmod.screen_sequences(opt, seq, t.LIMITS, chunk_size=7 * 50)
    print(json.dumps({{"ndev": jax.local_device_count(), "feasible": feas.tolist(),
                      "first": first.tolist(), "value": value.tolist()}}))
    """
)


# the same kind of check as tests/screen/test_screen.py's four-device screen (kept there)
@pytest.mark.slow
def test_rows_sharded_over_four_devices():
    """Rows split over 4 CPU devices (chunks of 52 rows, rounded to 4): same answers."""
    env = dict(os.environ)
    env["XLA_FLAGS"] = f"{env['XLA_FLAGS']} --xla_force_host_platform_device_count=4"
    env["JAX_PLATFORMS"] = "cpu"
    here = os.path.dirname(__file__)
    script = _SHARD_SCRIPT.format(tests=here, screen_tests=os.path.join(here, "..", "screen"))
    out = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["ndev"] == 4
    opt = _options()
    want = seqmod.screen_sequences(opt, _sequences(opt, k=999), LIMITS)
    _assert_same(
        (np.array(got["feasible"]), np.array(got["first"], np.int64), np.array(got["value"])),
        want,
        exact_value=True,
    )
