"""Feasible near transitions in 8 bytes a pair: a CSR table by destination option.

The planner screens every same-satellite option pair closer than the satellite's
always-feasible gap; the feasible ones are the graph every search stage walks. Each
destination option owns one row, its feasible predecessors ``src[ptr[r]:ptr[r + 1]]``
(int32 option ids, ascending) with their required times ``need`` (float32, rounded up
so that a pair never looks cheaper than screened). Rows come in the order ``rows``
given at construction (the DP's start order, so a block of starts is one contiguous
range of pairs); ``row_of[j]`` is option j's row. Memory: 8 bytes a pair plus 24
bytes an option (``nbytes``); no index is kept per pair (a pair's destination is its
row).

:class:`PairsBuilder` fills the table chunk by chunk as the screen streams its rows:
one satellite's rows are held compactly (12 bytes a pair) until the satellite is done,
then sorted into rows and kept in pieces; the pieces are copied once into the final
arrays, each freed once placed.
"""

from __future__ import annotations

import bisect
import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from jaxspline.search.memory import trim_heap

__all__ = ["PIECE_PAIRS", "TRIM_PAIRS", "NearPairs", "PairsBuilder", "start_order"]

_INDEX = np.int32  # option ids of the stored pairs (< 2**31 options)
_NEED = np.float32  # stored required times [s], rounded up
_SRC_BITS = 32  # a pair's sort key while building: (row << _SRC_BITS) | source
#: Pairs of one sorted piece kept by :class:`PairsBuilder` (2 MB of int32 + float32).
PIECE_PAIRS = 1 << 18
#: Pairs placed by :meth:`PairsBuilder.build` between two heap trims (64 MB of pieces).
TRIM_PAIRS = 1 << 23


def start_order(start, sat) -> np.ndarray:
    """Option ids by start, then satellite: the row order of the DP.

    Args:
      start: float [N] start times [s].
      sat: int [N] satellites.
    Returns:
      int64 [N].
    """
    return np.lexsort((np.asarray(sat), np.asarray(start))).astype(np.int64)


def _round_up32(need) -> np.ndarray:
    """float32 copy of ``need`` that is never below it: each value rounded down by the
    cast moves up one float32 step (``np.nextafter`` towards +inf, done on the bits: +1
    for a positive value, -1 for a negative one; 6x faster than ``nextafter``)."""
    need = np.asarray(need, np.float64)
    n32 = need.astype(_NEED)
    up = n32 < need
    bits = n32.view(np.int32)
    bits += up
    neg = np.signbit(n32) & up
    if neg.any():
        bits -= 2 * neg
    return n32


class NearPairs:
    """CSR table of feasible near pairs (module docstring).

    Attributes:
      ptr: int64 [N + 1], row starts (row j = the predecessors of option j).
      src: int32 [P], predecessor option ids, ascending within a row.
      need: float32 [P], required time of each pair [s] (>= the screened value).
    """

    def __init__(self, ptr, src, need, rows):
        self.ptr = np.asarray(ptr, np.int64)
        self.src = np.asarray(src, _INDEX)
        self.need = np.asarray(need, _NEED)
        self.rows = np.asarray(rows, np.int64)
        self.row_of = np.empty_like(self.rows)
        self.row_of[self.rows] = np.arange(self.rows.size)
        if (
            self.src.shape != self.need.shape
            or self.ptr[-1] != self.src.size
            or self.ptr.size != self.rows.size + 1
        ):
            raise ValueError(
                f"NearPairs: ptr {self.ptr.shape} ending at {self.ptr[-1]}, src "
                f"{self.src.shape}, need {self.need.shape}, rows {self.rows.shape} do "
                "not describe one table"
            )
        # scalar lookups (the search's hot path) go through memoryviews: plain Python
        # ints and floats per access, no numpy scalar boxing
        self._mv_ptr = memoryview(self.ptr)
        self._mv_row = memoryview(self.row_of)
        self._mv_src = memoryview(self.src)
        self._mv_need = memoryview(self.need)

    @classmethod
    def from_arrays(cls, n: int, src, dst, need, rows=None) -> NearPairs:
        """Table of ``n`` options from pair arrays in any order.

        Args:
          n: number of options.
          src, dst: int [P] option ids.
          need: float [P] required times [s].
          rows: int [n], the options in row order (default: by id; the search wants
            :func:`start_order`).
        Returns:
          NearPairs.
        """
        builder = PairsBuilder(n, np.arange(n) if rows is None else rows)
        builder.add(src, dst, need)
        return builder.build()

    def __len__(self) -> int:
        return int(self.src.size)

    @property
    def n_options(self) -> int:
        """Number of options (rows)."""
        return int(self.ptr.size - 1)

    @property
    def nbytes(self) -> int:
        """Bytes held by the table (pairs, row pointers and the row order)."""
        arrays = (self.ptr, self.src, self.need, self.rows, self.row_of)
        return int(sum(a.nbytes for a in arrays))

    def lookup(self, i: int, j: int) -> float:
        """Required time of the pair i -> j, or ``inf`` when it is not a feasible near pair.

        Args:
          i: int, source option id.
          j: int, destination option id.
        Returns:
          float [s].
        """
        r = self._mv_row[j]
        a, b = self._mv_ptr[r], self._mv_ptr[r + 1]
        p = bisect.bisect_left(self._mv_src, i, a, b)
        if p < b and self._mv_src[p] == i:
            return self._mv_need[p]
        return math.inf

    def row(self, j: int) -> slice:
        """Positions of option j's predecessors in ``src`` / ``need``."""
        r = int(self.row_of[j])
        return slice(int(self.ptr[r]), int(self.ptr[r + 1]))

    def gather(self, options) -> tuple[np.ndarray, np.ndarray]:
        """Pair positions and destinations of the given options' rows.

        Args:
          options: int [R] option ids.
        Returns:
          (idx int64 [Q] positions into ``src`` / ``need``, dst int64 [Q]).
        """
        r = self.row_of[np.asarray(options, np.int64)]
        starts = self.ptr[r]
        counts = self.ptr[r + 1] - starts
        first = np.cumsum(counts) - counts
        idx = np.arange(int(counts.sum()), dtype=np.int64) + np.repeat(starts - first, counts)
        return idx, np.repeat(np.asarray(options, np.int64), counts)

    def dst(self) -> np.ndarray:
        """Destination option id of every pair (int64 [P], built on demand)."""
        return np.repeat(self.rows, np.diff(self.ptr))


