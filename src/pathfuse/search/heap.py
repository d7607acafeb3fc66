"""A binary min-heap on two parallel arrays (keys, int64 nodes), for the numba searches.

Shared by Theta*, the visibility graph's A* and the cost-aware grid A*.  Ties
keep the order of the sift rules below (a parent not greater than the key stops
a push; a child not less than the moved key stops a pop), so every search that
uses it breaks ties the same way.

>>> import numpy as np
>>> k, n, size = np.empty(1), np.empty(1, dtype=np.int64), 0
>>> for key, node in ((3.0, 30), (1.0, 10), (2.0, 20)):
...     k, n, size = heap_push(k, n, size, key, node)
>>> out = []
>>> while size:
...     node, size = heap_pop(k, n, size)
...     out.append(int(node))
>>> out
[10, 20, 30]
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["heap_push", "heap_pop"]


@njit(cache=True, inline="always")
def heap_push(hkey, hnode, size, key, node):
    """Push ``node`` with ``key``; the arrays double when full.  Returns ``(hkey, hnode, size)``."""
    if size >= hkey.shape[0]:
        nk = np.empty(2 * hkey.shape[0])
        nn = np.empty(2 * hkey.shape[0], dtype=np.int64)
        for j in range(size):
            nk[j] = hkey[j]
            nn[j] = hnode[j]
        hkey = nk
        hnode = nn
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if hkey[p] <= key:
            break
        hkey[i] = hkey[p]
        hnode[i] = hnode[p]
        i = p
    hkey[i] = key
    hnode[i] = node
    return hkey, hnode, size + 1


@njit(cache=True, inline="always")
def heap_pop(hkey, hnode, size):
    """Pop the node of least key (``size > 0``).  Returns ``(node, size)``."""
    top = hnode[0]
    size -= 1
    key = hkey[size]
    node = hnode[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and hkey[c + 1] < hkey[c]:
            c += 1
        if hkey[c] >= key:
            break
        hkey[i] = hkey[c]
        hnode[i] = hnode[c]
        i = c
    if size > 0:
        hkey[i] = key
        hnode[i] = node
    return top, size
