"""Compiled cell loops of the coverage planner: region labelling across cuts,
flood fill, the neighbour table, breadth-first travel to the nearest
unvisited cell, and the turn tests (the sweeping walker: :mod:`._walker`).

Why compiled: the full tank wall (π·24 m × 9.6 m at D = 0.1 m) has ~72 000
cells; a Python loop that looks at eight neighbours per step costs ~1 s there,
the whole budget. These loops run on flat arrays under ``njit(cache=True)``.

Conventions: ``free`` is a C-contiguous uint8 array (1 = free); a cell is the
flat index ``r * W + c``; with ``wrap`` the columns 0 and W−1 are neighbours
(the tank's seam). Moves are the eight neighbours, and a diagonal step only
when both orthogonal cells it passes are free (no corner cutting).
"""

from __future__ import annotations

import numpy as np
from numba import njit

# The eight moves: four straight, then four diagonal.
DR = np.array([-1, 1, 0, 0, -1, -1, 1, 1], dtype=np.int64)
DC = np.array([0, 0, -1, 1, -1, 1, -1, 1], dtype=np.int64)


@njit(cache=True)
def _col(c, w, wrap):
    """Column index after a step, or -1 off the map (wraps round with wrap)."""
    if 0 <= c < w:
        return c
    if wrap:
        return c % w
    return -1


@njit(cache=True)
def _step_ok(free, r, c, dr, dc, wrap):
    """Target flat index of the move (dr, dc) from (r, c), or -1 when the
    target is off the map or blocked or the diagonal would cut a corner."""
    h, w = free.shape
    nr = r + dr
    if nr < 0 or nr >= h:
        return -1
    nc = _col(c + dc, w, wrap)
    if nc < 0 or free[nr, nc] == 0:
        return -1
    if dr != 0 and dc != 0:
        if free[nr, c] == 0 or free[r, nc] == 0:
            return -1
    return nr * w + nc


@njit(cache=True)
def label_regions(free, vcut, hcut):
    """4-connected components of the free cells where a step never crosses a
    cut: vcut[r, c] separates (r, c−1) from (r, c); hcut[r, c] separates
    (r, c) from (r+1, c). Returns int32 labels, −1 on blocked cells."""
    h, w = free.shape
    lab = np.full((h, w), -1, dtype=np.int32)
    queue = np.empty(h * w, dtype=np.int64)
    n = 0
    for s in range(h * w):
        sr, sc = s // w, s % w
        if free[sr, sc] == 0 or lab[sr, sc] >= 0:
            continue
        lab[sr, sc] = n
        head, tail = 0, 1
        queue[0] = s
        while head < tail:
            v = queue[head]
            head += 1
            r, c = v // w, v % w
            if r > 0 and not hcut[r - 1, c] and free[r - 1, c] and lab[r - 1, c] < 0:
                lab[r - 1, c] = n
                queue[tail] = v - w
                tail += 1
            if r < h - 1 and not hcut[r, c] and free[r + 1, c] and lab[r + 1, c] < 0:
                lab[r + 1, c] = n
                queue[tail] = v + w
                tail += 1
            if c > 0 and not vcut[r, c] and free[r, c - 1] and lab[r, c - 1] < 0:
                lab[r, c - 1] = n
                queue[tail] = v - 1
                tail += 1
            if c < w - 1 and not vcut[r, c + 1] and free[r, c + 1] and lab[r, c + 1] < 0:
                lab[r, c + 1] = n
                queue[tail] = v + 1
                tail += 1
        n += 1
    return lab