class PairsBuilder:
    """Fill a :class:`NearPairs` from streamed pair chunks, one satellite at a time.

    Call :meth:`add` with the chunks of one satellite (any order), then :meth:`close`
    before the next one: a closed satellite's pairs are sorted by (row, source) and
    kept compact (8 bytes a pair) in pieces of :data:`PIECE_PAIRS` pairs. :meth:`build`
    places the pieces of all satellites in row order and frees each once placed, the
    freed heap pages handed back to the OS every :data:`TRIM_PAIRS` pairs
    (:func:`jaxspline.search.memory.trim_heap`), so the final table fills as the pieces
    go (peak: 8 bytes a pair plus about 64 MB, where moving whole satellites would
    hold 16 bytes a pair). With ``background``, a closed satellite is sorted in a
    thread while the caller streams the next one (both held at once: 12 bytes a pair
    of the one streaming besides the sort's); :meth:`build` waits for it.
    """

    def __init__(self, n: int, rows, background: bool = False):
        self.n = int(n)
        self._pool = ThreadPoolExecutor(1) if background else None
        self._job = None  # the closing satellite's sort in the background, or None
        self.rows = np.asarray(rows, np.int64)
        self.row_of = np.empty(self.n, np.int64)
        self.row_of[self.rows] = np.arange(self.n)
        self._open = []  # the open satellite's (src, dst, need) compact chunks
        self._pieces = []  # closed pairs: (rows, pairs per row, src, need), each by row
        self.counts = np.zeros(self.n, np.int64)  # pairs per row

    def add(self, src, dst, need) -> None:
        """Add feasible pairs (option ids, required times [s]) of the open satellite."""
        if len(src):
            self._open.append((np.asarray(src, _INDEX), np.asarray(dst, _INDEX), _round_up32(need)))

    def close(self) -> None:
        """Sort the open satellite's pairs by (row, source) and keep them compact; with
        ``background``, in a thread while the caller screens the next satellite (the
        sort's numpy steps release the GIL), after the previous satellite's sort."""
        if not self._open:
            return
        chunks, self._open = self._open, []
        self._wait()
        if self._pool is None:
            self._close(chunks)
        else:
            self._job = self._pool.submit(self._close, chunks)

    def _wait(self) -> None:
        """Wait for the background sort (its error, if any, raised here)."""
        job, self._job = self._job, None
        if job is not None:
            job.result()

    def _close(self, chunks) -> None:
        ids = self._by_source(chunks)
        if ids is None:
            self._sort(chunks)
        else:
            self._transpose(chunks, *ids)

    def _by_source(self, chunks):
        """The destinations' id range ``(lo, hi)`` when ``chunks`` come by source, as the
        planner's screen streams them (sources ascending within and across chunks), with
        option ids increasing with their rows over that range (a satellite's ids, in start
        order); else None."""
        last = -1
        for s, _, _ in chunks:
            if s[0] < last or np.any(s[1:] < s[:-1]):
                return None
            last = s[-1]
        lo = min(int(d.min()) for _, d, _ in chunks)
        hi = max(int(d.max()) for _, d, _ in chunks)
        return (lo, hi) if np.all(np.diff(self.row_of[lo : hi + 1]) > 0) else None

    def _transpose(self, chunks, lo: int, hi: int) -> None:
        """Pieces of chunks that come by source (:meth:`_by_source`, destinations in
        ``lo..hi``): each destination's pair count first, then each chunk (freed once
        placed) stably sorted by destination and scattered into the satellite's rows,
        which leaves every row's sources in stream order, ascending."""
        span = hi - lo + 1
        ptr = np.zeros(span + 1, np.int64)
        for _, d, _ in chunks:
            ptr[1:] += np.bincount(d - lo, minlength=span)
        np.cumsum(ptr, out=ptr)
        src, need = np.empty(int(ptr[-1]), _INDEX), np.empty(int(ptr[-1]), _NEED)
        fill = ptr[:-1].copy()  # next free position of each destination
        while chunks:
            s, d, w = chunks.pop(0)
            o = np.argsort(d, kind="stable")
            d = d[o] - lo
            cut = np.flatnonzero(np.r_[True, d[1:] != d[:-1]])
            seg = np.diff(np.r_[cut, d.size])
            head = d[cut]
            at = np.repeat(fill[head] - cut, seg) + np.arange(d.size)
            src[at], need[at] = s[o], w[o]
            fill[head] += seg
        rows = self.row_of[lo : lo + span]
        for a in range(0, src.size, PIECE_PAIRS):
            b = min(a + PIECE_PAIRS, src.size)
            r0 = int(np.searchsorted(ptr, a, "right")) - 1
            r1 = int(np.searchsorted(ptr, b - 1, "right"))
            counts = np.minimum(ptr[r0 + 1 : r1 + 1], b) - np.maximum(ptr[r0:r1], a)
            some = counts > 0
            held, counts = rows[r0:r1][some], counts[some]
            self.counts[held] += counts
            self._pieces.append((held, counts, src[a:b].copy(), need[a:b].copy()))

    def _sort(self, chunks) -> None:
        """Pieces of chunks in any order: one int64 key a pair, ``(row << 32) | src``."""
        src, dst, need = (np.concatenate(c) for c in zip(*chunks, strict=True))
        chunks.clear()
        key = (self.row_of[dst] << _SRC_BITS) | src.astype(np.int64)
        order = np.argsort(key, kind="stable")  # the order of lexsort((src, row))
        for a in range(0, order.size, PIECE_PAIRS):
            part = order[a : a + PIECE_PAIRS]
            row = key[part] >> _SRC_BITS
            cut = np.flatnonzero(np.r_[True, row[1:] != row[:-1]])
            rows, counts = row[cut], np.diff(np.r_[cut, row.size])
            self.counts[rows] += counts
            self._pieces.append((rows, counts, src[part], need[part]))

    def build(self) -> NearPairs:
        """The table (closes the open satellite); the builder is emptied."""
        try:
            self.close()
            self._wait()
        finally:
            if self._pool is not None:
                self._pool.shutdown()
        ptr = np.zeros(self.n + 1, np.int64)
        np.cumsum(self.counts, out=ptr[1:])
        src = np.empty(int(ptr[-1]), _INDEX)
        need = np.empty(int(ptr[-1]), _NEED)
        fill = ptr[:-1].copy()  # next free position of each row
        # pieces by first row (stable: a row split over pieces fills in their order)
        pieces = sorted(self._pieces, key=lambda pc: int(pc[0][0]))
        pieces.reverse()  # popped from the end: first rows ascending, ties in order
        self._pieces = []
        placed = 0
        while pieces:  # place and free one piece at a time
            rows, counts, s, w = pieces.pop()
            first = np.cumsum(counts) - counts
            at = np.repeat(fill[rows] - first, counts) + np.arange(s.size)
            fill[rows] += counts
            src[at] = s
            need[at] = w
            placed += s.size
            del s, w, at
            if placed >= TRIM_PAIRS:  # freed pieces stay on the heap: hand them back
                trim_heap()
                placed = 0
        trim_heap()  # and the sort's temporaries
        return NearPairs(ptr, src, need, self.rows)
