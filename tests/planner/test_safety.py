"""The hybrid planner's safety layer at station speeds: braking for a fast
crossing walker, the emergency stop when contact cannot be avoided, and the
avoidance bench's scenario draw (no obstacle on the robot's start or goal)."""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from app.core.planner import GridMap
from app.core.planner.dwa import Kinematics
from app.core.planner.hybrid import REACHED, HybridConfig, HybridPlanner

STATION = Kinematics(
    v_max_mps=0.6, v_min_mps=-0.2, omega_max_rps=1.0, accel_mps2=0.5, alpha_rps2=2.0
)


def corridor() -> GridMap:
    """12 m × 1.5 m between two walls: no room to swerve round a walker."""
    b = np.zeros((30, 240), bool)  # 0.05 m cells
    b[:2, :] = b[-2:, :] = True
    b[:, :2] = b[:, -2:] = True
    return GridMap(b, 0.05, (0.0, 0.0))


def drive(hp, start, goal, obstacles, v0=0.0, t_max=60.0, dt=0.1):
    """Closed loop with non-reactive obstacles; per step (t, v, smallest gap)."""
    assert hp.plan(start, goal)
    x, y = start
    th, v, w = 0.0, v0, 0.0
    obs = np.array(obstacles, float).reshape(-1, 5)
    log = []
    t = 0.0
    status = ""
    while t < t_max:
        cv, cw, status = hp.step((x, y, th), (v, w), obs, dt)
        if status == REACHED:
            break
        k = hp.cfg.kin
        assert abs(cv - v) <= k.accel_mps2 * dt + 1e-9, "deceleration within the base's limit"
        v, w = cv, cw
        x, y, th = x + v * math.cos(th) * dt, y + v * math.sin(th) * dt, th + w * dt
        obs[:, :2] += obs[:, 2:4] * dt
        t += dt
        gap = np.hypot(obs[:, 0] - x, obs[:, 1] - y) - obs[:, 4] - hp.cfg.robot_radius_m
        log.append((t, v, float(gap.min())))
    return status, log


def test_brakes_for_a_fast_walker_crossing_a_corridor():
    """A walker at 1.2 m/s crosses the corridor (through its doors) where the
    robot, cruising at 0.6 m/s, would be when he passes; the robot cannot
    swerve, so it must slow down, let him pass, and drive on."""
    hp = HybridPlanner(corridor(), HybridConfig(robot_radius_m=0.25, kin=STATION))
    start, goal = (1.0, 0.75), (11.0, 0.75)
    # Without braking the robot (0.6 m/s from 1 m) is at x = 4 after about 5.6 s.
    walker = (4.0, 0.75 - 1.2 * 5.6, 0.0, 1.2, 0.3)
    status, log = drive(hp, start, goal, [walker], v0=0.6)
    assert status == REACHED
    t, v, gap = np.array(log).T
    assert gap.min() > 0.0, "no contact"
    crossing = (t > 4.5) & (t < 6.2)
    assert v[crossing].min() < 0.3, "slowed down for the walker"
    assert hp.governor_count > 0


def test_emergency_stop_when_contact_cannot_be_avoided():
    """A walker at 1.4 m/s comes head-on down the corridor, 1.5 m away: no
    motion avoids him. The robot brakes at its deceleration limit to stand
    when he arrives instead of fleeing or driving on."""
    hp = HybridPlanner(corridor(), HybridConfig(robot_radius_m=0.25, kin=STATION))
    start, goal = (3.0, 0.75), (11.0, 0.75)
    walker = (3.0 + 0.25 + 0.3 + 1.5, 0.75, -1.4, 0.0, 0.3)
    status, log = drive(hp, start, goal, [walker], v0=0.6, t_max=1.5)
    t, v, gap = np.array(log).T
    assert hp.estop_count > 0
    contact = np.flatnonzero(gap <= 0.0)
    assert len(contact), "the walker reaches the robot (it cannot be avoided)"
    # Braking from the first step, at the limit (0.5 m/s² → 0.05 m/s per step).
    assert v[0] == pytest.approx(0.55)
    assert v[: contact[0] + 1].max() <= 0.55 + 1e-9
    assert abs(v[contact[0]]) < 0.6 - 0.05 * contact[0] + 1e-9


def yard() -> GridMap:
    """10 m × 10 m, walls round the edge only."""
    b = np.zeros((200, 200), bool)  # 0.05 m cells
    b[:2, :] = b[-2:, :] = True
    b[:, :2] = b[:, -2:] = True
    return GridMap(b, 0.05, (0.0, 0.0))


