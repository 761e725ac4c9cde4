"""Detours to a vertical seam between x fixes (sim_robot/climber/seam_detour.py)."""

from __future__ import annotations

import numpy as np

from app.core.planner.coverage.wall import plate_seams
from sim_robot.climber.seam_detour import SeamDetour, grid_path, seam_cells

D = 0.1


def test_grid_path_takes_straight_steps_round_obstacles_and_the_wall_seam():
    blocked = np.zeros((6, 12), dtype=bool)
    blocked[0:5, 5] = True  # a wall with a gap in the top row
    path = grid_path(blocked, (0, 2), {(0, 8)})
    assert path[-1] == (0, 8)
    assert not any(blocked[c] for c in path)
    prev = (0, 2)
    for r, c in path:  # every step is one row or one column, never both
        dr, dc = abs(r - prev[0]), min(abs(c - prev[1]), 12 - abs(c - prev[1]))
        assert dr + dc == 1
        prev = (r, c)
    # round the wall's seam, column 0 to 11 is one step; the shorter way is taken
    assert grid_path(np.zeros((3, 12), dtype=bool), (1, 0), {(1, 11)}) == [(1, 11)]
    # a goal beyond max_steps is not reached
    assert grid_path(np.zeros((3, 40), dtype=bool), (1, 0), {(1, 20)}, max_steps=10) == []
    assert len(grid_path(np.zeros((3, 40), dtype=bool), (1, 0), {(1, 20)}, 20)) == 20


def test_seam_cells_are_the_vertical_seams_crossing_the_row_in_its_course():
    circ = 8.0  # a wall 8 m round, 4.8 m high: two courses of two plates
    seams = plate_seams(circ / np.pi, 4.8, course_m=2.4, plates=2)
    blocked = np.zeros((48, 80), dtype=bool)
    # the bottom course's seams are at x = 0 and 4 m, the top course's at 2 and 6 m
    assert seam_cells(seams, 0, D, blocked) == {(0, 0), (0, 40)}
    assert seam_cells(seams, 47, D, blocked) == {(47, 20), (47, 60)}
    blocked[0, 40] = True
    assert seam_cells(seams, 0, D, blocked) == {(0, 0)}


def test_a_detour_is_due_after_max_lanes_without_an_x_fix_and_comes_back():
    seams = plate_seams(8.0 / np.pi, 4.8, course_m=2.4, plates=2)
    blocked = np.zeros((48, 80), dtype=bool)
    det = SeamDetour(blocked, seams, D, max_lanes=3, max_steps=15)
    for _ in range(2):
        det.lane_changed()
    assert det.route((0, 10)) == []  # not yet due
    det.lane_changed()
    route = det.route((0, 10))
    # to the bottom course's seam at column 0 (10 steps) and back
    assert route[9] == (0, 0) and route[-1] == (0, 10) and len(route) == 20
    assert det.driven == 1 and det.cells == 20
    # a seam farther than max_steps: none now, tried again at the next lane's end
    assert det.route((0, 20)) == []
    det.fixed()
    assert det.lanes == 0 and det.route((0, 1)) == []
