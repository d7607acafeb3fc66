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
  computed for the corner-cutting rule).  On a map of more than
  ``_EAGER_LABELS`` cells (2**21) the labels are made only when a search
  first exhausts its region: labelling 4096 x 4096 cells costs about half a
  second, which the first query on a new map would otherwise pay even though
  most queries have a path; until then a query between two regions answers
  ``NO_PATH`` after searching the start's region.
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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pathfuse.grid import label_regions
from pathfuse.result import (
    CODE_GROW,
    CODE_NO_PATH,
    CODE_SUCCESS,
    ConfigError,
    MapError,
    QueryError,
    Status,
)
from pathfuse.search.kernel import (
    _BLOCKED,
    _CHUNK,
    _RADIX_HEADS,
    _RING_SIZE,
    _STAMP_LIMIT,
    _astar_radix,
    _astar_ring,
)
from pathfuse.tier import interpreting
from pathfuse.validate import short as _shown

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

_EAGER_LABELS = 1 << 21  # maps of more cells label their regions on first need
_FLAT_LABELS = 1 << 16  # maps of at most this many cells also keep them as a Python list
_NO_CELLS = np.zeros((0, 2), dtype=np.int64)
_NO_CELLS.setflags(write=False)
_NO_POINTS = np.zeros((0, 2))
_NO_POINTS.setflags(write=False)


# ----------------------------------------------------------------------------- Python API
@dataclass
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
    points : ndarray, shape (N, 2), float
        The cells' centres in world metres for the ``origin`` given to
        :meth:`AStarSearcher.search_checked` (cell units with the origin at
        ``(0, 0)`` otherwise).
    """

    status: Status
    cells: np.ndarray
    cost: float
    expansions: int
    points: np.ndarray = field(default_factory=lambda: _NO_POINTS)


class _Regions:
    """The connected-region labels of a searcher's free cells, made eagerly on a small map
    and on first need (a search that exhausted its region) on a large one."""

    corner_cutting: bool

    def _init_labels(self, occ: np.ndarray, labels: np.ndarray | None) -> None:
        self._occ = occ
        self._grid: weakref.ref | None = None  # a GridMap whose cached labels to use
        self._labels: np.ndarray | None = None
        if labels is not None:
            self._labels = np.asarray(labels)
        elif occ.size <= _EAGER_LABELS:
            self._labels = self._make_labels()
        # on a small map, the labels as a list of row-major ints too: a query's label test
        # without numpy's indexing (issue 21: on a 32 x 32 map every step of a query counts)
        self._flat: list[int] | None = None
        if self._labels is not None and occ.size <= _FLAT_LABELS and \
                self._labels.shape == occ.shape:
            self._flat = self._labels.ravel().tolist()

    def _make_labels(self) -> np.ndarray:
        """The component labels of the free cells under this searcher's corner rule (the
        map's cached ``components`` when the searcher came from the per-map cache)."""
        grid = self._grid() if self._grid is not None else None
        if grid is not None and not self.corner_cutting:
            return np.asarray(grid.components)
        return label_regions(~self._occ, eight=self.corner_cutting)


