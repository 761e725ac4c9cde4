import math

import numpy as np
import pytest

from app.core.planner import GridMap
from app.core.planner.apf import APFConfig, PotentialField
from app.core.planner.dwa import DynamicWindow, Kinematics
from app.core.planner.hybrid import (
    AVOIDING,
    REACHED,
    HybridConfig,
    HybridPlanner,
    rollout_ramp,
)


def u_trap() -> GridMap:
    """10 m × 10 m; a U open towards the robot sits between it and the goal."""
    b = np.zeros((200, 200), bool)
    b[60:140, 120:124] = True
    b[60:64, 80:124] = True
    b[136:140, 80:124] = True
    return GridMap(b, 0.05, (0.0, 0.0))


def run_point(pf, grid, q, goal, steps=3000, speed=0.3, dt=0.1):
    q = np.asarray(q, float)
    goal = np.asarray(goal, float)
    v = np.zeros(2)
    min_clear = math.inf
    for _ in range(steps):
        f = pf.desired_velocity(q, v, goal, [], dt)
        n = np.hypot(*f)
        v = f / n * min(speed, n) if n > 1e-9 else np.zeros(2)
        q = q + v * dt
        min_clear = min(min_clear, grid.distance_m[grid.world_to_cell(*q)] - pf.robot_radius_m)
        if np.hypot(*(goal - q)) < 0.15:
            return True, min_clear
    return False, min_clear


def test_potential_field_escapes_local_minimum():
    grid = u_trap()
    stuck = PotentialField(grid, 0.2, APFConfig(escape_gain=0.0))
    reached, _ = run_point(stuck, grid, (2.0, 5.0), (8.5, 5.0))
    assert not reached, "the plain field of eqs. 28–33 is trapped in the U"
    pf = PotentialField(grid, 0.2)
    reached, min_clear = run_point(pf, grid, (2.0, 5.0), (8.5, 5.0))
    assert reached
    assert min_clear > 0.0


def test_velocity_term_pushes_sideways_off_a_collision_course():
    pf = PotentialField(None, 0.25)
    q, v, goal = (0.0, 0.0), (0.15, 0.0), (5.0, 0.0)
    head_on = [(1.2, 0.05, -0.1, 0.0, 0.3)]
    _, rep = pf.force(q, v, goal, head_on)
    _, rep_still = pf.force(q, v, goal, [(1.2, 0.05, 0.0, 0.0, 0.3)])
    assert np.hypot(*rep) > np.hypot(*rep_still), "closing speed adds repulsion (eq. 38)"
    assert rep[1] < 0, "steered to the side away from the obstacle"
    receding = [(1.2, 0.05, 0.5, 0.0, 0.3)]
    _, rep_r = pf.force(q, v, goal, receding)
    _, rep_pos = pf.force(q, (0.0, 0.0), goal, [(1.2, 0.05, 0.0, 0.0, 0.3)])
    assert np.allclose(rep_r, rep_pos), "no velocity term when not closing (eq. 38)"


def test_dwa_respects_window_and_avoids_wall():
    b = np.zeros((100, 100), bool)
    b[:, 60:62] = True  # wall at x = 3.0 m
    grid = GridMap(b, 0.05)
    k = Kinematics()
    dwa = DynamicWindow(grid, 0.25, k)
    x, y, th, v, w = 1.0, 2.5, 0.0, 0.0, 0.0
    for _ in range(300):
        nv, nw, _ok = dwa.step((x, y, th), (v, w), (4.5, 2.5), [], 0.1)
        assert abs(nv - v) <= k.accel_mps2 * 0.1 + 1e-9
        assert abs(nw - w) <= k.alpha_rps2 * 0.1 + 1e-9
        assert 0 <= nv <= k.v_max_mps and abs(nw) <= k.omega_max_rps
        v, w = nv, nw
        x, y, th = x + v * math.cos(th) * 0.1, y + v * math.sin(th) * 0.1, th + w * 0.1
        assert grid.distance_m[grid.world_to_cell(x, y)] > 0.25
    assert x < 3.0 - 0.25


