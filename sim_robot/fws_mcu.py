"""The 4WS patrol robot's board (seed 004 §2.1): the patrol robot's firmware
(sensors, warning limits, link watchdog, e-stop, obstacle stop — :class:`McuModel`)
driving four steering servos and four drive motors (:class:`FwsBase`) instead
of the skid-steer base.

The relay sends the same ``MOTOR_CMD`` (v, ω) as to the patrol robot, or a
``BODY_CMD`` (v, vy, ω) with a sideways speed; the board turns it into the four
wheels' steering angles and speeds with the 4WS kinematics
(:func:`app.core.kinematics.wheel_commands`, Figs. 1–2), choosing the steering
mode by :func:`app.core.kinematics.select_mode`: PIVOT (turn in place) for ω
without v, CRAB (in-phase: all four wheels at one angle) for a sideways speed
without ω, FRONT (Ackermann-like, rear wheels straight) on gentle arcs at speed,
COUNTER (counter-phase, ICR on the lateral axis: the tightest arcs) otherwise,
the turn limited to δmax (:func:`app.core.kinematics.limit_twist`). A stop
holds the wheels' angles. The body moves by the full twist (vx, vy, ω) the
wheels' actual states give (:class:`FwsBase`) — in FRONT mode the centre slides
sideways at ω·L/2, in CRAB mode it translates at an angle — and the world
moves it so. The link watchdog, the e-stop and the obstacle stop drop the
sideways speed with the forward one.

Reports: the usual ``SENSOR_REPORT`` (its left/right wheel speeds and encoder
counts are the body motion folded onto a left and a right side, so the relay's
odometry reads it as it reads the patrol robot's) and, after it, a
``WHEEL_REPORT`` with the four wheels' angles, speeds and encoder counts and
the mode (docs/mcu-serial.md).
"""

from __future__ import annotations

import logging

from app.core.kinematics import Mode, Twist, limit_twist, realise, select_mode, wheel_commands

from .fws_base import FwsActuators, FwsBase
from .mcu import McuModel, McuThread
from .mcu_link import Ack, McuFrame, McuType, MotorCmd, WheelReport

log = logging.getLogger(__name__)

STILL_MPS = 1e-3
STILL_RPS = 1e-3
MODE_CODE = {name: i for i, name in enumerate(WheelReport.MODES)}


class FwsMcu(McuModel):
    """:class:`McuModel` with the 4WS base; ``wheel_report()`` is the last sample's
    wheels."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        w = self.world.pose
        self.base = FwsBase(actuators=FwsActuators(), pose=(w.x, w.y, w.theta))
        self.steer_mode = "stopped"
        self._v_out = 0.0
        self.target_vy = 0.0  # the sideways speed of the last BODY_CMD
        self.last_wheels = WheelReport()

    def handle(self, frame: McuFrame) -> Ack | None:
        """A ``BODY_CMD`` is a ``MOTOR_CMD`` with a sideways speed (clamped to the
        forward limit); a ``MOTOR_CMD`` sets the sideways speed back to 0."""
        m = frame.message
        if frame.msg_type == McuType.BODY_CMD:
            ack = super().handle(McuFrame(McuType.MOTOR_CMD, frame.seq,
                                          MotorCmd(m.linear_mps, m.angular_rps)))
            lim = self.robot.max_linear_mps
            ok = ack is not None and ack.status == 0
            self.target_vy = max(-lim, min(lim, m.lateral_mps)) if ok else 0.0
            return Ack(frame.msg_type, frame.seq, ack.status if ack is not None else 0)
        if frame.msg_type in (McuType.MOTOR_CMD, McuType.ESTOP):
            self.target_vy = 0.0
        return super().handle(frame)

    def step(self, t: float, dt: float):
        if self.link_lost() or self.estop:
            self.target_vy = 0.0
        return super().step(t, dt)

    def _drive(self, tv: float, tw: float, dt: float) -> tuple[float, float, float]:
        b = self.base
        if self.v < self._v_out - 1e-9:
            # the firmware braked at once (obstacle stop, e-stop, link loss)
            b.speeds[:] = 0.0
        # the obstacle stop zeroed the forward speed: no sliding on either
        vy = 0.0 if (self.target_v > 0 and tv == 0.0) else self.target_vy
        if abs(tv) < STILL_MPS and abs(tw) < STILL_RPS and abs(vy) < STILL_MPS:
            mode = "stopped"
            b.stop()
        else:
            if abs(vy) >= STILL_MPS:  # in-phase: every wheel at the travel's angle
                mode, twist = "crab", realise(b.geom, Mode.CRAB, Twist(tv, vy, 0.0))
            elif abs(tv) < STILL_MPS:
                mode, twist = "pivot", Twist(0.0, 0.0, tw)
            else:  # front steer on gentle arcs at speed, counter-phase otherwise
                lim = limit_twist(b.geom, Twist(tv, 0.0, tw))
                m = select_mode(b.geom, lim)
                mode, twist = m.value, realise(b.geom, m, lim)
            try:
                b.command(wheel_commands(b.geom, twist, hold=b.angles))
            except ValueError as e:  # beyond the servo travel: refuse, hold still
                log.warning("4WS board: %s", e)
                b.stop()
                mode = "stopped"
        self.steer_mode = mode
        b.step(dt)
        body = b.twist
        self.world.move_robot(body.vx, body.omega, dt, self.robot.radius_m, self.t,
                              lateral_mps=body.vy)
        self.v, self.w = body.vx, body.omega
        self._v_out = self.v
        half = body.omega * self.robot.track_m / 2
        self.last_wheels = WheelReport(int(self.t * 1000), MODE_CODE[mode],
                                       tuple(float(a) for a in b.angles),
                                       tuple(float(s) for s in b.speeds),
                                       tuple(int(round(t)) for t in b.ticks))
        return body.vx - half, body.vx + half, body.omega

    def wheel_report(self) -> WheelReport:
        return self.last_wheels


class FwsMcuThread(McuThread):
    """The patrol robot's MCU thread serving an :class:`FwsMcu`: each sensor
    report is followed by the wheels' report."""

    def _send(self, msg) -> None:
        super()._send(msg)
        if msg is self.model.report:
            super()._send(self.model.wheel_report())