class AStarSearcher(_Regions):
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
        (0 on blocked cells); computed when not given (on a map of more than
        ``_EAGER_LABELS`` cells, only once a search has exhausted a region).

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
        cell = np.full((h + 2, w + 2), _BLOCKED, dtype=np.uint32)
        np.multiply(occ, _BLOCKED, out=cell[1:-1, 1:-1], dtype=np.uint32)  # 3x a mask
        self._cell = cell.ravel()  # blocked / stamp and move: see kernel._make_kernel
        n = self._cell.size
        # g and the kernel's scratch (one expansion's queued neighbours' f), in one array
        self._f8 = np.empty(n + 8, dtype=np.float64)
        self._g = self._f8[:n]
        self._meta = np.zeros(6, dtype=np.int64)  # see kernel._make_kernel
        self._pack(int(min(max(1024, n // 4), 1 << 20)), None)
        self._gen = 0
        self._closed_gen = -1  # stamp of the cells the last search closed (-1: none)
        self.free_count = int(occ.size - np.count_nonzero(occ))
        self._init_labels(occ, labels)
        self.lock = threading.Lock()

    def _pack(self, cap: int, old: dict[str, np.ndarray] | None) -> None:
        """The open list's buffers for a pool and heap of ``cap`` entries, packed by dtype
        in two arrays that the kernel takes apart (5 arrays to unbox per call, not 12:
        issue 21): ``_u64`` = qkey | skey | bits | cq (the scratch of one expansion's
        queued neighbours) and ``_i32`` = heads (the ring's) | rheads (the radix heap's) |
        qnode | qnext | snode, each part also
        kept as a view under its own name.  With ``old``, its entries are copied (they
        keep their indices; the ring's heads and bits too, a search paused midway resumes
        on them)."""
        nb = _RING_SIZE // 64
        h0 = _RING_SIZE + _RADIX_HEADS
        u64 = np.empty(2 * cap + nb + 8, dtype=np.uint64)
        i32 = np.empty(h0 + 3 * cap, dtype=np.int32)
        self._qkey, self._skey = u64[:cap], u64[cap:2 * cap]
        self._bits, self._cq = u64[2 * cap:2 * cap + nb], u64[2 * cap + nb:]
        self._heads, self._rheads = i32[:_RING_SIZE], i32[_RING_SIZE:h0]
        self._qnode = i32[h0:h0 + cap]
        self._qnext = i32[h0 + cap:h0 + 2 * cap]
        self._snode = i32[h0 + 2 * cap:]
        self._cf = self._f8[self._g.shape[0]:]
        if old is not None:
            for name, src in old.items():
                getattr(self, name)[:src.shape[0]] = src
        self._u64, self._i32 = u64, i32

    def _grow_heap(self) -> None:
        """Double the open-list pool and heap (entries keep their indices)."""
        self._pack(2 * self._qkey.shape[0], {name: getattr(self, name) for name in (
            "_qkey", "_skey", "_qnode", "_qnext", "_snode", "_heads", "_rheads", "_bits")})

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
                              f"got {_shown(heuristic)}")
        h, w = self.shape
        (sr, sc), (gr, gc) = (int(v) for v in start_cell), (int(v) for v in goal_cell)
        for what, r, c in (("start", sr, sc), ("goal", gr, gc)):
            if not (0 <= r < h and 0 <= c < w):
                raise QueryError(f"{what} cell ({r}, {c}) is outside the {h}x{w} grid")
            if self._cell[(r + 1) * self._wp + c + 1] == _BLOCKED:
                raise QueryError(f"{what} cell ({r}, {c}) is occupied")
        return SearchResult(*self.search_fields((sr, sc), (gr, gc), heuristic, max_expansions,
                                                time_limit_s))

    def search_checked(self, start_cell: tuple[int, int], goal_cell: tuple[int, int],
                       heuristic: str, max_expansions: int | None,
                       time_limit_s: float | None,
                       origin: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> SearchResult:
        """:meth:`search` for cells a :class:`~pathfuse.problem.Problem` has already checked
        (in bounds and free; the heuristic a known name): the checks are not repeated.
        ``origin`` is ``(x0, y0, resolution)`` of the map, for :attr:`SearchResult.points`."""
        return SearchResult(*self.search_fields(start_cell, goal_cell, heuristic,
                                                max_expansions, time_limit_s, origin))

    def search_fields(self, start_cell: tuple[int, int], goal_cell: tuple[int, int],
                      heuristic: str, max_expansions: int | None,
                      time_limit_s: float | None,
                      origin: tuple[float, float, float] = (0.0, 0.0, 1.0),
                      ) -> tuple[Status, np.ndarray, float, int, np.ndarray]:
        """:meth:`search_checked`'s fields ``(status, cells, cost, expansions, points)`` as a
        tuple, without building the :class:`SearchResult` (the ``plan()`` lane,
        :func:`pathfuse.planners.run._astar_as_planned`; the cells checked as for
        :meth:`search_checked`).  The body of every search."""
        with self.lock:
            (sr, sc), (gr, gc) = start_cell, goal_cell
            t0 = time.perf_counter() if time_limit_s is not None else 0.0
            self._closed_gen = -1
            if sr == gr and sc == gc:
                ox, oy, res = origin
                return (Status.SUCCESS, np.array([[sr, sc]], dtype=np.int64), 0.0, 0,
                        np.array([[ox + (sc + 0.5) * res, oy + (sr + 0.5) * res]]))
            flat = self._flat
            if flat is not None:
                w = self.shape[1]
                if flat[sr * w + sc] != flat[gr * w + gc]:
                    return Status.NO_PATH, _NO_CELLS, math.inf, 0, _NO_POINTS
            else:
                labels = self._labels
                if labels is not None and labels[sr, sc] != labels[gr, gc]:
                    return Status.NO_PATH, _NO_CELLS, math.inf, 0, _NO_POINTS
            # a search never expands more than the free cells: a larger budget (even 10**30)
            # means no cap, and stays within the kernel's 64-bit integers
            budget = self.free_count if max_expansions is None else \
                min(int(max_expansions), self.free_count)
            wp = self._wp
            start = (sr + 1) * wp + sc + 1
            goal = (gr + 1) * wp + gc + 1
            if self._gen >= _STAMP_LIMIT:
                self._cell[self._cell != _BLOCKED] = 0
                self._gen = 0
            self._gen += 2
            gen = self._gen
            self._closed_gen = gen + 1
            kernel = _KERNEL_ENTRY["octile" if heuristic == "octile" else "euclidean"]
            chunk = _CHUNK if time_limit_s is not None else budget
            if interpreting():  # kernels run interpreted (pathfuse.tier): its budget is
                chunk = min(chunk, 4096)  # checked between calls (some 0.1 s apart)
            done = 0
            first = start
            ox, oy, res = origin
            while True:
                step = min(chunk, budget - done)
                code, n, cells, pts, cost = kernel(
                    self._cell, self._f8, self._u64, self._i32, self._meta, gen, first, goal,
                    wp, self.corner_cutting, step, start, ox, oy, res,
                )
                first = -1
                done += n
                if code == CODE_SUCCESS:  # the kernel traced the path in the same call
                    return Status.SUCCESS, cells, cost, done, pts
                if code == CODE_NO_PATH:
                    if self._labels is None:  # the next query between regions: no search
                        self._labels = self._make_labels()
                    return Status.NO_PATH, _NO_CELLS, math.inf, done, _NO_POINTS
                if code == CODE_GROW:
                    self._grow_heap()
                    continue
                if done >= budget:
                    return Status.MAX_ITERATIONS, _NO_CELLS, math.inf, done, _NO_POINTS
                if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
                    return Status.TIMEOUT, _NO_CELLS, math.inf, done, _NO_POINTS

    def closed_mask(self) -> np.ndarray:
        """The cells the last search closed (expanded), as an (H, W) bool array.

        For looking inside a search (``pathfuse serve`` draws it); nothing on
        the search path computes it.  All False when the last search expanded
        nothing (start equal to goal, or answered from connectivity labels).

        >>> occ = np.zeros((3, 4), dtype=bool)
        >>> s = AStarSearcher(occ)
        >>> r = s.search((0, 0), (0, 3))
        >>> int(s.closed_mask().sum()) == r.expansions
        True
        """
        h, w = self.shape
        if self._closed_gen < 0:
            return np.zeros((h, w), dtype=bool)
        word = self._cell.reshape(h + 2, w + 2)[1:-1, 1:-1]
        return (word != _BLOCKED) & ((word >> 5) == self._closed_gen)

    def expansion_order(self, goal_cell: tuple[int, int],
                        heuristic: str = "euclidean") -> np.ndarray:
        """The cells of :meth:`closed_mask` in the order the last search expanded them, as
        row-major indices ``row * W + col`` (int64).

        The kernel pops nodes in non-decreasing ``f = g + h`` (``h`` consistent, so ``g`` is
        final once a node is closed), so sorting the closed cells by their ``f``, recomputed
        from the stored ``g`` as the kernel computes it, gives its order; among equal ``f``
        (to 1e-9 cell, so that rounding does not split a tie) the lower ``g`` comes first
        (the goal, which ends the search, is last).  The kernel breaks such ties its own
        way, so cells of equal ``f`` may be permuted.  For looking inside a search
        (``pathfuse serve`` animates it); nothing on the search path computes it.
        ``goal_cell`` and ``heuristic`` must be those of the last search.

        >>> occ = np.zeros((3, 4), dtype=bool)
        >>> s = AStarSearcher(occ)
        >>> r = s.search((0, 0), (0, 3))
        >>> order = s.expansion_order((0, 3))
        >>> int(order[0]), int(order[-1]), len(order) == r.expansions
        (0, 3, True)
        """
        h, w = self.shape
        mask = self.closed_mask()
        idx = np.flatnonzero(mask)
        if idx.size == 0:
            return idx.astype(np.int64)
        g = self._g.reshape(h + 2, w + 2)[1:-1, 1:-1].ravel()[idx]
        dy = np.abs(idx // w - int(goal_cell[0]))
        dx = np.abs(idx % w - int(goal_cell[1]))
        if heuristic == "octile":
            hv = np.where(dx > dy, dx + (1.4142135623730951 - 1.0) * dy,
                          dy + (1.4142135623730951 - 1.0) * dx)
        else:
            hv = np.sqrt((dx * dx + dy * dy).astype(np.float64))
        # f rounded to 1e-9 cell: sums that tie exactly tie here too, whatever the rounding
        return idx[np.lexsort((idx, g, np.round(g + hv, 9)))].astype(np.int64)


# ----------------------------------------------------------------------------- cache
_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_CACHE_LOCK = threading.Lock()


def _dead() -> None:
    return None


#: The map of the last :func:`get_searcher` call (weakly) and its searchers: the look-up
#: without :class:`weakref.WeakKeyDictionary`'s call (issue 21: a query on a small map
#: pays for every layer); forgotten when the map goes.
_LAST: tuple[Any, dict[bool, AStarSearcher] | None] = (_dead, None)


def _remember(grid: Any, per_map: dict[bool, AStarSearcher]) -> None:
    global _LAST

    def forget(ref: Any) -> None:
        global _LAST
        if _LAST[0] is ref:
            _LAST = (_dead, None)

    try:
        _LAST = (weakref.ref(grid, forget), per_map)
    except TypeError:  # not weakly referable: the WeakKeyDictionary would have refused it
        pass


def get_searcher(grid, corner_cutting: bool = False) -> AStarSearcher:
    """The cached :class:`AStarSearcher` of ``grid`` (a GridMap) for a corner rule.

    The first call on a map builds the padded grid and the buffers; later
    calls reuse them.  The cache holds the map weakly, so it goes when the map
    goes.  If the cached searcher is busy in another thread, a fresh one is
    returned (its buffers are not cached).
    """
    key = bool(corner_cutting)
    last = _LAST  # one read: the pair is replaced whole
    if last[0]() is grid:  # the map of the last look-up (a loop of queries on one map)
        per_map = last[1]
    else:
        per_map = _CACHE.get(grid)  # a read needs no lock (the GIL); adding a map takes it
        if per_map is not None:
            _remember(grid, per_map)
    searcher = per_map.get(key) if per_map is not None else None
    if searcher is not None:
        return _new_searcher(grid, key, searcher._labels) if searcher.lock.locked() \
            else searcher
    with _CACHE_LOCK:
        per_map = _CACHE.get(grid)
        if per_map is None:
            per_map = {}
            _CACHE[grid] = per_map
        searcher = per_map.get(key)
    _remember(grid, per_map)
    if searcher is None:
        searcher = _new_searcher(grid, key, None)
        with _CACHE_LOCK:
            searcher = per_map.setdefault(key, searcher)
    if searcher.lock.locked():
        return _new_searcher(grid, key, searcher._labels)
    return searcher


def _new_searcher(grid, corner_cutting: bool,  # type: ignore[no-untyped-def]
                  labels: np.ndarray | None) -> AStarSearcher:
    """A searcher on ``grid`` that takes its labels from the map's cache (eagerly on a
    small map, on first need on a large one)."""
    occ = grid.occupied
    if labels is None and not corner_cutting and occ.size <= _EAGER_LABELS:
        labels = grid.components
    s = AStarSearcher(occ, corner_cutting=corner_cutting, labels=labels)
    s._grid = weakref.ref(grid)
    return s


# What a search calls for each heuristic: its kernel, or after warmup() numba's compiled
# entry of it for the searcher's argument types (see _entry_point).  The kernel traces the
# path itself (kernel._trace), so a query makes one call into compiled code.
_KERNEL_ENTRY: dict[str, Any] = {"euclidean": _astar_ring, "octile": _astar_radix}


def _entry_point(dispatcher: Any, args: tuple[Any, ...]) -> Any:
    """The compiled entry of the numba ``dispatcher`` for the types of ``args``: numba's own
    wrapper of the machine code, which unboxes each argument by its compiled type (an
    array of another dtype is a TypeError).  Calling it skips the dispatcher's
    resolution of every argument's type, which the searcher's arguments (arrays of fixed
    dtypes, Python ints and bools) never need: 0.6 of the kernel's 1.3 µs call and
    0.3 of the trace's 1.6 µs on a tiny query (issue 21).  The dispatcher itself where
    numba keeps no such entry (``NUMBA_DISABLE_JIT``, another numba)."""
    try:
        from numba import typeof

        return dispatcher.overloads[tuple(typeof(a) for a in args)].entry_point
    except Exception:  # noqa: BLE001 - no entry: the dispatcher resolves the types itself
        return dispatcher


_WARM: set[str] = set()  # the heuristics whose kernel is compiled or loaded


def warmup(heuristics: tuple[str, ...] = HEURISTICS) -> None:
    """Compile (or load from numba's on-disk cache) the A* kernels of ``heuristics`` (each
    has its own) on a tiny grid."""
    todo = [h for h in heuristics if h not in _WARM]
    if not todo:
        return
    occ = np.zeros((3, 4), dtype=bool)
    occ[1, 1] = True
    for cut in (False, True):
        s = AStarSearcher(occ, corner_cutting=cut)
        for heur in todo:
            s.search((0, 0), (2, 3), heuristic=heur)
            s.search((0, 0), (2, 3), heuristic=heur, time_limit_s=10.0)
    # the arguments of a search (the types are all that matters; nothing is called)
    for heur in todo:
        _KERNEL_ENTRY[heur] = _entry_point(_KERNEL_ENTRY[heur], (
            s._cell, s._f8, s._u64, s._i32, s._meta, 2, 5, 7, s._wp, False, 1, 5, 0.0, 0.0,
            1.0))
    _WARM.update(todo)
