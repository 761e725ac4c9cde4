"""The STM32's role: sample sensors, check warning limits, drive the skid-steer base.

:class:`McuModel` is the firmware logic, stepped at the sampling rate in sim
time and fed decoded serial frames; :class:`McuThread` runs it on the board's
end of a serial link (:mod:`sim_robot.mcu_port`: a loopback socket, or a
pseudo-terminal on Unix) so the relay talks to it through pyserial, exactly as
to a real board.

The link watchdog (no valid frame for ``link_timeout_s``: stop the motors) runs on
the link's clock, wall time, because the serial link itself is real: the relay
keeps it alive every ``keepalive_s`` of wall time whatever the time scale, and the
thread reads the port before every sample, so a simulation running many times
faster than real time does not trip it. A silent link stops the robot
``link_timeout_s`` of wall time after its last frame, which at a time scale ``k``
is ``k * link_timeout_s`` of sim time (plus one sampling period) of motion. The
lock-step runners (no threads, no wall time) pass their sim clock as the link's.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable

import numpy as np

from app.comm.protocol import AlarmFlag, RobotMode

from .config import McuLimits, RobotParams
from .mcu_link import (
    Ack,
    ConfigLimits,
    Estop,
    McuDecoder,
    McuEncoder,
    McuFrame,
    McuType,
    MotorCmd,
    SensorReport,
)
from .mcu_port import FdPort, McuPort
from .sensors import Battery, Dht22, GasSensor, Imu, TurnSlip, Ultrasonic, WheelEncoders
from .world import World

log = logging.getLogger(__name__)

ACK_OK, ACK_REJECTED = 0, 1
REPORT_GAP_MAX_S = 0.2  # catching up, a report at least this often (sim time)
SIDE_OBSTACLE_FACTOR = 0.6  # side rangers stop the robot at 60 % of the front limit


def _approach(cur: float, target: float, step: float) -> float:
    return target if abs(target - cur) <= step else cur + math.copysign(step, target - cur)


class McuModel:
    def __init__(self, world: World, robot: RobotParams, limits: McuLimits | None = None,
                 seed: int = 0, link_timeout_s: float = 0.5,
                 link_clock: Callable[[], float] = time.monotonic) -> None:
        self.world = world
        self.robot = robot
        self.limits = limits or McuLimits()
        rng = np.random.default_rng(seed + 1000)
        self.gas = GasSensor(rng)
        self.dht = Dht22(rng)
        self.sonar = Ultrasonic(rng)
        self.battery = Battery()
        self.imu = Imu(rng)
        self.encoders = WheelEncoders(rng, robot.wheel_radius_m, robot.ticks_per_rev)
        self.turn_slip = TurnSlip(np.random.default_rng(seed + 2000))  # own stream
        self.link_timeout_s = link_timeout_s
        self.link_clock = link_clock
        self.last_rx = -math.inf  # link clock of the last valid frame
        self.target_v = 0.0
        self.target_w = 0.0
        self.v = 0.0
        self.w = 0.0
        self.estop = False
        self.flags = 0
        self.t = 0.0
        self.report = SensorReport()
        self.imu_yaw = 0.0  # integrated gyro heading
        self._gas_flag_on = False

    # ------------------------------------------------------------------ frames in

    def handle(self, frame: McuFrame) -> Ack | None:
        """Apply a frame from the relay; returns the ack to send (if any)."""
        self.last_rx = self.link_clock()
        m = frame.message
        if frame.msg_type == McuType.MOTOR_CMD:
            assert isinstance(m, MotorCmd)
            if self.estop and (m.linear_mps or m.angular_rps):
                return Ack(frame.msg_type, frame.seq, ACK_REJECTED)
            r = self.robot
            self.target_v = max(-r.max_linear_mps, min(r.max_linear_mps, m.linear_mps))
            self.target_w = max(-r.max_angular_rps, min(r.max_angular_rps, m.angular_rps))
            return Ack(frame.msg_type, frame.seq, ACK_OK)
        if frame.msg_type == McuType.ESTOP:
            assert isinstance(m, Estop)
            self.estop = m.engage
            if m.engage:
                self.target_v = self.target_w = self.v = self.w = 0.0
            return Ack(frame.msg_type, frame.seq, ACK_OK)
        if frame.msg_type == McuType.CONFIG:
            assert isinstance(m, ConfigLimits)
            self.limits = McuLimits(m.gas_lel_pct, m.temp_c, m.humidity_pct, m.obstacle_m,
                                    m.battery_low_v)
            return Ack(frame.msg_type, frame.seq, ACK_OK)
        return None  # keepalive: nothing to answer

    def link_lost(self) -> bool:
        return self.link_clock() - self.last_rx > self.link_timeout_s

    # ------------------------------------------------------------------ one sample

    def step(self, t: float, dt: float) -> SensorReport:
        """One sampling period ending at sim time ``t``."""
        self.t = t
        w = self.world
        p = w.pose
        lim = self.limits
        left, front, right = self.sonar.sample(w, p.x, p.y, p.theta)
        failsafe = False
        tv, tw = self.target_v, self.target_w
        if self.link_lost():
            failsafe = True
            self.target_v = self.target_w = tv = tw = 0.0
            self.v = self.w = 0.0
        if self.estop:
            tv = tw = self.v = self.w = 0.0
        blocked = front < lim.obstacle_m or min(left, right) < lim.obstacle_m * \
            SIDE_OBSTACLE_FACTOR
        if blocked and tv > 0:
            failsafe = True
            tv = 0.0
            self.v = min(self.v, 0.0)  # brake at once; turning on the spot stays allowed
        vl, vr, body_w = self._drive(tv, tw, dt)
        yaw = self.imu.sample(dt, body_w)
        self.imu_yaw = (self.imu_yaw + yaw * dt + math.pi) % (2 * math.pi) - math.pi
        enc_l, enc_r = self.encoders.step(dt, vl, vr)
        charging = w.at_dock() and abs(self.v) < 0.01 and abs(self.w) < 0.01
        bat = self.battery.step(dt, (abs(vl) + abs(vr)) / 2, charging)
        gas = self.gas.sample(t, w.gas_lel_pct(p.x, p.y, t))
        temp, hum = self.dht.sample(t, *w.ambient(t))

        flags = 0
        # gas keeps its alarm until 80 % of the limit (hysteresis against noise)
        self._gas_flag_on = gas > lim.gas_lel_pct or (self._gas_flag_on
                                                       and gas > 0.8 * lim.gas_lel_pct)
        if self._gas_flag_on:
            flags |= AlarmFlag.GAS_HIGH
        if temp > lim.temp_c:
            flags |= AlarmFlag.TEMP_HIGH
        if hum > lim.humidity_pct:
            flags |= AlarmFlag.HUMIDITY_HIGH
        if min(left, front, right) < lim.obstacle_m:
            flags |= AlarmFlag.OBSTACLE_NEAR
        if bat < lim.battery_low_v:
            flags |= AlarmFlag.BATTERY_LOW
        if failsafe:
            flags |= AlarmFlag.FAILSAFE_STOP
        if self.estop:
            flags |= AlarmFlag.ESTOP
        self.flags = int(flags)
        if self.estop:
            mode = RobotMode.ESTOP
        elif failsafe:
            mode = RobotMode.FAILSAFE
        elif self.target_v or self.target_w:
            mode = RobotMode.TELEOP
        elif charging:
            mode = RobotMode.DOCKED
        else:
            mode = RobotMode.IDLE
        self.report = SensorReport(
            int(t * 1000), gas, temp, hum, left, front, right, bat, vl, vr, yaw, enc_l, enc_r,
            self.v, self.w, self.flags, int(mode), self.imu_yaw)
        return self.report


    def _drive(self, tv: float, tw: float, dt: float) -> tuple[float, float, float]:
        """The base: approach the target speeds (tv, tw) at the acceleration limits,
        move the robot; returns the left and right side's speeds and the body's
        yaw rate (the skid-steer base here; another base overrides this)."""
        r = self.robot
        slowing = abs(tv) < abs(self.v) or tv * self.v < 0
        self.v = _approach(self.v, tv, (r.brake_mps2 if slowing else r.accel_mps2) * dt)
        self.w = _approach(self.w, tw, r.angular_accel_rps2 * dt)
        half = self.w * r.track_m * r.skid_factor / 2
        vl, vr = self.v - half, self.v + half
        body_w = (vr - vl) / (r.track_m * r.skid_factor) * (1 - self.turn_slip.step(dt, self.w))
        self.world.move_robot((vl + vr) / 2, body_w, dt, r.radius_m, self.t)
        return vl, vr, body_w


class McuThread(threading.Thread):
    """Serves an :class:`McuModel` on the board's end of a serial link: a
    :class:`~sim_robot.mcu_port.McuPort`, or a file descriptor (a pty master)."""

    def __init__(self, model: McuModel, port: McuPort | int, clock,
                 rate_hz: float = 20.0) -> None:
        super().__init__(name="mcu", daemon=True)
        self.model = model
        self.port = FdPort(port) if isinstance(port, int) else port
        self.clock = clock
        self.period = 1.0 / rate_hz
        self.decoder = McuDecoder()
        self.encoder = McuEncoder()
        self.tx_dropped = 0
        # One report per sampling period of sim time, as the board does, but at
        # most ~500 a second of wall time (a very high time scale would flood
        # the port; up to 25x a 20 Hz board keeps its own rate, so the relay's
        # odometry is as fresh as on the real robot).
        scale = float(getattr(clock, "time_scale", 1.0))
        self.min_report_wall_s = max(0.9 * self.period / scale, 0.002)
        self._last_report = -math.inf
        self._last_report_t = -math.inf  # sim time of the last report sent
        self._halt = threading.Event()

    def stop(self) -> None:
        self._halt.set()

    def _send(self, msg) -> None:
        data = self.encoder.encode(msg)
        try:
            self.port.write(data)
        except BlockingIOError:
            self.tx_dropped += 1  # nobody reads the port: drop like a full UART buffer

    def _take(self, timeout_s: float) -> bool:
        """Read what the port has (waiting up to ``timeout_s``) and apply its frames;
        False when the port was closed under us."""
        try:
            data = self.port.read(timeout_s)
        except (OSError, ValueError):
            return False
        if data:
            for frame in self.decoder.feed(data):
                ack = self.model.handle(frame)
                if ack is not None:
                    self._send(ack)
        return True

    def run(self) -> None:
        t_next = self.clock.now() + self.period
        t_prev = self.clock.now()
        # the clock waits for this loop as for the navigation (SimClock); it
        # starts here (sim time held for it since the robot was built must
        # now run on to its first sample)
        step_done = getattr(self.clock, "control_step", None)
        if step_done is not None:
            step_done(t_prev, "board")
        while not self._halt.is_set():
            wait = max(0.002, self.clock.wall_until(t_next))
            if not self._take(min(wait, 0.05)):
                break
            now = self.clock.now()
            if now < t_next:
                continue
            # catch up in whole sampling periods (many per wake-up at a high time scale)
            # The reports of a catch-up are thinned, but one goes out at least
            # every REPORT_GAP_MAX_S of sim time: the relay's odometry integrates
            # each report's increment as one arc, and an arc over seconds of
            # turning is no pose (the estimate jumped metres after a stall).
            # Before each sample the port is read again (without waiting): the link
            # watchdog runs on the link's clock, and frames that arrived while this
            # thread was busy sampling must reach it; at a high time scale a catch-up
            # can take longer than the watchdog's limit, and the robot then stopped
            # on a healthy link.
            n = 0
            while t_next <= now and n < 400:
                if n and not self._take(0.0):
                    return
                rep = self.model.step(t_next, t_next - t_prev)
                t_prev, t_next = t_next, t_next + self.period
                n += 1
                if t_next <= now and t_prev - self._last_report_t >= REPORT_GAP_MAX_S - 1e-9:
                    self._last_report_t = t_prev
                    self._send(rep)
            if t_next <= now:  # far behind: skip ahead rather than spiral
                t_prev, t_next = now, now + self.period
            if step_done is not None:
                step_done(t_prev, "board")
            mono = time.monotonic()
            if mono - self._last_report >= self.min_report_wall_s:
                self._last_report = mono
                self._last_report_t = t_prev
                self._send(self.model.report)