@pytest.mark.parametrize("commit_s", [0.3, 0.0])
def test_does_not_drive_on_where_it_could_no_longer_stop_clear_of_a_walker(commit_s):
    """Heading north at 0.6 m/s toward the line a walker (0.8 m/s, from the
    east) walks along: driving on would cross ahead of him as predicted, but
    one more step at full speed leaves no stop short of his line. With the
    braking contingency (commit_s) the governor brakes now; without it, it
    keeps the cruise."""
    hp = HybridPlanner(yard(), HybridConfig(robot_radius_m=0.25, kin=STATION, commit_s=commit_s))
    q, th = np.array([5.0, 2.45]), math.pi / 2
    walker = np.array([[8.5, 3.5, -0.8, 0.0, 0.3]])
    assert hp._clearance(q, th, 0.6, 0.0, walker) > hp.cfg.safety_margin_m  # passes ahead
    v, _w = hp._govern(q, th, 0.6, 0.0, 0.6, 0.0, 0.1, walker)
    if commit_s:
        assert hp._can_stop(q, th, 0.6, 0.0, 0.6, 0.0, walker) < hp.cfg.safety_margin_m
        assert v < 0.6 - 1e-9, "brakes while it can still stop short of his line"
    else:
        assert v == pytest.approx(0.6)


def test_moves_away_from_a_standing_person_instead_of_freezing_beside_him():
    """The robot stands 0.2 m from a person standing in its way. His disc as
    the governor predicts it (he may set off: it grows up to 0.9 m) touches
    every motion, but that is a precaution, not a contact: the robot backs
    away rather than freezing there, then goes round him (the replan keeps
    the grown distance) to its goal, never touching him."""
    hp = HybridPlanner(
        yard(),
        HybridConfig(robot_radius_m=0.25, kin=STATION, slow_grow_mps=1.0, slow_grow_cap_m=0.9),
    )
    person = (5.75, 5.0, 0.0, 0.0, 0.3)
    status, log = drive(hp, (5.0, 5.0), (9.0, 5.2), [person], t_max=90.0)
    t, v, gap = np.array(log).T
    assert gap.min() > 0.0
    assert gap[t <= 3.05][-1] > 0.5, "backed away within 3 s"
    assert status == REACHED


def _avoid_bench():
    path = Path(__file__).resolve().parents[2] / "bench" / "avoid_bench.py"
    spec = importlib.util.spec_from_file_location("avoid_bench", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("config", ["table3", "station"])
def test_bench_never_draws_an_obstacle_on_the_robot(config):
    ab = _avoid_bench()
    conf = ab.CONFIGS[config]
    rng = np.random.default_rng(5)
    drawn = 0
    while drawn < 40:
        grid = ab.make_world(rng)
        hp = HybridPlanner(grid, HybridConfig(robot_radius_m=ab.ROBOT_R, kin=conf["kin"]))
        sc = ab.scenario(rng, hp, grid, conf["obs_speed"])
        if sc is None:
            continue
        drawn += 1
        start, _th, goal, _opt, obs = sc
        assert len(obs) >= 1
        for end in (start, goal):
            gap = np.hypot(obs[:, 0] - end[0], obs[:, 1] - end[1]) - obs[:, 4] - ab.ROBOT_R
            assert gap.min() >= ab.SPAWN_GAP_M - 1e-9


def test_replan_around_moving_obstacles_searches_a_window():
    """The search around moving obstacles is confined to a box round start
    and goal (a failing search stays cheap); when the obstacles cut the goal
    off, the replan falls back to the map alone."""
    b = np.zeros((300, 400), bool)  # 40 m × 30 m at 0.1 m
    b[:2, :] = b[-2:, :] = True
    b[:, :2] = b[:, -2:] = True
    grid = GridMap(b, 0.1, (0.0, 0.0))
    hp = HybridPlanner(grid, HybridConfig(robot_radius_m=0.25, replan_window_m=5.0))
    start, goal = (3.0, 5.0), (30.0, 5.0)
    assert hp.plan(start, goal)
    q = np.array(start)
    walker = np.array([[15.0, 5.0, 0.0, 0.0, 0.3]])
    blocked = hp._blocked_with(q, walker)
    row_top = grid.world_to_cell(15.0, 10.0 + 0.2)[0]
    assert blocked[row_top:, :].all(), "outside the window: blocked"
    inside = blocked[5 : row_top - 5, 5:300]
    assert not inside.all() and inside.any(), "inside: the map and the walker's disc"
    assert blocked[grid.world_to_cell(15.0, 5.0)], "the walker's disc is blocked"
    # Goal ringed by standing people: the window search fails, the map path stands.
    ring = np.array(
        [
            [30.0 + 1.0 * math.cos(a), 5.0 + 1.0 * math.sin(a), 0.0, 0.0, 0.3]
            for a in np.linspace(0, 2 * math.pi, 12, endpoint=False)
        ]
    )
    assert hp._replan(q, ring)
    assert tuple(hp.path[-1]) == pytest.approx(goal)
    assert hp.last_plan.found
