"""Turn-exact links between lanes (coverage/links.py): the fewest changes of
heading over the fewest-step paths, checked against every such path
enumerated apart; the paths made are those priced; lane tours using them
stay complete and valid; and the full tank wall's plan turns less than
BCD swept along its fewer-lane axis (the bench's fair anchor)."""

import itertools

import numpy as np
import pytest

from app.core.planner.coverage import _kernels as K
from app.core.planner.coverage import best_plan, figures
from app.core.planner.coverage.lanes import NO_DIR, kicked_t, lane_tour, tour_cost_t
from app.core.planner.coverage.links import link_paths, link_turns
from app.core.planner.coverage.plan import MAX_REPETITION
from bench.coverage_bench import bcd_axis
from bench.coverage_maps import full_wall, start_cell

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable

MOVES = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]


def _moves(blocked, cell):
    h, w = blocked.shape
    r, c = cell
    for dr, dc in MOVES:
        nr, nc = r + dr, c + dc
        if not (0 <= nr < h and 0 <= nc < w) or blocked[nr, nc]:
            continue
        if dr and dc and (blocked[r + dr, c] or blocked[r, c + dc]):
            continue
        yield (dr, dc), (nr, nc)


def _layers(blocked, src):
    dist, frontier = {src: 0}, [src]
    while frontier:
        nxt = []
        for v in frontier:
            for _, u in _moves(blocked, v):
                if u not in dist:
                    dist[u] = dist[v] + 1
                    nxt.append(u)
        frontier = nxt
    return dist


def _fewest_turns(blocked, src, out, dst, into):
    """Every fewest-step path src → dst enumerated; the least of: turns along
    it, + 1 when its first step is not ``out`` (0.5 with out None), + 1 when
    its last step is not ``into`` (0.5 with into None)."""
    to_dst = _layers(blocked, dst)
    d = to_dst.get(src)
    best = None

    def walk(v, steps):
        nonlocal best
        if v == dst:
            t = sum(a != b for a, b in itertools.pairwise(steps))
            t += 0.5 if out is None else float(steps[0] != out)
            t += 0.5 if into is None else float(steps[-1] != into)
            best = t if best is None else min(best, t)
            return
        for s, u in _moves(blocked, v):
            if to_dst.get(u) == to_dst[v] - 1:
                walk(u, [*steps, s])

    walk(src, [])
    return d, best


def test_link_turns_match_every_fewest_step_path(rng):
    heads = [None, (0, 1), (0, -1), (1, 0), (-1, 0)]
    checked = 0
    for _ in range(12):
        blocked = random_grid(rng, 7, 8, 0.2)
        w = blocked.shape[1]
        free = np.ascontiguousarray(~blocked, dtype=np.uint8)
        nbr = K.neighbour_table(free, False)
        free_cells = [tuple(int(x) for x in p) for p in np.argwhere(~blocked)]
        ends = [free_cells[i] for i in rng.choice(len(free_cells), 6, replace=False)]
        outs = [heads[int(rng.integers(len(heads)))] for _ in ends]
        cell = np.array([r * w + c for r, c in ends], dtype=np.int64)
        ur = np.array([NO_DIR if o is None else o[0] for o in outs], dtype=np.int64)
        uc = np.array([NO_DIR if o is None else o[1] for o in outs], dtype=np.int64)
        table = link_turns(nbr, cell, ur, uc, 6)
        for x, y in itertools.permutations(range(len(ends)), 2):
            into = None if outs[y] is None else (-outs[y][0], -outs[y][1])
            d, want = _fewest_turns(blocked, ends[x], outs[x], ends[y], into)
            if d is None or d < 2 or d > 6:
                assert table[x, y] == -1
                continue
            assert table[x, y] == want, (ends[x], outs[x], ends[y], outs[y])
            cells, offs = link_paths(
                nbr, cell[[x]], ur[[x]], uc[[x]], cell[[y]], ur[[y]], uc[[y]], 6
            )
            path = [ends[x]] + [divmod(int(v), w) for v in cells[offs[0] : offs[1]]]
            assert len(path) == d + 1 and path[-1] == ends[y]
            steps = [(b[0] - a[0], b[1] - a[1]) for a, b in itertools.pairwise(path)]
            for a, s in zip(path, steps, strict=False):
                assert s in dict(_moves(blocked, a))  # a valid move, no corner cut
            t = sum(a != b for a, b in itertools.pairwise(steps))
            t += 0.5 if outs[x] is None else float(steps[0] != outs[x])
            t += 0.5 if into is None else float(steps[-1] != into)
            assert t == want
            checked += 1
    assert checked > 50


@pytest.mark.parametrize("split", [False, True])
def test_lane_tour_with_exact_links_complete_and_valid(rng, split):
    for density in (0.1, 0.25, 0.4):
        for _ in range(8):
            h, w = int(rng.integers(2, 25)), int(rng.integers(2, 25))
            blocked = random_grid(rng, h, w, density)
            if blocked.all():
                continue
            start = free_cell(rng, blocked)
            reach = reachable(blocked, start)
            labels = np.full((h, w), -1, dtype=np.int32)
            for r, c in reach:
                labels[r, c] = 0
            free = np.ascontiguousarray(labels >= 0, dtype=np.uint8)
            for axis in (0, 1):
                arr = lane_tour(
                    free, labels, np.array([axis]), start[0] * w + start[1], 1.0,
                    kicks=20, turn_radius=8, span=4, split=split,
                )  # fmt: skip
                cells = list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))
                assert check(blocked, start, cells) == reach


def test_full_wall_turns_less_than_bcd_along_its_fewer_lane_axis():
    # the default tank wall unrolled (96 × 754 cells): the lane tour with
    # turn-priced links and a local order search turns less than BCD swept
    # along rows (399 turns at 5.3 % repetition), within the cap; the lane
    # tour without them, the old plan, turned 459 times
    blocked = full_wall()
    start = start_cell(blocked)
    cells = best_plan(blocked, start).cells
    got = figures(blocked, start, cells)
    anchor = figures(blocked, start, bcd_axis(blocked, start))
    assert check(blocked, start, cells) == reachable(blocked, start)
    assert got.visits - got.covered <= MAX_REPETITION * got.reachable
    assert got.turns < anchor.turns


@pytest.mark.parametrize("local", [False, True])
def test_local_double_bridges_keep_a_valid_order_and_never_raise_its_cost(rng, local):
    n = 60
    pts = rng.random((2 * n, 2)) * 50
    cost = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
    seq = np.array([2 * i for i in range(n)], dtype=np.int64)
    before = tour_cost_t(seq, cost)
    got = kicked_t(seq.copy(), cost, 2, 200, 7, 5, local)
    assert got[0] == seq[0]  # the first lane stays first, entered as it was
    assert sorted((got // 2).tolist()) == list(range(n))  # each lane once
    assert tour_cost_t(got, cost) <= before
