"""Exact 8-connected grid A*: a numba kernel with reusable per-map buffers.

Model
-----
* Cells are nodes; a move goes to one of the 8 neighbours; a straight move
  costs 1 and a diagonal move ``sqrt(2)`` (multiply by the map resolution for
  metres).
* ``corner_cutting=False`` (the default, and the MovingAI convention): a
  diagonal move needs *both* orthogonally adjacent cells free, so a path never
  touches an obstacle corner.  ``corner_cutting=True``: a diagonal move only
  needs the diagonal cell free.
* Heuristics: ``"euclidean"`` (straight-line distance, eq. 2 of Ju, Luo and
  Yan; the default) or ``"octile"`` (the exact 8-connected distance on an empty
  grid; tighter, so fewer expansions).  Both are consistent, so A* with a
  closed set returns optimal costs.

Implementation
--------------
* The occupancy is copied once into a flat ``uint8`` array with a one-cell
  blocked border, so neighbour lookups are index additions without bounds
  checks; the eight neighbour offsets are precomputed.
* The open list is exact (ordered by the exact double ``f``, no rounding)
  and keyed by the IEEE-754 bits of ``f`` (non-negative doubles order like
  their bits).  An improved node is pushed again and its stale entry skipped
  when popped ("lazy deletion").  Two structures, picked by heuristic:

  - ``"octile"``: a *radix heap* (Ahuja, Mehlhorn, Orlin and Tarjan, 1990).
    It only needs the popped ``f`` never to decrease, which a consistent
    heuristic guarantees; equal keys (very common with octile) cost O(1).
  - ``"euclidean"``: a *ring of buckets* of width 1/1024 cell over
    ``[f_min, f_min + 2 sqrt 2]`` (the range every open ``f`` lies in), a
    bitmap to find the next non-empty bucket, and a small binary heap that
    orders the current bucket exactly.  Each entry moves once, which suits
    euclidean ``f`` values, nearly all distinct.

  On the MovingAI 512/1024 maps these were about 1.5-3x faster than one binary
  heap (measured while developing; ``benchmarks/bench_astar.py`` compares
  with other libraries).
* Ties in ``f`` are broken last-in first-out (radix) or by heap position
  (ring); everything is deterministic: the same query on the same map
  returns the same path.
* ``g``, the parent direction and a generation stamp per cell live in arrays
  owned by an :class:`AStarSearcher`; a query bumps the generation instead of
  clearing them, so a query costs time in proportion to the cells it touches,
  not to the map size.  :func:`get_searcher` keeps one searcher per map and
  corner rule (weakly keyed by the :class:`~pathfuse.grid.GridMap`).
* Start and goal in different connected free regions answer ``NO_PATH``
  without searching (``GridMap.components``, 4-connected labels, which equal
  8-connected reachability without corner cutting; 8-connected labels are
  computed for the corner-cutting rule).
* The kernel runs in chunks of expansions; between chunks the wall clock is
  checked, which bounds the time a query can overrun its limit.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((4, 5), dtype=bool); occ[1:3, 2] = True
>>> s = AStarSearcher(occ)
>>> r = s.search((1, 0), (1, 4))
>>> r.status.name, round(r.cost, 6), r.cells.tolist()
('SUCCESS', 4.828427, [[1, 0], [0, 1], [0, 2], [0, 3], [1, 4]])
>>> s.search((1, 0), (1, 4), max_expansions=2).status.name
'MAX_ITERATIONS'
"""

from __future__ import annotations

import math
import threading
import time
import weakref
from dataclasses import dataclass

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from pathfuse.result import ConfigError, MapError, QueryError, Status

__all__ = [
    "AStarSearcher",
    "SearchResult",
    "get_searcher",
    "warmup",
    "HEURISTICS",
    "SQRT2",
]

SQRT2 = math.sqrt(2.0)
HEURISTICS = ("euclidean", "octile")
"""Accepted heuristic names."""

# kernel return codes
_FOUND = 0
_EXHAUSTED = 1
_CHUNK_DONE = 2
_HEAP_FULL = 3

