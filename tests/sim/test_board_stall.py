"""A starved MCU thread must not let the robot run blind: the desk soak at
36x (minute 13) lost localisation after the MCU model fell 23 s of sim time
behind the clock and caught up in one burst with the last motor command it had
read — the robot spun on the spot for 20 s with nobody steering, and the
odometry's heading after that spin was far beyond what the scan matcher
searches. Sim time now waits for the MCU model's sampling as it waits for the
navigation (:class:`sim_robot.sim.SimClock`)."""

from __future__ import annotations

import math
import threading
import time

import pytest

from sim_robot.config import SimConfig
from sim_robot.patrol import DONE
from sim_robot.sim import SimClock, SimRobot
from sim_robot.world import World

STALL_WALL_S = 0.4  # under the MCU's 0.5 s wall-time link watchdog
TIME_SCALE = 50.0  # ... so 20 s of sim time


def test_sim_time_waits_for_the_slowest_control_loop():
    wall = [0.0]
    c = SimClock(10.0, 0.5, wall=lambda: wall[0])
    c.control_step(0.0, "board")
    for _ in range(10):  # the navigation steps on; the board is starved
        wall[0] += 0.1
        c.control_step(c.now(), "navigation")
    assert c.now() == pytest.approx(0.5)
    c.control_step(0.5, "board")  # it sampled: time runs on, 0.5 s past it at most
    wall[0] += 1.0
    c.control_step(c.now())
    assert c.now() == pytest.approx(1.0)


def test_a_stalled_board_does_not_spin_the_robot_blind_and_lose_it():
    cfg = SimConfig(seed=1, video=False, time_scale=TIME_SCALE)
    robot = SimRobot(cfg)
    robot.world.walkers, robot.world.vehicles = [], []
    relay, nav = robot.relay, robot.relay.nav
    ex = nav.executor
    model = robot.mcu_thread.model
    step = model.step
    stalled = threading.Event()
    lag_after: list[float] = []  # sim time the clock ran ahead of each sample, after the stall

    def starved_step(t, dt):
        # the MCU thread loses the CPU once, while the robot turns on the spot
        if not stalled.is_set() and ex.phase == "face" and abs(model.w) > 0.3:
            stalled.set()
            time.sleep(STALL_WALL_S)
        elif stalled.is_set():
            lag_after.append(robot.clock.now() - t)
        return step(t, dt)

    model.step = starved_step
    d = robot.world.dock  # facing west; the point 1.5 m west, to be faced east
    route = {"name": "turn", "points": [{"name": "p", "kind": "waypoint", "x_m": d[0] - 1.5,
                                         "y_m": d[1], "heading_rad": 0.0, "dwell_s": 1.0}]}
    robot.start()
    try:
        with relay._lock:
            ok, why = relay._mission_command("start_patrol", {"route": route})
        assert ok, why
        t0 = time.monotonic()
        while time.monotonic() - t0 < 60 and ex.state != DONE and not nav.localiser.lost:
            time.sleep(0.05)
        assert stalled.is_set(), "the robot never turned on the spot"
        with relay._lock:
            lost, state = nav.localiser.lost_count, ex.state
            est = nav.localiser.pose
        truth = World.pose.fget(robot.world)  # the test may read the truth
    finally:
        robot.close()
    assert lost == 0, f"localisation lost after the stall (estimate {est}, truth {truth})"
    assert state == DONE
    assert abs((est[2] - truth.theta + math.pi) % (2 * math.pi) - math.pi) < math.radians(5)
    assert lag_after and max(lag_after) <= cfg.control_lead_s + 0.2
