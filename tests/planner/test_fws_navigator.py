"""The 4WS robot's navigator: any-angle plan kept off the inflated obstacles,
a turn in place when the path starts behind the robot, pure pursuit along the
TEB band, a stop for a person on the band that holds until the band has been
clear for a while, and the goal reached."""

from __future__ import annotations

import math
import threading
from concurrent.futures import wait

import numpy as np
import pytest

from app.core.kinematics import Mode, Twist, integrate_pose, wheel_commands
from app.core.planner import GridMap
from app.core.planner.fws_navigator import (
    BLOCKED,
    FOLLOWING,
    NO_PATH,
    REACHED,
    FwsNavConfig,
    FwsNavigator,
)


def _room():
    b = np.zeros((60, 80), bool)
    b[0, :] = b[-1, :] = b[:, 0] = b[:, -1] = True
    b[20:60, 38:42] = True  # a wall from the north side, a gap at the south
    return GridMap(b, 0.1, (0.0, 0.0))


def test_plan_keeps_off_the_inflated_wall():
    nav = FwsNavigator(_room())
    path = np.array(nav.plan((1.5, 4.5), (6.5, 4.5)))
    assert len(path) > 2 and np.allclose(path[0], (1.5, 4.5)) and np.allclose(path[-1],
                                                                              (6.5, 4.5))
    assert path[:, 1].min() < 2.0  # around the wall's end
    assert all(nav.inflated.is_free_xy(x, y) for x, y in path[1:-1])
    with pytest.raises(ValueError, match="outside the map"):
        nav.plan((1.5, 4.5), (9.5, 4.5))
    nav.set_path([])
    assert nav.step((1.5, 4.5, 0.0), (0.0, 0.0))[2] == NO_PATH


def test_drive_to_the_goal_turning_in_place_first():
    nav = FwsNavigator(_room())
    nav.plan((1.5, 4.5), (6.5, 4.5))
    pose, v, dt = (1.5, 4.5, math.pi / 2), 0.0, 0.1  # facing north; the path leaves south
    first = nav.step(pose, (v, 0.0), [], dt)
    assert first[0] == 0.0 and first[1] < 0  # pivot clockwise, towards the south
    pivots = 0
    for _ in range(1500):
        vx, om, status = nav.step(pose, (v, 0.0), [], dt)
        if status == REACHED:
            break
        assert vx >= 0.0  # never reverses
        pivots += vx == 0.0 and om != 0.0
        pose = integrate_pose(pose, Twist(vx, 0.0, om), dt)
        v = vx
        assert nav.grid.is_free_xy(pose[0], pose[1])
    assert status == REACHED and math.hypot(pose[0] - 6.5, pose[1] - 4.5) <= 0.12
    assert pivots >= 3 and nav.teb_cycles > 10


def test_a_person_on_the_band_stops_the_base_until_clear():
    nav = FwsNavigator(_room())
    nav.plan((1.0, 1.0), (6.5, 1.0))
    pose = (1.0, 1.0, 0.0)
    assert nav.step(pose, (0.3, 0.0), [], 0.1)[0] > 0
    person = [(1.6, 1.0, 0.0, 0.0, 0.25)]  # standing 0.6 m ahead on the band
    vx, om, status = nav.step(pose, (0.3, 0.0), person, 0.1)
    assert (vx, om, status) == (0.0, 0.0, BLOCKED) and nav.governor_count == 1
    held = [nav.step(pose, (0.0, 0.0), [], 0.1)[2] for _ in range(5)]  # he left
    assert held == [BLOCKED] * 5  # still holding (resume_s = 1 s)
    for _ in range(10):
        vx, _om, status = nav.step(pose, (0.0, 0.0), [], 0.1)
    assert status != BLOCKED and vx > 0
    # one walking towards the band from the side is a threat before he is on it
    walker = [(1.6, 2.2, 0.0, -1.0, 0.25)]
    assert nav.step(pose, (0.3, 0.0), walker, 0.1)[2] == BLOCKED


def test_start_and_goal_in_one_cell():
    nav = FwsNavigator(_room())
    nav.set_path([(1.52, 1.0)])
    vx, om, status = nav.step((1.25, 1.0, 0.0), (0.0, 0.0), [], 0.1)
    assert status != NO_PATH and np.isfinite([vx, om]).all()


def _wait_idle(nav, timeout_s=60.0):
    """Until the TEB worker has no cycle under way (waits on the cycle's future)."""
    job = nav._job
    if job is not None:
        done, _ = wait([job], timeout=timeout_s)
        assert done, "the TEB worker did not finish"


