"""screen_chunks: the streamed screen equals screen_transitions and keeps its order contract."""

from __future__ import annotations

import jax
import numpy as np
import pytest
from test_screen import LIMITS, synthetic_options

from jaxspline.screen import pairs as screen

_COLS = ("src", "dst", "T", "feasible", "margin", "effort", "t_min")
_FLOATS = ("t_start", "t_end", "start_angle", "start_rate", "end_angle", "end_rate", "value")


def _concat(chunks):
    chunks = list(chunks)
    assert all(isinstance(c, screen.Transitions) for c in chunks)
    cols = {k: np.concatenate([getattr(c, k) for c in chunks]) for k in _COLS}
    return chunks, cols, sum(c.n_screened for c in chunks)


def _time_rank(opt):
    valid = np.flatnonzero(np.asarray(opt.scan_ok, bool))
    order = valid[np.argsort(np.asarray(opt.t_start)[valid], kind="stable")]
    rank = np.full(len(opt.t_start), -1, np.int64)
    rank[order] = np.arange(order.size)
    return rank


def _check_order(opt, chunks, cols, top_k):
    rank = _time_rank(opt)
    r_src = rank[cols["src"]]
    assert np.all(r_src >= 0) and np.all(np.diff(r_src) >= 0)  # grouped, sources in time order
    same = np.diff(r_src) == 0
    if top_k is None:  # destinations in (t_start, index) order within a source
        assert np.all(np.diff(rank[cols["dst"]])[same] > 0)
    else:  # merged best rows: decreasing margin, each source in exactly one chunk
        assert np.all(np.diff(cols["margin"])[same] <= 0)
        owner = [set(np.unique(c.src).tolist()) for c in chunks]
        for a in range(len(owner)):
            for b in range(a + 1, len(owner)):
                assert not owner[a] & owner[b]


_CHUNK_KW = [
    {},
    {"feasible_only": False},
    {"feasible_only": False, "chunk_size": 8},
    {"max_gap": 80.0, "chunk_size": 1},
    {"max_gap": 80.0, "feasible_only": False, "chunk_size": 37},
    {"top_k": 1, "chunk_size": 8},
    {"top_k": 3, "chunk_size": 64},
    {"top_k": 2, "max_gap": 120.0, "chunk_size": 2},
    {"top_k": 500},
]
# float32 (x64 off) runs the same code at another dtype: three option sets (plain, gap
# with odd chunks, top_k with a gap over tiny chunks) by default, the rest as slow variants
_F32_DEFAULT = (0, 4, 7)


@pytest.mark.parametrize(
    "kw, x64",
    [(kw, True) for kw in _CHUNK_KW]
    + [
        pytest.param(kw, False, marks=() if i in _F32_DEFAULT else pytest.mark.slow)
        for i, kw in enumerate(_CHUNK_KW)
    ],
)
def test_chunks_concatenate_to_screen_transitions(kw, x64):
    rng = np.random.default_rng(31)
    opt = synthetic_options(rng, n_routes=14, per_route=4, horizon=500.0, spread=0.8)
    opt = opt._replace(scan_ok=rng.uniform(size=len(opt.route)) > 0.1)
    if kw.get("chunk_size", 64) < 8:
        opt = opt._replace(scan_ok=opt.scan_ok & (np.arange(len(opt.route)) < 30))
    if not x64:
        opt = opt._replace(**{f: np.asarray(getattr(opt, f), np.float32) for f in _FLOATS})
    with jax.enable_x64(x64):
        chunks, cols, n = _concat(screen.screen_chunks(opt, LIMITS, progress=False, **kw))
        kw.setdefault("feasible_only", True)  # the default of screen_chunks
        ref = screen.screen_transitions(opt, LIMITS, progress=False, **kw)
    assert n == ref.n_screened > 0
    for k in _COLS:
        np.testing.assert_array_equal(cols[k], getattr(ref, k), err_msg=k)
        assert cols[k].dtype == getattr(ref, k).dtype, k
    if kw.get("chunk_size", 2**18) <= 8:
        assert len(chunks) > 1
    assert ref.feasible.any()
    _check_order(opt, chunks, cols, kw.get("top_k"))


def test_chunks_span_sources_and_are_lazy_but_validate_eagerly():
    rng = np.random.default_rng(32)
    opt = synthetic_options(rng, n_routes=10, per_route=4, horizon=300.0)
    it = screen.screen_chunks(opt, LIMITS, progress=False, feasible_only=False, chunk_size=4)
    first = next(it)
    rest = list(it)
    src = [c.src for c in [first, *rest] if c.src.size]
    # a source whose run is longer than a chunk continues in the next chunk
    assert any(a[-1] == b[0] for a, b in zip(src, src[1:], strict=False))
    with pytest.raises(ValueError, match="max_gap"):
        screen.screen_chunks(opt, LIMITS, max_gap=0.0)
    with pytest.raises(ValueError, match="top_k"):
        screen.screen_chunks(opt, LIMITS, top_k=0)
    with pytest.raises(ValueError, match="model"):
        screen.screen_chunks(opt, object())


def test_no_candidates_yields_empty_chunks():
    opt = synthetic_options(np.random.default_rng(2), n_routes=1, per_route=3)
    chunks = list(screen.screen_chunks(opt, LIMITS, progress=False, feasible_only=False))
    assert all(c.src.size == 0 and c.n_screened == 0 for c in chunks)
    lone = opt._replace(scan_ok=np.arange(len(opt.route)) == 0)  # one valid option: no slot
    assert list(screen.screen_chunks(lone, LIMITS, progress=False)) == []


def test_release_keeps_a_small_screens_programs_and_drops_a_large_ones():
    from jaxspline.screen import fused

    rng = np.random.default_rng(5)
    opt = synthetic_options(rng, n_routes=6, per_route=3, horizon=300.0)
    ref = screen.screen_transitions(opt, LIMITS, progress=False)
    held = fused._fused_program.cache_info().currsize
    assert held > 0
    fused.release_programs(fused._MIN_TABLE)  # a small screen: every one pads to this size
    assert fused._fused_program.cache_info().currsize == held
    again = screen.screen_transitions(opt, LIMITS, progress=False)  # the same programs
    assert fused._fused_program.cache_info().hits > 0
    np.testing.assert_array_equal(again.feasible, ref.feasible)
    fused.release_programs(fused._MIN_TABLE + 1)
    assert fused._fused_program.cache_info().currsize == 0
    fused.release_programs()
    assert fused._compact_program.cache_info().currsize == 0


def test_the_default_chunk_follows_the_devices_platform(monkeypatch):
    """None picks 2**18 candidates on a CPU and 2**22 on an accelerator (a device whose
    platform is not "cpu"); a chunk given is kept, and a bad one is named."""
    from types import SimpleNamespace

    from jaxspline.screen import transitions

    assert transitions.default_chunk_size() == 2**18  # the tests run on the CPU
    assert transitions.default_chunk_size(4096) == 4096
    gpu = [SimpleNamespace(platform="gpu")]
    monkeypatch.setattr(transitions.jax, "local_devices", lambda: gpu)
    assert transitions.default_chunk_size() == 2**22
    monkeypatch.undo()
    opt = synthetic_options(np.random.default_rng(3), n_routes=6, per_route=2)
    with pytest.raises(ValueError, match="chunk_size"):
        screen.screen_transitions(opt, LIMITS, chunk_size=0, progress=False)
