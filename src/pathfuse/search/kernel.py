"""The numba kernel of grid A* (see :mod:`pathfuse.search.astar` for the model and the
open lists), and the path tracing.  Low level: :class:`~pathfuse.search.astar.AStarSearcher`
owns the buffers and calls it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from pathfuse.result import CODE_GROW, CODE_NO_PATH, CODE_RUNNING, CODE_SUCCESS
from pathfuse.tier import python_for

_CHUNK = 1 << 16  # expansions between clock checks when a time limit is set
_RING_SCALE = 1024.0  # ring buckets per cell of f (euclidean open list)
_RING_SIZE = 4096  # > 2 * sqrt(2) * _RING_SCALE + 2, a power of two
_RADIX_HEADS = 65  # the radix heap's buckets (a key and the last differ in bit 0..63, or not)
_STAMP_LIMIT = (1 << 27) - 4  # stamps live in the 27 high bits of a cell's word
_BLOCKED = np.uint32(0xFFFFFFFF)  # the word of a blocked (or border) cell


# ----------------------------------------------------------------------------- kernels
@intrinsic
def _bit_length(typingctx, x):
    """Number of significant bits of a uint64 (LLVM ctlz), as int64."""
    sig = types.int64(types.uint64)

    def codegen(context, builder, signature, args):
        lz = builder.ctlz(args[0], ir.Constant(ir.IntType(1), 0))
        return builder.sub(ir.Constant(ir.IntType(64), 64), lz)

    return sig, codegen


@python_for(_bit_length)
def _bit_length_py(x: np.uint64) -> int:
    return int(x).bit_length()


@intrinsic
def _bits_of(typingctx, x):
    """The IEEE-754 bits of a float64, as uint64 (an LLVM bitcast: no memory round trip)."""
    sig = types.uint64(types.float64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return sig, codegen


@python_for(_bits_of)
def _bits_of_py(x: float) -> np.uint64:
    return np.float64(x).view(np.uint64)  # type: ignore[no-any-return]


@intrinsic
def _fetch(typingctx, cell, gbuf, q, uw):
    """Prefetch what expanding cell ``q`` reads: its row and the rows above and below
    (``q - uw``, ``q``, ``q + uw``), in the cell words and in ``g`` (at 4096 x 4096 cells the
    search waits on memory).  LLVM ``prefetch`` (read, high locality); no effect on what the
    program computes.  An intrinsic, not a numba function inlined at each call site, so
    numba types one call per site instead of a body (issue 21: the kernel's first compile)."""
    sig = types.void(cell, gbuf, q, uw)

    def codegen(context, builder, signature, args):
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        # declare_intrinsic mangles the name for llvmlite's pointer type ("p0i8"), which the
        # LLVM of every numba we support reads (newer ones upgrade it to the opaque "p0")
        fn = builder.module.declare_intrinsic(
            "llvm.prefetch", [i8p], ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32]))
        q, uw = args[2], args[3]
        idx = (builder.sub(q, uw), q, builder.add(q, uw))
        for k in (0, 1):
            ary = context.make_array(signature.args[k])(context, builder, args[k])
            for i in idx:
                ptr = builder.bitcast(builder.gep(ary.data, [i]), i8p)
                builder.call(fn, [ptr, ir.Constant(i32, 0), ir.Constant(i32, 3),
                                  ir.Constant(i32, 1)])
        return context.get_dummy_value()

    return sig, codegen


@python_for(_fetch)
def _fetch_py(cell: Any, gbuf: Any, q: Any, uw: Any) -> None:
    """A prefetch only hints the cache: nothing to do in the interpreter."""


@njit(cache=True, nogil=True)
def _h(dy: float, dx: float, octile: bool) -> float:
    """The heuristic of a cell ``(dy, dx)`` from the goal (octile or euclidean), given as
    floats that hold integers (so the squares and their sum are exact: the value is that of
    the same sums in integers)."""
    if octile:
        ax = abs(dx)
        ay = abs(dy)
        if ax > ay:
            return ax + (1.4142135623730951 - 1.0) * ay
        return ay + (1.4142135623730951 - 1.0) * ax
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True, nogil=True)
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


