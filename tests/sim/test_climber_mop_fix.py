"""The relay executor's mop-up fixes its belief first when the estimate's own σ says it
cannot find the next target (sim_robot/climber/executor_route.py, ``_fix_first``): a route
to a height landmark (an edge row here) and back when σ_y is beyond half a cell, to a
vertical seam and back when σ_x is beyond a cell; none when σ is small."""

from __future__ import annotations

import numpy as np
import pytest

from app.core.planner.coverage.wall import Band
from sim_robot.climber.executor import InspectionExecutor
from sim_robot.climber.kinematics import ClimberParams
from sim_robot.climber.seam_detour import SeamDetour

D = 0.1
SEAM_COL = 1  # a vertical seam down the middle of this column


def _in_mop_up(sigma_x: float, sigma_y: float):
    """An executor at the end of its sweep of an 8 × 6 wall (the sweep cut short to end
    mid-lane, away from the edge rows), one cell missed in the middle, (4, 3), and a step
    with a covariance of these σ: its route after that step, and the sweep's last cell."""
    blocked = np.zeros((8, 6), bool)
    seams = (Band((SEAM_COL + 0.5) * D, 0.0, (SEAM_COL + 0.5) * D, 1.0, 0.01, crossable=True),)
    ex = InspectionExecutor(blocked, D, (0, 0), ClimberParams(), sure_ends=True, seams=seams,
                            detour=SeamDetour(blocked, seams, D, max_lanes=10))
    ex.start(0.0)
    while not 3 <= ex.cells[-1][0] <= ex.rows - 4:
        ex.cells.pop()
    ex.planned = len(ex.cells)
    ex.covered[:] = True
    ex.covered[4, 3] = False
    ex.index = len(ex.cells)
    swept = len(ex.cells)
    last = ex.cells[-1]
    pose = ((last[1] + 0.5) * D - ex.lead, (last[0] + 0.5) * D, 0.0)
    cov = np.eye(11) * 1e-8
    cov[0, 0], cov[1, 1] = sigma_x**2, sigma_y**2
    ex.step(pose, 1.0, 1.0, cov)
    assert ex.mop_ups == 1 and ex.index == swept  # the mop-up's first target at hand
    return ex, ex.cells[swept:], last


@pytest.mark.parametrize("sigma_y", [0.06, 1.0, 10.0])
def test_a_large_sigma_y_drives_to_a_height_landmark_before_the_mop_ups_target(sigma_y):
    ex, route, last = _in_mop_up(0.01, sigma_y)
    assert ex.mop_fixes == {"height": 1}
    assert route[-1] == (4, 3)  # the target still comes, after the fix
    k = route.index(last)  # the route comes back to the cell it left from ...
    fix = route[:k + 1]
    assert min(r for r, _ in fix) == 0 or max(r for r, _ in fix) == ex.rows - 1  # an edge row
    assert ex.sure.far == ex.index + fix.index(max(fix, key=lambda c: abs(c[0] - 3.5)))


@pytest.mark.parametrize("sigma", [(0.01, 0.01), (0.09, 0.04)])
def test_a_small_sigma_drives_straight_to_the_mop_ups_target(sigma):
    ex, route, last = _in_mop_up(*sigma)
    assert ex.mop_fixes == {}
    assert (4, 3) in route and last not in route  # the mop-up's own route, no way back


def test_a_large_sigma_x_drives_to_a_vertical_seam_first():
    ex, route, last = _in_mop_up(0.2, 0.01)
    assert ex.mop_fixes == {"vertical seam": 1}
    k = route.index(last)
    assert any(c == SEAM_COL for _, c in route[:k]) and route[-1] == (4, 3)
