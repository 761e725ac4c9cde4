"""The robot's navigation on its own localisation: scan-to-map matching fused
with odometry, never the simulator's true pose; lost localisation stops the
robot until the operator sets the pose."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import sim_robot.navigation as navigation_module
from app.comm import protocol as P
from sim_robot.config import SimConfig
from sim_robot.patrol import ACTIVE, DONE, PAUSED
from sim_robot.patrol_sim import OfflinePatrol
from sim_robot.route import parse_route
from sim_robot.world import World

pytestmark = pytest.mark.slow(34)

GAUGES = {"PG-101", "PG-102", "PG-201", "CG-301", "PG-302"}
ROUTE = {"name": "r", "points": [
    {"name": "a", "kind": "waypoint", "x_m": 61.5, "y_m": 45.0, "gauge": None, "dwell_s": 0.5},
    {"name": "PG-302", "kind": "meter", "x_m": 58.6, "y_m": 38.0, "gauge": "PG-302",
     "dwell_s": 1.0}]}

# who may read World.pose: the world itself, its sensors (the lidar casts from
# where the robot really is, the MCU model moves it), and the lock-step
# harness (its start pose and the clearance figure). Nothing in the navigation.
TRUTH_READERS = {"world.py", "lidar.py", "mcu.py", "sensors.py", "patrol_sim.py", "camera.py"}
SIM_DIR = os.path.dirname(navigation_module.__file__)
APP_DIR = os.path.join(os.path.dirname(SIM_DIR), "app")


@pytest.fixture
def truth_guard(monkeypatch):
    """World.pose and World.pose_and_time raise (and are recorded) when read
    from navigation code."""
    real = World.pose
    real_timed = World.pose_and_time
    reads: list[str] = []

    def check():
        import sys
        caller = sys._getframe(2).f_code.co_filename
        inside = caller.startswith(SIM_DIR) or caller.startswith(APP_DIR)
        if inside and os.path.basename(caller) not in TRUTH_READERS:
            reads.append(caller)
            raise AssertionError(f"{caller} read the world's true pose")

    def guarded(self):
        check()
        return real.fget(self)

    def guarded_timed(self):
        check()
        return real_timed(self)

    monkeypatch.setattr(World, "pose", property(guarded))
    monkeypatch.setattr(World, "pose_and_time", guarded_timed)
    return reads


def _offline(seed=1, people=False) -> OfflinePatrol:
    op = OfflinePatrol(SimConfig(seed=seed, video=False))
    if not people:
        op.world.walkers = []
        op.world.vehicles = []
    return op


def _error(op) -> tuple[float, float]:
    t = World.pose.fget(op.world)
    x, y, th = op.nav.localiser.pose
    return math.hypot(x - t.x, y - t.y), abs((th - t.theta + math.pi) % (2 * math.pi) - math.pi)


def test_the_guard_catches_a_read_from_navigation_code(truth_guard):
    w = World()
    for read in ("w.pose", "w.pose_and_time()"):
        code = compile(read, navigation_module.__file__, "eval")
        with pytest.raises(AssertionError, match="true pose"):
            eval(code, {"w": w})
    assert truth_guard == [navigation_module.__file__] * 2


def test_scans_wait_for_odometry_that_lags_them_by_seconds(truth_guard):
    """At 20x on a busy host the MCU's reports reached the navigation up to
    seconds of sim time after the lidar saw the world; scans matched from the
    stale odometry pose fitted wrongly or not at all, and the robot got lost
    near PG-302. Here every odometry sample arrives 1.0 s late (sim): each
    scan waits for the odometry to pass its time and is matched from where
    the robot was then."""
    lag_s = 1.0
    op = _offline()
    nav_step = op.nav.step
    samples = []  # (t, pose, velocity) as the MCU measured them
    truth = []  # (t, true pose), to score the estimate at the odometry's time

    def late_step(t_s, dt, odom, vel=(0.0, 0.0), odom_t_s=None):
        samples.append((t_s, odom, vel))
        while len(samples) > 1 and samples[1][0] <= t_s - lag_s:
            samples.pop(0)  # samples[0]: the newest that has arrived
        t_odom, odom_then, vel_then = samples[0]
        return nav_step(t_s, dt, odom_then, vel_then, t_odom)

    op.nav.step = late_step
    ex = op.nav.executor
    assert ex.start(parse_route(ROUTE, GAUGES), op.t)[0]
    errs = []
    while op.t < 200 and ex.state in ACTIVE and len(op.codes("point_reached")) < 2:
        op.step()
        p = World.pose.fget(op.world)
        truth.append((op.t, p.x, p.y))
        while truth[0][0] < op.nav.odom_t - 1e-6:
            truth.pop(0)
        if abs(truth[0][0] - op.nav.odom_t) < 1e-6:
            x, y, _ = op.nav.localiser.pose
            errs.append(math.hypot(x - truth[0][1], y - truth[0][2]))
    assert truth_guard == []
    assert [d["point"] for d in op.codes("point_reached")] == ["a", "PG-302"], ex.reason
    loc = op.nav.localiser
    assert loc.lost_count == 0
    assert loc.fixes > 0.9 * loc.scans > 50
    assert np.median(errs) < 0.05 and np.max(errs) < 0.25


def test_patrol_on_the_robots_own_estimate_never_reads_the_true_pose(truth_guard):
    op = _offline()
    ex = op.nav.executor
    assert ex.start(parse_route(ROUTE, GAUGES), op.t)[0]
    errs = []
    while op.t < 300 and ex.state in ACTIVE:
        op.step()
        errs.append(_error(op))
    assert truth_guard == []
    assert ex.state == DONE
    assert [d["point"] for d in op.codes("point_reached")] == ["a", "PG-302"]
    assert op.world.collisions == []
    loc = op.nav.localiser
    assert not loc.lost and loc.lost_count == 0
    assert loc.fixes > 0.9 * loc.scans > 100  # scans matched the map all the way
    e = np.array(errs)
    assert np.median(e[:, 0]) < 0.05
    assert np.max(e[:, 0]) < 0.25
    assert np.median(e[:, 1]) < math.radians(1.0)
    # the published pose carries the estimate and its quality
    msg = op.nav.pose_message(0.0, 0.0)
    assert msg.status == P.Pose.STATUS_TRACKING
    assert 0.0 < msg.cov_xx < 0.05 and 0.5 <= msg.match_score <= 1.0
    assert (msg.x_m, msg.y_m, msg.theta_rad) == loc.pose


def _kidnapped(to: tuple[float, float, float]):
    """A patrol whose robot is carried off to ``to`` at 15 s; stepped until it
    notices."""
    op = _offline()
    ex = op.nav.executor
    assert ex.start(parse_route(ROUTE, GAUGES), op.t)[0]
    while op.t < 15:
        op.step()
    assert ex.owns_motors
    assert ex.reachable(*to[:2])
    op.world.set_pose(*to)
    t_kidnap = op.t
    while op.t < t_kidnap + 20 and not op.codes("localisation_lost"):
        op.step()
    lost = op.codes("localisation_lost")
    assert len(lost) == 1, "the robot did not notice it was carried off"
    assert ex.state == PAUSED and ex.reason == "localisation lost"
    assert op.nav.localiser.lost
    assert op.nav.pose_message(0.0, 0.0).lost
    return op, t_kidnap


def test_a_robot_carried_off_nearby_stops_finds_itself_and_goes_on(truth_guard):
    op, t_kidnap = _kidnapped((58.2, 39.0, 0.5))  # a few metres away, turned round
    ex = op.nav.executor
    while op.t < t_kidnap + 400 and ex.state != DONE:
        op.step()
    assert ex.state == DONE, (ex.reason, [(round(t), c, d) for t, c, d in op.events][-6:])
    found = op.codes("localisation_recovered")
    assert len(found) == 1 and op.codes("pose_set") == []  # by itself, not the operator
    assert len(op.codes("localisation_lost")) == 1  # reported once
    assert not op.nav.localiser.lost
    assert _error(op)[0] < 0.1
    assert truth_guard == []


def test_a_robot_carried_beyond_its_search_stops_and_waits_for_the_operator(truth_guard):
    op, t_kidnap = _kidnapped((47.6, 37.0, -1.0))  # 14 m away, by the tank T-102
    ex = op.nav.executor
    for _ in range(20):  # 2 s to brake
        op.step()
    p0 = World.pose.fget(op.world)
    while op.t < t_kidnap + 40:  # its searches (5 s apart) find nothing
        op.step()
    p1 = World.pose.fget(op.world)
    assert math.hypot(p1.x - p0.x, p1.y - p0.y) < 0.02  # no driving on a guess
    assert op.nav.localiser.lost and op.codes("localisation_recovered") == []
    assert len(op.codes("relocalisation_failed")) == 1
    assert len(op.codes("localisation_lost")) == 1  # reported once
    # the operator sets the pose near where the robot really is, then resumes
    t = World.pose.fget(op.world)
    op.nav.set_pose(t.x + 0.1, t.y - 0.1, t.theta + 0.05)
    assert not op.nav.localiser.lost
    assert op.codes("pose_set")[-1]["was_lost"] is True
    assert ex.resume()[0]
    while op.t < t_kidnap + 500 and ex.state in ACTIVE:
        op.step()
    assert ex.state == DONE, (ex.reason, [(round(t), c, d) for t, c, d in op.events][-6:])
    assert not op.nav.localiser.lost
    assert _error(op)[0] < 0.1
    assert truth_guard == []


def test_pose_message_quality_is_optional_on_the_wire():
    old = P.Pose(1.0, 2.0, 0.5, 0.1, 0.0)
    assert len(old.pack()) == 32
    back_old = P.Pose.unpack(old.pack())
    assert back_old.x_m == 1.0 and back_old.v_mps == pytest.approx(0.1) and not back_old.has_quality
    new = P.Pose(1.0, 2.0, 0.5, 0.1, 0.0, 0.0004, -0.0001, 0.0009, 1e-4, 0.93, 0.02,
                 P.Pose.STATUS_LOST)
    back = P.Pose.unpack(new.pack())
    assert len(new.pack()) == 57 and back.lost and back.has_quality
    assert back.cov_xy == pytest.approx(-0.0001) and back.match_score == pytest.approx(0.93)
    with pytest.raises(P.ProtocolError):
        P.Pose.unpack(new.pack()[:-1])
    with pytest.raises(P.ProtocolError, match="status"):
        P.Pose.unpack(new.pack()[:-1] + b"\x07")


def test_relay_refuses_missions_while_lost_and_takes_the_operators_pose():
    from sim_robot.sim import SimRobot

    from .conftest import Desk, wait_until

    r = SimRobot(SimConfig(video=False, seed=2, time_scale=5.0))
    r.world.walkers, r.world.vehicles = [], []
    r.start()
    desk = Desk(*r.address)
    try:
        assert r.relay.nav_ready.wait(30)
        wait_until(lambda: any(p.status == P.Pose.STATUS_TRACKING
                               for p in desk.of(P.MsgType.POSE)), 10)
        r.world.set_pose(58.2, 39.0, 0.5)  # carried off while standing at the dock
        ev = wait_until(lambda: desk.events("localisation_lost"), 20)
        assert ev[0].level == "alarm"
        wait_until(lambda: desk.of(P.MsgType.POSE)[-1].lost, 5)

        def cmd(name, **args):
            seq = desk.send(P.Command(name, args))
            return wait_until(lambda: desk.ack(seq), 5)

        refused = cmd("goto", x_m=62.0, y_m=45.0)
        assert not refused.ok and "localisation lost" in refused.reason
        assert not cmd("set_pose", x_m="here", y_m=39.0, theta_rad=0.5).ok
        assert not cmd("set_pose", x_m=41.0, y_m=36.0, theta_rad=0.0).ok  # inside a tank
        assert cmd("set_pose", x_m=58.3, y_m=38.9, theta_rad=0.45).ok
        wait_until(lambda: desk.events("pose_set"), 5)
        wait_until(lambda: desk.of(P.MsgType.POSE)[-1].status == P.Pose.STATUS_TRACKING, 5)
        p = desk.of(P.MsgType.POSE)[-1]
        assert math.hypot(p.x_m - 58.2, p.y_m - 39.0) < 0.2
        assert cmd("goto", x_m=60.0, y_m=42.0).ok
    finally:
        desk.close()
        r.close()


def test_standing_still_only_every_tenth_scan_is_fused():
    from sim_robot.lidar import Lidar
    from sim_robot.localisation import RobotLocaliser, load_station_map

    w = World(seed=1)
    w.walkers, w.vehicles = [], []
    lidar = Lidar(w, np.random.default_rng(3))
    start = (62.9, 45.0, math.pi)
    loc = RobotLocaliser(load_station_map(), start)
    for _ in range(30):
        loc.predict(start)
        loc.correct(lidar.scan(*start))
    assert loc.scans == 4 and loc.skipped == 26 and not loc.lost  # the first, then 1 in 10
    for k in range(1, 11):  # driving 6 cm per scan: every scan is fused
        pose = (62.9 - 0.06 * k, 45.0, math.pi)
        loc.predict(pose)
        loc.correct(lidar.scan(*pose))
    assert loc.scans == 14 and loc.skipped == 26