@python_for(_trailing_zeros)
def _trailing_zeros_py(x: np.uint64) -> int:
    v = int(x)
    return (v & -v).bit_length() - 1


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def _trace(cell, start, goal, wp, ox, oy, res):
    """The path from start to goal: ``(cells, points)``, the (n, 2) unpadded ``(row, col)``
    cells and their centres ``[x, y]`` for a grid of origin ``(ox, oy)`` and cell side
    ``res`` (one call, so a query pays one dispatch for both)."""
    offs = (1, -1, wp, -wp, wp + 1, wp - 1, -wp + 1, -wp - 1)  # a tuple: no np.array to compile
    n = 1
    p = goal
    while p != start:
        p -= offs[(cell[p] >> 1) & 15]
        n += 1
    out = np.empty((n, 2), dtype=np.int64)
    pts = np.empty((n, 2))
    p = goal
    for i in range(n - 1, -1, -1):
        r = p // wp
        out[i, 0] = r - 1
        out[i, 1] = p - r * wp - 1
        pts[i, 0] = ox + (out[i, 1] + 0.5) * res
        pts[i, 1] = oy + (out[i, 0] + 0.5) * res
        if i > 0:
            p -= offs[(cell[p] >> 1) & 15]
    return out, pts


# Long on purpose (~270 lines): the hot loop of every grid search, one function so
# that numba keeps its state (the open list's heads, the current cell's word and its
# neighbours') in locals; the pieces that stand alone are already helpers, and
# tests/test_astar_golden.py pins its paths and expansion counts.  The 8 moves are
# written out: a loop over tuples of offsets compiled to a jump table with spilled
# registers, a relaxation helper that takes the arrays to a call per move (each array's
# fields on the stack) and, inlined by numba (inline="always"), to reference counting per
# array and move; the helper versions ran 3-6x slower than the loop (issue 21).
def _make_kernel(use_ring: bool) -> Any:
    """The A* kernel of one open list: ``use_ring`` (the euclidean heuristic) or the radix
    heap (octile).  ``use_ring`` and ``octile`` are constants of the closure, so numba
    prunes the other open list's code before typing it: each kernel compiles about half the
    code, and a query compiles only the one its heuristic runs (numba's cache keeps both
    apart: its index key hashes a closure's variables)."""
    octile = not use_ring

    @njit(cache=True, nogil=True)
    def kernel(
        cell, f8, u64, i32, meta, gen, start, goal, wp, corner_cutting, max_exp, root, ox, oy,
        res,
    ):
        """Run A* until the goal is closed, the open list empties or ``max_exp`` expansions.

        One ``uint32`` word per padded cell (``cell``) holds what a relaxation
        reads: ``_BLOCKED`` (all bits set) on a blocked or border cell, else
        ``stamp << 5 | move << 1`` with ``move`` (0-8) the move that reached it.
        ``stamp == gen``: ``gbuf[p]`` is valid and ``p`` open; ``stamp == gen +
        1``: ``p`` closed.  So one compare (``word >= (gen + 1) << 5``) rejects a
        closed or blocked neighbour, bit 0 tells blocked from free for the corner
        rule, and a cell's state costs one load from one array (the search is
        bound by memory on large maps: separate free, stamp and parent arrays cost
        2-4x more in the grid work).  Indices are unsigned (no negative-index
        wraparound test on each access).  ``start >= 0`` starts a query;
        ``start < 0`` resumes the one whose open list is saved in the arrays and
        ``meta``.

        Two open lists, both exact and both keyed by the IEEE-754 bits of ``f``
        (non-negative doubles order like their bits); entries live in a pool
        (``qkey``, ``qnode``, ``qnext``) of singly linked lists with a free list:

        * radix kernel (``use_ring`` false, octile): a radix heap (Ahuja et al.
          1990).  Bucket ``b`` of ``heads[:65]`` holds keys whose highest bit
          differing from the last popped key is ``b - 1`` (bucket 0: equal keys,
          popped last-in first-out).
          When bucket 0 is empty the first non-empty bucket is searched for its
          minimum, which becomes the new last key, and spread over lower buckets.
          Best when many ``f`` are exactly equal (the octile heuristic).
        * ring kernel (``use_ring``, euclidean): ``f`` is cut into buckets of ``1 / _RING_SCALE``
          cells.  With a consistent heuristic every open ``f`` lies in
          ``[f_min, f_min + 2 sqrt 2]`` (a child's ``f`` exceeds its parent's by at
          most two steps), so ``_RING_SIZE`` buckets used cyclically hold them
          all; a bitmap (``bits``) finds the next non-empty one.  The bucket being
          expanded is moved into a binary heap (``skey``, ``snode``) ordered
          exactly by ``f``; children falling into it go straight there.  Each entry
          moves once: best when ``f`` values are mostly distinct (euclidean).  A
          bucket of one entry, the usual case, is popped without the heap.  The
          heap is a binary min-heap: a parent not greater than the key stops a
          push (:func:`_spush`), a child not less than the moved key stops a pop
          (written out in the loop).

        ``meta`` = [radix: last key / ring: current bucket, free-list head, pool
        slots used, pool entries, heap entries, ring: 1 when its buckets are all
        empty (a query ended), else they are cleared when a query starts].  ``cq``
        (uint64) and ``cf`` (float64), 8 entries each, hold the neighbours one
        expansion queues and their ``f`` (the caller's, so that the search
        allocates nothing).  Returns (code, expansions in this call, cells,
        points, cost): on ``CODE_SUCCESS`` the path from ``root`` (the query's
        start) to the goal as :func:`_trace` gives it for the grid origin
        ``(ox, oy)`` and cell side ``res``, and ``g`` of the goal; else two
        empty (0, 2) arrays and ``inf``.
        """
        # the buffers, packed by dtype in four arrays (one unboxing each per call, not
        # twelve: issue 21), as views: f8 = g (one per cell) | cf (8); u64 = qkey (cap) |
        # skey (cap) | bits | cq (8); i32 = the ring's heads | the radix heap's heads (65) |
        # qnode (cap) | qnext (cap) | snode (cap).  Each open list has heads of its own, so
        # an octile query leaves the ring empty for the next euclidean one (it cleared all
        # 4096 buckets after each octile query when they shared them)
        nc = cell.shape[0]
        gbuf = f8[:nc]
        cf = f8[nc:]
        h0 = _RING_SIZE + _RADIX_HEADS
        pc = (i32.shape[0] - h0) // 3
        if use_ring:
            heads = i32[:_RING_SIZE]
        else:
            heads = i32[_RING_SIZE:h0]
        qnode = i32[h0:h0 + pc]
        qnext = i32[h0 + pc:h0 + 2 * pc]
        snode = i32[h0 + 2 * pc:]
        qkey = u64[:pc]
        skey = u64[pc:2 * pc]
        bits = u64[2 * pc:2 * pc + _RING_SIZE // 64]
        cq = u64[2 * pc + _RING_SIZE // 64:]
        s2 = 1.4142135623730951
        one = np.uint64(1)
        rmask = _RING_SIZE - 1
        gr = goal // wp
        gc = goal - gr * wp
        uw = np.uint64(wp)
        ugoal = np.uint64(goal)
        openv = np.uint32(gen << 5)
        closedv = np.uint32((gen + 1) << 5)
        bit0 = np.uint32(1)
        low = np.uint32(31)
        invw = 1.0 / wp
        if start >= 0:
            us = np.uint64(start)
            gbuf[us] = 0.0
            cell[us] = openv | np.uint32(8 << 1)
            sr = start // wp
            f0 = _h(float(sr - gr), float(start - sr * wp - gc), octile)
            k0 = _bits_of(f0)
            fh = np.int64(-1)  # typed int64, not a literal: one signature of _qpush and _spush
            used = np.int64(0)
            if use_ring:
                # a query that ended (goal closed, or region exhausted) left the ring empty
                # (meta[5] = 1, see the end); a new searcher's buffers or a query stopped
                # midway (budget, time) are cleared here, 16 KiB of writes a query no longer
                # pays on a small map (issue 21)
                if meta[5] != 1:
                    for i in range(_RING_SIZE):
                        heads[i] = -1
                    for i in range(_RING_SIZE // 64):
                        bits[i] = 0
                meta[5] = 0
                last = np.uint64(0)
                cur = np.int64(f0 * _RING_SCALE)
                size = 0
                ssize = _spush(skey, snode, np.int64(0), k0, start)
            else:
                for i in range(_RADIX_HEADS):
                    heads[i] = -1
                last = k0
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
        code = CODE_NO_PATH
        while size > 0 or ssize > 0:
            if n_exp >= max_exp:
                code = CODE_RUNNING
                break
            if used + 8 > cap or size + ssize + 8 > scap:
                code = CODE_GROW
                break
            # ---- pop the entry with the smallest f
            if use_ring:
                pi = -1  # set below when a bucket of one entry gives the node directly
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
                    rest = word & (word - one)  # the next bucket in this word: prefetch ahead
                    if rest != 0:
                        nb = heads[(w << 6) + _trailing_zeros(rest)]
                        _fetch(cell, gbuf, np.uint64(qnode[nb]), uw)
                    e = heads[b]
                    heads[b] = -1
                    if qnext[e] < 0:  # one entry (the usual case): the heap would pop it
                        pi = qnode[e]
                        _fetch(cell, gbuf, np.uint64(pi), uw)
                        size -= 1
                        qnext[e] = fh
                        fh = e
                    else:
                        while e >= 0:
                            nxt = qnext[e]
                            _fetch(cell, gbuf, np.uint64(qnode[e]), uw)
                            ssize = _spush(skey, snode, ssize, qkey[e], np.int64(qnode[e]))
                            size -= 1
                            qnext[e] = fh
                            fh = e
                            e = nxt
                if pi < 0:  # pop the small heap's root, written out here (as a helper it
                    # was a call that LLVM did not inline, the arrays' fields pushed on the
                    # stack for each of about one pop per expansion on the Boston maps)
                    pi = snode[0]
                    ssize -= 1
                    if ssize > 0:
                        key = skey[ssize]
                        node = snode[ssize]
                        i = 0
                        while True:
                            child = 2 * i + 1
                            if child >= ssize:
                                break
                            ck = skey[child]
                            if child + 1 < ssize and skey[child + 1] < ck:
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
                        if k == last:
                            b = 0
                            _fetch(cell, gbuf, np.uint64(qnode[e]), uw)
                        else:
                            b = _bit_length(k ^ last)
                        qnext[e] = heads[b]
                        heads[b] = e
                        e = nxt
                e = heads[0]
                heads[0] = qnext[e]
                pi = qnode[e]
                if heads[0] >= 0:
                    _fetch(cell, gbuf, np.uint64(qnode[heads[0]]), uw)
                qnext[e] = fh
                fh = e
                size -= 1
            p = np.uint64(pi)
            sp = cell[p]
            if sp >= closedv:
                continue  # stale duplicate of a node already expanded
            cell[p] = closedv | (sp & low)
            n_exp += 1
            if p == ugoal:
                code = CODE_SUCCESS
                break
            # ---- relax the 8 moves k = 0..7 (the word's move bits k << 1; row, col steps
            # (0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1), as in
            # _trace), written out: the queue order, which decides ties, is k's
            g0 = gbuf[p]
            ur = np.uint64(np.int64(pi) * invw)  # p // wp, off by at most one: corrected
            if ur * uw > p:
                ur -= one
            elif ur * uw + uw <= p:
                ur += one
            dy = float(np.int64(ur) - gr)  # integers in floats: the heuristic's sums are exact
            dx = float(np.int64(p - ur * uw) - gc)
            se = cell[p + one]
            sw = cell[p - one]
            sn = cell[p + uw]
            ss = cell[p - uw]
            n = 0  # improved neighbours, queued below in this order
            if se < closedv:
                ng = g0 + 1.0
                if se < openv or ng < gbuf[p + one]:
                    cq[n], cf[n], n = p + one, ng + _h(dy, dx + 1.0, octile), n + 1
                    gbuf[p + one], cell[p + one] = ng, openv
            if sw < closedv:
                ng = g0 + 1.0
                if sw < openv or ng < gbuf[p - one]:
                    cq[n], cf[n], n = p - one, ng + _h(dy, dx - 1.0, octile), n + 1
                    gbuf[p - one], cell[p - one] = ng, openv | np.uint32(1 << 1)
            if sn < closedv:
                ng = g0 + 1.0
                if sn < openv or ng < gbuf[p + uw]:
                    cq[n], cf[n], n = p + uw, ng + _h(dy + 1.0, dx, octile), n + 1
                    gbuf[p + uw], cell[p + uw] = ng, openv | np.uint32(2 << 1)
            if ss < closedv:
                ng = g0 + 1.0
                if ss < openv or ng < gbuf[p - uw]:
                    cq[n], cf[n], n = p - uw, ng + _h(dy - 1.0, dx, octile), n + 1
                    gbuf[p - uw], cell[p - uw] = ng, openv | np.uint32(3 << 1)
            # a diagonal move needs both orthogonal cells it passes free (bit 0 clear: the
            # words read above; a relaxation never changes bit 0) unless corners may be cut
            fe = (se & bit0) == 0
            fw = (sw & bit0) == 0
            fn = (sn & bit0) == 0
            fs = (ss & bit0) == 0
            ng = g0 + s2
            if corner_cutting or (fn and fe):
                q = p + uw + one
                st = cell[q]
                if st < closedv and (st < openv or ng < gbuf[q]):
                    cq[n], cf[n], n = q, ng + _h(dy + 1.0, dx + 1.0, octile), n + 1
                    gbuf[q], cell[q] = ng, openv | np.uint32(4 << 1)
            if corner_cutting or (fn and fw):
                q = p + uw - one
                st = cell[q]
                if st < closedv and (st < openv or ng < gbuf[q]):
                    cq[n], cf[n], n = q, ng + _h(dy + 1.0, dx - 1.0, octile), n + 1
                    gbuf[q], cell[q] = ng, openv | np.uint32(5 << 1)
            if corner_cutting or (fs and fe):
                q = p - uw + one
                st = cell[q]
                if st < closedv and (st < openv or ng < gbuf[q]):
                    cq[n], cf[n], n = q, ng + _h(dy - 1.0, dx + 1.0, octile), n + 1
                    gbuf[q], cell[q] = ng, openv | np.uint32(6 << 1)
            if corner_cutting or (fs and fw):
                q = p - uw - one
                st = cell[q]
                if st < closedv and (st < openv or ng < gbuf[q]):
                    cq[n], cf[n], n = q, ng + _h(dy - 1.0, dx - 1.0, octile), n + 1
                    gbuf[q], cell[q] = ng, openv | np.uint32(7 << 1)
            for j in range(n):
                f = cf[j]
                kf = _bits_of(f)
                qi = np.int64(cq[j])
                if use_ring:
                    kq = np.int64(f * _RING_SCALE)
                    if kq <= cur:  # the bucket being expanded (or below it, by rounding)
                        ssize = _spush(skey, snode, ssize, kf, qi)
                    else:
                        if fh >= 0:
                            e = fh
                            fh = qnext[e]
                        else:
                            e = used
                            used += 1
                        qkey[e] = kf
                        qnode[e] = qi
                        b = kq & rmask
                        qnext[e] = heads[b]
                        heads[b] = e
                        bits[b >> 6] |= one << np.uint64(b & 63)
                        size += 1
                else:
                    fh, used = _qpush(qkey, qnode, qnext, heads, last, fh, used, kf, qi)
                    size += 1
        meta[0] = cur if use_ring else np.int64(last)
        meta[1] = fh
        meta[2] = used
        meta[3] = size
        meta[4] = ssize
        if use_ring and (code == CODE_SUCCESS or code == CODE_NO_PATH):
            # the query is over: empty the buckets still holding entries (their bits; a
            # bucket's head and bit are set and cleared together), so the next query
            # finds the ring empty without clearing all of it
            for w in range(_RING_SIZE // 64):
                word = bits[w]
                while word != 0:
                    heads[(w << 6) + _trailing_zeros(word)] = -1
                    word &= word - one
                bits[w] = 0
            meta[5] = 1
        if code == CODE_SUCCESS:  # the path, in the same call (no second dispatch)
            cells, pts = _trace(cell, root, goal, wp, ox, oy, res)
            return code, n_exp, cells, pts, gbuf[goal]
        return code, n_exp, np.empty((0, 2), dtype=np.int64), np.empty((0, 2)), math.inf

    return kernel


_astar_ring = _make_kernel(True)  # the euclidean heuristic's kernel
_astar_radix = _make_kernel(False)  # the octile heuristic's kernel