def yard() -> GridMap:
    b = np.zeros((120, 200), bool)  # 10 m × 6 m
    b[:2, :] = b[-2:, :] = True
    b[:, :2] = b[:, -2:] = True
    b[0:45, 95:105] = True  # a block the path must pass
    return GridMap(b, 0.05, (0.0, 0.0))


def simulate(hp, start, goal, obstacles, t_max=150.0, dt=0.1):
    hp.plan(start, goal)
    x, y = start
    th = 0.0
    v = w = 0.0
    obs = np.array(obstacles, float).reshape(-1, 5)
    statuses = set()
    min_gap = math.inf
    t = 0.0
    while t < t_max:
        cv, cw, status = hp.step((x, y, th), (v, w), obs, dt)
        statuses.add(status)
        if status == REACHED:
            break
        v, w = cv, cw
        x, y, th = x + v * math.cos(th) * dt, y + v * math.sin(th) * dt, th + w * dt
        obs[:, :2] += obs[:, 2:4] * dt
        t += dt
        if len(obs):
            gaps = np.hypot(obs[:, 0] - x, obs[:, 1] - y) - obs[:, 4] - hp.cfg.robot_radius_m
            min_gap = min(min_gap, gaps.min())
        min_gap = min(min_gap, hp.grid.distance_m[hp.grid.world_to_cell(x, y)] - 0.25)
    return statuses, min_gap, (x, y)


@pytest.mark.parametrize("local", ["apf", "dwa"])
def test_hybrid_avoids_an_obstacle_crossing_the_path(local):
    grid = yard()
    hp = HybridPlanner(grid, HybridConfig(robot_radius_m=0.25, local_planner=local))
    start, goal = (1.0, 3.0), (9.0, 3.0)
    path = hp.plan(start, goal)
    assert path[0] == pytest.approx(start) and path[-1] == pytest.approx(goal)
    # A person walking down across the path, timed to meet the robot near x = 3.5.
    crossing = [(3.5, 5.2, 0.0, -0.1, 0.3)]
    statuses, min_gap, end = simulate(hp, start, goal, crossing)
    assert REACHED in statuses and AVOIDING in statuses
    assert min_gap > 0.0, "no contact with the obstacle or the walls"
    assert math.dist(end, goal) <= hp.cfg.goal_tolerance_m


def test_hybrid_follows_without_obstacles_and_reports_errors():
    grid = yard()
    hp = HybridPlanner(grid)
    statuses, min_gap, _ = simulate(hp, (1.0, 3.0), (9.0, 3.0), [])
    assert statuses <= {"following", REACHED} and REACHED in statuses
    assert min_gap > 0
    with pytest.raises(ValueError, match="outside"):
        hp.plan((-1.0, 3.0), (9.0, 3.0))
    assert hp.plan((1.0, 3.0), (5.0, 0.5)) != []  # goal near a wall: snapped
    boxed = grid.blocked.copy()
    boxed[:, 150:152] = True
    hp2 = HybridPlanner(GridMap(boxed, 0.05))
    assert hp2.plan((1.0, 3.0), (9.0, 3.0)) == []
    assert hp2.step((1.0, 3.0, 0.0), (0.0, 0.0), [], 0.1)[2] == "no_path"


@pytest.mark.parametrize("local", ["apf", "dwa"])
def test_hybrid_gets_out_of_a_squeeze_by_two_obstacles(local):
    """Two obstacles converge on the robot's path from both sides at once; the
    governor (whole velocity space, every obstacle's prediction) keeps it clear."""
    grid = yard()
    hp = HybridPlanner(grid, HybridConfig(robot_radius_m=0.25, local_planner=local))
    start, goal = (1.0, 3.0), (9.0, 3.0)
    assert hp.plan(start, goal)
    squeeze = [(3.0, 5.0, 0.0, -0.1, 0.3), (3.0, 1.0, 0.0, 0.1, 0.3)]
    statuses, min_gap, end = simulate(hp, start, goal, squeeze)
    assert min_gap > 0.0, "no contact with the obstacles or the walls"
    assert REACHED in statuses