def test_background_teb_never_holds_up_a_step_and_drops_stale_cycles():
    nav = FwsNavigator(_room(), FwsNavConfig(background_teb=True))
    gate = threading.Event()
    real = nav.teb.plan_step

    def gated(*a, **kw):
        assert gate.wait(60)
        return real(*a, **kw)

    nav.teb.plan_step = gated
    try:
        nav.plan((1.5, 4.5), (6.5, 4.5))
        pose = (1.5, 4.5, math.pi / 2)
        # the cycle is held at the gate, and the step still returns: nothing to follow yet
        assert nav.step(pose, (0.0, 0.0), [], 0.1) == (0.0, 0.0, FOLLOWING)
        nav.plan((1.5, 4.5), (6.5, 4.5))  # the path is replaced: that cycle is stale
        gate.set()
        _wait_idle(nav)
        nav.step(pose, (0.0, 0.0), [], 0.1)  # drops it and starts one for the new path
        assert nav.teb_cycles == 0 and nav.last_teb is None
        _wait_idle(nav)
        vx, om, _ = nav.step(pose, (0.0, 0.0), [], 0.1)
        assert nav.teb_cycles == 1 and nav.last_teb.turning_in_place
        assert vx == 0.0 and om < 0  # pivot clockwise, towards the south
        # then on to the goal, each step with the last finished cycle
        v, dt, pivots = 0.0, 0.1, 0
        for k in range(1500):
            if k % 3 == 0:
                _wait_idle(nav)  # the worker finishes about every third step
            vx, om, status = nav.step(pose, (v, 0.0), [], dt)
            if status == REACHED:
                break
            assert vx >= 0.0
            pivots += vx == 0.0 and om != 0.0
            pose = integrate_pose(pose, Twist(vx, 0.0, om), dt)
            v = vx
            assert nav.grid.is_free_xy(pose[0], pose[1])
        assert status == REACHED and pivots >= 3 and nav.teb_cycles > 10
    finally:
        gate.set()
        nav.close()


def test_each_steering_mode_is_commanded():
    """Pivot at the start (the path leaves behind the robot), front steer on the
    long straight at speed, counter-phase round the wall's end, and with
    crab docking the last sideways offset closed in CRAB mode."""
    nav = FwsNavigator(_room(), FwsNavConfig(crab_docking=True, goal_tolerance_m=0.05))
    nav.plan((1.5, 4.5), (6.5, 4.5))
    # the goal 0.2 m to one side of where the path ends, as a gauge's stand-off
    # point a little off the approach line
    nav.set_path(np.vstack([nav.path[:-1], [6.5, 4.7]]))
    pose, v, dt = (1.5, 4.5, math.pi / 2), 0.0, 0.1
    modes = []
    for _ in range(2000):
        vx, om, status = nav.step(pose, (v, 0.0), [], dt)
        if status == REACHED:
            break
        mode, tw = nav.command
        modes.append(mode)
        assert (vx, om) == (tw.vx, tw.omega) or mode is Mode.CRAB
        pose = integrate_pose(pose, tw, dt)  # the base drives the mode's whole twist
        v = vx
        assert nav.grid.is_free_xy(pose[0], pose[1])
    assert status == REACHED and math.hypot(pose[0] - 6.5, pose[1] - 4.7) <= 0.05
    assert {Mode.PIVOT, Mode.FRONT, Mode.COUNTER, Mode.CRAB} <= set(modes)
    assert modes[0] is Mode.PIVOT and Mode.CRAB in modes[-20:] and modes.count(Mode.CRAB) >= 3


def test_a_crab_slide_goes_on_to_the_goal_and_reports_its_sideways_speed():
    """A goal 0.3 m ahead and 0.25 m to the left: the step slides (forward speed
    returned, sideways in lateral_mps); once sliding, a noisy estimate that puts
    the offset under half the tolerance does not end the slide (a fresh
    navigator would not start one there)."""
    cfg = FwsNavConfig(crab_docking=True, goal_tolerance_m=0.12)
    nav = FwsNavigator(_room(), cfg)
    nav.set_path([(6.0, 4.5), (6.3, 4.75)])
    pose = np.array([6.0, 4.5, 0.0])
    assert nav._crab(pose) is not None
    vx, om, _status = nav.step(pose, (0.0, 0.0), [], 0.1)
    mode, tw = nav.command
    assert mode is Mode.CRAB and om == 0.0 and vx == tw.vx > 0
    assert nav.lateral_mps == tw.vy > 0 and tw.vy / tw.vx == pytest.approx(0.25 / 0.3)
    near = np.array([6.2, 4.72, 0.0])  # 0.03 m off the line to the goal, 0.1 m away
    assert nav._crab(near) is not None
    fresh = FwsNavigator(_room(), cfg)
    fresh.set_path([(6.0, 4.5), (6.3, 4.75)])
    assert fresh._crab(near) is None
    nav.close()
    fresh.close()