_CHUNK = 1 << 16  # expansions between clock checks when a time limit is set
_RING_SCALE = 1024.0  # ring buckets per cell of f (euclidean open list)
_RING_SIZE = 4096  # > 2 * sqrt(2) * _RING_SCALE + 2, a power of two
_STAMP_LIMIT = np.iinfo(np.int32).max - 4


# ----------------------------------------------------------------------------- kernels
@intrinsic
def _bit_length(typingctx, x):
    """Number of significant bits of a uint64 (LLVM ctlz), as int64."""
    sig = types.int64(types.uint64)

    def codegen(context, builder, signature, args):
        lz = builder.ctlz(args[0], ir.Constant(ir.IntType(1), 0))
        return builder.sub(ir.Constant(ir.IntType(64), 64), lz)

    return sig, codegen


@njit(cache=True, nogil=True, inline="always")
def _heuristic(r: int, c: int, gr: int, gc: int, octile: bool) -> float:
    dy = abs(r - gr)
    dx = abs(c - gc)
    if octile:
        if dx > dy:
            return dx + (1.4142135623730951 - 1.0) * dy
        return dy + (1.4142135623730951 - 1.0) * dx
    return math.sqrt(float(dx * dx + dy * dy))


@njit(cache=True, nogil=True, inline="always")
def _qpush(qkey, qnode, qnext, heads, last, fh, used, key, node):
    """Insert (key, node) into the radix heap; returns (free-list head, used)."""
    if key < last:  # only by float rounding: f is monotone for a consistent heuristic
        key = last
    b = 0 if key == last else _bit_length(key ^ last)
    if fh >= 0:
        e = fh
        fh = qnext[e]
    else:
        e = used
        used += 1
    qkey[e] = key
    qnode[e] = node
    qnext[e] = heads[b]
    heads[b] = e
    return fh, used


@intrinsic
def _trailing_zeros(typingctx, x):
    """Index of the lowest set bit of a non-zero uint64 (LLVM cttz), as int64."""
    sig = types.int64(types.uint64)

    def codegen(context, builder, signature, args):
        return builder.cttz(args[0], ir.Constant(ir.IntType(1), 0))

    return sig, codegen


@njit(cache=True, nogil=True, inline="always")
def _spush(skey, snode, size, key, node):
    """Push onto the small binary min-heap of the current ring bucket."""
    i = size
    while i > 0:
        up = (i - 1) >> 1
        if key < skey[up]:
            skey[i] = skey[up]
            snode[i] = snode[up]
            i = up
        else:
            break
    skey[i] = key
    snode[i] = node
    return size + 1


@njit(cache=True, nogil=True, inline="always")
def _spop(skey, snode, size):
    """Pop the root of the small heap; returns (node, new size)."""
    top = snode[0]
    size -= 1
    if size > 0:
        key = skey[size]
        node = snode[size]
        i = 0
        while True:
            child = 2 * i + 1
            if child >= size:
                break
            ck = skey[child]
            if child + 1 < size and skey[child + 1] < ck:
                child += 1
                ck = skey[child]
            if ck < key:
                skey[i] = ck
                snode[i] = snode[child]
                i = child
            else:
                break
        skey[i] = key
        snode[i] = node
    return top, size


