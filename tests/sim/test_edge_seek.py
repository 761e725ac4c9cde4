"""The guarded move to the shell's edge before a run along it
(sim_robot/climber/edge_seek.py), alone, in the relay's executor and in the
headless inspection."""

import math

import numpy as np
import pytest

from sim_robot.climber.edge_seek import BOTTOM, TOP, EdgeSeek, SeekConfig


def test_a_stale_edge_row_starts_a_seek_that_ends_on_the_edge():
    s = EdgeSeek(rows=10, cell_m=0.1, height_m=1.0)
    assert not s.before(5, 0.5, 0.55, 0.0)  # not an edge row
    assert s.before(9, 0.5, 0.85, 0.0)  # the top row; the edge never seen
    assert s.side == TOP
    assert s.velocity(0.5, 0.85) == (0.0, pytest.approx(SeekConfig().speed_mps))
    s.fixed(0.6)  # a girth seam: not the edge, the seek goes on
    assert s.active
    s.fixed(1.0 - 0.01)  # the top edge, as the corrected belief puts it
    assert not s.active and s.found == 1 and s.velocity(0.5, 0.95) is None
    s.moved(0.5, 0.95)
    s.moved(0.6, 0.95)  # 0.1 m along the edge: still fresh
    assert not s.before(9, 0.6, 0.95, 0.0)
    assert s.before(9, 0.6, 0.95, 0.05)  # ... unless the height is uncertain
    s.abandon()
    assert s.given_up == 1
    assert s.before(0, 0.6, 0.15, 0.0) and s.side == BOTTOM  # the bottom edge: never seen
    assert s.velocity(0.6, 0.15)[1] < 0


def test_the_guard_gives_up_after_its_travel():
    s = EdgeSeek(rows=10, cell_m=0.1, height_m=1.0, config=SeekConfig(max_travel_m=0.3))
    assert s.before(9, 0.5, 0.5, 0.0)
    assert s.velocity(0.5, 0.79) is not None
    assert s.velocity(0.5, 0.81) is None  # 0.31 m climbed, no edge
    assert s.given_up == 1 and not s.active


def test_travel_across_the_walls_seam_is_not_counted():
    s = EdgeSeek(rows=10, cell_m=0.1, height_m=1.0)
    s.fixed(1.0)
    s.moved(9.99, 0.95)
    s.moved(0.01, 0.95)  # wrapped round the tank: 2 cm, not 9.98 m
    assert not s.before(9, 0.01, 0.95, 0.0)


def test_executor_climbs_to_the_edge_before_the_top_row_then_goes_on():
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    ex = InspectionExecutor(np.zeros((4, 12), bool), 0.1, (0, 0), ClimberParams(),
                            seek_edges=True)
    ex.start(0.0)
    lead = ex.lead
    top = next(i for i, c in enumerate(ex.cells) if c[0] == 3)
    ex.index = top
    r, c = ex.cells[top]
    px, py = (c + 0.5) * 0.1, 0.25  # the probe a row below its target, heading up
    pose = (px, py - lead, math.pi / 2)
    v, w = ex.step(pose, 1.0)
    assert ex.seek.active and v > 0 and abs(w) < 1e-9  # straight up, towards the edge
    ex.edge_fixed(0.4)  # the camera saw the top edge
    v2, _ = ex.step(pose, 1.05)
    assert not ex.seek.active and ex.seek.found == 1
    assert v2 > 0  # on to the target cell above
    plain = InspectionExecutor(np.zeros((4, 12), bool), 0.1, (0, 0), ClimberParams())
    plain.start(0.0)
    plain.index = top
    plain.step(pose, 1.0)
    assert not plain.seek.active  # no camera, no seek


def test_headless_inspection_finds_the_edges_it_seeks():
    from app.core.planner.coverage.wall import WallSpec, plate_seams
    from sim_robot.climber.inspection import inspect_wall
    from sim_robot.climber.wall_world import WallWorld

    circ, height = 3.0, 1.2
    spec = WallSpec(circ / math.pi, height, 0.1, seams=plate_seams(circ / math.pi, height, 0.6, 2))
    world = WallWorld(spec, seed=3)
    res = inspect_wall(world, (0, 0), seed=3, localise="ekf", seam_fixes=True, gravity=True,
                       lanes="vertical")
    started, found, given_up = res.seeks
    assert started >= world.cols // 2  # a lane end at each edge at least every other column
    assert found == started and given_up == 0
    assert res.probed == res.planned
    off = inspect_wall(world, (0, 0), seed=3, localise="ekf", seam_fixes=True, gravity=True,
                       lanes="vertical", seek=False)
    assert off.seeks == (0, 0, 0)
