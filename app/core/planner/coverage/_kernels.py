"""Compiled cell loops of the coverage planner: region labelling across cuts,
breadth-first travel to the nearest unvisited cell, and the sweeping walker.

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


@njit(cache=True, inline="always")
def _col(c, w, wrap):
    """Column index after a step, or -1 off the map (wraps round with wrap)."""
    if 0 <= c < w:
        return c
    if wrap:
        return c % w
    return -1


@njit(cache=True, inline="always")
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
def _open_degree(free, visits, region, reg, r, c, wrap):
    """Unvisited neighbours of (r, c) in region ``reg`` reachable by a move."""
    w = free.shape[1]
    n = 0
    for k in range(8):
        u = _step_ok(free, r, c, DR[k], DC[k], wrap)
        if u >= 0:
            ur, uc = u // w, u % w
            if visits[ur, uc] == 0 and region[ur, uc] == reg:
                n += 1
    return n


@njit(cache=True)
def _run(free, visits, region, reg, r, c, dr, dc, wrap):
    """Unvisited cells of region ``reg`` in a straight line from (r, c)."""
    h, w = free.shape
    n = 0
    while n < h + w:
        r += dr
        cc = _col(c + dc, w, wrap)
        if r < 0 or r >= h or cc < 0 or free[r, cc] == 0:
            break
        if visits[r, cc] != 0 or region[r, cc] != reg:
            break
        c = cc
        n += 1
    return n


@njit(cache=True)
def sweep_step(free, visits, region, reg, r, c, axis, head, side, wrap, weights, pdr, pdc, deg):
    """One move of the boustrophedon walker inside region ``reg`` (§3.4).

    Lanes run along rows (axis 0) or columns (axis 1); ``head`` is the way
    along the lane, ``side`` the way to the next lane. Preference: on along
    the lane; a cell that would be left with no open neighbour (an orphan)
    before anything; then the next lane straight across, then diagonally;
    then back along the lane; last the previous lane. Ties go to the cell
    with fewer open neighbours (``deg``: each cell's :func:`_open_degree`
    in its own region, kept up to date by :func:`_visit`). Returns the flat
    target or −1 (dead zone)."""
    w = free.shape[1]
    best = -1
    best_score = 1 << 30
    for k in range(8):
        u = _step_ok(free, r, c, DR[k], DC[k], wrap)
        if u < 0:
            continue
        ur, uc = u // w, u % w
        if visits[ur, uc] != 0 or region[ur, uc] != reg:
            continue
        if axis == 1:
            along, lat = DR[k], DC[k]
        else:
            along, lat = DC[k], DR[k]
        if lat == 0 and along == head:
            s = weights[0]
        elif lat == side and along == 0:
            s = weights[1]
        elif lat == side:
            s = weights[2]
        elif lat == 0:
            s = weights[3]
        else:
            s = weights[4]
        d = deg[u]
        if d == 0:
            s = weights[5]
        score = s * 16 + d * weights[6]
        if DR[k] != pdr or DC[k] != pdc:
            score += weights[8]
        if weights[7] > 0:
            score = score * 64 + np.random.randint(0, weights[7])
        if score < best_score:
            best_score = score
            best = u
    return best


@njit(cache=True)
def new_heading(free, visits, region, reg, r, c, axis, head, wrap):
    """Heading on entering a lane at (r, c): the way with open cells, the
    shorter run first when both are open (the longer one then ends the lane
    where the next lane begins)."""
    if axis == 1:
        a = _run(free, visits, region, reg, r, c, head, 0, wrap)
        b = _run(free, visits, region, reg, r, c, -head, 0, wrap)
    else:
        a = _run(free, visits, region, reg, r, c, 0, head, wrap)
        b = _run(free, visits, region, reg, r, c, 0, -head, wrap)
    if a == 0 and b == 0:
        return head
    if a == 0:
        return -head
    if b == 0:
        return head
    return -head if b < a else head


@njit(cache=True)
def _push(path, n, v):
    if n == path.shape[0]:
        bigger = np.empty(2 * n, dtype=np.int64)
        bigger[:n] = path
        path = bigger
    path[n] = v
    return path


@njit(cache=True)
def _lane_side(reg, r, c, axis, bbox):
    """Way to the next lane on entering region ``reg`` at (r, c): away from
    the nearer side of its bounding box."""
    if axis == 1:
        lo, hi, x = bbox[reg, 2], bbox[reg, 3], c
    else:
        lo, hi, x = bbox[reg, 0], bbox[reg, 1], r
    return 1 if x - lo <= hi - x else -1


@njit(cache=True)
def _degrees(free, visits, region, wrap):
    """Every region cell's :func:`_open_degree` in its own region (flat)."""
    h, w = free.shape
    deg = np.zeros(h * w, dtype=np.int32)
    for r in range(h):
        for c in range(w):
            if free[r, c] and region[r, c] >= 0:
                deg[r * w + c] = _open_degree(free, visits, region, region[r, c], r, c, wrap)
    return deg


