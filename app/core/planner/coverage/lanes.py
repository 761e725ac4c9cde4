"""Lane tours: boustrophedon lanes (§3.4) joined in the order that turns least.

The walker of :mod:`._kernels` decides cell by cell, so it breaks lanes where
an obstacle ends and leaves short pieces; boustrophedon cellular
decomposition (Choset) keeps whole lanes but links its cells by long
returns over swept wall. Here the lanes are fixed first and only their
order is searched:

1. lanes: the maximal runs of reachable cells along each region's sweep
   axis (rows or columns, §3.4); the lane holding the start is cut there;
2. link costs between lane ends: the ends' breadth-first distance d (cells
   of travel, no corner cutting) within ``radius``; a link of one step costs
   its changes of heading (0, 1 or 2: a side step between parallel lanes is
   the U-turn of eqs. 2–3), a longer one 3 + λ·(d − 1), the d − 1 cells
   crossed being repetition (Definition 7) — or, with ``turn_radius``, its
   fewest changes of heading (:mod:`.links`) + λ·(d − 1) up to that length;
3. order: nearest-neighbour from the start lane, then 2-opt (reverse a run
   of lanes, each swept the other way) and or-opt (move one lane, either
   way round) while the total cost falls — the lanes form a symmetric
   travelling-salesman tour over lane ends (each lane's two ends joined) —
   and optionally ``kicks`` rounds of iterated local search (double
   bridges anywhere, or of at most ``span`` lanes); a set of many lanes of
   a few cells (scattered obstacles) on neighbour lists instead of the
   dense (2n)² table (SPARSE_LANES, :mod:`.sparse`);
4. the path: the lanes in that order, joined by fewest-step paths (the
   ones :mod:`.links` priced, where it did).

With ``wrap`` (the tank wall's seam) columns 0 and W−1 are neighbours: a
row's run that reaches both edges is one lane across the seam, and links
may cross it.

The coverage is complete by construction (every reachable cell lies in one
lane); the repetition is the links' travel, so :func:`.plan.best_plan`
keeps a lane tour only when it is within its repetition cap.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import _kernels as K
from ._kernels import bfs_layers
from .links import NO_DIR, _dcol, link_cost, link_paths, link_turns
from .sparse import (
    improve_s,
    kicked_s,
    kth_costs,
    nearest_tour_s,
    neighbour_lists,
    symmetric_lists,
)

FAR = 1 << 20  # distance of ends that the bounded search did not reach
# A round of iterated local search over the whole order (a double bridge anywhere, then
# passes of improve_t) costs ∝ n² for n lanes; orders longer than this many lanes get
# kicks · (KICK_LANES / n)² rounds, so the search's effort stays bounded (maps cut into
# hundreds of one- and two-cell lanes by scattered obstacles took seconds per plan).
KICK_LANES = 200
# The tours price every pair of lane ends in dense (2n)² tables and search the order in
# O(n²) passes: a map cut into more lanes than this (scattered obstacles leave lanes of
# one or two cells: 2358 lanes on a 60 × 60 grid a fifth blocked, 7747 on the Moving AI
# map 32room_000, 125 s and 7.5 GB) gets no lane tour; its plan comes from the walkers.
# The project's walls have at most 773 (docs/coverage.md, "What is weaker").
MAX_TOUR_LANES = 2000
# A set of more than SPARSE_LANES lanes averaging fewer than SPARSE_CELLS cells each
# (scattered obstacles: the split lanes of a 40 × 40 grid a fifth blocked are about 770
# lanes of 1.7 cells, the whole lanes of an 80 × 80 one about 1050 of 4.9) is ordered on
# neighbour lists (each end's NEIGHBOURS cheapest links, :mod:`.sparse`), not on
# the dense table: its 2-opt and or-opt passes cost ∝ n · NEIGHBOURS (and n per link
# longer than its end's list reaches) instead of n². The project's walls have no such set
# (the toured sets of over 500 lanes, on the crowded panels, average 5.9 cells or more),
# so their tours are the same.
SPARSE_LANES = 500
SPARSE_CELLS = 5.5
NEIGHBOURS = 24


def lanes_of(labels: np.ndarray, axes: np.ndarray, wrap: bool = False) -> list[np.ndarray]:
    """Maximal runs of cells of one region along the region's axis (0: along
    rows, 1: along columns), as flat-index arrays, rows first; with ``wrap``
    a row's last and first runs join across the seam when they touch it."""
    h, w = labels.shape
    lanes: list[np.ndarray] = []
    for axis in (0, 1):
        lab = labels if axis == 0 else labels.T
        on = (lab >= 0) & (axes[np.maximum(lab, 0)] == axis)
        for i in range(lab.shape[0]):
            row, ok = lab[i], on[i]
            if not ok.any():
                continue
            brk = np.ones(len(row) + 1, dtype=bool)
            brk[1:-1] = (row[1:] != row[:-1]) | ~ok[1:] | ~ok[:-1]
            edges = np.nonzero(brk)[0]
            first = len(lanes)
            for a, b in zip(edges[:-1].tolist(), edges[1:].tolist(), strict=True):
                if ok[a]:
                    idx = np.arange(a, b, dtype=np.int64)
                    lanes.append(i * w + idx if axis == 0 else idx * w + i)
            seam = axis == 0 and wrap and len(lanes) - first >= 2 and ok[0] and ok[-1]
            if seam and row[0] == row[-1]:  # the last run goes on across the seam
                tail = lanes.pop()
                lanes[first] = np.concatenate((tail, lanes[first]))
    return lanes


