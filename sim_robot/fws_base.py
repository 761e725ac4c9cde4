"""The four-wheel independent-steering base as the MCU drives it (seed 004
§2.1): four steering servos and four drive motors, with their encoders.

A building block for the simulated 4WS robot (issue 15, item 5): it takes the
per-wheel commands of :func:`app.core.kinematics.wheel_commands`, moves each
servo at its slew rate and each motor at its acceleration limit, and moves
the body with the twist the wheels' actual states imply
(:func:`app.core.kinematics.body_twist`, least squares over the eight
rolling constraints) — so while the servos are still turning the wheels
disagree and the residual is reported as slip. A motor is held at rest while
its servo is more than ``align_tol_rad`` from its target (the firmware's
interlock: no driving a wheel sideways). The pose update is the exact arc
(Fig. 3). Bad commands (wrong length, not finite) are refused and counted.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from app.core.kinematics import FwsGeometry, Twist, WheelCommand, body_twist, integrate_pose

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FwsActuators:
    servo_rate_rps: float = 3.0  # steering slew rate, rad/s
    motor_accel_mps2: float = 1.5
    align_tol_rad: float = math.radians(10.0)
    wheel_radius_m: float = 0.1
    ticks_per_rev: int = 1024


class FwsBase:
    """State: ``angles`` and ``speeds`` of the four wheels (FL, FR, RL, RR),
    encoder ``ticks`` (float, signed), ``pose`` (x, y, θ), ``slip_mps`` of the
    last step, ``rejected`` commands."""

    def __init__(self, geometry: FwsGeometry | None = None,
                 actuators: FwsActuators | None = None, pose=(0.0, 0.0, 0.0)):
        self.geom = geometry or FwsGeometry()
        self.act = actuators or FwsActuators()
        self.angles = np.zeros(4)
        self.speeds = np.zeros(4)
        self.ticks = np.zeros(4)
        self.target_angles = np.zeros(4)
        self.target_speeds = np.zeros(4)
        self.pose = tuple(float(v) for v in pose)
        self.slip_mps = 0.0
        self.twist = Twist(0.0)  # the body twist of the last step
        self.rejected = 0

    def command(self, cmd: WheelCommand) -> bool:
        """Set the wheels' targets; False (and counted) for a bad command."""
        a = np.asarray(cmd.angles_rad, dtype=float)
        s = np.asarray(cmd.speeds_mps, dtype=float)
        if a.shape != (4,) or s.shape != (4,) or not np.all(np.isfinite(np.r_[a, s])):
            self.rejected += 1
            log.warning("4WS base: refused a wheel command %r (need 4 finite angles and speeds)",
                        cmd)
            return False
        g = self.geom
        self.target_angles = np.clip(a, -g.servo_range_rad, g.servo_range_rad)
        self.target_speeds = np.clip(s, -g.max_wheel_speed_mps, g.max_wheel_speed_mps)
        return True

    def stop(self) -> None:
        self.target_speeds = np.zeros(4)

    def step(self, dt: float) -> None:
        act = self.act
        err = self.target_angles - self.angles
        self.angles += np.clip(err, -act.servo_rate_rps * dt, act.servo_rate_rps * dt)
        aligned = np.abs(self.target_angles - self.angles) <= act.align_tol_rad
        want = np.where(aligned, self.target_speeds, 0.0)
        dv = np.clip(want - self.speeds, -act.motor_accel_mps2 * dt, act.motor_accel_mps2 * dt)
        self.speeds += dv
        tw, self.slip_mps = body_twist(self.geom, WheelCommand(tuple(self.angles),
                                                               tuple(self.speeds)))
        self.twist = tw
        self.pose = integrate_pose(self.pose, tw, dt)
        rev = self.speeds * dt / (2.0 * math.pi * act.wheel_radius_m)
        self.ticks += rev * act.ticks_per_rev

    def wheel_state(self) -> dict:
        """The four wheels' angles (degrees) and speeds (m/s) for the desk."""
        names = ("front_left", "front_right", "rear_left", "rear_right")
        return {n: {"angle_deg": float(math.degrees(a)), "speed_mps": float(s)}
                for n, a, s in zip(names, self.angles, self.speeds, strict=True)}
