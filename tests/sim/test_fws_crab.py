"""Crab driving on the simulated 4WS robot: the board takes a body twist with a
sideways speed (MCU ``BODY_CMD``), steers all four wheels to one angle and the
world moves the body sideways; the relay's odometry recovers the sideways
travel from the wheel reports; the skid-steer world step is unchanged."""

import math

import numpy as np
import pytest

from app.core.kinematics import FwsGeometry
from sim_robot.config import RobotParams
from sim_robot.fws_base import FwsActuators
from sim_robot.fws_mcu import FwsMcu
from sim_robot.fws_robot import wheel_travel
from sim_robot.mcu_link import BodyCmd, McuDecoder, McuEncoder, MotorCmd
from sim_robot.odometry import Odometry
from sim_robot.world import World

OPEN = (65.0, 15.0)  # an open spot of the station (checked below)


class _Board:
    def __init__(self, theta=0.3):
        self.world = World(seed=0)
        self.world.set_pose(OPEN[0], OPEN[1], theta)
        self.t = 0.0
        self.mcu = FwsMcu(self.world, RobotParams(), seed=0, link_clock=lambda: self.t)
        self.enc, self.dec = McuEncoder(), McuDecoder()
        self.reports = []

    def send(self, msg):
        acks = [self.mcu.handle(f) for f in self.dec.feed(self.enc.encode(msg))]
        assert acks and acks[0] is not None and acks[0].status == 0

    def run(self, seconds, keep=None):
        for _ in range(int(round(seconds / 0.05))):
            self.t += 0.05
            if keep is not None:
                self.send(keep)
            self.mcu.step(self.t, 0.05)
            self.reports.append(self.mcu.wheel_report())


def _body_frame(p0, p1):
    dx, dy = p1.x - p0.x, p1.y - p0.y
    c, s = math.cos(p0.theta), math.sin(p0.theta)
    return c * dx + s * dy, -s * dx + c * dy


def test_a_body_command_drives_the_robot_sideways_in_crab_mode():
    b = _Board()
    assert b.world.clearance(*OPEN) > 2.0
    p0 = b.world.pose
    cmd = BodyCmd(0.1, 0.15, 0.0)  # 56° off the heading: within the servo travel
    b.run(4.0, keep=cmd)
    p1 = b.world.pose
    fwd, left = _body_frame(p0, p1)
    assert left > 0.4 and math.degrees(math.atan2(left, fwd)) == pytest.approx(56.3, abs=3)
    assert abs(p1.theta - p0.theta) < 1e-6  # no rotation
    last = b.reports[-1]
    assert last.mode == 3  # crab
    assert np.ptp(last.angles_rad) < 1e-6  # all four wheels at one angle
    assert last.angles_rad[0] == pytest.approx(math.atan2(0.15, 0.1), abs=0.02)
    # a MOTOR_CMD sets the sideways speed back to 0
    b.send(MotorCmd(0.0, 0.0))
    b.run(1.5)
    assert b.mcu.target_vy == 0.0 and b.reports[-1].mode == 0
    p2 = b.world.pose
    b.run(0.5)
    assert math.hypot(b.world.pose.x - p2.x, b.world.pose.y - p2.y) < 1e-9


def test_link_loss_stops_the_sideways_motion():
    b = _Board()
    b.run(2.0, keep=BodyCmd(0.1, 0.15, 0.0))
    assert b.reports[-1].mode == 3
    b.run(3.0)  # no frames: the watchdog (0.5 s of link time) trips
    assert b.mcu.target_vy == 0.0
    p = b.world.pose
    b.run(0.5)
    assert math.hypot(b.world.pose.x - p.x, b.world.pose.y - p.y) < 1e-9


def test_odometry_recovers_the_sideways_travel_from_the_wheel_reports():
    b = _Board(theta=-1.1)
    act = FwsActuators()
    tpm = act.ticks_per_rev / (2 * math.pi * act.wheel_radius_m)
    p0 = b.world.pose
    odo = Odometry(1.0, 0.5, p0.x, p0.y, p0.theta)
    b.run(3.0, keep=BodyCmd(0.1, -0.15, 0.0))
    geom = FwsGeometry()
    for prev, cur in zip(b.reports[:-1], b.reports[1:], strict=True):
        move = wheel_travel(geom, prev, cur, tpm)
        # the forward travel and the turn are the sensor report's; here only the slide
        c, s = math.cos(odo.theta), math.sin(odo.theta)
        odo.x, odo.y = odo.x + c * move.vx, odo.y + s * move.vx
        odo.slide(move.vy)
    p1 = b.world.pose
    assert math.hypot(p1.x - p0.x, p1.y - p0.y) > 0.3
    assert odo.x == pytest.approx(p1.x, abs=0.02) and odo.y == pytest.approx(p1.y, abs=0.02)
    # without the sideways term the odometry would be off by the whole slide
    assert abs(_body_frame(p0, p1)[1]) > 0.25


def test_wheel_travel_refuses_a_reset_board():
    b = _Board()
    b.run(0.2, keep=BodyCmd(0.1, 0.1, 0.0))
    a, c = b.reports[-1], b.reports[0]
    assert wheel_travel(FwsGeometry(), a, c, 1000.0) is None  # time ran backwards


def test_the_skid_steer_step_is_a_unicycle_step():
    w = World(seed=0)
    w.set_pose(OPEN[0], OPEN[1], 0.5)
    w.move_robot(0.5, 0.2, 1.0, 0.3, 0.0)
    p = w.pose
    a = 0.5 + 0.1  # the mid-step heading
    assert p.x == pytest.approx(OPEN[0] + 0.5 * math.cos(a), abs=0.01)
    assert p.y == pytest.approx(OPEN[1] + 0.5 * math.sin(a), abs=0.01)
    assert p.theta == pytest.approx(0.7)
