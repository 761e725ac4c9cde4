"""Bit-parallel JPS (JPS-B): the word scans against the plain byte scans, and
the search on prepared maps against Dijkstra and the plain search."""

import importlib

import numpy as np
import pytest

from app.core.planner import JpsMap, jps
from app.core.planner import _jps_bits as B
from app.core.planner import _jps_kernel as K

from .conftest import dijkstra_length, free_cell, random_grid
from .test_grid_search import _check_path, _plain_jps

# the module (the package exports the function under the same name)
jps_module = importlib.import_module("app.core.planner.jps")

# widths and heights around the 64-bit word boundaries (padded: +2)
SIZES = [1, 2, 5, 61, 62, 63, 64, 65, 66, 126, 127, 129, 200]


def _prepared(blocked):
    m = JpsMap(blocked)
    h, w = blocked.shape
    return m, w + 2


def _compare_all_scans(blocked, goal):
    """Every free cell, every straight and diagonal move: the bit scan finds
    the same jump point and step count as _jps_kernel's byte scan."""
    m, wp = _prepared(blocked)
    gr, gc = goal[0] + 1, goal[1] + 1
    t = gr * wp + gc
    h, w = blocked.shape
    checked = 0
    for r in range(1, h + 1):
        for c in range(1, w + 1):
            cur = r * wp + c
            if m.gp[cur]:
                continue
            for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
                d = dr * wp + dc
                side = 1 if dr else wp
                want = K._jump_straight(m.gp, cur, d, side, t)
                p = B._straight(m.rows, m.cols, r, c, dr, dc, gr, gc)
                if p < 0:
                    got = (-1, 0)
                elif dr == 0:
                    got = (r * wp + p, abs(p - c))
                else:
                    got = (p * wp + c, abs(p - r))
                assert got == tuple(int(x) for x in want), ((r - 1, c - 1), (dr, dc), goal)
                checked += 1
            for dr, dc in ((-1, -1), (-1, 1), (1, -1), (1, 1)):
                want = K._jump_diag(m.gp, wp, cur, dr * wp, dc, t)
                k = B._diag(m.gp, m.rows, m.cols, wp, r, c, dr, dc, gr, gc)
                got = (cur + k * (dr * wp + dc), k) if k else (-1, 0)
                assert got == tuple(int(x) for x in want), ((r - 1, c - 1), (dr, dc), goal)
    return checked


def test_pack_lines_bit_layout():
    g = np.zeros((2, 70), dtype=np.uint8)
    g[0, [0, 63, 64, 69]] = 1
    words = B.pack_lines(g)
    assert words.shape == (2, 2) and words.dtype == np.uint64
    assert int(words[0, 0]) == (1 | (1 << 63))
    # bit 0 and bit 5 of the second word are cells 64 and 69; 70..127 count as blocked
    assert int(words[0, 1]) & 0b100001 == 0b100001
    assert int(words[0, 1]) >> 6 == (1 << 58) - 1
    assert int(words[1, 0]) == 0


@pytest.mark.parametrize("density", [0.0, 0.1, 0.3, 0.5])
def test_bit_scans_equal_plain_scans_on_random_grids(rng, density):
    checked = 0
    for _ in range(6):
        h = SIZES[int(rng.integers(len(SIZES)))]
        w = SIZES[int(rng.integers(len(SIZES)))]
        if h * w > 6000:
            h = min(h, 30)
        blocked = random_grid(rng, h, w, density)
        if blocked.all():
            continue
        checked += _compare_all_scans(blocked, free_cell(rng, blocked))
    assert checked > 0


def test_bit_scans_across_word_boundaries():
    """Stops placed exactly at and beside positions 63/64/65 of a line (the
    padded position is one more), in both scan directions."""
    for wall in (61, 62, 63, 64, 65, 126, 127):
        blocked = np.zeros((5, 131), bool)
        blocked[1, wall] = True  # a side obstacle: forced neighbours beside it
        blocked[3, wall + 2] = True
        blocked.T[wall, 4] = True
        _compare_all_scans(blocked, (0, 130))
        _compare_all_scans(blocked, (2, wall + 1))
        _compare_all_scans(blocked.T.copy(), (130, 0))


