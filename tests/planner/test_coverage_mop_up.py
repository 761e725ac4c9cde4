"""The mop-up route: back to the cells a sweep's own record missed."""

import numpy as np
import pytest

from app.core.planner.coverage import mop_up_route


def _valid(blocked, start, route, wrap=False):
    h, w = blocked.shape
    prev = start
    for r, c in route:
        assert not blocked[r, c]
        dr, dc = r - prev[0], c - prev[1]
        if wrap and abs(dc) == w - 1:
            dc = -int(np.sign(dc))
        assert max(abs(dr), abs(dc)) == 1, (prev, (r, c))
        if dr and dc:  # no corner cutting
            assert not blocked[prev[0] + dr, prev[1]]
            assert not blocked[prev[0], (prev[1] + dc) % w]
        prev = (r, c)


def test_route_visits_every_reachable_missed_cell_nearest_first():
    blocked = np.zeros((8, 12), bool)
    blocked[:6, 5] = True  # a wall with a gap at the top
    blocked[7, 10:] = True
    blocked[6, 10] = blocked[6, 11] = True  # (7, 11) is boxed in: unreachable
    missed = np.zeros_like(blocked)
    for cell in [(0, 1), (0, 8), (3, 3), (7, 11), (2, 5)]:  # (2, 5) is an obstacle
        missed[cell] = True
    route = mop_up_route(blocked, (0, 0), missed)
    _valid(blocked, (0, 0), route)
    assert {(0, 1), (0, 8), (3, 3)} <= set(route)
    assert (7, 11) not in route and (2, 5) not in route
    # nearest first: (0, 1) next door, then (3, 3), then round the wall to (0, 8)
    order = [c for c in route if missed[c]]
    assert order == [(0, 1), (3, 3), (0, 8)]
    assert route[-1] == (0, 8)


def test_route_crosses_the_seam_when_that_is_shorter():
    blocked = np.zeros((4, 20), bool)
    missed = np.zeros_like(blocked)
    missed[1, 18] = True
    route = mop_up_route(blocked, (1, 1), missed, wrap=True)
    _valid(blocked, (1, 1), route, wrap=True)
    assert route == [(1, 0), (1, 19), (1, 18)]
    assert len(mop_up_route(blocked, (1, 1), missed)) == 17  # no wrap: the long way


def test_nothing_missed_and_bad_input():
    blocked = np.zeros((3, 3), bool)
    assert mop_up_route(blocked, (0, 0), np.zeros_like(blocked)) == []
    only_start = np.zeros_like(blocked)
    only_start[0, 0] = True
    assert mop_up_route(blocked, (0, 0), only_start) == []
    with pytest.raises(ValueError, match="shape"):
        mop_up_route(blocked, (0, 0), np.zeros((2, 2), bool))
    blocked[1, 1] = True
    with pytest.raises(ValueError, match="obstacle"):
        mop_up_route(blocked, (1, 1), np.zeros_like(blocked))
