"""The wall climber's STM32: drives the crawler on the wall, samples its wheel
encoders, gyro and ultrasonic thickness probe, and talks to the relay through
the same serial framing as the patrol robot's board (docs/mcu-serial.md).

:class:`ClimberMcu` is the firmware logic (stepped in sim time by the patrol
robot's :class:`~sim_robot.mcu.McuThread`); each sample's sensor report is the
patrol robot's ``SensorReport`` (encoders, yaw rate, battery, and in the
IMU heading field the heading from the accelerometer's view of gravity —
absolute on a vertical wall, :mod:`.accelerometer`; the gas, climate and
ranging fields hold fixed "not fitted" values: no gas, 20 °C, 50 %RH, the
ranger's 4 m maximum), and each probe sample is a
``ProbeReport`` frame (``PROBE_REPORT``, 0x03). :class:`ClimberMcuThread` sends
the probe samples queued since the last report right after it.

A contact (the body stopped at the wall's top or bottom or at an obstacle:
:class:`~.kinematics.ClimberBody` with :class:`~.contact.WallContact`, its
wheels stalling) raises the report's ``OBSTACLE_NEAR`` flag, as the patrol
robot's board raises it at an obstacle; the climber has no rangers, so on its
board the flag means a contact (a stall or a bumper on a real one). It is held
``CONTACT_HOLD_S`` after the last step in contact, so that a report thinned out
at a high time scale does not lose a short one.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable

import numpy as np

from app.comm.protocol import AlarmFlag, RobotMode

from ..config import McuLimits
from ..mcu import ACK_OK, ACK_REJECTED, McuThread
from ..mcu_link import (
    Ack,
    ConfigLimits,
    McuFrame,
    McuType,
    ProbeReport,
    SensorReport,
)
from ..sensors import Battery, Imu, WheelEncoders
from .accelerometer import WallAccelerometer
from .kinematics import ClimberBody, ClimberParams
from .wall_world import WallWorld

NOT_FITTED = {"gas_lel_pct": 0.0, "temp_c": 20.0, "humidity_pct": 50.0, "range_m": 4.0}
PROBE_QUEUE = 4096  # samples kept while the relay does not read (like a UART FIFO)
CONTACT_HOLD_S = 0.5  # the contact flag stays raised this long after the last contact


class ClimberMcu:
    """The climber's board: motors, encoders, gyro, probe. ``body`` holds the
    true pose (ground truth: the relay never sees it)."""

    def __init__(self, world: WallWorld, body: ClimberBody, limits: McuLimits | None = None,
                 seed: int = 0, link_timeout_s: float = 0.5,
                 link_clock: Callable[[], float] = time.monotonic,
                 imu_walk: float = 2e-6) -> None:
        self.world = world
        self.body = body
        p: ClimberParams = body.p
        self.params = p
        self.limits = limits or McuLimits()
        rng = np.random.default_rng(seed + 1000)
        self.imu = Imu(rng, walk_rps_per_sqrt_s=imu_walk)
        self.accel = WallAccelerometer(rng)
        self.encoders = WheelEncoders(rng, p.wheel_radius_m, p.ticks_per_rev, slip=0.0)
        self.battery = Battery()
        self.link_timeout_s = link_timeout_s
        self.link_clock = link_clock
        self.last_rx = -math.inf
        self.target_v = self.target_w = 0.0
        self.estop = False
        self.imu_yaw = 0.0
        self.ticks = (0, 0)
        self.report = SensorReport()
        self.t_s = 0.0  # sim time of the last step: the time of the body's state
        self._touched_t = -math.inf  # sim time of the last step stopped by a contact
        self.probes: deque[ProbeReport] = deque(maxlen=PROBE_QUEUE)
        # ground truth for evaluation only (never sent): cells the probe truly read
        self.probed = np.zeros(world.blocked.shape, bool)

    @property
    def probe_lead_m(self) -> float:
        """The probe sits at the body's front face, L/2 ahead of the axle (seed 001 Fig. 2)."""
        return self.params.length_m / 2

    def handle(self, frame: McuFrame) -> Ack | None:
        self.last_rx = self.link_clock()
        m = frame.message
        if frame.msg_type == McuType.MOTOR_CMD:
            if self.estop and (m.linear_mps or m.angular_rps):
                return Ack(frame.msg_type, frame.seq, ACK_REJECTED)
            p = self.params
            self.target_v = max(-p.v_max_mps, min(p.v_max_mps, m.linear_mps))
            self.target_w = max(-p.omega_max_rps, min(p.omega_max_rps, m.angular_rps))
            return Ack(frame.msg_type, frame.seq, ACK_OK)
        if frame.msg_type == McuType.ESTOP:
            self.estop = bool(m.engage)
            if self.estop:
                self.target_v = self.target_w = 0.0
            return Ack(frame.msg_type, frame.seq, ACK_OK)
        if frame.msg_type == McuType.CONFIG:
            assert isinstance(m, ConfigLimits)
            self.limits = McuLimits(m.gas_lel_pct, m.temp_c, m.humidity_pct, m.obstacle_m,
                                    m.battery_low_v)
            return Ack(frame.msg_type, frame.seq, ACK_OK)
        return None

    def step(self, t: float, dt: float) -> SensorReport:
        failsafe = self.link_clock() - self.last_rx > self.link_timeout_s
        if failsafe:
            self.target_v = self.target_w = 0.0
        v, w = (0.0, 0.0) if self.estop else (self.target_v, self.target_w)
        vl, vr, w_true = self.body.step(v, w, dt)
        self.t_s = t
        s = self.body.s
        yaw = self.imu.sample(dt, w_true)
        fx, fy = self.accel.sample(dt, s.theta_rad, self.body.v_true_mps, w_true)
        # the IMU heading field carries the accelerometer's gravity heading
        # (absolute on the wall), not an integrated gyro
        self.imu_yaw = self.accel.heading(dt, fx, fy, (vl + vr) / 2, yaw)
        self.ticks = self.encoders.step(dt, vl, vr)
        bat = self.battery.step(dt, (abs(vl) + abs(vr)) / 2, False)
        lead = self.probe_lead_m
        px, py = s.x_m + lead * math.cos(s.theta_rad), s.y_m + lead * math.sin(s.theta_rad)
        mm = self.world.probe(px, py)
        if mm is not None:
            cell = self.world.cell_of(px, py)
            if cell is not None:
                self.probed[cell] = True
        t_ms = int(t * 1000)
        self.probes.append(ProbeReport(t_ms, ProbeReport.NO_ECHO if mm is None
                                       else max(0, min(65534, round(mm * 1000)))))
        flags = 0
        if self.body.touching:
            self._touched_t = t
        if t - self._touched_t <= CONTACT_HOLD_S:
            flags |= AlarmFlag.OBSTACLE_NEAR
        if bat < self.limits.battery_low_v:
            flags |= AlarmFlag.BATTERY_LOW
        if failsafe:
            flags |= AlarmFlag.FAILSAFE_STOP
        if self.estop:
            flags |= AlarmFlag.ESTOP
        mode = (RobotMode.ESTOP if self.estop else RobotMode.FAILSAFE if failsafe
                else RobotMode.TELEOP if (v or w) else RobotMode.IDLE)
        r = NOT_FITTED["range_m"]
        self.report = SensorReport(
            t_ms, NOT_FITTED["gas_lel_pct"], NOT_FITTED["temp_c"], NOT_FITTED["humidity_pct"],
            r, r, r, bat, vl, vr, yaw, self.ticks[0], self.ticks[1], s.v_mps, s.omega_rps,
            int(flags), int(mode), self.imu_yaw)
        return self.report

    def take_probes(self) -> list[ProbeReport]:
        out = list(self.probes)
        self.probes.clear()
        return out


class ClimberMcuThread(McuThread):
    """The patrol robot's MCU thread serving a :class:`ClimberMcu`; the probe
    samples queued since the last sensor report follow it on the wire."""

    def _send(self, msg) -> None:
        super()._send(msg)
        if isinstance(msg, SensorReport):
            for p in self.model.take_probes():
                super()._send(p)
