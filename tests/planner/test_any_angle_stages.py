"""The optimised A*'s inner stages (app/core/planner/_chord.py, _vg_repair.py):
the chord corridor's pins and octile lengths, the repair's visibility-graph
search with its turn rule against an independent Dijkstra, and the skip of the
second corridor when the repair has proved the path shortest."""

import math
from pathlib import Path

import numpy as np
import pytest

import app.core.planner.optimised_astar as OA
from app.core.planner import _chord as C
from app.core.planner import _edge_kernels as E
from app.core.planner import _vg_repair as V
from app.core.planner import any_angle

from .test_any_angle import _check_path, shortest_length


def test_pins_are_the_free_cells_nearest_the_chord_points():
    g = (np.random.default_rng(3).random((90, 120)) < 0.3).astype(np.uint8)
    s, t, k = (4, 7), (85, 110), 4
    got = C.pins(g, s[0], s[1], t[0], t[1], k, 2)
    want = []
    for i in range(1, k):
        r = s[0] + (t[0] - s[0]) * i / k
        c = s[1] + (t[1] - s[1]) * i / k
        near = [(math.hypot(rr - r, cc - c), rr, cc)
                for rr in range(max(0, int(r) - 2), int(r) + 3)
                for cc in range(max(0, int(c) - 2), int(c) + 3)
                if rr < g.shape[0] and cc < g.shape[1] and not g[rr, cc]]
        if near:
            want.append(min(near)[1:])
    assert [tuple(p) for p in got.tolist()] == want
    # a chord point walled in for two cells around gets no pin
    g2 = np.zeros((40, 40), dtype=np.uint8)
    g2[17:24, 17:24] = 1
    assert len(C.pins(g2, 0, 0, 40, 40, 2, 2)) == 0


def test_octile_length_counts_straight_and_diagonal_steps():
    cells = np.array([(0, 0), (0, 3), (2, 5), (2, 5), (5, 4)], dtype=np.int64)
    # 3 straight; 2 diagonal; none; 2 straight + 1 diagonal
    assert C.octile_length(cells) == pytest.approx(5 + 3 * math.sqrt(2))
    assert C.octile_between((0, 0), (3, 7)) == pytest.approx(4 + 3 * math.sqrt(2))


@pytest.mark.parametrize("seed", [2, 5])
def test_visibility_graph_search_finds_the_true_shortest_path(seed):
    """The repair's search over every convex corner (taut edges, and a turn
    only round the corner's blocked cell) against Dijkstra over the full
    visibility graph of tests/planner/test_any_angle.py."""
    rng = np.random.default_rng(seed)
    checked = 0
    for _ in range(6):
        g = rng.random((11, 14)) < 0.25
        g8 = g.astype(np.uint8)
        free = np.argwhere(~g)
        a, b = free[rng.choice(len(free), 2, replace=False)]
        cum = V.corner_rows(g8)
        ends = [2 * np.asarray(a, dtype=np.int64) + 1, 2 * np.asarray(b, dtype=np.int64) + 1]
        nodes = V.ellipse_nodes(g8, cum, ends[0], ends[1], 1e6, 10 ** 6)
        best = shortest_length(g, tuple(a), tuple(b))
        path = V.vg_search(g8, nodes, 1e6)
        if best is None:
            assert len(path) == 0
            continue
        assert E.path_len(path) / 2.0 == pytest.approx(best, abs=1e-9)
        checked += 1
    assert checked >= 4


