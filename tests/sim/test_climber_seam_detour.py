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


def _drive(ex, on_target=None):
    """Teleport the probe onto each target in turn until the inspection ends; the
    targets in the order driven."""
    from app.comm.wall_protocol import CoverageState

    t, seen = 0.0, []
    for _ in range(20 * len(ex.cells) + 100):
        if ex.state != CoverageState.RUNNING:
            break
        target = ex.cells[min(ex.index, len(ex.cells) - 1)]
        if not seen or seen[-1] != target:
            seen.append(target)
            if on_target is not None:
                on_target(target)
        pose = ((target[1] + 0.5) * D - ex.lead, (target[0] + 0.5) * D, 0.0)
        ex.reading(pose, 9.0)
        ex.step(pose, t)
        t += 0.05
    return seen


def test_the_relays_executor_detours_to_a_seam_and_back_between_x_fixes():
    from app.comm.wall_protocol import CoverageState
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    # 4 m round, 1.2 m high, one course of two plates: vertical seams at x = 0 and 2 m
    seams = plate_seams(4.0 / np.pi, 1.2, course_m=1.2, plates=2)
    blocked = np.zeros((12, 40), dtype=bool)
    det = SeamDetour(blocked, seams, D, max_lanes=4, max_steps=15)
    ex = InspectionExecutor(blocked, D, (0, 5), ClimberParams(), detour=det)
    plan = list(ex.cells)
    ex.start(0.0)
    seen = _drive(ex)
    assert ex.state == CoverageState.DONE and ex.covered.sum() == ex.reachable
    assert det.driven >= 3 and len(ex.cells) == len(plan) + det.cells
    # each detour leaves the plan at a lane's end, runs along that row to a seam's column
    # and comes back to the same cell before the plan goes on
    rest = list(seen)
    for cell in plan:
        k = rest.index(cell)
        extra, rest = rest[:k], rest[k + 1:]
        if extra:
            assert {c[0] for c in extra} == {extra[0][0]}  # along one row
            assert {0, 20} & {c[1] for c in extra}  # to a seam's column
    # a new start drives the plan as planned again, without the old detours
    ex.start(100.0)
    assert ex.cells == plan and ex.planned == len(plan)


def _relay_executor(max_lanes: int):
    """The relay's executor on a 4 m x 1.2 m wall with detours due every ``max_lanes``."""
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    seams = plate_seams(4.0 / np.pi, 1.2, course_m=1.2, plates=2)
    blocked = np.zeros((12, 40), dtype=bool)
    det = SeamDetour(blocked, seams, D, max_lanes=max_lanes, max_steps=15)
    ex = InspectionExecutor(blocked, D, (0, 5), ClimberParams(), detour=det)
    ex.start(0.0)
    return ex, det


def test_x_fixes_reported_by_the_relay_make_the_detours_unneeded():
    ex, det = _relay_executor(4)
    _drive(ex, on_target=lambda cell: ex.x_fixed())  # a fix on every cell
    assert det.driven == 0 and ex.covered.sum() == ex.reachable


def test_a_detour_is_due_sooner_when_the_x_fixes_show_a_fast_drift():
    # traced through the link on the tank: the belief's x drifted 0.5 cm a lane, one way,
    # so the tenth lane ran 5 cm off and each fix found ten lanes not surely in their
    # columns (sure_lanes); a quarter of a cell is the drift let grow before a fix
    seams = plate_seams(8.0 / np.pi, 4.8, course_m=2.4, plates=2)
    blocked = np.zeros((48, 80), dtype=bool)
    det = SeamDetour(blocked, seams, D, max_lanes=10, max_steps=15)
    assert det.rate_m is None and det.due_lanes == 10
    for _ in range(10):
        det.lane_changed()
    det.fixed(-0.05)  # 5 cm after 10 lanes
    assert det.rate_m == 0.005 and det.due_lanes == 5
    det.fixed(0.03)  # the fixes that follow on the same seam measure no drift
    assert det.due_lanes == 5
    for _ in range(4):
        det.lane_changed()
    assert det.route((0, 10)) == []  # not yet due
    det.lane_changed()
    assert det.route((0, 10))[-1] == (0, 10)
    # a slow drift (and a fix without a correction known) leaves max_lanes; a very fast
    # one a detour every MIN_DUE_LANES lane changes, not at every one
    slow = SeamDetour(blocked, seams, D, max_lanes=10)
    for _ in range(10):
        slow.lane_changed()
    slow.fixed(0.005)
    slow.fixed()
    assert slow.due_lanes == 10
    fast = SeamDetour(blocked, seams, D, max_lanes=10)
    fast.lane_changed()
    fast.fixed(0.08)
    assert fast.due_lanes == 2


