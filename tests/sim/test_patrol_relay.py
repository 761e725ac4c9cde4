"""Patrol commands through the relay (in-process robot at 10x, a plain-socket desk)."""

from __future__ import annotations

import pytest

from app.comm import protocol as P
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot
from sim_robot.world import Walker

from .conftest import Desk, wait_until

ROUTE = {"name": "one", "points": [
    {"name": "far", "kind": "waypoint", "x_m": 58.0, "y_m": 45.0, "gauge": None,
     "dwell_s": 0.0}]}


@pytest.fixture
def fast_robot():
    r = SimRobot(SimConfig(video=False, seed=4, time_scale=10.0))
    r.world.walkers = []
    r.world.vehicles = []
    r.start()
    assert r.relay.nav_ready.wait(30)
    yield r
    r.close()


def _cmd(desk: Desk, name: str, **args) -> P.CommandAck:
    seq = desk.send(P.Command(name, args))
    return wait_until(lambda: desk.ack(seq), 5)


def test_patrol_commands_takeover_and_estop(fast_robot):
    desk = Desk(*fast_robot.address)
    try:
        wait_until(lambda: desk.of(P.MsgType.MAP), 5)
        wait_until(lambda: desk.of(P.MsgType.PATROL_STATUS), 5)
        assert desk.of(P.MsgType.PATROL_STATUS)[0].state == "idle"
        assert not _cmd(desk, "resume_patrol").ok
        assert not _cmd(desk, "goto", x_m="here").ok
        assert not _cmd(desk, "goto", point="nowhere").ok
        bad = _cmd(desk, "start_patrol", route={"name": "x", "points": [{"name": "p"}]})
        assert not bad.ok and "kind" in bad.reason
        inside = {"name": "x", "points": [{"name": "tank", "kind": "waypoint", "x_m": 41.0,
                                           "y_m": 36.0}]}
        bad = _cmd(desk, "start_patrol", route=inside)
        assert not bad.ok and "cannot stand there" in bad.reason
        assert _cmd(desk, "start_patrol", route=ROUTE).ok
        wait_until(lambda: desk.events("patrol_started"), 5)
        wait_until(lambda: any(s.state == "driving"
                               for s in desk.of(P.MsgType.PATROL_STATUS)), 10)
        wait_until(lambda: any(t.mode == P.RobotMode.PATROL
                               for t in desk.of(P.MsgType.TELEMETRY)), 5)
        wait_until(lambda: desk.of(P.MsgType.OBSTACLES), 5)
        # the operator drives: the patrol pauses and says why
        assert _cmd(desk, "drive", linear_mps=0.0, angular_rps=0.3).ok
        ev = wait_until(lambda: desk.events("patrol_paused"), 5)
        assert "drive" in ev[-1].data["reason"]
        wait_until(lambda: desk.of(P.MsgType.PATROL_STATUS)[-1].state == "paused", 5)
        assert _cmd(desk, "resume_patrol").ok
        assert _cmd(desk, "estop").ok
        wait_until(lambda: desk.events("patrol_paused")[-1].data["reason"] == "estop", 5)
        assert not _cmd(desk, "resume_patrol").ok  # latched
        assert _cmd(desk, "reset_estop").ok
        assert _cmd(desk, "resume_patrol").ok
        wait_until(lambda: desk.events("patrol_done"), 30)
        assert desk.events("collision") == []
        assert _cmd(desk, "goto", point="PG-302").ok
        wait_until(lambda: desk.of(P.MsgType.PATROL_STATUS)[-1].route == "goto", 5)
        assert _cmd(desk, "abort_patrol").ok
        wait_until(lambda: desk.events("patrol_aborted"), 5)
        assert _cmd(desk, "dock").ok
        wait_until(lambda: desk.events("patrol_done"), 5)
        wait_until(lambda: len(desk.events("patrol_done")) >= 2, 30)
        assert fast_robot.world.at_dock()
    finally:
        desk.close()


def test_idle_robot_publishes_tracked_walkers_at_10x():
    r = SimRobot(SimConfig(video=False, seed=5, time_scale=10.0))
    r.world.walkers = [Walker({"id": "w", "path": [[63.0, 43.2], [63.0, 46.8]],
                               "speed_mps": 0.5, "pause_s": 1.0, "radius_m": 0.25}, 0.0)]
    r.world.vehicles = []
    r.start()
    desk = Desk(*r.address)
    try:
        assert r.relay.nav_ready.wait(30)

        def moving_track():
            for m in desk.of(P.MsgType.OBSTACLES)[-5:]:
                for x, y, _vx, vy, _rad in m.rows:
                    if abs(x - 63.0) < 0.5 and 43.0 < y < 47.0 and abs(vy) > 0.2:
                        return True
            return False

        wait_until(moving_track, 15)
    finally:
        desk.close()
        r.close()


def test_a_patrol_pauses_when_the_control_lease_holder_goes_silent(fast_robot):
    """The lease lapses when its holder's heartbeats stop, and the robot stops:
    a running patrol pauses (lease_lost_action = "pause") until a desk resumes it."""
    desk = Desk(*fast_robot.address)
    try:
        wait_until(lambda: desk.of(P.MsgType.PATROL_STATUS), 5)
        assert _cmd(desk, "start_patrol", route=ROUTE).ok
        wait_until(lambda: any(t.cmd_linear_mps > 0.05 for t in desk.of(P.MsgType.TELEMETRY)),
                   15)
        desk.heartbeat = False  # the desk freezes; its socket stays open
        wait_until(lambda: desk.events("lease_lapsed"), 10)
        ev = wait_until(lambda: desk.events("patrol_paused"), 5)
        assert "control lost" in ev[-1].data["reason"]
        n = len(desk.of(P.MsgType.TELEMETRY))
        wait_until(lambda: any(t.cmd_linear_mps == 0.0 and abs(t.wheel_left_mps) < 1e-3
                               for t in desk.of(P.MsgType.TELEMETRY)[n:]), 5)
        desk.heartbeat = True  # back: it takes control again and resumes
        assert _cmd(desk, "request_control").ok
        assert _cmd(desk, "resume_patrol").ok
    finally:
        desk.close()


def test_lease_lost_action_is_checked(tmp_path):
    f = tmp_path / "robot.toml"
    f.write_text('lease_lost_action = "wander"\n')
    with pytest.raises(ValueError, match="lease_lost_action"):
        SimConfig.from_toml(f)
    f.write_text('lease_lost_action = "continue"\n')
    assert SimConfig.from_toml(f).lease_lost_action == "continue"
