"""Numba kernels of the any-angle path's homotopy repair (optimised_astar.py,
stage 3): the shortest path between two path vertices over the visibility
graph of the convex corners that could lie on a shorter path.

Any path from a to b no longer than ``bound`` lies inside the ellipse
|p a| + |p b| ≤ bound (foci a and b); a shortest any-angle path on a grid turns
only at convex corners of the blocked set (corners with exactly one blocked
cell of four). So A* over the convex corners inside that ellipse, with the
segment rule of :mod:`._edge_kernels`, finds the shortest path from a to b
— the exact answer for the window, whatever its homotopy class.

The candidates are counted before they are gathered, from per-row running
counts of the map's convex corners (:func:`corner_rows`, once per map) and
the ellipse's column interval on each corner row, so a window whose ellipse
holds too many corners is skipped at the cost of one pass over its rows.

The search scans every node not yet expanded at each expansion
(:func:`vg_search`, quadratic); with more than a few dozen nodes
:func:`vg_search_buckets` keeps them in square buckets and visits only the
buckets a relaxation could reach within the bound — the same shortest length
at about a third of the CPU on random512's whole-path searches.

Coordinates in half-cell units as in :mod:`._edge_kernels`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import _edge_kernels as E


@njit(cache=True)
def corner_rows(grid):
    """Running counts of convex corners along each corner row: cum[R, C] is
    the number of convex corners (R, C') with C' < C; shape (H + 1, W + 2)."""
    h, w = grid.shape
    cum = np.zeros((h + 1, w + 2), dtype=np.int32)
    for R in range(h + 1):
        for C in range(w + 1):
            cum[R, C + 1] = cum[R, C] + (E.corner_free_count(grid, R, C) == 3)
    return cum


@njit(cache=True)
def _row_span(ar, ac, br, bc, bound2, y):
    """Columns x (half units) of the ellipse |p a| + |p b| ≤ bound2 on the
    line row = y: (lo, hi), lo > hi when the line misses it."""
    mr = 0.5 * (ar + br)
    mc = 0.5 * (ac + bc)
    semi = 0.5 * bound2
    foc = 0.5 * math.hypot(br - ar, bc - ac)
    minor2 = max(semi * semi - foc * foc, 1e-12)
    if foc > 0:
        ur = (br - ar) / (2 * foc)
        uc = (bc - ac) / (2 * foc)
    else:
        ur = 1.0
        uc = 0.0
    # (Y ur + X uc)² / semi² + (X ur − Y uc)² / minor² ≤ 1, X = x − mc, Y = y − mr
    Y = y - mr
    ia = 1.0 / (semi * semi)
    ib = 1.0 / minor2
    qa = uc * uc * ia + ur * ur * ib
    qb = 2.0 * Y * ur * uc * (ia - ib)
    qc = Y * Y * (ur * ur * ia + uc * uc * ib) - 1.0
    disc = qb * qb - 4.0 * qa * qc
    if disc < 0:
        return 1.0, 0.0
    sq = math.sqrt(disc)
    return mc + (-qb - sq) / (2 * qa), mc + (-qb + sq) / (2 * qa)


@njit(cache=True)
def ellipse_nodes(grid, cum, a, b, bound2, nmax):
    """[a, b, convex corners p with |p a| + |p b| ≤ bound2] (k × 2, half-cell
    units), or an empty array when more than ``nmax`` corners may lie inside
    (counted on the rows' column spans, widened by one corner each side)."""
    h, w = grid.shape
    ar = float(a[0])
    ac = float(a[1])
    br = float(b[0])
    bc = float(b[1])
    R0 = max(0, int(math.floor((min(ar, br) - bound2) / 2.0)))
    R1 = min(h, int(math.ceil((max(ar, br) + bound2) / 2.0)))
    lo = np.zeros(R1 - R0 + 1, dtype=np.int64)
    hi = np.zeros(R1 - R0 + 1, dtype=np.int64)
    total = 0
    for R in range(R0, R1 + 1):
        x0, x1 = _row_span(ar, ac, br, bc, bound2, 2.0 * R)
        if x0 > x1:
            lo[R - R0] = 1
            continue
        c0 = max(0, int(math.floor(x0 / 2.0)) - 1)
        c1 = min(w, int(math.ceil(x1 / 2.0)) + 1)
        if c0 > c1:
            lo[R - R0] = 1
            continue
        lo[R - R0] = c0
        hi[R - R0] = c1
        total += cum[R, c1 + 1] - cum[R, c0]
        if total > nmax:
            return np.empty((0, 2), dtype=np.int64)
    out = np.empty((total + 2, 2), dtype=np.int64)
    out[0, 0] = a[0]
    out[0, 1] = a[1]
    out[1, 0] = b[0]
    out[1, 1] = b[1]
    m = 2
    for R in range(R0, R1 + 1):
        for C in range(lo[R - R0], hi[R - R0] + 1):
            if cum[R, C + 1] == cum[R, C]:
                continue
            pr = 2.0 * R
            pc = 2.0 * C
            if math.hypot(pr - ar, pc - ac) + math.hypot(pr - br, pc - bc) > bound2:
                continue
            out[m, 0] = 2 * R
            out[m, 1] = 2 * C
            m += 1
    return out[:m]


@njit(cache=True)
def _taut_quadrant(grid, nodes):
    """The diagonal direction (±1, ±1) of each convex corner's one blocked cell
    (0, 0 for the two end points): an edge leaving the corner along (dr, dc)
    is taut only if (dr·qr)(dc·qc) ≤ 0 (it does not cut that cell — the
    taut-edge rule of sparse visibility graphs)."""
    n = nodes.shape[0]
    q = np.zeros((n, 2), dtype=np.int64)
    for i in range(2, n):
        R = nodes[i, 0] // 2
        C = nodes[i, 1] // 2
        for k in range(4):
            qr = 2 * (k // 2) - 1
            qc = 2 * (k % 2) - 1
            if not E._free(grid, R + (qr - 1) // 2, C + (qc - 1) // 2):
                q[i, 0] = qr
                q[i, 1] = qc
                break
    return q


@njit(cache=True)
def _best_open(opn, no, g, hh):
    """The open list's entry (its place in ``opn``) of least g + h, and that f."""
    bi = -1
    best = np.inf
    for k in range(no):
        i = opn[k]
        f = g[i] + hh[i]
        if f < best:
            best = f
            bi = k
    return bi, best


@njit(cache=True)
def _trace(par, nodes):
    """The path from nodes[0] to nodes[1] (k × 2) by the parents ``par``."""
    k = 1
    v = 1
    while v != 0:
        v = par[v]
        k += 1
    out = np.empty((k, 2), dtype=np.int64)
    v = 1
    for i in range(k - 1, -1, -1):
        out[i, 0] = nodes[v, 0]
        out[i, 1] = nodes[v, 1]
        v = par[v]
    return out


@njit(cache=True)
def vg_search(grid, nodes, bound2):
    """A* from nodes[0] to nodes[1] over the visibility graph of ``nodes``
    (taut edges only, each tested by the segment rule when it would improve
    a node; paths longer than bound2 pruned). The nodes not yet expanded are
    kept packed in one array for the relaxation, and those of them already
    reached (the open list) in another for the selection, so each touches
    only those. Returns the path (k × 2) or an empty array."""
    n = nodes.shape[0]
    q = _taut_quadrant(grid, nodes)
    fr = nodes[:, 0].astype(np.float64)
    fc = nodes[:, 1].astype(np.float64)
    hh = np.empty(n)
    for i in range(n):
        hh[i] = math.sqrt((fr[i] - fr[1]) ** 2 + (fc[i] - fc[1]) ** 2)
    g = np.full(n, np.inf)
    par = np.full(n, -1, dtype=np.int64)
    live = np.arange(n)
    at = np.arange(n)  # each node's place in live
    m = n
    opn = np.empty(n, dtype=np.int64)
    no = 1
    opn[0] = 0
    g[0] = 0.0
    lim = bound2 + 1e-9
    while True:
        bi, best = _best_open(opn, no, g, hh)
        if bi < 0 or best > lim:
            return np.empty((0, 2), dtype=np.int64)
        u = opn[bi]
        no -= 1
        opn[bi] = opn[no]
        m -= 1
        w = live[m]
        live[at[u]] = w
        at[w] = at[u]
        if u == 1:
            break
        ur = fr[u]
        uc = fc[u]
        gu = g[u]
        qur = q[u, 0]
        quc = q[u, 1]
        # the way in: a shortest path turns at u only round u's blocked cell
        # (the turn from p→u to u→v goes the way u's blocked cell lies), else
        # it could cut the corner; no test when p→u points at that cell
        p = par[u]
        ir = ur - fr[p] if p >= 0 else 0.0
        ic = uc - fc[p] if p >= 0 else 0.0
        side = ir * quc - ic * qur
        for k in range(m):
            v = live[k]
            dr = fr[v] - ur
            dc = fc[v] - uc
            if (dr * qur) * (dc * quc) > 0 or (dr * q[v, 0]) * (dc * q[v, 1]) > 0:
                continue  # not taut at u or at v: half the directions at each
            if (ir * dc - ic * dr) * side < 0:
                continue  # turns away from u's blocked cell
            if gu + max(abs(dr), abs(dc)) >= g[v] - 1e-9:
                continue  # no shorter even by the longer side alone (no square root)
            nv = gu + math.sqrt(dr * dr + dc * dc)
            if nv >= g[v] - 1e-9 or nv + hh[v] > lim:
                continue
            if E.seg_free(grid, nodes[u, 0], nodes[u, 1], nodes[v, 0], nodes[v, 1]):
                if g[v] == np.inf:
                    opn[no] = v
                    no += 1
                g[v] = nv
                par[v] = u
    return _trace(par, nodes)


@njit(cache=True)
def repair_pass(grid, cum, pts, window, nmax, skip_gap, overlap, bucket_min=2 ** 62,
                bucket_thin=0.0):
    """One pass of windows ``window`` cells of path long, each overlapping the
    last by ``overlap``: a window's piece is replaced by the shortest path
    between its ends over the convex corners in its ellipse when that is
    shorter (windows within ``skip_gap`` of their chord, or whose ellipse
    holds more than ``nmax`` corners, are left; one with more than
    ``bucket_min`` whose piece is under ``bucket_thin`` × its chord — a thin
    ellipse — is searched with the nodes in buckets). Returns (points, exact):
    exact when one window spanned the whole path and was searched, so the
    path is the shortest there is."""
    exact = False
    i = 0
    while i < pts.shape[0] - 1:
        acc = 0.0
        j = i + 1
        while j < pts.shape[0] - 1:
            acc += E._d(pts[j - 1, 0], pts[j - 1, 1], pts[j, 0], pts[j, 1]) / 2.0
            if acc >= window:
                break
            j += 1
        sub = pts[i:j + 1]
        straight = E._d(sub[0, 0], sub[0, 1], sub[-1, 0], sub[-1, 1])
        plen = E.path_len(sub)
        if sub.shape[0] > 2 and plen - straight > skip_gap * straight:
            bound2 = plen + 1e-6
            nodes = ellipse_nodes(grid, cum, sub[0], sub[-1], bound2, nmax)
            if nodes.shape[0]:
                exact = exact or (i == 0 and j == pts.shape[0] - 1)
                if nodes.shape[0] > bucket_min and plen < bucket_thin * straight:
                    better = vg_search_buckets(grid, nodes, bound2)
                else:
                    better = vg_search(grid, nodes, bound2)
                if better.shape[0] and E.path_len(better) < plen - 1e-9:
                    out = np.empty((i + better.shape[0] + pts.shape[0] - j - 1, 2), dtype=np.int64)
                    out[:i] = pts[:i]
                    out[i:i + better.shape[0]] = better
                    out[i + better.shape[0]:] = pts[j + 1:]
                    pts = out
                    j = i + better.shape[0] - 1
        if j >= pts.shape[0] - 1:
            break
        i = max(i + 1, j - int(overlap * (j - i)))
    return pts, exact


@njit(cache=True)
def _buckets(nodes, bs):
    """The nodes in square buckets of ``bs`` half-cells (compressed rows):
    (r0, c0, nr, nc, start, order); bucket k = (br, bc) holds
    order[start[k]:start[k + 1]], k = br · nc + bc."""
    n = nodes.shape[0]
    r0 = nodes[0, 0]
    c0 = nodes[0, 1]
    r1 = r0
    c1 = c0
    for i in range(n):
        r0 = min(r0, nodes[i, 0])
        r1 = max(r1, nodes[i, 0])
        c0 = min(c0, nodes[i, 1])
        c1 = max(c1, nodes[i, 1])
    nr = (r1 - r0) // bs + 1
    nc = (c1 - c0) // bs + 1
    start = np.zeros(nr * nc + 1, dtype=np.int64)
    key = np.empty(n, dtype=np.int64)
    for i in range(n):
        key[i] = ((nodes[i, 0] - r0) // bs) * nc + (nodes[i, 1] - c0) // bs
        start[key[i] + 1] += 1
    for k in range(nr * nc):
        start[k + 1] += start[k]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        order[fill[key[i]]] = i
        fill[key[i]] += 1
    return r0, c0, nr, nc, start, order


@njit(cache=True)
def _rect_dist(pr, pc, rlo, rhi, clo, chi):
    dr = max(rlo - pr, 0.0, pr - rhi)
    dc = max(clo - pc, 0.0, pc - chi)
    return math.sqrt(dr * dr + dc * dc)


@njit(cache=True)
def vg_search_buckets(grid, nodes, bound2, bs=16):
    """:func:`vg_search` with the nodes in buckets of ``bs`` half-cells: an
    expansion of u with budget B = bound2 − g(u) relaxes only nodes v with
    |u v| + |v goal| ≤ B, which lie in the ellipse with foci u and the goal,
    so it visits only the buckets in that ellipse's bounding box that a
    lower bound (the distances from u and the goal to the bucket's square)
    does not rule out — the same relaxations as the scan over every node,
    and so the same shortest length. For the certificate, whose bound leaves
    little slack, that ellipse is a thin sliver from u to the goal."""
    n = nodes.shape[0]
    q = _taut_quadrant(grid, nodes)
    fr = nodes[:, 0].astype(np.float64)
    fc = nodes[:, 1].astype(np.float64)
    tr = fr[1]
    tc = fc[1]
    hh = np.empty(n)
    for i in range(n):
        hh[i] = math.sqrt((fr[i] - tr) ** 2 + (fc[i] - tc) ** 2)
    r0, c0, nr, nc, start, order = _buckets(nodes, bs)
    g = np.full(n, np.inf)
    par = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    opn = np.empty(n, dtype=np.int64)
    no = 1
    opn[0] = 0
    g[0] = 0.0
    lim = bound2 + 1e-9
    while True:
        bi, best = _best_open(opn, no, g, hh)
        if bi < 0 or best > lim:
            return np.empty((0, 2), dtype=np.int64)
        u = opn[bi]
        no -= 1
        opn[bi] = opn[no]
        closed[u] = True
        if u == 1:
            break
        ur = fr[u]
        uc = fc[u]
        gu = g[u]
        qur = q[u, 0]
        quc = q[u, 1]
        p = par[u]
        ir = ur - fr[p] if p >= 0 else 0.0
        ic = uc - fc[p] if p >= 0 else 0.0
        turn = ir * quc - ic * qur
        budget = lim - gu
        # bounding box of the ellipse |u v| + |v t| <= budget
        semi = 0.5 * budget
        foc = 0.5 * hh[u]
        minor2 = max(semi * semi - foc * foc, 0.0)
        cr = (tr - ur) / hh[u] if hh[u] > 0 else 1.0
        cc = (tc - uc) / hh[u] if hh[u] > 0 else 0.0
        er = math.sqrt(semi * semi * cr * cr + minor2 * cc * cc)
        ec = math.sqrt(semi * semi * cc * cc + minor2 * cr * cr)
        mr = 0.5 * (ur + tr)
        mc = 0.5 * (uc + tc)
        b0 = max(0, int(math.floor((mr - er - r0) / bs)))
        b1 = min(nr - 1, int(math.floor((mr + er - r0) / bs)))
        k0 = max(0, int(math.floor((mc - ec - c0) / bs)))
        k1 = min(nc - 1, int(math.floor((mc + ec - c0) / bs)))
        for br in range(b0, b1 + 1):
            rlo = float(r0 + br * bs)
            rhi = rlo + bs - 1
            for bc in range(k0, k1 + 1):
                clo = float(c0 + bc * bs)
                chi = clo + bs - 1
                if (_rect_dist(ur, uc, rlo, rhi, clo, chi)
                        + _rect_dist(tr, tc, rlo, rhi, clo, chi)) > budget:
                    continue
                b = br * nc + bc
                for k in range(start[b], start[b + 1]):
                    v = order[k]
                    if closed[v]:
                        continue
                    dr = fr[v] - ur
                    dc = fc[v] - uc
                    if (dr * qur) * (dc * quc) > 0 or (dr * q[v, 0]) * (dc * q[v, 1]) > 0:
                        continue
                    if (ir * dc - ic * dr) * turn < 0:
                        continue
                    if gu + max(abs(dr), abs(dc)) >= g[v] - 1e-9:
                        continue
                    nv = gu + math.sqrt(dr * dr + dc * dc)
                    if nv >= g[v] - 1e-9 or nv + hh[v] > lim:
                        continue
                    if E.seg_free(grid, nodes[u, 0], nodes[u, 1], nodes[v, 0], nodes[v, 1]):
                        if g[v] == np.inf:
                            opn[no] = v
                            no += 1
                        g[v] = nv
                        par[v] = u
    return _trace(par, nodes)


@njit(cache=True)
def certify(grid, cum, pts, ratio, nmax):
    """The certificate stage: is the path ``pts`` within ``ratio`` of the
    shortest there is? Any path shorter than |pts| / ratio lies in the
    ellipse of that length round the path's ends, so A* over the convex
    corners inside it (:func:`vg_search`, bounded by that length) either
    finds the shortest path — shorter than |pts| / ratio, returned — or proves
    that none is that short. Returns (points, status): status 1 proved
    within ``ratio`` (the path unchanged), 2 a shorter path found (the
    shortest there is), 0 not searched (the ellipse holds more than ``nmax``
    corners; the path unchanged)."""
    a = pts[0]
    b = pts[pts.shape[0] - 1]
    bound2 = E.path_len(pts) / ratio
    if bound2 <= E._d(a[0], a[1], b[0], b[1]) + 1e-9:
        return pts, 1  # within ratio of the straight line
    nodes = ellipse_nodes(grid, cum, a, b, bound2, nmax)
    if not nodes.shape[0]:
        return pts, 0
    better = vg_search_buckets(grid, nodes, bound2)
    if better.shape[0]:
        return better, 2
    return pts, 1