def test_search_equals_dijkstra_and_plain_search(rng):
    solved = 0
    for trial in range(200):
        h = SIZES[int(rng.integers(len(SIZES)))]
        w = int(rng.integers(1, 140)) if trial % 2 else SIZES[int(rng.integers(len(SIZES)))]
        if h * w > 4000:
            h = max(1, 4000 // w)
        blocked = random_grid(rng, h, w, [0.05, 0.2, 0.35][trial % 3])
        if (~blocked).sum() < 2:
            continue
        m = JpsMap(blocked)
        s, g = free_cell(rng, blocked), free_cell(rng, blocked)
        res = jps(m, s, g)
        cells, length, _ = _plain_jps(blocked, s, g)
        if trial % 4 == 0:
            want = dijkstra_length(blocked, s, g)
            assert (want is None) == (res.length is None)
            if want is not None:
                assert res.length == pytest.approx(want, rel=1e-9)
        if length is None:
            assert res.length is None and res.cells == [] and res.expanded > 0
            continue
        solved += 1
        assert res.length == pytest.approx(length, rel=1e-9), (trial, s, g)
        _check_path(blocked, res, s, g)
    assert solved > 100


def test_no_corner_cutting_at_a_word_boundary():
    # padded column 64 is map column 63: two blocks touching at a corner there
    blocked = np.zeros((6, 130), bool)
    blocked[0:3, 64] = True
    blocked[3:6, 63] = True
    res = jps(JpsMap(blocked), (2, 63), (3, 64))
    assert res.length is None
    blocked[3, 63] = False  # opening one side cell allows the way round it
    res = jps(JpsMap(blocked), (2, 63), (3, 64))
    assert res.cells == [(2, 63), (3, 63), (3, 64)] and res.length == 2.0


def test_long_straight_runs_through_many_words():
    blocked = np.zeros((3, 1000), bool)
    res = jps(JpsMap(blocked), (1, 0), (1, 999))
    assert res.length == 999.0 and len(res.cells) == 1000 and res.expanded <= 3
    tall = np.zeros((1000, 3), bool)
    res = jps(JpsMap(tall), (999, 1), (0, 1))
    assert res.length == 999.0 and res.expanded <= 3


def test_small_heap_grows_and_results_hold(rng):
    blocked = random_grid(rng, 80, 80, 0.25)
    m = JpsMap(blocked)
    pairs = [(free_cell(rng, blocked), free_cell(rng, blocked)) for _ in range(10)]
    want = [jps(m, s, g) for s, g in pairs]
    jps_module._WS._heap(2)
    got = [jps(m, s, g) for s, g in pairs]
    assert jps_module._WS.heap_n > 2
    assert [(r.cells, r.length) for r in got] == [(r.cells, r.length) for r in want]


def test_generation_stamp_wraps_without_stale_records(rng):
    blocked = random_grid(rng, 40, 40, 0.2)
    m = JpsMap(blocked)
    s, g = free_cell(rng, blocked), free_cell(rng, blocked)
    want = jps(m, s, g)
    jps_module._WS.gen = 2**B.GEN_BITS - 2
    for _ in range(3):
        res = jps(m, s, g)
        assert (res.cells, res.length) == (want.cells, want.length)
    assert jps_module._WS.gen < 5


def test_plain_array_cache_sees_edits_and_copies():
    blocked = np.zeros((10, 70), bool)
    assert jps(blocked, (0, 0), (0, 69)).length == 69.0
    blocked[:, 35] = True  # edited in place: same object, new content
    assert jps(blocked, (0, 0), (0, 69)).length is None
    m = JpsMap(blocked)
    blocked[:, 35] = False  # the prepared map keeps its own copy
    assert jps(m, (0, 0), (0, 69)).length is None
    assert jps(blocked, (0, 0), (0, 69)).length == 69.0
