"""The numba kernel of grid A* (see :mod:`pathfuse.search.astar` for the model and the
open lists), and the path tracing.  Low level: :class:`~pathfuse.search.astar.AStarSearcher`
owns the buffers and calls it."""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

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
def _trace(parent, start, goal, wp, ox, oy, res):
    """The path from start to goal: ``(cells, points)``, the (n, 2) unpadded ``(row, col)``
    cells and their centres ``[x, y]`` for a grid of origin ``(ox, oy)`` and cell side
    ``res`` (one call, so a query pays one dispatch for both)."""
    offs = np.array([1, -1, wp, -wp, wp + 1, wp - 1, -wp + 1, -wp - 1], dtype=np.int64)
    n = 1
    p = goal
    while p != start:
        p -= offs[parent[p]]
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
            p -= offs[parent[p]]
    return out, pts
