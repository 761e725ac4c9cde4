"""The robot's own pose estimate: dead reckoning from wheel encoders and the IMU.

Distance comes from the mean of the two encoder increments; heading from the
MCU's integrated gyro heading (or its yaw rate when that is absent), blended
with the encoder heading (a skid-steer base slips when
turning, so the encoders over-state rotation and get a small weight). Both
gyro bias and wheel slip make the estimate drift slowly, as a real one does.

Standing still (the encoders unchanged for ``STILL_SETTLE_S``) the base has
not turned either — a skid-steer body turns only by its wheels — so the
heading is held (a zero-velocity update, as INS/odometry fusion does at
rest) and what the gyro reports meanwhile is its bias: it is learnt there,
and taken off the gyro's rate while the robot drives. The gyro's bias wanders
with time: after days of runs the simulated one reads 6–7°/s on a robot
standing on its charger (the desk soak at 36x, robot hour 64), and an
estimate that integrated it turned by a radian within seconds whenever the
scan matches lapsed, lost itself on the dock and never came back.
"""

from __future__ import annotations

import math

STILL_SETTLE_S = 0.5  # the encoders unchanged this long: the base stands still
BIAS_TAU_S = 30.0  # the gyro bias estimate's memory while standing (sim seconds)


class Odometry:
    def __init__(self, ticks_per_m: float, track_m: float, x: float = 0.0, y: float = 0.0,
                 theta: float = 0.0, gyro_weight: float = 0.9) -> None:
        self.ticks_per_m = ticks_per_m
        self.track_m = track_m
        self.x, self.y, self.theta = x, y, theta
        self.v = 0.0
        self.omega = 0.0
        self.gyro_weight = gyro_weight
        self._last: tuple | None = None  # (time ms, left, right, imu heading)
        self.gyro_bias_rps = 0.0  # learnt while standing still
        self.still_s = 0.0  # how long the encoders have not changed

    def update(self, mcu_time_ms: int, enc_left: int, enc_right: int,
               yaw_rate_rps: float, imu_yaw_rad: float | None = None) -> None:
        if self._last is None:
            self._last = (mcu_time_ms, enc_left, enc_right, imu_yaw_rad)
            return
        t0, l0, r0, h0 = self._last
        self._last = (mcu_time_ms, enc_left, enc_right, imu_yaw_rad)
        dt = ((mcu_time_ms - t0) & 0xFFFFFFFF) / 1000.0
        if dt <= 0 or dt > 120.0:  # a reset MCU or a very long gap: re-anchor, no jump
            return
        ticks_l, ticks_r = _wrap32(enc_left - l0), _wrap32(enc_right - r0)
        dl = ticks_l / self.ticks_per_m
        dr = ticks_r / self.ticks_per_m
        ds = (dl + dr) / 2
        dth_enc = (dr - dl) / self.track_m
        if imu_yaw_rad is not None and h0 is not None:
            dth_gyro = (imu_yaw_rad - h0 + math.pi) % (2 * math.pi) - math.pi
        else:
            dth_gyro = yaw_rate_rps * dt
        self.still_s = self.still_s + dt if ticks_l == 0 and ticks_r == 0 else 0.0
        if self.still_s >= STILL_SETTLE_S:
            # at rest: hold the pose, learn the bias (a running mean over the
            # first BIAS_TAU_S of the stop, then an exponential one)
            a = dt / min(max(self.still_s - STILL_SETTLE_S, dt), BIAS_TAU_S)
            self.gyro_bias_rps += min(a, 1.0) * (dth_gyro / dt - self.gyro_bias_rps)
            self.v = self.omega = 0.0
            return
        dth_gyro -= self.gyro_bias_rps * dt
        dth = self.gyro_weight * dth_gyro + (1 - self.gyro_weight) * dth_enc
        mid = self.theta + dth / 2
        self.x += ds * math.cos(mid)
        self.y += ds * math.sin(mid)
        self.theta = (self.theta + dth + math.pi) % (2 * math.pi) - math.pi
        self.v = ds / dt
        self.omega = dth / dt


    def slide(self, lateral_m: float) -> None:
        """Move sideways (to the left of the heading) by ``lateral_m``: the
        body's sideways travel a base that can slide reports besides its
        forward travel (the 4WS robot: from its four wheels' encoders and
        angles, ``sim_robot.fws_robot``)."""
        self.x -= lateral_m * math.sin(self.theta)
        self.y += lateral_m * math.cos(self.theta)


def _wrap32(d: int) -> int:
    return ((d + 0x80000000) & 0xFFFFFFFF) - 0x80000000
