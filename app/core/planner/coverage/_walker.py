"""The sweeping walker of the coverage planner (§3.4, §4), compiled.

It sweeps each region lane by lane (:func:`sweep_step` scores the moves
under one of plan.FAMILIES' preferences), leaves a dead zone by the
fewest-step way to the nearest open cell of the region, and switches
regions through the nearest open associated cell (eq. 11). Moves come from
a neighbour table (:func:`._kernels.neighbour_table`: each cell's eight
targets, −1 where a move is off the map, blocked or would cut a corner),
built once per map, so the inner loops read a table instead of testing
bounds and corners; each cell's count of open neighbours is kept up to
date as cells are visited (:func:`_visit`) rather than recounted per
candidate move. Conventions as in :mod:`._kernels`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import DC, DR, _col, trace_back


@njit(cache=True)
def _open_degree(nbr, visits, region, reg, v):
    """Unvisited neighbours of flat cell v in region ``reg`` reachable by a
    move (visits, region: flat views)."""
    n = 0
    for k in range(8):
        u = nbr[v, k]
        if u >= 0 and visits[u] == 0 and region[u] == reg:
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
def sweep_step(nbr, visits, region, reg, v, axis, head, side, weights, pdr, pdc, deg):
    """One move of the boustrophedon walker inside region ``reg`` (§3.4).

    Lanes run along rows (axis 0) or columns (axis 1); ``head`` is the way
    along the lane, ``side`` the way to the next lane. Preference: on along
    the lane; a cell that would be left with no open neighbour (an orphan)
    before anything; then the next lane straight across, then diagonally;
    then back along the lane; last the previous lane. Ties go to the cell
    with fewer open neighbours (``deg``: each cell's :func:`_open_degree`
    in its own region, kept up to date by :func:`_visit`). Returns the flat
    target or −1 (dead zone). visits, region: flat views."""
    best = -1
    best_score = 1 << 30
    for k in range(8):
        u = nbr[v, k]
        if u < 0 or visits[u] != 0 or region[u] != reg:
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
def _degrees(nbr, visits, region):
    """Every region cell's :func:`_open_degree` in its own region (flat)."""
    m = nbr.shape[0]
    deg = np.zeros(m, dtype=np.int32)
    for v in range(m):
        if region[v] >= 0:
            deg[v] = _open_degree(nbr, visits, region, region[v], v)
    return deg


@njit(cache=True)
def _visit(nbr, visits, region, deg, v):
    """Count a visit of flat cell v; on its first, its neighbours of the same
    region lose an open neighbour (moves are symmetric, so these are the
    cells that counted v). Returns True on the first visit."""
    visits[v] += 1
    if visits[v] != 1:
        return False
    reg = region[v]
    for k in range(8):
        u = nbr[v, k]
        if u >= 0 and region[u] == reg:
            deg[u] -= 1
    return True


@njit(cache=True)
def _escape(nbr, visits, region, start, goal, target, parent, stamp, gen, queue):
    """:func:`._kernels.bfs_path` on the neighbour table: the fewest-step
    path from ``start`` to ``goal`` (goal ≥ 0), or else to the nearest
    unvisited cell of region ``target``; the same search order, so the
    same path. Returns it without ``start`` (empty when nothing is reachable)."""
    stamp[start] = gen
    parent[start] = -1
    queue[0] = start
    head, tail = 0, 1
    found = -1
    while head < tail and found < 0:
        v = queue[head]
        head += 1
        for k in range(8):
            u = nbr[v, k]
            if u < 0 or stamp[u] == gen:
                continue
            stamp[u] = gen
            parent[u] = v
            if goal >= 0:
                if u == goal:
                    found = u
                    break
            elif visits[u] == 0 and (target < 0 or region[u] == target):
                found = u
                break
            queue[tail] = u
            tail += 1
    return trace_back(parent, start, found)


@njit(cache=True)
def walk(free, region, order, axes, bbox, corners, start, wrap, nearest_next, weights, seed, nbr):
    """Cover every free cell: sweep the regions one by one in ``order``
    (§3.3–3.4), leave a dead zone by the shortest way to the nearest open cell
    of the region (§3.4, what eqs. 6–9 steer towards), and switch regions
    through the nearest open associated cell (§4, eq. 11; with nearest_next
    the next region is the one whose associated cell is nearest, not the
    next in order). ``free`` must hold only cells reachable from start;
    ``nbr``: its :func:`._kernels.neighbour_table` (same wrap). Returns
    (path of flat indices, visit counts)."""
    h, w = free.shape
    nreg = bbox.shape[0]
    np.random.seed(seed)
    visits = np.zeros((h, w), dtype=np.int32)
    vis = visits.reshape(h * w)  # flat views for the table's cells
    reg_f = region.reshape(h * w)
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
    deg = _degrees(nbr, vis, reg_f)
    remaining[reg] -= 1
    total -= 1
    axis = axes[reg]
    side = _lane_side(reg, r, c, axis, bbox)
    head = new_heading(free, visits, region, reg, r, c, axis, 1, wrap)
    k = 0
    pdr, pdc = 0, 0
    while total > 0:
        r, c = cur // w, cur % w
        u = sweep_step(nbr, vis, reg_f, reg, cur, axis, head, side, weights, pdr, pdc, deg)
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
            if _visit(nbr, vis, reg_f, deg, u):
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
        trip = _escape(nbr, vis, reg_f, cur, goal, target, parent, stamp, gen, queue)
        if trip.shape[0] == 0:
            # Nothing reachable in that region (cannot happen when free holds
            # only reachable cells); drop it so the loop ends.
            total -= remaining[target]
            remaining[target] = 0
            continue
        for v in trip:
            path = _push(path, n, v)
            n += 1
            if _visit(nbr, vis, reg_f, deg, v):
                remaining[reg_f[v]] -= 1
                total -= 1
        cur = trip[trip.shape[0] - 1]
        r, c = cur // w, cur % w
        if target != reg:
            reg = target
            axis = axes[reg]
            side = _lane_side(reg, r, c, axis, bbox)
        head = new_heading(free, visits, region, reg, r, c, axis, head, wrap)
    return path[:n], visits