def test_the_relays_executor_hands_the_fixes_correction_to_the_detours():
    ex, det = _relay_executor(8)
    for _ in range(8):
        det.lane_changed()
    ex.x_fixed(-0.04, 0.01)  # 4 cm after 8 lanes: 0.5 cm a lane
    assert det.lanes == 0 and det.due_lanes == 5


def test_a_detour_goes_to_a_seam_on_another_row_when_none_of_its_own_row_is_near():
    """Traced through the link on the tank: in the wedge between the stair band and the
    top edge the seams crossing a lane's end row were 56-78 cells along it, beyond
    ``max_steps``, while another course's seam passed a few rows away; no detour was
    driven for 5 900 s of simulated time. With ``any_row`` a detour goes to the nearest
    cell any vertical seam crosses, on any row, and back the same way."""
    # 8 m round, 4.8 m high, two courses of two plates: the bottom course's seams at
    # columns 0 and 40 (rows 0-23), the top course's at columns 20 and 60 (rows 24-47)
    seams = plate_seams(8.0 / np.pi, 4.8, course_m=2.4, plates=2)
    blocked = np.zeros((48, 80), dtype=bool)
    det = SeamDetour(blocked, seams, D, max_lanes=1, max_steps=15)
    det.lane_changed()
    assert seam_cells(seams, 21, D, blocked) == {(21, 0), (21, 40)}  # 20 cells along
    assert det.route((21, 20)) == []  # on its own row only (the default): none near
    det.any_row = True
    route = det.route((21, 20))
    # up the lane's column to the top course's seam (row 24, column 20) and back down
    assert route == [(22, 20), (23, 20), (24, 20), (23, 20), (22, 20), (21, 20)]
    assert det.driven == 1 and det.cells == 6
    # something over the seam's lower cells: up the lane's column, then along its row to
    # the seam (fewest steps, of them the way with one turn), and back the same way
    blocked[22:27, 20] = True
    det = SeamDetour(blocked, seams, D, max_lanes=1, max_steps=15)
    det.any_row = True
    det.lane_changed()
    route = det.route((21, 18))
    there = [*((r, 18) for r in range(22, 28)), (27, 19), (27, 20)]
    assert route == [*there, *there[-2::-1], (21, 18)]
    # with a reach of 7 steps the seam is out of reach: none now, again later
    det.max_steps = 7
    assert det.route((21, 18)) == []


def test_the_way_to_a_seam_takes_the_fewest_turns_of_the_shortest_ways():
    """Along an obstacle's diagonal edge (the stair band) a fewest-step search may
    return a staircase, a turn in place at every cell; of the shortest ways the one
    with the fewest turns is taken."""
    from sim_robot.climber.seam_detour import straight_path

    rows, cols = 20, 40
    r, c = np.mgrid[0:rows, 0:cols]
    blocked = (c - r >= 10) & (c - r < 20)  # a band rising to the right
    start, goal = (15, 24), (5, 14)  # both just above-left of it
    path = straight_path(blocked, start, {goal})
    assert len(path) == len(grid_path(blocked, start, {goal})) == 20
    steps = [(b[0] - a[0], b[1] - a[1]) for a, b in zip([start, *path], path, strict=False)]
    assert sum(a != b for a, b in zip(steps, steps[1:], strict=False)) == 1
    assert not any(blocked[p] for p in path)
