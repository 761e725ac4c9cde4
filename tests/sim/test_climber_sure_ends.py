"""The lanes' ends judged by the estimate and its covariance (sim_robot/climber/sure_ends.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.core.planner.coverage.wall import Disc, WallSpec, plate_seams
from sim_robot.climber.edge_seek import BOTTOM, TOP
from sim_robot.climber.sure_ends import SureEnds, probe_sigma_y, run_ends
from sim_robot.climber.wall_world import WallWorld


def test_run_ends_are_the_cells_the_route_does_not_cross_straight_up_or_down():
    route = [(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (0, 1), (0, 2), (0, 3), (1, 3)]
    # (1, 0) and (1, 1) are crossed from below to above (or back); the rest are ends,
    # the lane changes and the run along the bottom row included
    assert run_ends(route) == {0, 2, 3, 5, 6, 7, 8}
    assert run_ends([(3, 4)]) == {0}


def test_an_end_is_sure_when_the_belief_lies_k_sigma_inside_the_row():
    ends = SureEnds(rows=10, cell_m=0.1)
    # row 9's centre is 0.95 m: 1.5 cm off with σ 3 cm is sure, with σ 4 cm not
    assert ends.sure(9, 0.935, 0.03)
    assert not ends.sure(9, 0.935, 0.04)
    assert not ends.sure(9, 0.95, 0.06)
    assert ends.edge_side(9) == TOP and ends.edge_side(7) == TOP and ends.edge_side(6) == 0
    assert ends.edge_side(0) == BOTTOM and ends.edge_side(5) == 0
    ends.judged((9, 3), False)
    assert ends.unsure == {(9, 3)}
    ends.judged((9, 3), True)
    ends.judged((9, 3), False)  # once sure, it stays so
    assert ends.unsure == set()


def test_the_probe_points_height_deviation_carries_the_heading_ahead():
    cov = np.zeros((6, 6))
    cov[1, 1] = 0.02**2
    cov[2, 2] = 0.1**2
    # facing up the heading moves the probe sideways only; facing along the row it
    # moves it up and down by lead · σ_θ
    assert probe_sigma_y(cov, math.pi / 2, 0.144) == pytest.approx(0.02)
    assert probe_sigma_y(cov, 0.0, 0.144) == pytest.approx(math.hypot(0.02, 0.0144))


def test_unsure_lane_ends_near_the_edge_seek_it_and_the_wall_is_probed_in_full():
    """A wall 1.2 m round and 3.6 m high of one plate a course: no girth seam, so
    the up lanes climb 3.5 m with no height landmark but the top edge, which the
    camera sees within 8 cm. Without the judgement of the lanes' ends the belief
    reaches the top row too high and top-row cells are missed (7 of 432 on this
    seed); with it the estimate's σ_y says the end is not sure, the crawler seeks
    the edge, and every cell is probed."""
    from sim_robot.climber.inspection import inspect_wall

    d = 1.2 / math.pi
    world = WallWorld(WallSpec(d, 3.6, 0.1, seams=plate_seams(d, 3.6, 3.6, 1)), seed=0)
    opts = {"seed": 0, "localise": "ekf", "gravity": True, "seam_fixes": True,
            "lanes": "vertical"}
    before = inspect_wall(world, (0, 0), sure_ends=False, **opts)
    missed = np.isnan(before.measured) & ~world.blocked
    assert missed.sum() >= 5 and missed[-1].sum() >= 5  # on the top row
    res = inspect_wall(world, (0, 0), **opts)  # the default on the estimate
    assert res.sure_seeks > 0 and res.unsure == ()
    assert res.probed == res.planned == int((~world.blocked).sum())
    assert res.sim_time_s < 1.05 * before.sim_time_s


def test_unsure_ends_far_from_the_edge_drive_to_a_height_landmark_and_back(monkeypatch):
    """The same wall 1.2 m round and 3.6 m high of one plate a course (no girth
    seam), with a nozzle 0.3 m across at 1.4 m: the lanes above it come down 2 m
    from the top edge with no height landmark and end in row 16, 1.65 m from the
    nearest edge, with the estimate unsure of their height. Without the routes to a
    height landmark those ends stay unsure; with them the crawler drives to the
    bottom row (the edge sought there) and back, and judges each end sure."""
    from sim_robot.climber import sure_ends
    from sim_robot.climber.inspection import inspect_wall

    d = 1.2 / math.pi
    spec = WallSpec(d, 3.6, 0.1, nozzles=(Disc(0.6, 1.4, 0.3),),
                    seams=plate_seams(d, 3.6, 3.6, 1))
    world = WallWorld(spec, seed=0)
    opts = {"seed": 0, "localise": "ekf", "gravity": True, "seam_fixes": True,
            "lanes": "vertical"}
    with monkeypatch.context() as m:
        m.setattr(sure_ends.SureEnds, "fix_route", lambda self, cell: ([], []))
        before = inspect_wall(world, (0, 0), **opts)
    far = [c for c in before.unsure if not SureEnds(world.rows, 0.1).edge_side(c[0])]
    assert len(far) >= 3 and {r for r, _ in far} == {16}
    res = inspect_wall(world, (0, 0), **opts)
    assert res.sure_fixes[0] > 0 and res.unsure == ()
    assert res.probed == res.planned == int((~world.blocked).sum())