@njit(cache=True)
def _visit(free, visits, region, deg, v, wrap):
    """Count a visit of flat cell v; on its first, its neighbours of the same
    region lose an open neighbour (moves are symmetric, so these are the
    cells that counted v). Returns True on the first visit."""
    w = free.shape[1]
    r, c = v // w, v % w
    visits[r, c] += 1
    if visits[r, c] != 1:
        return False
    reg = region[r, c]
    for k in range(8):
        u = _step_ok(free, r, c, DR[k], DC[k], wrap)
        if u >= 0 and region[u // w, u % w] == reg:
            deg[u] -= 1
    return True


@njit(cache=True)
def walk(free, region, order, axes, bbox, corners, start, wrap, nearest_next, weights, seed):
    """Cover every free cell: sweep the regions one by one in ``order``
    (§3.3–3.4), leave a dead zone by the shortest way to the nearest open cell
    of the region (§3.4, what eqs. 6–9 steer towards), and switch regions
    through the nearest open associated cell (§4, eq. 11; with nearest_next
    the next region is the one whose associated cell is nearest, not the
    next in order). ``free`` must hold only cells reachable from start.
    Returns (path of flat indices, visit counts)."""
    h, w = free.shape
    nreg = bbox.shape[0]
    np.random.seed(seed)
    visits = np.zeros((h, w), dtype=np.int32)
    remaining = np.zeros(nreg, dtype=np.int64)
    total = 0
    for r in range(h):
        for c in range(w):
            if free[r, c] and region[r, c] >= 0:
                remaining[region[r, c]] += 1
                total += 1
    parent = np.empty(h * w, dtype=np.int64)
    stamp = np.zeros(h * w, dtype=np.int64)
    queue = np.empty(h * w, dtype=np.int64)
    gen = 0
    path = np.empty(max(16, 2 * total), dtype=np.int64)
    n = 0
    cur = start
    r, c = cur // w, cur % w
    reg = region[r, c]
    path = _push(path, n, cur)
    n += 1
    visits[r, c] = 1
    deg = _degrees(free, visits, region, wrap)
    remaining[reg] -= 1
    total -= 1
    axis = axes[reg]
    side = _lane_side(reg, r, c, axis, bbox)
    head = new_heading(free, visits, region, reg, r, c, axis, 1, wrap)
    k = 0
    pdr, pdc = 0, 0
    while total > 0:
        r, c = cur // w, cur % w
        u = sweep_step(
            free, visits, region, reg, r, c, axis, head, side, wrap, weights, pdr, pdc, deg
        )
        if u >= 0:
            ur, uc = u // w, u % w
            dr, dc = ur - r, uc - c
            if dc > 1:
                dc = -1
            elif dc < -1:
                dc = 1
            lat = dc if axis == 1 else dr
            pdr, pdc = dr, dc
            if lat != 0:
                head = new_heading(free, visits, region, reg, ur, uc, axis, -head, wrap)
            cur = u
            path = _push(path, n, cur)
            n += 1
            if _visit(free, visits, region, deg, u, wrap):
                remaining[reg] -= 1
                total -= 1
            continue
        goal = -1
        target = reg
        if remaining[reg] == 0:
            # §4: the next region and its entry (eq. 11).
            best_d = 1e300
            nxt = -1
            if nearest_next:
                for q in range(nreg):
                    if remaining[q] == 0:
                        continue
                    for j in range(4):
                        v = corners[q, j]
                        if visits[v // w, v % w] == 0:
                            d = (v // w - r) ** 2 + (v % w - c) ** 2
                            if d < best_d:
                                best_d, goal, nxt = d, v, q
                if nxt < 0:
                    for q in range(nreg):
                        if remaining[q] > 0:
                            nxt = q
                            break
            else:
                while remaining[order[k]] == 0:
                    k += 1
                nxt = order[k]
                for j in range(4):
                    v = corners[nxt, j]
                    if visits[v // w, v % w] == 0:
                        d = (v // w - r) ** 2 + (v % w - c) ** 2
                        if d < best_d:
                            best_d, goal = d, v
            target = nxt
        gen += 1
        trip = bfs_path(free, visits, region, cur, goal, target, wrap, parent, stamp, gen, queue)
        if trip.shape[0] == 0:
            # Nothing reachable in that region (cannot happen when free holds
            # only reachable cells); drop it so the loop ends.
            total -= remaining[target]
            remaining[target] = 0
            continue
        for v in trip:
            path = _push(path, n, v)
            n += 1
            if _visit(free, visits, region, deg, v, wrap):
                remaining[region[v // w, v % w]] -= 1
                total -= 1
        cur = trip[trip.shape[0] - 1]
        r, c = cur // w, cur % w
        if target != reg:
            reg = target
            axis = axes[reg]
            side = _lane_side(reg, r, c, axis, bbox)
        head = new_heading(free, visits, region, reg, r, c, axis, head, wrap)
    return path[:n], visits


@njit(cache=True, inline="always")
def _move_ok(free, a, b, w):
    ar, ac = a // w, a % w
    br, bc = b // w, b % w
    dr, dc = br - ar, bc - ac
    if dr < -1 or dr > 1 or dc < -1 or dc > 1 or (dr == 0 and dc == 0):
        return False
    if dr != 0 and dc != 0 and (free[br, ac] == 0 or free[ar, bc] == 0):
        return False
    return True


@njit(cache=True, inline="always")
def _heading_change(a, b, c, w):
    return (b // w - a // w) != (c // w - b // w) or (b % w - a % w) != (c % w - b % w)


@njit(cache=True, inline="always")
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
