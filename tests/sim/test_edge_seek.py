"""The guarded move to the shell's edge when an edge row is reached and the
camera has not seen the edge (sim_robot/climber/edge_seek.py), alone, in the
relay's executor and in the headless inspection."""

import math

import numpy as np
import pytest

from sim_robot.climber.edge_seek import BOTTOM, TOP, EdgeSeek, SeekConfig


def test_an_edge_row_reached_with_its_edge_unseen_starts_a_seek_that_ends_on_it():
    s = EdgeSeek(rows=10, height_m=1.0)
    assert not s.arrived(5, 0.55)  # not an edge row
    assert s.arrived(9, 0.95)  # the top row, and its edge never seen
    assert s.side == TOP
    assert s.velocity(0.95) == (0.0, pytest.approx(SeekConfig().speed_mps))
    s.fixed(0.6)  # a girth seam: not the edge, the seek goes on
    assert s.active
    s.fixed(1.0 - 0.01)  # the top edge, as the corrected belief puts it
    assert not s.active and s.found == 1 and s.velocity(0.97) is None
    s.moved(0.5, 0.95)
    s.moved(0.55, 0.95)  # 5 cm along the edge since it was seen
    assert not s.arrived(9, 0.95)
    s.moved(0.65, 0.95)  # 15 cm: the camera should have seen it again by now
    assert s.arrived(9, 0.95)
    s.abandon()
    assert s.given_up == 1
    assert s.arrived(0, 0.05) and s.side == BOTTOM  # the bottom edge: never seen
    assert s.velocity(0.05)[1] < 0


def test_the_guard_gives_up_after_its_travel():
    s = EdgeSeek(rows=10, height_m=1.0, config=SeekConfig(max_travel_m=0.3))
    assert s.arrived(9, 0.5)
    assert s.velocity(0.79) is not None
    assert s.velocity(0.81) is None  # 0.31 m climbed, no edge
    assert s.given_up == 1 and not s.active


def test_travel_across_the_walls_seam_is_not_counted():
    s = EdgeSeek(rows=10, height_m=1.0)
    s.fixed(1.0)
    s.moved(9.99, 0.95)
    s.moved(0.01, 0.95)  # wrapped round the tank: 2 cm, not 9.98 m
    assert not s.arrived(9, 0.95)


def test_executor_climbs_to_an_unseen_edge_then_takes_the_cell_again():
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    ex = InspectionExecutor(np.zeros((4, 12), bool), 0.1, (0, 0), ClimberParams(),
                            seek_edges=True)
    ex.start(0.0)
    lead = ex.lead
    top = next(i for i, c in enumerate(ex.cells) if c[0] == 3)
    ex.index = top
    r, c = ex.cells[top]
    px, py = (c + 0.5) * 0.1, 0.35  # the probe on its top-row target, as the belief puts it
    pose = (px, py - lead, math.pi / 2)
    v, w = ex.step(pose, 1.0)
    assert ex.seek.active and ex.index == top  # the edge unseen: no further yet
    assert v > 0 and abs(w) < 1e-9  # straight up, towards the edge
    ex.edge_fixed(0.4)  # the camera saw the top edge ...
    pose = (px, 0.38 - lead, math.pi / 2)  # ... and the belief moved 3 cm past the centre
    v2, _ = ex.step(pose, 1.05)
    assert not ex.seek.active and ex.seek.found == 1
    assert ex.index == top and v2 < 0  # back onto the cell, on the corrected belief
    pose = (px, py - lead, math.pi / 2)
    ex.step(pose, 1.1)
    assert ex.index == top + 1 and not ex.seek.active  # reached, the edge seen: on
    plain = InspectionExecutor(np.zeros((4, 12), bool), 0.1, (0, 0), ClimberParams())
    plain.start(0.0)
    plain.index = top
    plain.step((px, py - lead, math.pi / 2), 1.0)
    assert not plain.seek.active and plain.index == top + 1  # no camera, no seek


def test_headless_inspection_seeks_the_top_edge_its_belief_has_lost():
    """A 2 m × 4 m wall without seams: only the shell's edges fix the height, and
    lanes 4 m long drift past the camera's 8 cm. Without the seek part of the top
    row is missed; with it every seek finds the edge and every cell is probed."""
    from app.core.planner.coverage.wall import WallSpec
    from sim_robot.climber.inspection import inspect_wall
    from sim_robot.climber.wall_world import WallWorld

    world = WallWorld(WallSpec(2.0 / math.pi, 4.0, 0.1), seed=3)
    kw = dict(seed=3, localise="ekf", seam_fixes=True, gravity=True, lanes="vertical",
              turns_in_place=False, x_fix_lanes=0)
    off = inspect_wall(world, (0, 0), **kw)  # the default: no seek
    assert off.seeks == (0, 0, 0)
    assert np.isnan(off.measured[-1]).any()  # top-row cells never probed
    res = inspect_wall(world, (0, 0), seek=True, **kw)
    started, found, given_up = res.seeks
    assert started >= 1 and found == started and given_up == 0
    assert res.probed == res.planned


def test_a_contact_ends_the_executors_edge_seek():
    """Through the link (the 8 m × 2.4 m wall with the stair, seed 2, traced) the seek
    down to an unseen bottom edge pressed a corner against it; each contact renewed the
    seek's time, so it pushed on for 2400 s while the executor gave its cells up one
    after another. A contact now ends the seek (given up), and the recoil is made."""
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    ex = InspectionExecutor(np.zeros((4, 12), bool), 0.1, (0, 0), ClimberParams(),
                            seek_edges=True)
    ex.start(0.0)
    top = next(i for i, c in enumerate(ex.cells) if c[0] == 3)
    ex.index = top
    px = (ex.cells[top][1] + 0.5) * 0.1
    pose = (px, 0.35 - ex.lead, math.pi / 2)
    ex.step(pose, 1.0)
    assert ex.seek.active
    ex.touched(2.0, 0.05)  # pressed against the edge, driving up
    assert not ex.seek.active and ex.seek.given_up == 1
    v, _ = ex.step(pose, 2.1)
    assert v < 0 and ex.moves.queue and ex.moves.queue[0][0] == "recoil"  # backing away
