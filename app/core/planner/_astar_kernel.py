"""A* on the padded, flattened 8-connected grid, compiled (astar.py's search;
seed 000 eq. 24–27 for the heuristics, in _grid_search.heuristic).
Conventions, heap and search state: :mod:`._grid_search`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._grid_search import CLOSED, SQRT2, _h, _pop, _push, _touch


@njit(cache=True)
def astar_kernel(gp, w, s, goal, hmode, hscale, gen, stamp, g, parent, pos, hn, hf, hg):
    """A* (eq. 24: f = g + h) on the padded, flattened 8-connected grid.

    Returns (goal_reached, expanded); the path is in ``parent``. Closed nodes
    are never reopened: exact for the consistent octile/Euclidean heuristics;
    with the inadmissible Manhattan or improved heuristic paths may be longer.
    """
    gr = goal // w
    gc = goal - gr * w
    off = np.array([-w, w, -1, 1, -w - 1, -w + 1, w - 1, w + 1])
    offv = np.array([0, 0, 0, 0, -w, -w, w, w])
    offh = np.array([0, 0, 0, 0, -1, 1, -1, 1])
    _touch(s, gen, stamp, g, parent, pos)
    g[s] = 0.0
    size = _push(hn, hf, hg, pos, 0, s, _h(hmode, s, w, gr, gc, hscale), 0.0)
    expanded = 0
    while size > 0:
        cur, size = _pop(hn, hf, hg, pos, size)
        expanded += 1
        if cur == goal:
            return True, expanded
        gcur = g[cur]
        for k in range(8):
            nb = cur + off[k]
            if gp[nb]:
                continue
            if k >= 4:
                if gp[cur + offv[k]] or gp[cur + offh[k]]:
                    continue
                ng = gcur + SQRT2
            else:
                ng = gcur + 1.0
            _touch(nb, gen, stamp, g, parent, pos)
            if pos[nb] == CLOSED or ng >= g[nb]:
                continue
            g[nb] = ng
            parent[nb] = cur
            size = _push(hn, hf, hg, pos, size, nb, ng + _h(hmode, nb, w, gr, gc, hscale), ng)
    return False, expanded