def split_lanes(lanes: list[np.ndarray], labels: np.ndarray, axes: np.ndarray) -> list[np.ndarray]:
    """The lanes cut where a parallel lane beside them begins or ends (no
    wrap): at a staircase edge or beside an obstacle a whole lane forces
    its link back over cells it swept, while pieces let the tour hand the
    rest of a lane over to the lane beside it (what BCD's cells do).
    Joining the pieces straight on costs nothing, so the whole lanes stay
    one of the tours."""
    w = labels.shape[1]
    info, by_line = [], {}
    for i, ln in enumerate(lanes):
        r, c = divmod(int(ln[0]), w)
        axis = int(axes[labels[r, c]])
        pos = ln % w if axis == 0 else ln // w
        info.append((axis, r if axis == 0 else c, int(pos.min()), int(pos.max()), pos))
        by_line.setdefault((axis, info[-1][1]), []).append(i)
    out = []
    for ln, (axis, line, lo, hi, pos) in zip(lanes, info, strict=True):
        cuts = set()
        for j in by_line.get((axis, line - 1), []) + by_line.get((axis, line + 1), []):
            a, b = info[j][2], info[j][3]
            if lo < a <= hi:
                cuts.add(a)  # a piece starts where the neighbour starts
            if lo <= b < hi:
                cuts.add(b + 1)  # and after where it ends
        ks = sorted(int(np.nonzero(pos == c)[0][0]) for c in cuts)
        out += [piece for piece in np.split(ln, ks) if len(piece)]
    return out


def end_distances(free, cells, radius, wrap=False):
    """(m, m) fewest-step distances between the cells (no corner cutting,
    across the seam with ``wrap``), searched up to ``radius`` steps from
    each; FAR beyond."""
    nbr = K.neighbour_table(np.ascontiguousarray(free, dtype=np.uint8), wrap)
    return _end_distances(nbr, np.asarray(cells, dtype=np.int64), radius)


@njit(cache=True)
def _end_distances(nbr, cells, radius):
    """:func:`end_distances` on a neighbour table (:func:`._kernels.neighbour_table`)."""
    m = len(cells)
    out = np.full((m, m), FAR, dtype=np.int64)
    dist = np.full(nbr.shape[0], -1, dtype=np.int64)
    queue = np.empty(nbr.shape[0], dtype=np.int64)
    for i in range(m):
        tail = bfs_layers(nbr, cells[i], radius, dist, queue)
        for j in range(m):
            if dist[cells[j]] >= 0:
                out[i, j] = dist[cells[j]]
        for t in range(tail):  # reset only what this search touched
            dist[queue[t]] = -1
    return out


@njit(cache=True)
def link_table(dist, cell, ur, uc, w, lam):
    """(2n, 2n) :func:`link_cost` of every pair of lane ends, computed once
    per tour: the order searches below look costs up instead of recomputing
    them (the same numbers, so the same orders)."""
    m = len(cell)
    out = np.empty((m, m), dtype=np.float64)
    for x in range(m):
        for y in range(m):
            out[x, y] = link_cost(dist, cell, ur, uc, w, x, y, lam)
    return out


