"""Satellite sweeps: each satellite's observations replaced by its best path alone.

A plan built target by target (the greedy start, a repaired plan) leaves each
satellite's timeline far from the best one that satellite could fly over the targets
the others leave it. :func:`sweep` computes, in one pass of the bound's per-satellite
DP (:func:`jaxspline.search.dp.dp_paths`), every satellite's maximum-value sequence
over its options of targets that no *other* satellite images (its own included,
repeats in a row credited once), and then, satellite by satellite in random order,
replaces the satellite's observations by that path when the path is worth more:

* the path's options are inserted with the timeline's full check (maneuvers, battery);
  an option of a target imaged meanwhile (by a satellite swept earlier in the round, or
  by the path itself) is skipped;
* on a satellite whose battery has a rule, the path ignores energy, so its options go in
  by value per Wh (imaging plus the maneuver from the path's predecessor), not in time
  order: what the battery refuses is what pays least for its energy;
* the satellite keeps the new timeline only when the plan's score did not drop.

So a sweep never lowers the plan's score, and one round costs one DP over all
satellites plus the insertions. :func:`sweeps` repeats rounds until one gains nothing
(or, in a time-limited run, too little for its time).
On the unseen 12 x 12 h instance (367 k options) the first rounds (0.3 s each) from a
greedy start gain 10-15 % of the plan's value per second, an LNS from the same start
~1 %: nine rounds (the last below the rate) take it from 34,133 to 39,382 in 2.8 s. On
the constellation day the first round from a greedy start gains only 0.22 %/s, about the
LNS's pace. From the empty plan the rounds build a better start than the greedy on both
(:func:`jaxspline.search.solve`, stage 1: 40,023 and 83,464 before its greedy fill).
"""

from __future__ import annotations

import math
import time

import numpy as np

from jaxspline.base import clock
from jaxspline.search.dp import DPData, dp_paths
from jaxspline.search.lns_energy import option_wh
from jaxspline.search.timeline import Timeline

__all__ = ["sweep", "sweeps"]

_MIN_WH = 1e-9  # [Wh] floor of an energy in a value-per-Wh ratio
_MAX_ROUNDS = 30  # rounds of :func:`sweeps` at most (the gains fall fast: ~10 on large plans)
#: a time-limited run's sweeps stop at a round that gained less than this share of the
#: plan's value per second: the LNS's pace a few seconds into it from the same greedy
#: start (0.45-0.55 %/s on the unseen and the preset 12 x 12 h instances; on the
#: constellation day the first round already pays only 0.22 %/s, about the LNS's rate)
_MIN_RATE = 0.005


def _offered(tl: Timeline) -> np.ndarray | None:
    """bool [N], the options on offer in ``tl`` (None: all of them)."""
    pb = tl.pb
    if tl.target_options is pb.target_options:
        return None
    mask = np.zeros(pb.n_options, bool)
    ids = [c for opts in tl.target_options for c in opts]
    mask[np.asarray(ids, np.int64)] = True
    return mask


def _weights(tl: Timeline, d: DPData, offered) -> np.ndarray:
    """Option values of the sweep's DP: the target's value where no other satellite
    images it and the option is on offer, else a value below any path's (the options'
    targets and satellites from the DP layout ``d``, not the problem's lists); area
    options are shut (their moves are :mod:`jaxspline.search.area_moves`')."""
    tv = np.asarray(tl.pb.target_value, np.float64)
    ot, osat = d.target, d.sat
    area = ot >= tv.size  # area options (their own DP numbers): the area moves' business
    if area.any():
        ot = np.where(area, 0, ot)
    assigned = np.asarray(tl.assigned, np.int64)
    owner = np.where(assigned >= 0, osat[np.maximum(assigned, 0)], -1)[ot]
    ok = ((owner < 0) | (owner == osat)) & ~area
    if offered is not None:
        ok &= offered
    # never on a best path: a path through it is worth less than the empty one
    shut = -(float(tv.sum()) + 1.0)
    return np.where(ok, tv[ot], shut)


def _energy_order(tl: Timeline, k: int, path: list) -> list:
    """The options of satellite k's path by value per Wh (imaging + maneuver from the
    path's predecessor), most first; ties keep time order."""
    pb = tl.pb
    keys = []
    for i, c in enumerate(path):
        man = pb.option_first[c] if i == 0 else tl.need(path[i - 1], c)
        wh = option_wh(pb, c, man)
        keys.append(-pb.target_value[pb.option_target[c]] / max(wh, _MIN_WH))
    return [path[i] for i in sorted(range(len(path)), key=keys.__getitem__)]


def sweep(tl: Timeline, d: DPData, rng, offered=None) -> float:
    """One round over every satellite (module docstring); returns the value gained.

    Args:
      tl: Timeline, changed in place (its log committed).
      d: the problem's :func:`jaxspline.search.dp.dp_prepare`.
      rng: ``random.Random``: the order of the satellites.
      offered: bool [N] options on offer, as :func:`sweeps` finds them (None: computed).
    Returns:
      float, the plan's value after the round minus before (>= 0 unless the count or
      the end-time tie-break paid for it).
    """
    pb = tl.pb
    if offered is None:
        offered = _offered(tl)
    paths, vals = dp_paths(pb, d, _weights(tl, d, offered), merge_repeats=True)
    v0 = tl.value
    sats = list(range(pb.n_sats))
    rng.shuffle(sats)
    tl.commit()
    for k in sats:
        own = sum(pb.target_value[pb.option_target[c]] for c in tl.lines[k] if not pb.is_closed(c))
        if vals[k] <= own or not paths[k]:
            continue
        base = tl.score()
        for c in [c for c in tl.lines[k] if not pb.is_closed(c)]:
            tl.remove(c)
        path = paths[k]
        if pb.battery.has(k):
            path = _energy_order(tl, k, path)
        for c in path:
            if tl.check(c) is not None:
                tl.insert(c)
        if tl.score() < base:
            tl.undo_to(0)
        tl.commit()
    return tl.value - v0


def sweeps(
    tl: Timeline,
    d: DPData,
    deadline: float,
    rng,
    max_rounds: int = _MAX_ROUNDS,
    min_rate: float = _MIN_RATE,
) -> int:
    """Sweep rounds until one gains nothing, ``max_rounds`` or the deadline; with a finite
    deadline also once a round gained less than ``min_rate`` of the plan's value per
    second of it (the LNS's pace then beats the sweeps'). With an infinite one
    (iteration-capped runs) the rounds do not depend on the clock.

    Args:
      tl: Timeline, changed in place.
      d: the problem's :func:`jaxspline.search.dp.dp_prepare`.
      deadline: float, ``time.monotonic()`` value after which no round starts [s].
      rng: ``random.Random``.
      max_rounds: cap on the rounds.
      min_rate: share of the plan's value per second below which a time-limited run's
        rounds stop (default :data:`_MIN_RATE`).
    Returns:
      int, the rounds run.
    """
    offered = _offered(tl)
    rounds = 0
    while rounds < max_rounds and clock.now() < deadline:
        rounds += 1
        t0 = time.monotonic()
        gain = sweep(tl, d, rng, offered)
        if gain <= 0.0:
            break
        if math.isfinite(deadline) and gain < min_rate * tl.value * (time.monotonic() - t0):
            break
    return rounds
