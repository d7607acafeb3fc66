"""Jump point search (Harabor and Grastien), the variant without corner cutting.

The same model and the same optimal costs as :mod:`pathfuse.search.astar`
(8-connected, straight move 1, diagonal ``sqrt(2)``, a diagonal move needs both
orthogonally adjacent cells free), found by expanding far fewer nodes: from a
node, A* would push every neighbour; jump point search only follows the
directions that an optimal path can take on from there and *jumps* along each
one, cell after cell, until it meets a cell where a path has to turn (a jump
point), the goal, or a wall.  Only jump points enter the open list.

Rules, without corner cutting (Harabor and Grastien, "Improving jump point
search", ICAPS 2014, whose variant forbids corner cutting):

* Moving straight, say east, through ``x``: carry on east; if the cell north
  of ``x`` is free while the one north of the cell behind ``x`` is blocked, the
  north and north-east moves from ``x`` are *forced* (no path of equal cost
  avoids ``x``), and ``x`` is a jump point; likewise south.
* Moving diagonally, say north-east, through ``x``: carry on north-east, and
  from every cell jump east and north first; a cell from which one of them
  finds a jump point is a jump point.  A diagonal move has no forced
  neighbour under this corner rule (the two cells beside it are free).
* The start expands in all eight directions; the goal is a jump point.

Straight jumps read bit grids (one bit per free cell, the rows and, transposed,
the columns), 64 cells a step: a word's blocked cells and forced neighbours are
found with a few bit operations and a count of trailing (or leading) zeros, as
in the block-based jumps of the same paper.

The open list is a binary heap ordered by ``f = g + h`` with the octile
heuristic (the exact distance on an empty grid).  A jump of ``k`` cells costs
``k`` or ``k sqrt(2)``; every optimal path has the same number ``a`` of
straight moves and ``b`` of diagonal ones (``sqrt(2)`` is irrational), so the
cost is reported as ``a + b sqrt(2)``, the same double whichever optimal path
is found.  The path between jump points is filled in cell by cell:
:attr:`SearchResult.cells` is an 8-connected cell path like A*'s, and any
controller that follows an A* path follows it.

Examples
--------
>>> import numpy as np
>>> occ = np.zeros((4, 5), dtype=bool); occ[1:3, 2] = True
>>> s = JPSSearcher(occ)
>>> r = s.search((1, 0), (1, 4))
>>> r.status.name, round(r.cost, 6), len(r.cells)
('SUCCESS', 4.828427, 5)
"""

from __future__ import annotations

import math
import threading
import time
import weakref

import numpy as np
from numba import njit

from pathfuse.result import (
    CODE_NO_PATH,
    CODE_RUNNING,
    CODE_SUCCESS,
    MapError,
    QueryError,
    Status,
)
from pathfuse.search.astar import _EAGER_LABELS, SearchResult, _Regions
from pathfuse.search.heap import heap_pop, heap_push
from pathfuse.search.kernel import _bit_length, _trailing_zeros

__all__ = ["JPSSearcher", "get_jps_searcher", "warmup"]

_CHUNK = 1 << 14  # expansions between clock checks when a time limit is set
_STAMP_LIMIT = np.iinfo(np.int32).max - 4
_SQRT2 = 1.4142135623730951
_NO_CELLS = np.zeros((0, 2), dtype=np.int64)
_NO_CELLS.setflags(write=False)


@njit(cache=True, nogil=True)
def _octile(p, goal, wp):
    r = p // wp
    gr = goal // wp
    dy = abs(r - gr)
    dx = abs((p - r * wp) - (goal - gr * wp))
    if dx > dy:
        return dx + (_SQRT2 - 1.0) * dy
    return dy + (_SQRT2 - 1.0) * dx


@njit(cache=True, nogil=True)
def _window(words, base, s):
    """Bits ``s .. s + 63`` of the bit line starting at word ``base`` (bit ``j`` of the
    result is bit ``s + j``)."""
    w = base + (s >> 6)
    o = np.uint64(s & 63)
    if o == 0:
        return words[w]
    return (words[w] >> o) | (words[w + 1] << (np.uint64(64) - o))


