"""A mop-up route: after a coverage sweep, back to the cells its own record
says were missed.

A robot that files each probe reading under the cell it believes it is over
can end a sweep with cells it never read: a cell given up at its time limit,
or one the probe skimmed outside its core while steering round a lane end.
The sweep's record (the robot's, never ground truth) names them; this route
visits them nearest first, each reached by the fewest-step path over free
cells (the same moves as :func:`.coverage_path`: 8-adjacent, no corner
cutting, round the seam with ``wrap``).
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K


def mop_up_route(
    blocked, start: tuple[int, int], missed, wrap: bool = False
) -> list[tuple[int, int]]:
    """Cells from ``start`` (not included) that visit every cell of the bool
    mask ``missed`` reachable from it, nearest first; [] when none is. A
    missed cell on an obstacle or cut off from ``start`` is left out."""
    a = np.asarray(blocked, dtype=bool)
    todo = np.asarray(missed, dtype=bool)
    if todo.shape != a.shape:
        raise ValueError(f"missed has shape {todo.shape}, the wall {a.shape}")
    h, w = a.shape
    r0, c0 = (int(v) for v in start)
    if not (0 <= r0 < h and 0 <= c0 < w) or a[r0, c0]:
        raise ValueError(f"start {start} is off the wall or on an obstacle")
    free = np.ascontiguousarray(~a, dtype=np.uint8)
    reach = K.flood(free, r0 * w + c0, wrap).astype(bool)
    todo = todo & reach
    todo[r0, c0] = False
    # bfs_path looks for the nearest unvisited cell of region 0
    visits = np.where(todo, 0, 1).astype(np.int32)
    region = np.where(todo, 0, 1).astype(np.int32)
    n = h * w
    parent = np.empty(n, dtype=np.int64)
    stamp = np.zeros(n, dtype=np.int64)
    queue = np.empty(n, dtype=np.int64)
    route: list[tuple[int, int]] = []
    cur, gen = r0 * w + c0, 0
    for _ in range(int(todo.sum())):
        gen += 1
        trip = K.bfs_path(free, visits, region, cur, -1, 0, wrap, parent, stamp, gen, queue)
        if trip.shape[0] == 0:
            break
        for v in trip.tolist():
            route.append((v // w, v % w))
            visits[v // w, v % w] = 1  # a missed cell passed on the way is visited too
        cur = int(trip[-1])
    return route
