"""The simulation's clock waits for the robot's control: sim time runs at
most ``control_lead_s`` past the navigation's last step, so a starved host
slows the simulation down instead of letting the robot drive blind on its last
command; and the navigation's own speed cap for stale control."""

from __future__ import annotations

import math

import pytest

from sim_robot.config import SimConfig
from sim_robot.patrol_sim import OfflinePatrol
from sim_robot.sim import SimClock
from sim_robot.world import World


def test_sim_time_waits_for_the_control_step():
    wall = [100.0]
    c = SimClock(10.0, 0.5, wall=lambda: wall[0])
    wall[0] += 1.0
    assert c.now() == pytest.approx(10.0)  # no step reported yet: free running
    c.control_step(10.0)
    wall[0] += 1.0  # the navigation is starved for a second of wall time
    assert c.now() == pytest.approx(10.5)
    assert c.held_s == pytest.approx(9.5)
    wall[0] += 0.01
    assert c.now() == pytest.approx(10.5)  # still held
    c.control_step(10.5)  # it stepped: time runs on from where it stood
    wall[0] += 0.01
    assert c.now() == pytest.approx(10.6)
    assert c.wall_until(11.6) == pytest.approx(0.1)


def test_without_a_lead_the_clock_never_waits():
    wall = [0.0]
    c = SimClock(36.0, wall=lambda: wall[0])
    c.control_step(0.0)
    wall[0] += 2.0
    assert c.now() == pytest.approx(72.0) and c.held_s == 0.0
    with pytest.raises(ValueError, match="lead"):
        SimClock(1.0, -1.0)


def test_the_speed_is_capped_by_how_stale_the_control_is():
    cfg = SimConfig(seed=1, video=False)
    w = World(cfg.station_file, cfg.seed)
    w.walkers, w.vehicles = [], []
    op = OfflinePatrol(cfg, world=w)
    nav = op.nav
    room = nav.executor.recovery.clearance_m(52.5, 38.0)  # beside the bund's east wall
    assert 0.05 < room < 0.3
    assert nav._stale_cap(0.6, 0.1, (60.0, 45.0, 0.0)) == 0.6  # open ground, fresh control
    v = nav._stale_cap(0.6, 2.0, (52.5, 38.0, 0.0))  # a command held for 2 s, by the wall
    assert v == pytest.approx(max(room / 2.0, 0.1))
    assert nav._stale_cap(-0.2, 2.0, (52.5, 38.0, 0.0)) == pytest.approx(-v)
    for _ in range(10):  # fresh steps again: the cap fades, not at once
        nav._stale_cap(0.6, 0.1, (52.5, 38.0, 0.0))
    assert room / 2.0 < nav._stale_cap(0.6, 0.1, (52.5, 38.0, 0.0)) < room / 0.1
    assert nav.stale_capped >= 3
    assert math.isfinite(nav.hold_s)