def test_rollout_ramp_respects_acceleration_and_reports_contact():
    dist = np.full((100, 100), 5.0)
    obs = np.array([[2.0, 0.0, 0.0, 0.0, 0.3]])
    # From rest towards 1 m/s at 0.5 m/s²: after 1 s the robot has gone 0.25 m.
    ds, dm, t_hit = rollout_ramp(
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.5,
        1.0,
        1.0,
        0.1,
        dist,
        0.1,
        -5.0,
        -5.0,
        obs[:0],
        0.25,
    )
    assert math.isinf(t_hit) and ds == pytest.approx(4.75)
    ds, dm, t_hit = rollout_ramp(
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.5, 1.0, 5.0, 0.1, dist, 0.1, -5.0, -5.0, obs, 0.25
    )
    assert dm < 0 and 2.0 < t_hit < 3.0  # contact at x = 1.45 m, about 2.4 s


def test_rollout_grows_a_standing_persons_disc_with_time():
    """Passing 0.3 m (surface) beside a person who stands: clear at constant
    velocity; with the disc growing at 1 m/s up to 0.6 m, a contact once he
    could have stepped across; one walking at 1 m/s (above 0.5 m/s) is not
    grown."""
    dist = np.full((200, 200), 9.0)
    args = (-1.5, 0.0, 0.0, 0.6, 0.0, 0.6, 0.0, 0.5, 1.0, 5.0, 0.1, dist, 0.1, -10.0, -10.0)
    stand = np.array([[0.0, 0.85, 0.0, 0.0, 0.3]])  # 0.85 - 0.3 - 0.25 = 0.3 m gap
    _, dm, t_hit = rollout_ramp(*args, stand, 0.25)
    assert math.isinf(t_hit) and dm == pytest.approx(0.3, abs=0.01)
    _, dm, t_hit = rollout_ramp(*args, stand, 0.25, np.nan, 1.0, 0.6, 0.5)
    assert dm == pytest.approx(-0.3, abs=0.02) and 0.0 < t_hit < 5.0
    walk = np.array([[-1.5, 0.85, 1.0, 0.0, 0.3]])  # beside the robot, walking faster
    _, dm0, t0 = rollout_ramp(*args, walk, 0.25)
    _, dm1, t1 = rollout_ramp(*args, walk, 0.25, np.nan, 1.0, 0.6, 0.5)
    assert dm1 == dm0 and t1 == t0


def test_rollout_grows_a_walkers_disc_at_the_uncertainty_rate():
    """A walker keeping pace 0.3 m (surface) beside the robot: clear at
    constant velocity; with his disc growing at 0.2 m/s (moving_grow) it
    meets the robot after about 1.5 s, and the growth stops at the cap."""
    dist = np.full((200, 200), 9.0)
    args = (-1.5, 0.0, 0.0, 0.6, 0.0, 0.6, 0.0, 0.5, 1.0, 5.0, 0.1, dist, 0.1, -10.0, -10.0)
    walk = np.array([[-1.5, 0.85, 0.6, 0.0, 0.3]])
    _, dm, t_hit = rollout_ramp(*args, walk, 0.25)
    assert math.isinf(t_hit) and dm == pytest.approx(0.3, abs=0.01)
    _, dm, t_hit = rollout_ramp(*args, walk, 0.25, np.nan, 0.0, 1.5, 0.5, 0.2)
    assert 1.3 < t_hit < 1.7 and dm == pytest.approx(0.3 - 0.2 * 5.0, abs=0.02)
    _, dm, _ = rollout_ramp(*args, walk, 0.25, np.nan, 0.0, 0.5, 0.5, 0.2)
    assert dm == pytest.approx(0.3 - 0.5, abs=0.02)  # capped at 0.5 m
