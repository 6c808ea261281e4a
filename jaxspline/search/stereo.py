"""Stereo products in the search: which looks make a product, and what a plan's looks are worth.

A stereo target is imaged by *looks* (options of the problem whose target is the stereo
target); its value counts once, when every look of one of its *products* (a valid pair
or triple, :mod:`jaxspline.screen.stereo_products`) is in the plan, and then it is the
best such product's value. :class:`ProductTable` holds the products as the search reads
them; :class:`ProductCounts` follows a plan's looks (per product how many of its looks
are in) and gives the value change of adding or removing one look, as
:class:`jaxspline.search.cover.CoverCounts` does for area samples.

A look alone is worth nothing, so the search places and removes the looks of a product
together: :meth:`jaxspline.search.timeline.Timeline.insert_choices` offers a stereo
target's products (as :func:`product_code` candidates) and
:meth:`~jaxspline.search.timeline.Timeline.insert` of such a code inserts the product's
missing looks.

A product's value is weighed by its *confidence*, the chance that the benchmark's
random overlap estimate finds it valid; a failed estimate takes the product out. At the
end of a search :func:`add_backups` therefore gives a target whose collected products
could all fail (more than :data:`BACKUP_FAIL`) the looks of further products that fit
without removing anything: each product's estimate is seeded apart, so the target is
lost only when every one of them fails.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "BACKUP_FAIL",
    "ProductCounts",
    "add_backups",
    "fail_chance",
    "ProductTable",
    "drop_stray_looks",
    "upgrade_product",
    "is_product_code",
    "missing_looks",
    "product_choices",
    "product_code",
    "product_of",
]

#: A stereo target whose complete products all fail their overlap estimates with at
#: most this chance gets no backup product (:func:`add_backups`).
BACKUP_FAIL = 0.01


def product_code(p: int) -> int:
    """The candidate id of product p in insertion choices (negative: never an option id
    and never -1)."""
    return -2 - int(p)


def product_of(code: int) -> int:
    """The product of a candidate id made by :func:`product_code`."""
    return -2 - int(code)


def is_product_code(c: int) -> bool:
    """Whether the candidate id ``c`` stands for a product."""
    return c <= -2


@dataclass
class ProductTable:
    """The products of a problem's stereo targets.

    Attributes:
      looks: per product its look (option) ids, a tuple of 2 or 3.
      target: int64 [P], each product's target.
      value: float64 [P], the value the product's target collects with it.
      option_target: int64 [N], the problem's target of every option.
      stereo_targets: int64 [T'], the stereo targets (their options are looks).
      n_targets: number of targets of the problem.
      rank: float64 [P] in [0, 1], how good each product is among its target's (the
        insertion prefers higher ones; None: by value).
      confidence: float64 [P] in [0, 1], the chance that each product's overlap
        estimate passes (None: 1, every product sure).
      look_products: per option the products that use it (empty for other options;
        derived).
      target_products: per target its products by decreasing value (derived; empty for
        other targets).
      is_look: bool [N], options that are looks of a stereo target (derived).
      top_rank: float64 [T], each target's best product rank (derived; 0 without one).
    """

    looks: list
    target: np.ndarray
    value: np.ndarray
    option_target: np.ndarray
    stereo_targets: np.ndarray
    n_targets: int
    rank: np.ndarray | None = None
    confidence: np.ndarray | None = None
    look_products: list = field(init=False)
    target_products: list = field(init=False)
    is_look: np.ndarray = field(init=False)
    top_rank: np.ndarray = field(init=False)

    def __post_init__(self):
        self.target = np.asarray(self.target, np.int64)
        self.value = np.asarray(self.value, np.float64)
        top = float(self.value.max()) if self.value.size else 1.0
        rank = self.value / top if self.rank is None and top > 0 else self.rank
        self.rank = np.asarray(np.ones(self.value.size) if rank is None else rank, np.float64)
        conf = np.ones(self.value.size) if self.confidence is None else self.confidence
        self.confidence = np.clip(np.asarray(conf, np.float64), 0.0, 1.0)
        self.looks = [tuple(int(c) for c in lk) for lk in self.looks]
        if not (len(self.looks) == self.target.size == self.value.size):
            raise ValueError("ProductTable: looks, target and value need one entry a product")
        self.option_target = np.asarray(self.option_target, np.int64)
        self.stereo_targets = np.asarray(self.stereo_targets, np.int64)
        self.look_products = [[] for _ in range(self.option_target.size)]
        for p, lk in enumerate(self.looks):
            for c in lk:
                self.look_products[c].append(p)
        self.target_products = [[] for _ in range(self.n_targets)]
        for p in np.lexsort((np.arange(self.target.size), -self.value)).tolist():
            self.target_products[int(self.target[p])].append(p)
        self.is_look = np.isin(self.option_target, self.stereo_targets)
        self.top_rank = np.zeros(self.n_targets)
        np.maximum.at(self.top_rank, self.target, self.rank)

    def __len__(self) -> int:
        return int(self.target.size)

    def best_value(self, t: int) -> float:
        """The most target t can collect (its best product's value; 0 without one)."""
        ps = self.target_products[t]
        return float(self.value[ps[0]]) if ps else 0.0


class ProductCounts:
    """Per product the number of its looks a plan holds; per stereo target the product
    it collects (the most valuable complete one).

    Args:
      table: the problem's :class:`ProductTable`.

    Attributes:
      table: the ProductTable.
      present: int [P], looks of each product in the plan.
      best: per target its collected product (-1: none).
    """

    def __init__(self, table: ProductTable):
        self.table = table
        self.present = [0] * len(table)
        self.best = [-1] * table.n_targets
        self._size = [len(lk) for lk in table.looks]

    def _collected(self, t: int) -> int:
        """Target t's most valuable complete product, or -1."""
        present, size = self.present, self._size
        for p in self.table.target_products[t]:
            if present[p] == size[p]:
                return p
        return -1

    def change(self, c: int, sign: int) -> float:
        """Count look c in (+1) or out (-1) of the plan; returns the value change."""
        tb = self.table
        for p in tb.look_products[c]:
            self.present[p] += sign
        t = int(tb.option_target[c])
        old = self.best[t]
        new = self._collected(t)
        self.best[t] = new
        was = 0.0 if old < 0 else float(tb.value[old])
        now = 0.0 if new < 0 else float(tb.value[new])
        return now - was

    def missing(self, p: int, in_plan) -> list:
        """The looks of product p that ``in_plan(c)`` says the plan lacks."""
        return [c for c in self.table.looks[p] if not in_plan(c)]


def _in_plan(tl, c: int) -> bool:
    """Whether option c is in its satellite's timeline of ``tl``."""
    pb = tl.pb
    k = pb.option_sat[c]
    pos = bisect.bisect_left(tl.line_starts[k], pb.option_start[c])
    line = tl.lines[k]
    return pos < len(line) and line[pos] == c


def missing_looks(tl, p: int) -> list:
    """The looks of product p the plan of the timeline ``tl`` lacks."""
    return [c for c in tl.pb.stereo.looks[p] if not _in_plan(tl, c)]


def product_choices(tl, t: int, rng, turnaround: float, noise: float):
    """Stereo target t's products whose missing looks all fit the timeline ``tl`` now,
    as candidate ids (:func:`product_code`), and their costs: the timeline time the
    missing looks consume plus ``turnaround`` times the product's last end, times
    ``(2 - rank / best rank)^2`` (up to four times for a poor product), times
    ``1 + U(0, noise)``
    with ``rng`` (the costs of
    :meth:`jaxspline.search.timeline.Timeline.insert_choices`).

    Args:
      tl: the Timeline (tried insertions are undone).
      t: the stereo target; rng: ``random.Random`` or None.
    Returns:
      (candidates, costs), two lists; empty when the target already collects a product.
    """
    pb = tl.pb
    options, costs = [], []
    if tl.assigned[t] >= 0:
        return options, costs
    table = pb.stereo
    ps = table.target_products[t]
    top = float(table.rank[ps].max()) if ps else 0.0
    for p in ps:
        mark = len(tl.log)
        cost, ok = 0.0, True
        for c in missing_looks(tl, p):
            used = tl.check(c)
            if used is None:
                ok = False
                break
            cost += used
            tl.insert(c)
        tl.undo_to(mark)
        if not ok:
            continue
        cost += turnaround * max(pb.option_end[c] for c in table.looks[p])
        if top > 0:
            cost *= (2.0 - float(table.rank[p]) / top) ** 2
        if rng is not None:
            cost *= 1.0 + noise * rng.random()
        options.append(product_code(p))
        costs.append(cost)
    return options, costs


def drop_stray_looks(tl, targets) -> int:
    """Remove the looks of ``targets`` that no collected product uses (a look alone is
    worth nothing; each removal kept only when the plan stays feasible). Returns how many
    went."""
    pb = tl.pb
    table, counts = pb.stereo, tl.stereo
    gone = 0
    for t in targets:
        best = counts.best[t]
        keep = set(table.looks[best]) if best >= 0 else set()
        for c in [c for c in pb.target_options[t] if c not in keep and _in_plan(tl, c)]:
            k = pb.option_sat[c]
            pos = tl.lines[k].index(c)
            mark = len(tl.log)
            tl.remove(c)
            if tl.removal_ok(k, pos):
                gone += 1
            else:
                tl.undo_to(mark)
    return gone


def upgrade_product(tl, rng) -> bool:
    """One quality move: a stereo target that collects a product of less than its best
    rank gives it up for a better one that fits (the best first), kept only when the
    plan's value grows; else the plan is as before. Returns whether it changed."""
    pb = tl.pb
    table, counts = pb.stereo, tl.stereo
    cands = [
        int(t)
        for t in table.stereo_targets
        if counts.best[t] >= 0 and table.rank[counts.best[t]] < table.top_rank[t]
    ]
    if not cands:
        return False
    t = cands[rng.randrange(len(cands))]
    old = counts.best[t]
    base = tl.value
    mark = len(tl.log)
    for c in table.looks[old]:
        k = pb.option_sat[c]
        pos = tl.lines[k].index(c)
        tl.remove(c)
        if not tl.removal_ok(k, pos):
            tl.undo_to(mark)
            return False
    better = [p for p in table.target_products[t] if table.rank[p] > table.rank[old]]
    for p in sorted(better, key=lambda p: -table.rank[p]):
        inner = len(tl.log)
        if all(_try_insert(tl, c) for c in missing_looks(tl, p)) and tl.value > base + 1e-12:
            return True
        tl.undo_to(inner)
    tl.undo_to(mark)
    return False


def fail_chance(tl, t: int) -> float:
    """The chance that every complete product of stereo target t in the plan of ``tl``
    fails its overlap estimate (1 without one; the estimates taken as independent)."""
    table, counts = tl.pb.stereo, tl.stereo
    fail = 1.0
    for p in table.target_products[t]:
        if counts.present[p] == len(table.looks[p]):
            fail *= 1.0 - float(table.confidence[p])
    return fail


def add_backups(tl, targets=None) -> int:
    """Give each of ``targets`` (None: every stereo target; none without a product
    table) that collects a product but could lose it (its :func:`fail_chance` above
    :data:`BACKUP_FAIL`) the looks of further products, the surest first, while they fit
    without removing anything and until the chance is below :data:`BACKUP_FAIL`; the
    plan's value never drops. The last step of a search that hands its plan over (a
    walk that goes on from its plan would carry the extra looks). Returns the products
    added."""
    table, counts = tl.pb.stereo, tl.stereo
    if table is None:
        return 0
    added = 0
    for t in table.stereo_targets.tolist() if targets is None else targets:
        fail = fail_chance(tl, t)
        if counts.best[t] < 0 or fail <= BACKUP_FAIL:
            continue
        for p in sorted(table.target_products[t], key=lambda p: -table.confidence[p]):
            if counts.present[p] == len(table.looks[p]) or table.confidence[p] <= 0.0:
                continue
            mark, base = len(tl.log), tl.value
            if all(_try_insert(tl, c, True) for c in missing_looks(tl, p)) and tl.value >= base:
                added += 1
                fail = fail_chance(tl, t)  # its looks may complete more than p
                if fail <= BACKUP_FAIL:
                    break
            else:
                tl.undo_to(mark)
    return added


def _try_insert(tl, c: int, collected: bool = False) -> bool:
    """Insert option c when it fits (``collected``: also a look of a target the plan
    collects); whether it did."""
    if tl.check(c, collected) is None:
        return False
    tl.insert(c)
    return True