def test_repair_reports_a_window_spanning_the_whole_path():
    g = (np.random.default_rng(1).random((80, 80)) < 0.2).astype(np.uint8)
    cum = V.corner_rows(g)
    pts = 2 * np.array([(8, 3), (20, 20), (20, 50), (37, 70)], dtype=np.int64) + 1
    pts = np.array([p for p in pts if g[p[0] // 2, p[1] // 2] == 0])
    assert len(pts) >= 3
    _, whole = V.repair_pass(g, cum, pts, math.inf, 10 ** 6, 0.0, 0.5)
    assert whole
    _, whole = V.repair_pass(g, cum, pts, 10.0, 10 ** 6, 0.0, 0.5)  # short windows only
    assert not whole
    _, whole = V.repair_pass(g, cum, pts, math.inf, 5, 0.0, 0.5)  # too many corners: left
    assert not whole


def test_no_second_corridor_when_the_repair_proved_the_path_shortest(monkeypatch):
    """A chord-corridor path 4.8 % longer than the straight line (over the
    second corridor's trigger) whose whole-path repair window was searched:
    it is the shortest path, so JPS's corridor is not planned as well."""
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[2] / "bench"))
    g = (np.random.default_rng(1).random((80, 80)) < 0.2).astype(np.uint8)
    s, t = (8, 3), (37, 70)
    calls = []
    monkeypatch.setattr(OA, "_second_opinion", lambda *a, **k: calls.append(a) or (a[3], 0, False))
    res = any_angle(g, s, t)
    assert res.corridor == "chord"
    assert res.length > OA.ALT_TRIGGER * math.hypot(t[0] - s[0], t[1] - s[1])
    assert calls == []
    _check_path(g.astype(bool), s, t, res)
    from _visgraph import convex_corners, true_shortest

    best = true_shortest(g, s, t, np.array(convex_corners(g), dtype=np.int64).reshape(-1, 2),
                         res.length)
    assert res.length == pytest.approx(best, abs=1e-9)


def test_the_two_corridors_paths_are_crossed_over_where_they_part(monkeypatch):
    """Where the chord corridor's and JPS's paths share vertices, each stretch
    between two shared vertices is taken from whichever path is shorter
    there: on this 20 % random map the result is shorter than both paths
    (the shorter of the two, kept before, is 0.07 % longer)."""
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[2] / "bench"))
    from _visgraph import convex_corners, true_shortest

    monkeypatch.setattr(OA, "CERT_NODES", 0)  # no certificate: the second opinion decides
    g = (np.random.default_rng(16).random((200, 200)) < 0.2).astype(np.uint8)
    s, t = (189, 96), (74, 44)
    res = any_angle(g, s, t)
    _check_path(g.astype(bool), s, t, res)
    best = true_shortest(g, s, t, np.array(convex_corners(g), dtype=np.int64).reshape(-1, 2),
                         res.length)
    assert best - 1e-9 <= res.length <= 1.01 * best
    monkeypatch.setattr(OA, "_crossover",
                        lambda a, b: b if E.path_len(b) < E.path_len(a) else a)
    either = any_angle(g, s, t)
    assert res.length < either.length - 0.05


@pytest.mark.parametrize("seed", [3, 7])
def test_certificate_finds_the_shortest_path_or_proves_the_path_close(seed):
    """``certify`` on small random maps against Dijkstra over the full
    visibility graph: a staircase path through the free cells (A*'s cells,
    far longer than the shortest) is replaced by the shortest path; the
    shortest path itself, and a path within the ratio of it, are proved and
    kept; a too small corner limit leaves the path unsearched."""
    from app.core.planner import astar

    rng = np.random.default_rng(seed)
    checked = 0
    for _ in range(8):
        g = rng.random((14, 18)) < 0.25
        g8 = g.astype(np.uint8)
        free = np.argwhere(~g)
        a, b = (tuple(int(v) for v in p) for p in free[rng.choice(len(free), 2, replace=False)])
        best = shortest_length(g, a, b)
        cells = astar(g8, a, b)
        if best is None or not cells.found or best < 3.0:
            continue
        cum = V.corner_rows(g8)
        stairs = 2 * np.asarray(cells.cells, dtype=np.int64) + 1
        if E.path_len(stairs) / 2.0 <= 1.01 * best:
            continue
        got, status = V.certify(g8, cum, stairs, 1.01, 10 ** 6)
        assert status == 2
        assert E.path_len(got) / 2.0 == pytest.approx(best, abs=1e-9)
        assert all(E.seg_free(g8, *p, *q) for p, q in zip(got[:-1], got[1:], strict=True))
        again, status = V.certify(g8, cum, got, 1.01, 10 ** 6)
        assert status == 1 and np.array_equal(again, got)
        # the shortest path with a detour of under 1 %: proved, kept
        loose, status = V.certify(g8, cum, got, 1.0 + 0.999 * (E.path_len(stairs) /
                                                             E.path_len(got) - 1.0), 10 ** 6)
        assert status == 1 and np.array_equal(loose, got)
        kept, status = V.certify(g8, cum, stairs, 1.01, 0)
        assert status == 0 and np.array_equal(kept, stairs)
        checked += 1
    assert checked >= 3