@njit(cache=True, nogil=True)
def _scan(words, nw, line, x, forward, gpos):
    """A straight jump along bit line ``line`` of a bit grid (one bit per free cell, line
    ``k`` at words ``k * nw ...``, cell ``x`` at bit ``x + 64``) from cell ``x``, forward
    (increasing ``x``) or back: the first cell that is blocked (-1 returned), the goal
    (``gpos``, -1 when the goal is not on this line) or has a forced neighbour on line
    ``line +- 1`` (that cell is free while the one before it, seen from ``x``, is blocked;
    returned).  64 cells a step: the whole word is tested at once."""
    one = np.uint64(1)
    b0 = line * nw
    b1 = b0 + nw
    b2 = b0 - nw
    if forward:
        s = x + 65
        while True:
            m0 = _window(words, b0, s)
            u = _window(words, b1, s)
            d = _window(words, b2, s)
            stop = ~m0 | (u & ~_window(words, b1, s - 1)) | (d & ~_window(words, b2, s - 1))
            if stop != 0:
                t = _trailing_zeros(stop)
                n = s + t - 64
                if gpos > x and gpos <= n:
                    return gpos
                if (m0 >> np.uint64(t)) & one:
                    return n
                return -1
            if gpos > x and gpos <= s - 1:
                return gpos
            s += 64
    else:
        s = x - 1  # the window covers cells s - 63 .. s (bits s + 1 .. s + 64)
        while True:
            lo = s + 1  # bit of cell s - 63
            m0 = _window(words, b0, lo)
            u = _window(words, b1, lo)
            d = _window(words, b2, lo)
            stop = ~m0 | (u & ~_window(words, b1, lo + 1)) | (d & ~_window(words, b2, lo + 1))
            if stop != 0:
                t = _bit_length(stop) - 1
                n = s - 63 + t
                if gpos < x and gpos >= n and gpos >= 0:
                    return gpos
                if (m0 >> np.uint64(t)) & one:
                    return n
                return -1
            if gpos < x and gpos >= s - 63 and gpos >= 0:
                return gpos
            s -= 64


@njit(cache=True, nogil=True)
def _jump_line(rows, cols, nwr, nwc, y, x, dy, dx, gy, gx, wp):
    """A straight jump from padded cell ``(y, x)`` along ``(dy, dx)``: the flat index of
    the jump point, or -1.  Rows are scanned in ``rows``, columns in ``cols`` (the
    transposed bit grid), so both directions read consecutive words."""
    if dy == 0:
        j = _scan(rows, nwr, y, x, dx > 0, gx if gy == y else -1)
        return -1 if j < 0 else y * wp + j
    j = _scan(cols, nwc, x, y, dy > 0, gy if gx == x else -1)
    return -1 if j < 0 else j * wp + x


@njit(cache=True, nogil=True)
def _jump_diagonal(free, rows, cols, nwr, nwc, y, x, dy, dx, gy, gx, wp):
    """From padded cell ``(y, x)`` step diagonally by ``(dy, dx)`` until a cell from which
    a straight jump along ``dx`` or ``dy`` finds a jump point, the goal (its flat index
    returned), or a blocked move (-1)."""
    p = y * wp + x
    dv = dy * wp
    while True:
        if not (free[p + dx] and free[p + dv]):
            return -1
        p += dx + dv
        y += dy
        x += dx
        if not free[p]:
            return -1
        if y == gy and x == gx:
            return p
        if _jump_line(rows, cols, nwr, nwc, y, x, 0, dx, gy, gx, wp) >= 0 or \
                _jump_line(rows, cols, nwr, nwc, y, x, dy, 0, gy, gx, wp) >= 0:
            return p