@njit(cache=True)
def exact_table(cost, dist, turns, lam):
    """``cost`` (:func:`link_table`) with each link whose fewest changes of
    heading are known (``turns`` ≥ 0: :func:`.links.link_turns`) priced at
    those turns + lam per cell crossed instead of the flat 3 + lam."""
    m = cost.shape[0]
    out = cost.copy()
    for x in range(m):
        for y in range(m):
            if turns[x, y] >= 0:
                out[x, y] = turns[x, y] + lam * (dist[x, y] - 1)
    return out


@njit(cache=True)
def nearest_tour_t(cost, first):
    """Entry ends of the lanes (end e of lane e // 2, left by e ^ 1), from
    lane ``first`` entered at its end 2·first, each next lane the cheapest
    to reach (``cost``: :func:`link_table`)."""
    n = cost.shape[0] // 2
    done = np.zeros(n, dtype=np.bool_)
    seq = np.empty(n, dtype=np.int64)
    seq[0] = 2 * first
    done[first] = True
    for t in range(1, n):
        x = seq[t - 1] ^ 1
        best, be = np.inf, -1
        for e in range(2 * n):
            if not done[e // 2]:
                c = cost[x, e]
                if c < best:
                    best, be = c, e
        seq[t] = be
        done[be // 2] = True
    return seq


@njit(cache=True)
def improve_t(seq, cost, passes, first=1, last=-1):
    """2-opt and or-opt on the lane order (the first lane stays first and is
    entered as it is), costs from :func:`link_table`; returns the number of
    moves taken. Only moves of the lanes at positions first..last − 1 of the
    order (last < 0: to its end) are tried — reversals that begin there,
    lanes moved from there, to anywhere (after a change near there the
    rest of the order was already searched)."""
    n = len(seq)
    top = n if last < 0 else min(last, n)
    bottom = max(first, 1)
    moves = 0
    for _ in range(passes):
        gained = False
        for i in range(bottom, top):  # 2-opt: seq[i..j] reversed, each lane flipped
            a = seq[i - 1] ^ 1
            for j in range(i, n):
                old = cost[a, seq[i]]
                new = cost[a, seq[j] ^ 1]
                if j + 1 < n:
                    old += cost[seq[j] ^ 1, seq[j + 1]]
                    new += cost[seq[i], seq[j + 1]]
                if new < old - 1e-9:
                    lo, hi = i, j
                    while lo < hi:
                        t = seq[lo]
                        seq[lo] = seq[hi] ^ 1
                        seq[hi] = t ^ 1
                        lo += 1
                        hi -= 1
                    if lo == hi:
                        seq[lo] ^= 1
                    gained = True
                    moves += 1
        for i in range(bottom, top):  # or-opt: lane i moved after lane k, either way round
            e0 = seq[i]
            prv = seq[i - 1] ^ 1
            cut = cost[prv, e0]
            if i + 1 < n:
                cut += cost[e0 ^ 1, seq[i + 1]]
                cut -= cost[prv, seq[i + 1]]
            best, bk, bo = 1e-9, -1, 0
            for k in range(n):
                if k == i or k == i - 1:
                    continue
                x = seq[k] ^ 1
                y = seq[k + 1] if k + 1 < n else -1
                if k + 1 == i:
                    y = seq[i + 1] if i + 1 < n else -1
                base = cost[x, y] if y >= 0 else 0.0
                for o in range(2):
                    e = e0 ^ o
                    add = cost[x, e]
                    if y >= 0:
                        add += cost[e ^ 1, y]
                    if cut - (add - base) > best:
                        best, bk, bo = cut - (add - base), k, o
            if bk >= 0:
                e = e0 ^ bo
                if bk > i:
                    for t in range(i, bk):
                        seq[t] = seq[t + 1]
                    seq[bk] = e
                else:
                    for t in range(i, bk + 1, -1):
                        seq[t] = seq[t - 1]
                    seq[bk + 1] = e
                gained = True
                moves += 1
        if not gained:
            break
    return moves


@njit(cache=True)
def tour_cost_t(seq, cost):
    total = 0.0
    for t in range(1, len(seq)):
        total += cost[seq[t - 1] ^ 1, seq[t]]
    return total


@njit(cache=True)
def kicked_t(seq, cost, passes, kicks, seed, span=0, local=False):
    """Iterated local search (Lourenço, Martin & Stützle): from the best
    order so far, a random double bridge (A B C D → A C B D, the first lane
    kept), then ``passes`` rounds of :func:`improve_t`; kept when the cost
    falls. ``span`` > 0: a local double bridge, B and C each at most
    ``span`` lanes long (a small change the local search can repair, as
    for large travelling-salesman tours); 0: anywhere in the order. With
    ``local`` (and span > 0) the local search after a bridge moves only the
    lanes within 2·``span`` positions of it (a long order: many more
    rounds in the same time)."""
    np.random.seed(seed)
    n = len(seq)
    best = seq.copy()
    best_cost = tour_cost_t(best, cost)
    if n < 5:
        return best
    for _ in range(kicks):
        if span > 0 and n > 2 * span + 2:
            a = np.random.randint(1, n - 2 * span)
            b = a + np.random.randint(1, span + 1)
            c = b + np.random.randint(1, span + 1)
            if local:
                first, last = a - 2 * span, c + 2 * span
            else:
                first, last = 1, -1
        else:
            a, b, c = np.sort(np.random.choice(np.arange(1, n), 3, replace=False))
            first, last = 1, -1
        trial = np.concatenate((best[:a], best[b:c], best[a:b], best[c:]))
        improve_t(trial, cost, passes, first, last)
        c_trial = tour_cost_t(trial, cost)
        if c_trial < best_cost - 1e-9:
            best, best_cost = trial, c_trial
    return best


def nearest_tour(dist, cell, ur, uc, w, first, lam):
    """:func:`nearest_tour_t` on the link costs of these lane ends."""
    return nearest_tour_t(link_table(dist, cell, ur, uc, w, lam), first)


def improve(seq, dist, cell, ur, uc, w, lam, passes):
    """:func:`improve_t` on the link costs of these lane ends."""
    return improve_t(seq, link_table(dist, cell, ur, uc, w, lam), passes)


def tour_cost(seq, dist, cell, ur, uc, w, lam):
    """Total link cost of a lane order."""
    return tour_cost_t(seq, link_table(dist, cell, ur, uc, w, lam))


def kicked(seq, dist, cell, ur, uc, w, lam, passes, kicks, seed):
    """:func:`kicked_t` on the link costs of these lane ends."""
    return kicked_t(seq, link_table(dist, cell, ur, uc, w, lam), passes, kicks, seed)


def _ends(lanes: list[np.ndarray], w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell and outward direction of each lane end (2i: first cell, 2i+1: last)."""
    n = len(lanes)
    cell = np.empty(2 * n, dtype=np.int64)
    ur = np.full(2 * n, NO_DIR, dtype=np.int64)
    uc = np.full(2 * n, NO_DIR, dtype=np.int64)
    for i, ln in enumerate(lanes):
        cell[2 * i], cell[2 * i + 1] = ln[0], ln[-1]
        if len(ln) > 1:
            ur[2 * i], uc[2 * i] = ln[0] // w - ln[1] // w, _dcol(ln[0] % w - ln[1] % w, w)
            ur[2 * i + 1], uc[2 * i + 1] = -ur[2 * i], -uc[2 * i]
    return cell, ur, uc


def lane_set(
    labels: np.ndarray, axes: np.ndarray, start: int, wrap: bool = False, split: bool = False
) -> tuple[list[np.ndarray], int]:
    """The lanes of :func:`lane_tour` (:func:`lanes_of`, cut into pieces with
    ``split``) with the start lane cut at ``start``, and that lane's index."""
    w = labels.shape[1]
    lanes = lanes_of(labels, axes, wrap)
    if split and not wrap:
        lanes = split_lanes(lanes, labels, axes)
    for i, ln in enumerate(lanes):  # the start lane is cut at the start
        k = np.nonzero(ln == start)[0]
        if len(k) == 0:
            continue
        k = int(k[0])
        if k == len(ln) - 1:
            lanes[i] = ln[::-1].copy()
        elif k > 0:
            lanes[i] = ln[k:]
            lanes.append(ln[:k][::-1].copy())
        return lanes, i
    raise ValueError(f"start cell {divmod(start, w)} is in no lane")


def shared_distances(free: np.ndarray, cell_sets: list[np.ndarray], radius: int = 48) -> list:
    """:func:`end_distances` of several sets of lane ends at once (no wrap):
    one search per distinct cell, its distances written into the rows of
    every set that holds the cell (a search from a cell does not depend on
    the other cells); the same matrices, without a joint one of all cells."""
    union = np.unique(np.concatenate(cell_sets))
    sizes = np.array([len(c) for c in cell_sets], dtype=np.int64)
    starts = np.concatenate(([0], np.cumsum(sizes)))
    offs = np.concatenate(([0], np.cumsum(sizes * sizes)))
    allc = np.concatenate(cell_sets).astype(np.int64)
    out = np.empty(int(offs[-1]), dtype=np.int64)  # every entry written below
    nbr = K.neighbour_table(np.ascontiguousarray(free, dtype=np.uint8), False)
    _set_distances(nbr, union, allc, starts, offs, radius, out)
    return [
        out[offs[s] : offs[s + 1]].reshape(int(m), int(m)) for s, m in enumerate(sizes.tolist())
    ]


@njit(cache=True)
def _set_distances(nbr, union, allc, starts, offs, radius, out):
    """:func:`shared_distances`' searches: set s holds allc[starts[s]:starts[s + 1]]
    and its (m, m) matrix is out[offs[s]:offs[s + 1]] (every entry written)."""
    nu, total = len(union), len(allc)
    idx = np.searchsorted(union, allc)
    head = np.zeros(nu + 1, dtype=np.int64)  # the positions in allc of each distinct cell
    for t in range(total):
        head[idx[t] + 1] += 1
    head = np.cumsum(head)
    fill = head[:-1].copy()
    occ = np.empty(total, dtype=np.int64)
    owner = np.empty(total, dtype=np.int64)
    for s in range(len(starts) - 1):
        for t in range(starts[s], starts[s + 1]):
            owner[t] = s
    for t in range(total):
        occ[fill[idx[t]]] = t
        fill[idx[t]] += 1
    dist = np.full(nbr.shape[0], -1, dtype=np.int64)
    queue = np.empty(nbr.shape[0], dtype=np.int64)
    for u in range(nu):
        tail = bfs_layers(nbr, union[u], radius, dist, queue)
        for q in range(head[u], head[u + 1]):
            t = occ[q]
            s = owner[t]
            a, m = starts[s], starts[s + 1] - starts[s]
            base = offs[s] + (t - a) * m
            for j in range(m):
                d = dist[allc[a + j]]
                out[base + j] = d if d >= 0 else FAR
        for t in range(tail):  # reset only what this search touched
            dist[queue[t]] = -1


def prepared_sets(free: np.ndarray, sets: list[tuple], radius: int = 48) -> list[tuple | None]:
    """For each lane set (lanes, first) of :func:`lane_set`, the ``prepared``
    argument of :func:`lane_tour`: (lanes, first, the ends' distances within
    ``radius``), the distances of all sets from one search
    (:func:`shared_distances`); None for a set of more than MAX_TOUR_LANES
    lanes (no dense tables for it). No wrap."""
    w = free.shape[1]
    kept = [i for i, (lanes, _) in enumerate(sets) if len(lanes) <= MAX_TOUR_LANES]
    out: list[tuple | None] = [None] * len(sets)
    if not kept:
        return out
    dists = shared_distances(free, [_ends(sets[i][0], w)[0] for i in kept], radius)
    for i, dist in zip(kept, dists, strict=True):
        out[i] = (sets[i][0], sets[i][1], dist)
    return out


def lane_tour(
    free: np.ndarray,
    labels: np.ndarray,
    axes: np.ndarray,
    start: int,
    lam: float = 2.0,
    radius: int = 48,
    passes: int = 30,
    kicks: int = 0,
    seed: int = 1,
    kick_passes: int = 2,
    wrap: bool = False,
    split: bool = False,
    prepared: tuple | None = None,
    turn_radius: int = 0,
    span: int = 0,
    local: bool = False,
) -> np.ndarray:
    """A coverage path (flat cells from ``start``) of the cells with
    labels ≥ 0: their lanes (axes per region: 0 rows, 1 columns) in the
    order found by :func:`nearest_tour` and :func:`improve`, joined by
    fewest-step paths over ``free`` (uint8, C-contiguous); across the seam
    with ``wrap``; with ``split`` (no wrap) the lanes are cut into pieces
    where their neighbours begin or end (:func:`split_lanes`). ``prepared``:
    (lanes, first, dist) of :func:`lane_set` and the ends' distances
    (radius ``radius``), when already known. ``turn_radius`` > 0: links of
    2 to ``turn_radius`` steps are priced by their fewest changes of heading
    (:mod:`.links`) and made by the path so priced."""
    w = free.shape[1]
    if prepared is None:
        lanes, first = lane_set(labels, axes, start, wrap, split)
        dist = None
    else:
        lanes, first, dist = prepared
    cell, ur, uc = _ends(lanes, w)
    if dist is None:
        dist = end_distances(free, cell, radius, wrap)
    if sparse_set(lanes) and turn_radius == 0:  # many short lanes: neighbour lists
        nb = neighbour_lists(dist, cell, ur, uc, w, lam, NEIGHBOURS)
        seq = nearest_tour_s(nb, dist, cell, ur, uc, w, lam, first)
        offs, near = symmetric_lists(nb, dist, cell, ur, uc, w, lam)
        kth = kth_costs(nb, dist, cell, ur, uc, w, lam)
        improve_s(seq, offs, near, kth, dist, cell, ur, uc, w, lam, passes)
        if kicks > 0:
            kicks = max(1, round(kicks * (KICK_LANES / len(seq)) ** 2))
            seq = kicked_s(
                seq, offs, near, kth, dist, cell, ur, uc, w, lam, kick_passes, kicks, seed
            )
        return _joined(free, lanes, seq, dist, wrap, {})
    cost = link_table(dist, cell, ur, uc, w, lam)
    if turn_radius > 0:
        nbr = K.neighbour_table(np.ascontiguousarray(free, dtype=np.uint8), wrap)
        cost = exact_table(cost, dist, link_turns(nbr, cell, ur, uc, turn_radius), lam)
    seq = nearest_tour_t(cost, first)
    improve_t(seq, cost, passes)
    if kicks > 0 and not local and len(seq) > KICK_LANES:
        kicks = max(1, round(kicks * (KICK_LANES / len(seq)) ** 2))
    if kicks > 0:
        seq = kicked_t(seq, cost, kick_passes, kicks, seed, span, local)
    exact = {}
    if turn_radius > 0:  # the links priced by their turns, made that way
        x, y = seq[:-1] ^ 1, seq[1:]
        d = dist[x, y]
        sel = (d >= 2) & (d <= turn_radius)
        xs, ys = x[sel], y[sel]
        cells, offs = link_paths(
            nbr, cell[xs], ur[xs], uc[xs], cell[ys], ur[ys], uc[ys], turn_radius
        )
        for i, g in enumerate((np.nonzero(sel)[0] + 1).tolist()):
            if offs[i + 1] > offs[i]:
                exact[g] = cells[offs[i] : offs[i + 1]]
    return _joined(free, lanes, seq, dist, wrap, exact)


def sparse_set(lanes: list[np.ndarray]) -> bool:
    """Is this lane set ordered on neighbour lists (SPARSE_LANES, SPARSE_CELLS)?"""
    n = len(lanes)
    return n > SPARSE_LANES and sum(len(ln) for ln in lanes) < SPARSE_CELLS * n


def _joined(free, lanes, seq, dist, wrap, exact) -> np.ndarray:
    """The lanes in the order ``seq`` (entry ends), joined by the paths of
    ``exact`` (position → cells) or else by fewest-step paths (flat cells)."""
    n = free.size
    parent, stamp, queue = np.empty(n, np.int64), np.zeros(n, np.int64), np.empty(n, np.int64)
    none = np.zeros(free.shape, dtype=np.int32)
    parts = []
    for g, e in enumerate(seq.tolist()):
        ln = lanes[e // 2] if e % 2 == 0 else lanes[e // 2][::-1]
        if g in exact:
            parts.append(exact[g][:-1])
        elif parts and dist[seq[g - 1] ^ 1, e] != 1:
            trip = K.bfs_path(
                free, none, none, int(parts[-1][-1]), int(ln[0]), -1, wrap, parent, stamp, g, queue
            )
            parts.append(trip[:-1])
        parts.append(ln)
    return np.concatenate(parts).astype(np.int64)
