"""The safety governor and a robot the map has touching a wall already (a
bump, or a pose estimate a few centimetres off): it may move, by any motion
that goes no deeper, instead of braking to rest for good."""

import math

import numpy as np
import pytest

from app.core.planner import GridMap
from app.core.planner.dwa import Kinematics
from app.core.planner.hybrid import REACHED, HybridConfig, HybridPlanner

STATION = Kinematics(
    v_max_mps=0.6, v_min_mps=-0.2, omega_max_rps=1.0, accel_mps2=0.5, alpha_rps2=2.0
)


def room() -> HybridPlanner:
    """10 m × 4 m, its south wall 0.5 m thick (y < 0.5)."""
    b = np.zeros((40, 100), bool)
    b[:5, :] = True
    cfg = HybridConfig(robot_radius_m=0.35, inflation_margin_m=0.1, kin=STATION)
    return HybridPlanner(GridMap(b, 0.1, (0.0, 0.0)), cfg)


@pytest.mark.parametrize("theta", [-math.pi / 2, 0.0, math.pi / 2, math.pi])
def test_a_robot_touching_a_wall_moves_on_and_reaches_its_goal(theta):
    hp = room()
    x, y = 2.0, 0.75  # 10 cm into the wall by the map
    now = hp._clearance(np.array([x, y]), theta, 0.0, 0.0, np.zeros((0, 5)))
    assert now < 0.0
    assert hp.plan((x, y), (7.0, 2.5))
    v = w = 0.0
    t, status = 0.0, ""
    deepest = now
    while t < 60.0:
        v, w, status = hp.step((x, y, theta), (v, w), [], 0.1)
        if status == REACHED:
            break
        x, y = x + v * math.cos(theta) * 0.1, y + v * math.sin(theta) * 0.1
        theta += w * 0.1
        deepest = min(deepest, hp._clearance(np.array([x, y]), theta, 0.0, 0.0, np.zeros((0, 5))))
        t += 0.1
    assert status == REACHED
    assert deepest >= now - 1e-3  # never deeper into the wall than it started
    assert hp.estop_count == 0


def test_touching_a_wall_with_a_walker_near_it_still_backs_away():
    hp = room()
    x, y, th = 5.0, 0.75, -math.pi / 2  # facing the wall, 10 cm into it by the map
    walker = [(5.0, 2.2, 0.0, 0.0, 0.3)]  # standing behind it, 0.75 m off
    v, w = hp.govern((x, y, th), (0.0, 0.0), -0.15, 0.0, walker, 0.1)
    assert v < 0.0  # backs away from the wall, towards the free space