@njit(cache=True, nogil=True)
def _astar_kernel(
    free, gbuf, stamp, parent, qkey, qnode, qnext, heads, bits, skey, snode, meta, gen,
    start, goal, wp, octile, corner_cutting, use_ring, max_exp,
):
    """Run A* until the goal is closed, the open list empties or ``max_exp`` expansions.

    Cell state: ``stamp[p] == gen``: ``gbuf[p]`` is valid and ``p`` open;
    ``stamp[p] == gen + 1``: ``p`` closed; ``parent[p]`` is the move (0-7)
    that reached ``p``.  ``start >= 0`` starts a query; ``start < 0`` resumes
    the one whose open list is saved in the arrays and ``meta``.

    Two open lists, both exact and both keyed by the IEEE-754 bits of ``f``
    (non-negative doubles order like their bits); entries live in a pool
    (``qkey``, ``qnode``, ``qnext``) of singly linked lists with a free list:

    * ``use_ring=False``: a radix heap (Ahuja et al. 1990).  Bucket ``b`` of
      ``heads[:65]`` holds keys whose highest bit differing from the last
      popped key is ``b - 1`` (bucket 0: equal keys, popped last-in first-out).
      When bucket 0 is empty the first non-empty bucket is searched for its
      minimum, which becomes the new last key, and spread over lower buckets.
      Best when many ``f`` are exactly equal (the octile heuristic).
    * ``use_ring=True``: ``f`` is cut into buckets of ``1 / _RING_SCALE``
      cells.  With a consistent heuristic every open ``f`` lies in
      ``[f_min, f_min + 2 sqrt 2]`` (a child's ``f`` exceeds its parent's by at
      most two steps), so ``_RING_SIZE`` buckets used cyclically hold them
      all; a bitmap (``bits``) finds the next non-empty one.  The bucket being
      expanded is moved into a binary heap (``skey``, ``snode``) ordered
      exactly by ``f``; children falling into it go straight there.  Each entry
      moves once: best when ``f`` values are mostly distinct (euclidean).

    ``meta`` = [radix: last key / ring: current bucket, free-list head, pool
    slots used, pool entries, heap entries].  Returns (code, expansions in
    this call).
    """
    s2 = 1.4142135623730951
    fbuf = np.empty(1, dtype=np.float64)
    ubuf = fbuf.view(np.uint64)
    one = np.uint64(1)
    rmask = _RING_SIZE - 1
    gr = goal // wp
    gc = goal - gr * wp
    closed = gen + 1
    offs = (1, -1, wp, -wp, wp + 1, wp - 1, -wp + 1, -wp - 1)
    drs = (0, 0, 1, -1, 1, 1, -1, -1)
    dcs = (1, -1, 0, 0, 1, -1, 1, -1)
    if start >= 0:
        gbuf[start] = 0.0
        stamp[start] = gen
        parent[start] = 8
        sr = start // wp
        fbuf[0] = _heuristic(sr, start - sr * wp, gr, gc, octile)
        fh = -1
        used = 0
        if use_ring:
            for i in range(_RING_SIZE):
                heads[i] = -1
            for i in range(_RING_SIZE // 64):
                bits[i] = 0
            last = np.uint64(0)
            cur = np.int64(fbuf[0] * _RING_SCALE)
            size = 0
            ssize = _spush(skey, snode, 0, ubuf[0], start)
        else:
            for i in range(65):
                heads[i] = -1
            last = ubuf[0]
            cur = np.int64(0)
            fh, used = _qpush(qkey, qnode, qnext, heads, last, fh, used, last, start)
            size = 1
            ssize = 0
    else:
        last = np.uint64(meta[0])
        cur = meta[0]
        fh = meta[1]
        used = meta[2]
        size = meta[3]
        ssize = meta[4]
    cap = qkey.shape[0]
    scap = skey.shape[0]
    n_exp = 0
    code = _EXHAUSTED
    while size > 0 or ssize > 0:
        if n_exp >= max_exp:
            code = _CHUNK_DONE
            break
        if used + 8 > cap or size + ssize + 8 > scap:
            code = _HEAP_FULL
            break
        # ---- pop the entry with the smallest f
        if use_ring:
            if ssize == 0:
                pos = (cur + 1) & rmask
                w = pos >> 6
                word = bits[w] & (~np.uint64(0) << np.uint64(pos & 63))
                while word == 0:
                    w = (w + 1) & (_RING_SIZE // 64 - 1)
                    word = bits[w]
                b = (w << 6) + _trailing_zeros(word)
                cur += (b - cur) & rmask
                bits[b >> 6] &= ~(one << np.uint64(b & 63))
                e = heads[b]
                heads[b] = -1
                while e >= 0:
                    nxt = qnext[e]
                    ssize = _spush(skey, snode, ssize, qkey[e], qnode[e])
                    size -= 1
                    qnext[e] = fh
                    fh = e
                    e = nxt
            p, ssize = _spop(skey, snode, ssize)
        else:
            if heads[0] < 0:
                i = 1
                while heads[i] < 0:
                    i += 1
                e = heads[i]
                m = qkey[e]
                e = qnext[e]
                while e >= 0:
                    if qkey[e] < m:
                        m = qkey[e]
                    e = qnext[e]
                last = m
                e = heads[i]
                heads[i] = -1
                while e >= 0:
                    nxt = qnext[e]
                    k = qkey[e]
                    b = 0 if k == last else _bit_length(k ^ last)
                    qnext[e] = heads[b]
                    heads[b] = e
                    e = nxt
            e = heads[0]
            heads[0] = qnext[e]
            p = qnode[e]
            qnext[e] = fh
            fh = e
            size -= 1
        if stamp[p] == closed:
            continue  # stale duplicate of a node already expanded
        stamp[p] = closed
        n_exp += 1
        if p == goal:
            code = _FOUND
            break
        # ---- relax the 8 moves
        g0 = gbuf[p]
        r = p // wp
        c = p - r * wp
        fe = free[p + 1]
        fw = free[p - 1]
        fn = free[p + wp]
        fs = free[p - wp]
        for k in range(8):
            if k < 4:
                if k == 0:
                    ok = fe
                elif k == 1:
                    ok = fw
                elif k == 2:
                    ok = fn
                else:
                    ok = fs
                step = 1.0
            else:
                if k == 4:
                    corner = fn and fe
                elif k == 5:
                    corner = fn and fw
                elif k == 6:
                    corner = fs and fe
                else:
                    corner = fs and fw
                ok = free[p + offs[k]] and (corner_cutting or corner)
                step = s2
            if not ok:
                continue
            q = p + offs[k]
            st = stamp[q]
            if st == closed:
                continue
            ng = g0 + step
            if st == gen and ng >= gbuf[q]:
                continue
            gbuf[q] = ng
            stamp[q] = gen
            parent[q] = k
            f = ng + _heuristic(r + drs[k], c + dcs[k], gr, gc, octile)
            fbuf[0] = f
            if use_ring:
                kq = np.int64(f * _RING_SCALE)
                if kq <= cur:  # the bucket being expanded (or below it, by rounding)
                    ssize = _spush(skey, snode, ssize, ubuf[0], q)
                else:
                    if fh >= 0:
                        e = fh
                        fh = qnext[e]
                    else:
                        e = used
                        used += 1
                    qkey[e] = ubuf[0]
                    qnode[e] = q
                    b = kq & rmask
                    qnext[e] = heads[b]
                    heads[b] = e
                    bits[b >> 6] |= one << np.uint64(b & 63)
                    size += 1
            else:
                fh, used = _qpush(qkey, qnode, qnext, heads, last, fh, used, ubuf[0], q)
                size += 1
    meta[0] = cur if use_ring else np.int64(last)
    meta[1] = fh
    meta[2] = used
    meta[3] = size
    meta[4] = ssize
    return code, n_exp


@njit(cache=True, nogil=True)
def _trace(parent, start, goal, wp):
    """(n, 2) int array of unpadded (row, col) cells from start to goal."""
    offs = np.array([1, -1, wp, -wp, wp + 1, wp - 1, -wp + 1, -wp - 1], dtype=np.int64)
    n = 1
    p = goal
    while p != start:
        p -= offs[parent[p]]
        n += 1
    out = np.empty((n, 2), dtype=np.int64)
    p = goal
    for i in range(n - 1, -1, -1):
        r = p // wp
        out[i, 0] = r - 1
        out[i, 1] = p - r * wp - 1
        if i > 0:
            p -= offs[parent[p]]
    return out


# ----------------------------------------------------------------------------- Python API
@dataclass(frozen=True)
class SearchResult:
    """Outcome of :meth:`AStarSearcher.search`.

    Attributes
    ----------
    status : Status
        ``SUCCESS``, ``NO_PATH``, ``MAX_ITERATIONS`` or ``TIMEOUT``.
    cells : ndarray, shape (N, 2), int
        ``(row, col)`` cells from start to goal on success, else ``(0, 2)``.
    cost : float
        Path cost in cells (straight move 1, diagonal ``sqrt(2)``); ``inf``
        when there is no path.
    expansions : int
        Nodes closed by the search (0 when answered from connectivity labels).
    """

    status: Status
    cells: np.ndarray
    cost: float
    expansions: int


_NO_CELLS = np.zeros((0, 2), dtype=np.int64)
_NO_CELLS.setflags(write=False)


class AStarSearcher:
    """A* on one occupancy grid, with buffers kept between queries.

    Parameters
    ----------
    occupied : ndarray of bool, shape (H, W)
        ``True`` where a cell is blocked (row 0 is the bottom row, but the
        searcher does not care about orientation).
    corner_cutting : bool
        Allow a diagonal move past a blocked orthogonal neighbour.
    labels : ndarray of int, optional
        Connected-component labels of the free cells under this corner rule
        (0 on blocked cells); computed when not given.

    Notes
    -----
    A searcher is not re-entrant: :func:`get_searcher` hands a fresh one to a
    second thread that asks while the cached one is busy.
    """

    def __init__(
        self,
        occupied: np.ndarray,
        corner_cutting: bool = False,
        labels: np.ndarray | None = None,
    ) -> None:
        occ = np.asarray(occupied, dtype=bool)
        if occ.ndim != 2 or occ.size == 0:
            raise MapError(f"occupied must be a non-empty 2-D array, got shape {occ.shape}")
        self.shape = (int(occ.shape[0]), int(occ.shape[1]))
        self.corner_cutting = bool(corner_cutting)
        h, w = self.shape
        self._wp = w + 2
        free = np.zeros((h + 2, w + 2), dtype=np.uint8)
        free[1:-1, 1:-1] = ~occ
        self._free = free.ravel()
        n = self._free.size
        self._g = np.empty(n, dtype=np.float64)
        self._stamp = np.zeros(n, dtype=np.int32)
        self._parent = np.zeros(n, dtype=np.uint8)
        cap = int(min(max(1024, n // 4), 1 << 20))
        self._qkey = np.empty(cap, dtype=np.uint64)
        self._qnode = np.empty(cap, dtype=np.int32)
        self._qnext = np.empty(cap, dtype=np.int32)
        self._skey = np.empty(cap, dtype=np.uint64)
        self._snode = np.empty(cap, dtype=np.int32)
        self._heads = np.empty(_RING_SIZE, dtype=np.int32)
        self._bits = np.empty(_RING_SIZE // 64, dtype=np.uint64)
        self._meta = np.zeros(5, dtype=np.int64)
        self._gen = 0
        self.free_count = int(n - (self._free == 0).sum())
        if labels is None:
            structure = np.ones((3, 3), dtype=bool) if self.corner_cutting else None
            from scipy import ndimage

            labels, _ = ndimage.label(~occ, structure=structure)
        self._labels = np.asarray(labels)
        self.lock = threading.Lock()

    def _grow_heap(self) -> None:
        """Double the open-list pool and heap (entries keep their indices)."""
        for name in ("_qkey", "_qnode", "_qnext", "_skey", "_snode"):
            old = getattr(self, name)
            new = np.empty(2 * old.shape[0], dtype=old.dtype)
            new[: old.shape[0]] = old
            setattr(self, name, new)

    def search(
        self,
        start_cell: tuple[int, int],
        goal_cell: tuple[int, int],
        heuristic: str = "euclidean",
        max_expansions: int | None = None,
        time_limit_s: float | None = None,
    ) -> SearchResult:
        """Shortest path between two free cells.

        Parameters
        ----------
        start_cell, goal_cell : (int, int)
            ``(row, col)``; both must be in bounds and free (:class:`QueryError`
            otherwise).
        heuristic : {"euclidean", "octile"}
        max_expansions : int, optional
            Stop with ``MAX_ITERATIONS`` after this many expansions.  The
            default, the number of free cells, never cuts a search short.
        time_limit_s : float, optional
            Stop with ``TIMEOUT`` once this much wall time has passed (checked
            every 65,536 expansions).

        Returns
        -------
        SearchResult
        """
        if heuristic not in HEURISTICS:
            raise ConfigError(f"heuristic: must be one of {', '.join(map(repr, HEURISTICS))}, "
                              f"got {heuristic!r}")
        h, w = self.shape
        (sr, sc), (gr, gc) = (int(v) for v in start_cell), (int(v) for v in goal_cell)
        for what, r, c in (("start", sr, sc), ("goal", gr, gc)):
            if not (0 <= r < h and 0 <= c < w):
                raise QueryError(f"{what} cell ({r}, {c}) is outside the {h}x{w} grid")
            if not self._free[(r + 1) * self._wp + c + 1]:
                raise QueryError(f"{what} cell ({r}, {c}) is occupied")
        with self.lock:
            return self._search(sr, sc, gr, gc, heuristic, max_expansions, time_limit_s)

    def _search(self, sr, sc, gr, gc, heuristic, max_expansions, time_limit_s) -> SearchResult:
        t0 = time.perf_counter()
        if sr == gr and sc == gc:
            return SearchResult(Status.SUCCESS, np.array([[sr, sc]], dtype=np.int64), 0.0, 0)
        if self._labels[sr, sc] != self._labels[gr, gc]:
            return SearchResult(Status.NO_PATH, _NO_CELLS, math.inf, 0)
        budget = self.free_count if max_expansions is None else int(max_expansions)
        wp = self._wp
        start = (sr + 1) * wp + sc + 1
        goal = (gr + 1) * wp + gc + 1
        if self._gen >= _STAMP_LIMIT:
            self._stamp[:] = 0
            self._gen = 0
        self._gen += 2
        gen = self._gen
        octile = heuristic == "octile"
        chunk = _CHUNK if time_limit_s is not None else budget
        done = 0
        first = start
        while True:
            step = min(chunk, budget - done)
            code, n = _astar_kernel(
                self._free, self._g, self._stamp, self._parent, self._qkey, self._qnode,
                self._qnext, self._heads, self._bits, self._skey, self._snode, self._meta,
                gen, first, goal, wp, octile, self.corner_cutting, not octile, step,
            )
            first = -1
            done += n
            if code == _FOUND:
                cells = _trace(self._parent, start, goal, wp)
                return SearchResult(Status.SUCCESS, cells, float(self._g[goal]), done)
            if code == _EXHAUSTED:
                return SearchResult(Status.NO_PATH, _NO_CELLS, math.inf, done)
            if code == _HEAP_FULL:
                self._grow_heap()
                continue
            if done >= budget:
                return SearchResult(Status.MAX_ITERATIONS, _NO_CELLS, math.inf, done)
            if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
                return SearchResult(Status.TIMEOUT, _NO_CELLS, math.inf, done)


# ----------------------------------------------------------------------------- cache
_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_CACHE_LOCK = threading.Lock()


def get_searcher(grid, corner_cutting: bool = False) -> AStarSearcher:
    """The cached :class:`AStarSearcher` of ``grid`` (a GridMap) for a corner rule.

    The first call on a map builds the padded grid and the buffers; later
    calls reuse them.  The cache holds the map weakly, so it goes when the map
    goes.  If the cached searcher is busy in another thread, a fresh one is
    returned (its buffers are not cached).
    """
    key = bool(corner_cutting)
    with _CACHE_LOCK:
        per_map = _CACHE.get(grid)
        if per_map is None:
            per_map = {}
            _CACHE[grid] = per_map
        searcher = per_map.get(key)
    if searcher is None:
        labels = None if key else grid.components
        searcher = AStarSearcher(grid.occupied, corner_cutting=key, labels=labels)
        with _CACHE_LOCK:
            searcher = per_map.setdefault(key, searcher)
    if searcher.lock.locked():
        labels = searcher._labels
        return AStarSearcher(grid.occupied, corner_cutting=key, labels=labels)
    return searcher


_WARM = False


def warmup() -> None:
    """Compile (or load from numba's on-disk cache) the A* kernels on a tiny grid."""
    global _WARM
    if _WARM:
        return
    occ = np.zeros((3, 4), dtype=bool)
    occ[1, 1] = True
    for cut in (False, True):
        s = AStarSearcher(occ, corner_cutting=cut)
        for heur in HEURISTICS:
            s.search((0, 0), (2, 3), heuristic=heur)
            s.search((0, 0), (2, 3), heuristic=heur, time_limit_s=10.0)
    _WARM = True