@njit(cache=True)
def flood(free, start, wrap):
    """Cells reachable from flat index ``start`` by valid moves (uint8 mask)."""
    h, w = free.shape
    seen = np.zeros((h, w), dtype=np.uint8)
    queue = np.empty(h * w, dtype=np.int64)
    seen[start // w, start % w] = 1
    queue[0] = start
    head, tail = 0, 1
    while head < tail:
        v = queue[head]
        head += 1
        r, c = v // w, v % w
        for k in range(8):
            u = _step_ok(free, r, c, DR[k], DC[k], wrap)
            if u >= 0 and seen[u // w, u % w] == 0:
                seen[u // w, u % w] = 1
                queue[tail] = u
                tail += 1
    return seen


@njit(cache=True)
def neighbour_table(free, wrap):
    """(H·W, 8) targets of each cell's eight moves in DR/DC order (flat
    index; −1 where the move is off the map, blocked or cuts a corner):
    built once per map so that loops over moves read a row of it."""
    h, w = free.shape
    out = np.full((h * w, 8), -1, dtype=np.int64)
    for r in range(h):
        for c in range(w):
            if free[r, c] == 0:
                continue
            for k in range(8):
                out[r * w + c, k] = _step_ok(free, r, c, DR[k], DC[k], wrap)
    return out


@njit(cache=True)
def trace_back(parent, start, found):
    """The path to ``found`` by the parents, without ``start`` (flat indices);
    empty when nothing was found (found < 0)."""
    if found < 0:
        return np.empty(0, dtype=np.int64)
    n = 0
    v = found
    while v != start:
        n += 1
        v = parent[v]
    out = np.empty(n, dtype=np.int64)
    v = found
    for i in range(n - 1, -1, -1):
        out[i] = v
        v = parent[v]
    return out


@njit(cache=True)
def bfs_path(free, visits, region, start, goal, target, wrap, parent, stamp, gen, queue):
    """Fewest-step path from ``start`` to ``goal`` (goal ≥ 0), or else to the
    nearest cell not yet visited whose region is ``target`` (any region when
    target < 0). Returns the path as flat indices without ``start`` (empty
    when nothing is reachable). parent/stamp/queue are caller-owned scratch;
    gen marks which entries this search wrote, so nothing is cleared."""
    h, w = free.shape
    stamp[start] = gen
    parent[start] = -1
    queue[0] = start
    head, tail = 0, 1
    found = -1
    while head < tail and found < 0:
        v = queue[head]
        head += 1
        r, c = v // w, v % w
        for k in range(8):
            u = _step_ok(free, r, c, DR[k], DC[k], wrap)
            if u < 0 or stamp[u] == gen:
                continue
            stamp[u] = gen
            parent[u] = v
            ur, uc = u // w, u % w
            if goal >= 0:
                if u == goal:
                    found = u
                    break
            elif visits[ur, uc] == 0 and (target < 0 or region[ur, uc] == target):
                found = u
                break
            queue[tail] = u
            tail += 1
    return trace_back(parent, start, found)


@njit(cache=True)
def _move_ok(free, a, b, w):
    ar, ac = a // w, a % w
    br, bc = b // w, b % w
    dr, dc = br - ar, bc - ac
    if dr < -1 or dr > 1 or dc < -1 or dc > 1 or (dr == 0 and dc == 0):
        return False
    if dr != 0 and dc != 0 and (free[br, ac] == 0 or free[ar, bc] == 0):
        return False
    return True


@njit(cache=True)
def _heading_change(a, b, c, w):
    return (b // w - a // w) != (c // w - b // w) or (b % w - a % w) != (c % w - b % w)


@njit(cache=True)
def _t(a, b, c, w):
    """1 when the path turns at b coming from a and going to c (−1 = none)."""
    if a < 0 or c < 0:
        return 0
    return 1 if _heading_change(a, b, c, w) else 0


@njit(cache=True)
def straighten(free, path, perms, passes):
    """Fewer changes of heading without changing which cells are visited or
    how often: slide a window over the path and reorder its m inner cells
    (every permutation in ``perms``) when a valid order turns less. The
    two cells before and after the window are fixed, so the headings into and
    out of it count. No wrap. Returns the number of turns removed."""
    w = free.shape[1]
    n = path.shape[0]
    m = perms.shape[1]
    seq = np.empty(m + 4, dtype=np.int64)
    best = np.empty(m, dtype=np.int64)
    gained = 0
    for _ in range(passes):
        changed = False
        for i in range(2, n - m - 1):
            distinct = True
            for a in range(i, i + m):
                for b in range(a + 1, i + m):
                    if path[a] == path[b]:
                        distinct = False
            if not distinct:
                continue
            base = 0
            for k in range(i - 2, i + m):
                if _heading_change(path[k], path[k + 1], path[k + 2], w):
                    base += 1
            best_turns = base
            for p in range(perms.shape[0]):
                seq[0] = path[i - 2]
                seq[1] = path[i - 1]
                for k in range(m):
                    seq[2 + k] = path[i + perms[p, k]]
                seq[m + 2] = path[i + m]
                seq[m + 3] = path[i + m + 1]
                ok = True
                for k in range(1, m + 2):
                    if not _move_ok(free, seq[k], seq[k + 1], w):
                        ok = False
                        break
                if not ok:
                    continue
                t = 0
                for k in range(m + 2):
                    if _heading_change(seq[k], seq[k + 1], seq[k + 2], w):
                        t += 1
                if t < best_turns:
                    best_turns = t
                    for k in range(m):
                        best[k] = seq[2 + k]
            if best_turns < base:
                for k in range(m):
                    path[i + k] = best[k]
                gained += base - best_turns
                changed = True
        if not changed:
            break
    return gained


@njit(cache=True)
def bfs_layers(nbr, src, radius, dist, queue):
    """Breadth-first layers from ``src`` up to ``radius`` steps: fills dist
    (−1 = not reached, must be all −1 on entry) and queue; returns the
    number of cells reached."""
    dist[src] = 0
    queue[0] = src
    head, tail = 0, 1
    while head < tail:
        v = queue[head]
        head += 1
        if dist[v] >= radius:
            continue
        for k in range(8):
            u = nbr[v, k]
            if u >= 0 and dist[u] < 0:
                dist[u] = dist[v] + 1
                queue[tail] = u
                tail += 1
    return tail
