"""Fewer repeats, no more turns: dropping visits a path does not need.

A coverage path may visit a cell twice — the links between lanes of
:mod:`.lanes` cross swept lanes, the walker's escapes cross swept wall. The
visit p_k may be dropped when the cell is visited elsewhere too, its
neighbours p_{k−1} and p_{k+1} join (an 8-neighbour move without corner
cutting, so the path stays valid) and the changes of heading at the three
cells involved do not grow. Coverage stays; repetition (Definition 7)
falls by one per drop; turns (seed 001 eq. 3) never rise. No wrap.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import _move_ok, _t


@njit(cache=True)
def prune(free, path, passes):
    """The path without the visits it can drop (see the module); the first
    cell stays. Returns a new array."""
    w = free.shape[1]
    count = np.zeros(free.size, dtype=np.int64)
    for v in path:
        count[v] += 1
    cur = path.copy()
    for _ in range(passes):
        n = len(cur)
        out = np.empty(n, dtype=np.int64)
        m = 0
        dropped = 0
        for k in range(n):
            out[m] = cur[k]
            m += 1
            # may out[m − 2] go, now that its successor out[m − 1] is known?
            if m >= 3:
                x = out[m - 2]
                a, y = out[m - 3], out[m - 1]
                if count[x] > 1 and _move_ok(free, a, y, w):
                    pa = out[m - 4] if m >= 4 else -1
                    ny = cur[k + 1] if k + 1 < n else -1
                    old = _t(pa, a, x, w) + _t(a, x, y, w) + _t(x, y, ny, w)
                    new = _t(pa, a, y, w) + _t(a, y, ny, w)
                    if new <= old:
                        count[x] -= 1
                        out[m - 2] = y
                        m -= 1
                        dropped += 1
        if m >= 2 and count[out[m - 1]] > 1:  # a repeated last cell: the path just ends sooner
            count[out[m - 1]] -= 1
            m -= 1
            dropped += 1
        cur = out[:m].copy()
        if dropped == 0:
            break
    return cur