@njit(cache=True, nogil=True)
def _jps_kernel(free, rows, cols, nwr, nwc, gbuf, stamp, parent, hkey, hnode, meta, gen,
                start, goal, wp, max_exp):
    """Jump point search until the goal is closed, the heap empties or ``max_exp``
    expansions (``start < 0`` resumes; ``meta[0]`` is the heap size).  ``stamp[p] ==
    gen``: ``p`` open (``gbuf[p]`` valid), ``gen + 1``: closed; ``parent[p]`` is the jump
    point it was reached from.  Returns ``(code, expansions, hkey, hnode)`` (the heap
    arrays grow as needed)."""
    closed = gen + 1
    gy = goal // wp
    gx = goal - gy * wp
    if start >= 0:
        gbuf[start] = 0.0
        stamp[start] = gen
        parent[start] = start
        hkey, hnode, size = heap_push(hkey, hnode, 0, _octile(start, goal, wp), start)
    else:
        size = meta[0]
    n_exp = 0
    code = CODE_NO_PATH
    while size > 0:
        if n_exp >= max_exp:
            code = CODE_RUNNING
            break
        p, size = heap_pop(hkey, hnode, size)
        if stamp[p] == closed:
            continue
        stamp[p] = closed
        n_exp += 1
        if p == goal:
            code = CODE_SUCCESS
            break
        g0 = gbuf[p]
        # the direction p was reached in (none at the start: all eight)
        pp = parent[p]
        if pp == p:
            ddy = 0
            ddx = 0
        else:
            rr = p // wp - pp // wp
            cc = (p - (p // wp) * wp) - (pp - (pp // wp) * wp)
            ddy = int(rr > 0) - int(rr < 0)  # int(): numpy's bools do not subtract (pathfuse.tier)
            ddx = int(cc > 0) - int(cc < 0)
        for k in range(8):
            # candidate direction (dy, dx) of this successor
            if k == 0:
                dy, dx = 0, 1
            elif k == 1:
                dy, dx = 0, -1
            elif k == 2:
                dy, dx = 1, 0
            elif k == 3:
                dy, dx = -1, 0
            elif k == 4:
                dy, dx = 1, 1
            elif k == 5:
                dy, dx = 1, -1
            elif k == 6:
                dy, dx = -1, 1
            else:
                dy, dx = -1, -1
            if ddx != 0 or ddy != 0:
                # pruning: keep the natural and the forced successors only
                if ddx != 0 and ddy != 0:  # arrived diagonally: no forced neighbour
                    if not ((dy == ddy and dx == ddx) or (dy == ddy and dx == 0)
                            or (dy == 0 and dx == ddx)):
                        continue
                elif ddy == 0:  # arrived moving along a row
                    if dy == 0:
                        if dx != ddx:
                            continue
                    else:
                        if dx == -ddx:
                            continue
                        # forced: the cell at (dy, 0) free, the one behind it blocked
                        if not (free[p + dy * wp] and not free[p + dy * wp - ddx]):
                            continue
                else:  # arrived moving along a column
                    if dx == 0:
                        if dy != ddy:
                            continue
                    else:
                        if dy == -ddy:
                            continue
                        if not (free[p + dx] and not free[p + dx - ddy * wp]):
                            continue
            py = p // wp
            px = p - py * wp
            if dx != 0 and dy != 0:
                j = _jump_diagonal(free, rows, cols, nwr, nwc, py, px, dy, dx, gy, gx, wp)
            else:
                j = _jump_line(rows, cols, nwr, nwc, py, px, dy, dx, gy, gx, wp)
            if j < 0:
                continue
            st = stamp[j]
            if st == closed:
                continue
            jr = j // wp
            steps = max(abs(jr - p // wp), abs((j - jr * wp) - (p - (p // wp) * wp)))
            ng = g0 + (steps * _SQRT2 if dx != 0 and dy != 0 else float(steps))
            if st == gen and ng >= gbuf[j]:
                continue
            gbuf[j] = ng
            stamp[j] = gen
            parent[j] = p
            hkey, hnode, size = heap_push(hkey, hnode, size, ng + _octile(j, goal, wp), j)
    meta[0] = size
    return code, n_exp, hkey, hnode


@njit(cache=True, nogil=True)
def _jps_trace(parent, start, goal, wp, ox, oy, res):
    """The cell path (every cell between the jump points), its centres, and the numbers
    of straight and diagonal moves."""
    n = 1
    p = goal
    while p != start:
        q = parent[p]
        r, c = p // wp, p - (p // wp) * wp
        qr, qc = q // wp, q - (q // wp) * wp
        n += max(abs(r - qr), abs(c - qc))
        p = q
    out = np.empty((n, 2), dtype=np.int64)
    pts = np.empty((n, 2))
    i = n - 1
    p = goal
    straight = 0
    diagonal = 0
    while True:
        r, c = p // wp, p - (p // wp) * wp
        if p == start:
            out[i, 0] = r - 1
            out[i, 1] = c - 1
            break
        q = parent[p]
        qr, qc = q // wp, q - (q // wp) * wp
        sr = int(qr > r) - int(qr < r)
        sc = int(qc > c) - int(qc < c)
        k = max(abs(r - qr), abs(c - qc))
        if sr != 0 and sc != 0:
            diagonal += k
        else:
            straight += k
        for _ in range(k):
            out[i, 0] = r - 1
            out[i, 1] = c - 1
            i -= 1
            r += sr
            c += sc
        p = q
    for i in range(n):
        pts[i, 0] = ox + (out[i, 1] + 0.5) * res
        pts[i, 1] = oy + (out[i, 0] + 0.5) * res
    return out, pts, straight, diagonal


def _bit_lines(free: np.ndarray) -> tuple[np.ndarray, int]:
    """Each line of ``free`` (padded, 0/1) as bits, cell ``x`` at bit ``x + 64`` of its
    line (a blocked guard word on either side), ``nw`` words a line; returns the flat words
    and ``nw``."""
    n_lines, n = free.shape
    nw = (n + 128 + 63) // 64
    buf = np.zeros((n_lines, nw * 64), dtype=bool)
    buf[:, 64:64 + n] = free
    words = np.packbits(buf, axis=1, bitorder="little").view("<u8")
    return np.ascontiguousarray(words, dtype=np.uint64).ravel(), nw


class JPSSearcher(_Regions):
    """Jump point search on one occupancy grid, with buffers kept between queries.

    Parameters
    ----------
    occupied : ndarray of bool, shape (H, W)
        ``True`` where a cell is blocked.
    labels : ndarray of int, optional
        Connected-component labels of the free cells (4-connected: the same
        regions as 8-connected moves without corner cutting); computed when not
        given, as :class:`~pathfuse.search.astar.AStarSearcher` does.  A query
        between two labelled regions answers ``NO_PATH`` at once.

    Notes
    -----
    Only the rule without corner cutting.  Not re-entrant: :func:`get_jps_searcher`
    hands a fresh searcher to a second thread.
    """

    corner_cutting = False

    def __init__(self, occupied: np.ndarray, labels: np.ndarray | None = None) -> None:
        occ = np.asarray(occupied, dtype=bool)
        if occ.ndim != 2 or occ.size == 0:
            raise MapError(f"occupied must be a non-empty 2-D array, got shape {occ.shape}")
        self.shape = (int(occ.shape[0]), int(occ.shape[1]))
        h, w = self.shape
        self._wp = w + 2
        free = np.zeros((h + 2, w + 2), dtype=np.uint8)
        np.logical_not(occ, out=free[1:-1, 1:-1].view(bool))
        self._free = free.ravel()
        self._rows, self._nwr = _bit_lines(free)
        self._cols, self._nwc = _bit_lines(free.T)
        n = self._free.size
        self._g = np.empty(n, dtype=np.float64)
        self._stamp = np.zeros(n, dtype=np.int32)
        self._parent = np.empty(n, dtype=np.int64)
        self._hkey = np.empty(1024, dtype=np.float64)
        self._hnode = np.empty(1024, dtype=np.int64)
        self._meta = np.zeros(1, dtype=np.int64)
        self._gen = 0
        self.free_count = int(occ.size - np.count_nonzero(occ))
        self._init_labels(occ, labels)
        self.lock = threading.Lock()

    def search(self, start_cell: tuple[int, int], goal_cell: tuple[int, int],
               heuristic: str = "octile", max_expansions: int | None = None,
               time_limit_s: float | None = None) -> SearchResult:
        """Shortest path between two free cells (see :meth:`AStarSearcher.search
        <pathfuse.search.astar.AStarSearcher.search>`; ``heuristic`` is accepted for the
        same signature and ignored: jump point search uses the octile distance).

        ``max_expansions`` counts expanded jump points, not cells.
        """
        h, w = self.shape
        (sr, sc), (gr, gc) = (int(v) for v in start_cell), (int(v) for v in goal_cell)
        for what, r, c in (("start", sr, sc), ("goal", gr, gc)):
            if not (0 <= r < h and 0 <= c < w):
                raise QueryError(f"{what} cell ({r}, {c}) is outside the {h}x{w} grid")
            if not self._free[(r + 1) * self._wp + c + 1]:
                raise QueryError(f"{what} cell ({r}, {c}) is occupied")
        with self.lock:
            return self._search(sr, sc, gr, gc, max_expansions, time_limit_s, (0.0, 0.0, 1.0))

    def search_checked(self, start_cell: tuple[int, int], goal_cell: tuple[int, int],
                       heuristic: str, max_expansions: int | None,
                       time_limit_s: float | None,
                       origin: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> SearchResult:
        """:meth:`search` for cells already checked (in bounds and free); ``origin`` is
        ``(x0, y0, resolution)`` of the map, for :attr:`SearchResult.points`."""
        with self.lock:
            return self._search(start_cell[0], start_cell[1], goal_cell[0], goal_cell[1],
                                max_expansions, time_limit_s, origin)

    def _search(self, sr: int, sc: int, gr: int, gc: int, max_expansions: int | None,
                time_limit_s: float | None,
                origin: tuple[float, float, float]) -> SearchResult:
        t0 = time.perf_counter()
        ox, oy, res = origin
        if sr == gr and sc == gc:
            return SearchResult(Status.SUCCESS, np.array([[sr, sc]], dtype=np.int64), 0.0, 0,
                                np.array([[ox + (sc + 0.5) * res, oy + (sr + 0.5) * res]]))
        labels = self._labels
        if labels is not None and labels[sr, sc] != labels[gr, gc]:
            return SearchResult(Status.NO_PATH, _NO_CELLS, math.inf, 0)
        budget = self.free_count if max_expansions is None else \
            min(int(max_expansions), self.free_count)
        wp = self._wp
        start = (sr + 1) * wp + sc + 1
        goal = (gr + 1) * wp + gc + 1
        if self._gen >= _STAMP_LIMIT:
            self._stamp[:] = 0
            self._gen = 0
        self._gen += 2
        chunk = _CHUNK if time_limit_s is not None else budget
        done = 0
        first = start
        while True:
            code, n, self._hkey, self._hnode = _jps_kernel(
                self._free, self._rows, self._cols, self._nwr, self._nwc, self._g,
                self._stamp, self._parent, self._hkey, self._hnode, self._meta, self._gen,
                first, goal, wp, min(chunk, budget - done))
            first = -1
            done += n
            if code == CODE_SUCCESS:
                cells, pts, a, b = _jps_trace(self._parent, start, goal, wp, ox, oy, res)
                return SearchResult(Status.SUCCESS, cells, a + b * _SQRT2, done, pts)
            if code == CODE_NO_PATH:
                if self._labels is None:
                    self._labels = self._make_labels()
                return SearchResult(Status.NO_PATH, _NO_CELLS, math.inf, done)
            if done >= budget:
                return SearchResult(Status.MAX_ITERATIONS, _NO_CELLS, math.inf, done)
            if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
                return SearchResult(Status.TIMEOUT, _NO_CELLS, math.inf, done)


_CACHE_LOCK = threading.Lock()


def get_jps_searcher(grid) -> JPSSearcher:  # type: ignore[no-untyped-def]
    """The cached :class:`JPSSearcher` of ``grid`` (a :class:`~pathfuse.grid.GridMap`),
    kept beside the map's A* searchers (weakly keyed by the map); a fresh one when the
    cached one is busy in another thread."""
    from pathfuse.search.astar import _CACHE
    from pathfuse.search.astar import _CACHE_LOCK as _ALOCK

    with _ALOCK:
        per_map = _CACHE.get(grid)
        if per_map is None:
            per_map = {}
            _CACHE[grid] = per_map
        searcher = per_map.get("jps")
    if searcher is None:
        searcher = _new(grid, None)
        with _ALOCK:
            searcher = per_map.setdefault("jps", searcher)
    if searcher.lock.locked():
        return _new(grid, searcher._labels)
    return searcher  # type: ignore[no-any-return]


def _new(grid, labels: np.ndarray | None) -> JPSSearcher:  # type: ignore[no-untyped-def]
    occ = grid.occupied
    if labels is None and occ.size <= _EAGER_LABELS:
        labels = grid.components
    s = JPSSearcher(occ, labels=labels)
    s._grid = weakref.ref(grid)
    return s


_WARM = False


def warmup() -> None:
    """Compile (or load from numba's on-disk cache) the jump point search kernels."""
    global _WARM
    if _WARM:
        return
    occ = np.zeros((3, 4), dtype=bool)
    occ[1, 1] = True
    JPSSearcher(occ).search((0, 0), (2, 3))
    _WARM = True