def test_a_crab_slide_that_passed_the_goal_slides_back_without_a_pivot():
    """A late control step (a starved loop holds the last command) carries the
    slide past the goal: the navigator slides back to it in CRAB mode, the
    wheels at the same angle and the speed reversed, instead of leaving it to
    the TEB, which turns in place towards a goal 50° off the heading."""
    cfg = FwsNavConfig(crab_docking=True, goal_tolerance_m=0.12)
    nav = FwsNavigator(_room(), cfg)
    nav.set_path([(6.0, 4.5), (6.2, 4.75)])  # 0.2 m ahead, 0.25 m to the left
    pose, dt = np.array([6.0, 4.5, 0.0]), 0.1
    nav.step(pose, (0.0, 0.0), [], dt)
    assert nav.command[0] is Mode.CRAB
    ahead = nav.command[1]
    late = np.array([6.29, 4.86, 0.0])  # 0.14 m on past the goal along the slide
    nav.step(late, (0.0, 0.0), [], dt)
    mode, back = nav.command
    assert mode is Mode.CRAB and back.vx < 0 and back.vy < 0 and back.omega == 0.0
    assert math.atan2(-back.vy, -back.vx) == pytest.approx(math.atan2(ahead.vy, ahead.vx),
                                                           abs=math.radians(15))
    modes = []
    for _ in range(100):
        _vx, _om, status = nav.step(late, (0.0, 0.0), [], dt)
        if status == REACHED:
            break
        mode, tw = nav.command
        modes.append(mode)
        late = np.array(integrate_pose(late, tw, dt))
    assert status == REACHED and set(modes) == {Mode.CRAB}
    assert late[2] == 0.0 and math.hypot(late[0] - 6.2, late[1] - 4.75) <= 0.12
    nav.close()


def test_a_crab_slide_whose_goal_turned_beyond_the_servos_slides_at_their_limit():
    """Once sliding, an estimate that puts the goal 75° off the heading (the
    sideways travel lagging the forward one on a starved relay) leaves the
    wheels at the servo's limit, the distance shrinking, instead of a pivot."""
    cfg = FwsNavConfig(crab_docking=True, goal_tolerance_m=0.12)
    nav = FwsNavigator(_room(), cfg)
    nav.set_path([(6.0, 4.5), (6.2, 4.75)])
    nav.step(np.array([6.0, 4.5, 0.0]), (0.0, 0.0), [], 0.1)
    assert nav.command[0] is Mode.CRAB
    side = np.array([6.2 - 0.04, 4.75 - 0.15, 0.0])  # the goal 75° to the left
    nav.step(side, (0.0, 0.0), [], 0.1)
    mode, tw = nav.command
    assert mode is Mode.CRAB and tw.omega == 0.0
    lim = cfg.geometry.servo_range_rad
    assert math.atan2(tw.vy, tw.vx) == pytest.approx(lim)
    assert all(abs(a) <= lim + 1e-9 for a in wheel_commands(cfg.geometry, tw).angles_rad)
    nav.close()


@pytest.mark.parametrize("y0", [2.75, 3.3])
def test_the_base_does_not_stand_in_a_crossing_persons_way(y0):
    """A worker walks along y = 3.1 towards the robot crossing his line (north
    along x = 2). Braking to rest there would leave it in his way (he does not
    give way): the robot steps aside (entering his line) or drives on (mostly
    across), he passes clear of it, and it goes on. The robot sees him only as a track."""
    nav = FwsNavigator(_room())
    nav.plan((2.0, 1.0), (2.0, 5.5))
    pose, v, dt = np.array([2.0, y0, math.pi / 2]), 0.3, 0.1
    person = np.array([3.4, 3.1])
    vel = np.array([-0.7, 0.0])
    least = math.inf
    for _ in range(80):
        vx, om, _status = nav.step(pose, (v, 0.0), [(*person, *vel, 0.25)], dt)
        pose = np.array(integrate_pose(pose, Twist(vx, 0.0, om), dt))
        v = vx
        person = person + vel * dt
        least = min(least, float(np.hypot(*(person - pose[:2]))) - 0.25 - 0.35)
        assert nav.grid.is_free_xy(pose[0], pose[1])
    assert least > 0.05, least
    assert pose[1] > 3.1 + 0.6  # and went on across his line once he had passed
