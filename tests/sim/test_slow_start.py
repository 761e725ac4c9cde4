"""A slow first start does not let sim time run past the robot's control loops.

From a fresh clone under load the robot took 111 s to start (its first
compile); sim time ran free meanwhile — no control loop had stepped yet to
hold it — and again while the MCU model sampled and the navigation had not yet
stepped. Here the compile is played by a sleep in the navigation's warm-up
and a starved navigation thread by a sleep in its first step."""

from __future__ import annotations

import threading
import time

from sim_robot.config import SimConfig
from sim_robot.navigation import Navigation
from sim_robot.sim import SimRobot

from .desk import wait_until

TIME_SCALE = 50.0
SLOW_WALL_S = 1.0  # 50 s of sim time at 50x


def test_sim_time_waits_for_a_slow_first_start(monkeypatch):
    warm_up = Navigation.warm_up

    def slow_warm_up(self):  # a first run's compile
        time.sleep(SLOW_WALL_S)
        warm_up(self)

    monkeypatch.setattr(Navigation, "warm_up", slow_warm_up)
    cfg = SimConfig(seed=1, video=False, time_scale=TIME_SCALE)
    robot = SimRobot(cfg)
    relay, nav = robot.relay, robot.relay.nav
    step = nav.step
    first = threading.Event()

    def starved_first_step(*args, **kw):
        if not first.is_set():
            first.set()
            time.sleep(SLOW_WALL_S)
        return step(*args, **kw)

    nav.step = starved_first_step
    paced = relay.on_control_step
    reports: list[tuple[float, float]] = []  # (the step's sim time, the clock when it reported)

    def on_step(t: float) -> None:
        reports.append((t, robot.clock.now()))
        paced(t)

    relay.on_control_step = on_step
    robot.start()
    try:
        wait_until(lambda: len(reports) >= 20, timeout=60, what="20 navigation steps")
        board_t = robot.mcu_thread.model.t
    finally:
        robot.close()
    lead = cfg.control_lead_s
    t_first, clock_at_first = reports[0]
    assert t_first <= lead + 0.05, f"sim time ran {t_first:.1f} s before the first step"
    assert clock_at_first <= lead + 0.05, \
        f"sim time ran {clock_at_first:.1f} s while the first step was starved"
    assert board_t > t_first  # and then it runs