def test_certificate_stage_alone_mends_a_chord_path_a_lane_off(monkeypatch):
    """The 20 % random map where the chord corridor's path is 1.07 % longer
    than the shortest (tests/planner/test_any_angle.py): with the second
    opinion left out, the certificate stage finds the shortest path; with
    neither, the path stays 1.07 % long."""
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[2] / "bench"))
    from _visgraph import convex_corners, true_shortest

    from .test_any_angle import _check_path

    g = (np.random.default_rng(1).random((200, 200)) < 0.2).astype(np.uint8)
    s, t = (29, 34), (121, 140)
    calls = []
    monkeypatch.setattr(OA, "_second_opinion", lambda *a, **k: calls.append(a) or (a[3], 0, False))
    res = any_angle(g, s, t)
    best = true_shortest(g, s, t, np.array(convex_corners(g), dtype=np.int64).reshape(-1, 2),
                         res.length)
    _check_path(g.astype(bool), s, t, res)
    assert res.corridor == "visibility"
    assert res.length == pytest.approx(best, abs=1e-9)
    monkeypatch.setattr(OA, "CERT_NODES", 0)  # the ellipse "too large": not searched
    assert any_angle(g, s, t).length > 1.01 * best
    assert len(calls) == 2  # the (left out) second opinion was asked both times


def test_second_opinion_on_a_long_query_is_pinned(monkeypatch):
    """On a query over two ``ALT_STEP`` long the second opinion's JPS runs
    between pins about every ``ALT_STEP`` cells, not once from start to goal
    (3–10 ms on random512's long queries); its path is valid and the result
    no longer than the chord path alone."""
    from .test_any_angle import _check_path

    g = (np.random.default_rng(4).random((300, 300)) < 0.2).astype(np.uint8)
    s, t = (5, 3), (292, 290)
    g[s] = g[t] = 0
    monkeypatch.setattr(OA, "CERT_NODES", 0)
    pieces = []
    real = OA._bits_search

    def spy(m, a, b):
        pieces.append(math.dist(a, b))
        return real(m, a, b)

    monkeypatch.setattr(C, "_bits_search", spy)
    monkeypatch.setattr(OA, "_bits_search", spy)
    calls = []
    second = OA._second_opinion
    monkeypatch.setattr(OA, "_second_opinion",
                        lambda *a, **k: calls.append(len(pieces)) or second(*a, **k))
    res = any_angle(g, s, t)
    assert calls, "the query did not call for a second opinion"
    alt = pieces[calls[0]:]
    d = math.dist(s, t)
    assert len(alt) == int(d // OA.ALT_STEP)
    assert max(alt) < d / len(alt) + 2 * math.sqrt(2) * OA.PIN_RADIUS + 1 < 2 * OA.ALT_STEP
    _check_path(g.astype(bool), s, t, res)
    monkeypatch.setattr(OA, "ALT_TRIGGER", math.inf)
    assert res.length <= any_angle(g, s, t).length + 1e-9


@pytest.mark.parametrize("seed", [2, 5])
def test_bucketed_search_finds_the_same_shortest_path(seed):
    """The visibility-graph search with its nodes in buckets against Dijkstra
    over the full visibility graph (a loose bound) and against the scan over
    every node under tight bounds, as the certificate sets them (the same
    length found, or none under both)."""
    rng = np.random.default_rng(seed)
    checked = tight = 0
    for _ in range(8):
        g = rng.random((16, 20)) < 0.25
        g8 = g.astype(np.uint8)
        free = np.argwhere(~g)
        a, b = free[rng.choice(len(free), 2, replace=False)]
        cum = V.corner_rows(g8)
        ends = [2 * np.asarray(a, dtype=np.int64) + 1, 2 * np.asarray(b, dtype=np.int64) + 1]
        nodes = V.ellipse_nodes(g8, cum, ends[0], ends[1], 1e6, 10 ** 6)
        best = shortest_length(g, tuple(a), tuple(b))
        path = V.vg_search_buckets(g8, nodes, 1e6, 6)
        if best is None:
            assert len(path) == 0
            continue
        assert E.path_len(path) / 2.0 == pytest.approx(best, abs=1e-9)
        assert all(E.seg_free(g8, *p, *q) for p, q in zip(path[:-1], path[1:], strict=True))
        checked += 1
        for slack in (0.0, 1e-3, 0.01):  # bound just under, at and over the shortest
            for bound in (2 * best * (1 + slack), 2 * best * (1 - slack) - 1e-6):
                sub = V.ellipse_nodes(g8, cum, ends[0], ends[1], bound, 10 ** 6)
                want = V.vg_search(g8, sub, bound)
                got = V.vg_search_buckets(g8, sub, bound, 6)
                assert len(got) == len(want) == 0 or (
                    E.path_len(got) == pytest.approx(E.path_len(want), abs=1e-9))
                tight += len(want) == 0
    assert checked >= 5 and tight >= 5
