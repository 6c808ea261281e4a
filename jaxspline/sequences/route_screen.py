"""Screening whole candidate sequences on the device.

:func:`screen_sequences` takes K candidate sequences of L option indices and
returns, per row, whether it can be flown in order, where it first fails and its
summed value. Layout of the fused path (x64 on):

* The option table goes to the devices once per call, channel-major ([C, N] per boundary
  field, as :mod:`jaxspline.screen.fused` stores it), with ``t_start`` /
  ``t_end`` in float64, dense route ids (int32), ``scan_ok`` and ``value``.
* The [K, L] sequence table goes in chunks of rows padded to a fixed shape
  (columns: L rounded up to 1/8 of its power of two; rows: ``chunk_size // (L - 1)``
  so a chunk holds ~``chunk_size`` transitions, or fewer rows, rounded up to 1/8 of
  their power of two, when everything fits in one chunk), so a search calling it
  with similar shapes compiles few programs. The chunk is sized in transitions
  because the program's intermediates are per transition: on the 2-core CPU VM,
  30,000 rows of L = 64 took 87 ms in chunks of 2**17 transitions and 144 ms in
  chunks of 2**19; at L = 20, 2**16 to 2**18 were within noise.
  JAX dispatch is asynchronous: the host pads chunk k + 1 while the devices screen
  chunk k.
* ONE compiled program per chunk forms every consecutive pair
  ``(seq[:, l - 1], seq[:, l])``, ``T = t_start[dst] - t_end[src]`` in float64 then
  cast to the table dtype (bit-identical to the host path), runs the per-channel
  kernels through the model's pair function (:mod:`jaxspline.screen.pair_models`; one call, so the
  maneuver model stays swappable) and reduces to per-row outputs. Only the three
  [K] columns come back.
* Repeated routes are found on the device by comparing every position with every
  earlier one ([L, L] per row, padded L up to ``_PAIRWISE_MAX_L``) or, for longer
  rows, by sorting each row's (route, position) pairs and comparing sorted
  neighbours (O(L log L)). Measured on chunks of 2**17 transitions (2-core CPU VM,
  best of 9): the comparison adds ~1 ms to a ~4 ms program at L = 20 and ~4 ms at
  L = 128, the sort ~10 ms at any L up to 512; the comparison loses from L = 256
  (+17 ms against +10 ms).
* Rows are sharded over the local devices (``P("cand")`` on the row axis), the
  option table is replicated.
* x64 off: T needs float64 on the device, so the host path runs instead
  (:func:`_screen_sequences_host`: pairs built with numpy and screened by
  :func:`jaxspline.screen.pairs.screen_pairs`, which forms T in float64 on the host;
  same answers).

Units: radians, seconds.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import NamedSharding
from jax.sharding import PartitionSpec as P

from jaxspline.kernels.batch import round_up
from jaxspline.kernels.validate import check_positive
from jaxspline.screen.options import RouteOptions, options_dtype
from jaxspline.screen.pair_models import model_arrays, validate_model
from jaxspline.screen.pairs import screen_pairs
from jaxspline.screen.transitions import device_mesh

__all__ = ["screen_sequences"]

#: Longest (padded) row for the [L, L] route comparison; longer rows sort.
_PAIRWISE_MAX_L = 128

#: Default transitions per compiled chunk (rows = this // (L - 1)).
_CHUNK_TRANSITIONS = 2**17


def _validate_sequences(options: RouteOptions, sequences) -> np.ndarray:
    """The [K, L] int sequence table, checked against ``options`` (N options).

    Raises:
      ValueError: not a 2-D int array, an index outside -1..N-1, or -1 padding
        before an option index in a row.
    """
    seq = np.asarray(sequences)
    if seq.ndim != 2 or not np.issubdtype(seq.dtype, np.integer):
        raise ValueError(f"sequences must be an int array [K, L], got {seq.dtype} {seq.shape}")
    n = np.shape(options.t_start)[0]
    if seq.size and (seq.min() < -1 or seq.max() >= n):
        raise ValueError(
            f"sequences must hold option indices 0..{n - 1} or -1, got {seq.min()}..{seq.max()}"
        )
    pad = seq < 0
    gap = pad[:, :-1] & ~pad[:, 1:]
    if gap.any():
        k = int(np.flatnonzero(gap.any(axis=1))[0])
        raise ValueError(
            f"sequences row {k} has -1 padding before an option index: {seq[k].tolist()}"
        )
    return seq


def _bucket(n: int, maximum: int | None = None) -> int:
    """n rounded up to 1/8 of its power of two (<= 12.5 % padding), capped at ``maximum``.

    At most 8 padded sizes per octave: few compilations.
    """
    p = 1 << (max(int(n), 1) - 1).bit_length()
    size = round_up(max(int(n), 1), max(1, p // 8))
    return size if maximum is None else min(int(maximum), size)


def _first_repeat_pairwise(rid, pad, big):
    """Per row, the first position whose route occurs earlier in the row ([L, L] compare)."""
    length = rid.shape[1]
    pos = jnp.arange(length, dtype=jnp.int32)
    same = (rid[:, :, None] == rid[:, None, :]) & ~pad[:, :, None] & ~pad[:, None, :]
    earlier = pos[None, :] < pos[:, None]  # [p, q]: q < p
    rep = (same & earlier[None]).any(axis=2)
    return jnp.min(jnp.where(rep, pos, big), axis=1)


def _first_repeat_sorted(rid, pad, big):
    """As :func:`_first_repeat_pairwise`, by sorting each row's (route, position) pairs.

    After the sort a repeated route's later positions follow its first one, so a
    sorted neighbour with the same route marks a repeat at its (larger) position.
    Padding sorts last under the key int32 max and is masked (dense route ids are
    smaller).
    """
    length = rid.shape[1]
    pos = jnp.broadcast_to(jnp.arange(length, dtype=jnp.int32), rid.shape)
    key = jnp.where(pad, jnp.iinfo(jnp.int32).max, rid)
    k_s, p_s = jax.lax.sort((key, pos), dimension=1, num_keys=2)
    dup = (k_s[:, 1:] == k_s[:, :-1]) & (k_s[:, 1:] != jnp.iinfo(jnp.int32).max)
    return jnp.min(jnp.where(dup, p_s[:, 1:], big), axis=1)


@functools.lru_cache(maxsize=16)
def _sequence_program(pair, rows: int, length: int, mesh, repeats: str):
    """jit program screening one chunk of ``rows`` x ``length`` sequences (-1 padded).

    Per row: ``fail[p]`` = option p is not padding and (``scan_ok`` false, or its
    route occurs at an earlier position, or the transition p-1 -> p is infeasible:
    T <= 0 or infeasible under the maneuver model's pair function ``pair``, see
    :mod:`jaxspline.screen.pair_models`). Returns ``(feasible
    bool [rows], first_fail int32 [rows] (-1: none), value float64 [rows])``. The
    value is summed left to right (a chain of adds, not a reduction XLA vectorizes
    per shape), so a row's value does not depend on the chunk, padding or sharding.
    ``repeats`` is ``"pairwise"`` or ``"sorted"`` (see the module docstring).
    """
    cand = NamedSharding(mesh, P("cand"))
    first_repeat = _first_repeat_pairwise if repeats == "pairwise" else _first_repeat_sorted

    def run(table, params, aux, seq):
        te, ts, rid, scan_ok, value = aux
        seq = jax.lax.with_sharding_constraint(seq, cand)
        pad = seq < 0
        s0 = jnp.where(pad, 0, seq)
        big = jnp.int32(length)
        pos = jnp.arange(length, dtype=jnp.int32)
        src, dst = s0[:, :-1], s0[:, 1:]
        live = ~pad[:, 1:]
        T = jnp.where(live, ts[dst] - te[src], 0.0).astype(table[0].dtype)
        ok = pair(table, params, src, dst, T)[0]
        step = jnp.min(jnp.where(live & ~ok, pos[1:], big), axis=1)
        scan = jnp.min(jnp.where(~pad & ~scan_ok[s0], pos, big), axis=1)
        first = jnp.minimum(jnp.minimum(step, scan), first_repeat(rid[s0], pad, big))
        first = jnp.where(first < big, first, -1)
        vals = jnp.where(pad, 0.0, value[s0])
        total = functools.reduce(jnp.add, [vals[:, p] for p in range(length)])  # in order
        return first < 0, first, total

    return jax.jit(run)


def _device_inputs(options: RouteOptions, model, mesh):
    """The arguments of a :func:`_sequence_program`, replicated on ``mesh``'s devices.

    Args:
      options: RouteOptions (validated).
      model: AxisLimits or SlewTable (validated).
      mesh: the 1-D device mesh (``screen.device_mesh()``).
    Returns:
      ``(pair, table, params, aux)``: the model's pair function, its option columns and
      parameters (:func:`~jaxspline.screen.pair_models.model_arrays`, in the options'
      dtype) and ``aux = (t_end, t_start, dense route id, scan_ok, value)``, times and
      values in float64.
    """
    rep = NamedSharding(mesh, P())

    def put(a):
        return jax.device_put(jnp.asarray(a), rep)

    _, rid = np.unique(np.asarray(options.route), return_inverse=True)
    pair, table, params = model_arrays(model, options, options_dtype(options))
    aux = (
        np.asarray(options.t_end, np.float64),
        np.asarray(options.t_start, np.float64),
        rid.reshape(-1).astype(np.int32),
        np.asarray(options.scan_ok, bool),
        np.asarray(options.value, np.float64),
    )
    return pair, tuple(map(put, table)), tuple(map(put, params)), tuple(map(put, aux))


def screen_sequences(
    options: RouteOptions, sequences, model, *, chunk_size: int = _CHUNK_TRANSITIONS
):
    """Screen K whole candidate sequences at once.

    Args:
      options: RouteOptions (N options, C channels).
      sequences: int [K, L] option indices in time order, padded with -1 at the
        end of a row.
      model: the maneuver model, as in
        :func:`~jaxspline.screen.pairs.screen_transitions`: AxisLimits (per-channel
        exact-T reach sets) or a :class:`~jaxspline.screen.slew_table.SlewTable` (rest to
        rest, tabulated eigen-axis or flexible slew with settling).
      chunk_size: transitions per compiled chunk (a chunk is
        ``max(1, chunk_size // (L - 1))`` rows; device memory ~ 100 bytes per
        transition).

    Returns:
      ``(feasible [K] bool, first_fail [K] int64, value [K] float64)``.
      ``first_fail`` is the position (0..L-1) of the first option that cannot be
      appended to the prefix before it — its ``scan_ok`` is False, its route
      already occurs in the prefix, or the transition from the previous option
      fails (T <= 0 or infeasible under the model in exactly T) — and -1 when
      the whole row is feasible. ``value`` is the summed option value of the row
      (whether or not it is feasible). An all-padding row is feasible with value 0.

    Raises:
      ValueError: invalid options or model, ``sequences`` not an int [K, L]
        array of indices in -1..N-1, -1 padding before an index in a row, or
        ``chunk_size`` not positive.

    With x64 on, the transitions are formed and screened on the device and only
    the [K] outputs come back (module docstring); with x64 off, the host path runs.
    """
    validate_model(model, options)
    check_positive("chunk_size", chunk_size)
    seq = _validate_sequences(options, sequences)
    if jax.dtypes.canonicalize_dtype(np.float64) != np.float64:  # x64 off: T needs float64
        return _screen_sequences_host(options, seq, model)
    kk, ll = seq.shape
    if kk == 0 or ll == 0:
        return np.ones(kk, bool), np.full(kk, -1, np.int64), np.zeros(kk, np.float64)
    mesh = device_mesh()
    ndev = mesh.devices.size
    cand = NamedSharding(mesh, P("cand"))
    pair, table, params, aux = _device_inputs(options, model, mesh)
    length = max(2, _bucket(ll))
    rows = round_up(_bucket(kk, max(1, int(chunk_size) // (length - 1))), ndev)
    repeats = "pairwise" if length <= _PAIRWISE_MAX_L else "sorted"
    program = _sequence_program(pair, rows, length, mesh, repeats)

    feasible = np.empty(kk, bool)
    first = np.empty(kk, np.int64)
    value = np.empty(kk, np.float64)

    def collect(p):
        k0, n, out = p
        for buf, o in zip((feasible, first, value), out, strict=True):
            buf[k0 : k0 + n] = np.asarray(o)[:n]

    pending = None
    for k0 in range(0, kk, rows):
        n = min(rows, kk - k0)
        chunk = np.full((rows, length), -1, np.int32)
        chunk[:n, :ll] = seq[k0 : k0 + n]
        nxt = (k0, n, program(table, params, aux, jax.device_put(chunk, cand)))
        if pending is not None:
            collect(pending)  # the devices screen chunk k0 meanwhile
        pending = nxt
    collect(pending)
    return feasible, first, value


def _screen_sequences_host(options: RouteOptions, seq: np.ndarray, model):
    """The host path (x64 off): numpy checks and :func:`screen_pairs` on the transitions.

    Arguments as :func:`screen_sequences`, already validated; the route repeats are
    an O(K L^2) numpy comparison and every transition's full result comes back.
    """
    kk, ll = seq.shape
    if kk == 0 or ll == 0:
        return np.ones(kk, bool), np.full(kk, -1, np.int64), np.zeros(kk, np.float64)
    pad = seq < 0
    s0 = np.where(pad, 0, seq)
    scan_ok = np.asarray(options.scan_ok, bool)[s0] | pad
    route = np.asarray(options.route)[s0]
    # repeated route: position p whose route appears at an earlier position q < p
    same = (route[:, :, None] == route[:, None, :]) & ~pad[:, :, None] & ~pad[:, None, :]
    earlier = np.tril(np.ones((ll, ll), bool), k=-1)
    repeat = (same & earlier[None]).any(axis=2)
    # transitions l -> l+1
    bad_step = np.zeros((kk, ll), bool)
    if ll > 1:
        has = ~pad[:, 1:]
        rows, cols = np.nonzero(has)
        tr = screen_pairs(options, model, seq[rows, cols], seq[rows, cols + 1])
        bad_step[rows, cols + 1] = ~tr.feasible
    fail = (~scan_ok | repeat | bad_step) & ~pad
    first = np.where(fail.any(axis=1), np.argmax(fail, axis=1), -1)
    value = np.where(pad, 0.0, np.asarray(options.value, float)[s0]).sum(axis=1)
    return first < 0, first.astype(np.int64), value
