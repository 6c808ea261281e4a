"""screen_sequences: host path vs fused device path.

``python -m bench.seqscreen [--k 100000] [--l 20] [--routes 2000] [--repeats]``

Plausible sequences on :func:`bench.scenarios.synthetic_options`: each row starts
at a random option in the first half of the pass and takes, L - 1 times, the
first option starting 2-40 s after the current one ends; a quarter of the rows is
cut short (-1 padding). Reports sequences/s and transitions/s of the host path
(``_screen_sequences_host`` with the validation, i.e. the former implementation)
and of :func:`screen_sequences`, compile excluded, median of 3. ``--repeats``
times the chunk program with the two route-repeat strategies at several L.
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

from bench.scenarios import HORIZON_S, synthetic_options  # noqa: E402


def plausible_sequences(opts, k: int, length: int, seed: int = 0) -> np.ndarray:
    """[k, length] option indices in time order (see the module docstring)."""
    rng = np.random.default_rng(seed)
    ts = np.asarray(opts.t_start)
    te = np.asarray(opts.t_end)
    order = np.argsort(ts, kind="stable")
    ts_sorted = ts[order]
    cur = order[rng.integers(0, order.size // 2, k)]
    seq = np.empty((k, length), np.int64)
    seq[:, 0] = cur
    for p in range(1, length):
        at = np.searchsorted(ts_sorted, te[cur] + rng.uniform(2.0, 40.0, k))
        cur = order[np.minimum(at, order.size - 1)]
        seq[:, p] = cur
    short = rng.uniform(size=k) < 0.25
    cut = rng.integers(1, length + 1, k)
    seq[short[:, None] & (np.arange(length)[None, :] >= cut[:, None])] = -1
    return seq


def _median_time(fn, reps: int = 3) -> float:
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def compare(k: int, length: int, routes: int) -> dict:
    """Seconds, sequences/s and transitions/s of the host and the fused path."""
    import importlib

    mod = importlib.import_module("jaxspline.sequences.route_screen")
    opts, limits = synthetic_options(routes)
    seq = plausible_sequences(opts, k, length)
    n_tr = int((seq[:, 1:] >= 0).sum())

    def old():
        return mod._screen_sequences_host(opts, mod._validate_sequences(opts, seq), limits)

    def new():
        return mod.screen_sequences(opts, seq, limits)

    a, b = old(), new()  # compile (both) and agreement
    assert all(np.array_equal(x, y) for x, y in zip(a[:2], b[:2], strict=True))
    np.testing.assert_allclose(a[2], b[2], rtol=1e-13)
    out = {
        "K": k,
        "L": length,
        "options": len(opts.route),
        "transitions": n_tr,
        "feasible_rows": int(a[0].sum()),
        "first_fail_hist": np.bincount(a[1] + 1).tolist(),
    }
    for name, fn in (("old", old), ("new", new)):
        s = _median_time(fn)
        out[name] = {"s": s, "seq_per_s": k / s, "tr_per_s": n_tr / s}
    out["speedup"] = out["old"]["s"] / out["new"]["s"]
    return out


def repeats(k: int, routes: int, lengths=(8, 20, 64, 128)) -> dict:
    """Seconds of one chunk program over K rows per route-repeat strategy and L."""
    import importlib

    import jax.numpy as jnp

    mod = importlib.import_module("jaxspline.sequences.route_screen")
    from jaxspline.screen.transitions import device_mesh

    opts, limits = synthetic_options(routes)
    pair, table, params, aux = mod._device_inputs(opts, limits, device_mesh())
    res = {}
    for length in lengths:
        seq = jnp.asarray(plausible_sequences(opts, k, length).astype(np.int32))
        for how in ("pairwise", "sorted"):
            prog = mod._sequence_program(pair, k, length, device_mesh(), how)
            jax.block_until_ready(prog(table, params, aux, seq))
            res[f"L={length} {how}"] = _median_time(
                lambda p=prog, s=seq: jax.block_until_ready(p(table, params, aux, s))
            )
    return res


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m bench.seqscreen", description=__doc__)
    p.add_argument("--k", type=int, default=100_000)
    p.add_argument("--l", type=int, default=20)
    p.add_argument("--routes", type=int, default=2000)
    p.add_argument("--repeats", action="store_true", help="time the route-repeat strategies")
    a = p.parse_args(argv)
    if a.repeats:
        for key, s in repeats(a.k // 4, a.routes).items():
            print(f"{key:>16}: {s * 1e3:8.1f} ms")
        return
    r = compare(a.k, a.l, a.routes)
    print({k: v for k, v in r.items() if k not in ("old", "new")})
    for name in ("old", "new"):
        q = r[name]
        print(
            f"{name}: {q['s']:.3f} s  {q['seq_per_s']:.3g} seq/s  {q['tr_per_s']:.3g} transitions/s"
        )
    print(f"speedup {r['speedup']:.1f}x  (horizon {HORIZON_S} s)")


if __name__ == "__main__":
    main()
