"""The relay's own pose for the climber: encoders, gyro and the board's
gravity heading into the wall EKF (app/core/localisation/wall_ekf.py), with the
camera's sightings of seams and rims carried back to the estimate's time. No
ground truth: the MCU's reports and the camera's frames only.
"""

from __future__ import annotations

import math
from collections import deque

from app.core.localisation.ekf import interval_rate
from app.core.localisation.wall_ekf import WallEkf

from .kinematics import ClimberParams

MAX_SIGHTING_LAG_S = 0.25  # camera sightings further than this from the estimate are dropped
MAX_WAITING = 400  # camera sightings held for the estimate to reach their time
BOARD_SAMPLE_S = 0.05  # the board's sampling period (20 Hz): what one gyro sample covers


class ClimberOdometry:
    """Encoders, gyro and the accelerometer's gravity heading into the wall EKF
    (app/core/localisation/wall_ekf.py); the relay's ``odom`` for the climber
    (the same ``update`` call as the patrol robot's
    :class:`sim_robot.odometry.Odometry`: on the climber's board the report's
    IMU heading is the accelerometer's, absolute on a vertical wall). The
    gyro's bias is the filter's state (:attr:`WallEkf.gyro_bias`), learnt
    wherever the encoders and the gravity heading hold the heading still. (A
    mean rate over the reports with no encoder tick took samples of a turn's
    slow start or end, slower than a tick per report, and with a few such
    among the few at rest before the first move it put the bias 22 mrad/s
    off: the first lanes leant by up to 90 mrad with the heading believed to
    1.5 mrad, docs/climber.md.)

    A report's gyro sample is the rate over the board's last sampling period
    only; when reports are lost or thinned (a busy link or host: at a high
    time scale the simulated board sends one in two to four) the rest of the
    interval is taken from the previous sample and this one
    (:func:`~app.core.localisation.ekf.interval_rate`), its uncertainty added
    to the gyro's, so that the encoders and the gravity heading weigh in where
    the rate changed unseen (a turn's start, end or reversal)."""

    def __init__(self, params: ClimberParams, x: float, y: float, theta: float) -> None:
        self.ticks_per_m = params.ticks_per_rev / (2 * math.pi * params.wheel_radius_m)
        self.ekf = WallEkf(x, y, theta, track_m=params.track_m)
        self._last: tuple[int, int, int] | None = None
        self.v = self.omega = 0.0
        self.t_s: float | None = None  # MCU time of the last report folded in
        self.sample_s = BOARD_SAMPLE_S  # shortened by a shorter report interval seen
        self._gyro_prev: float | None = None  # the last report's gyro rate

    @property
    def x(self) -> float:
        return self.ekf.pose[0]

    @property
    def y(self) -> float:
        return self.ekf.pose[1]

    @property
    def theta(self) -> float:
        return self.ekf.pose[2]

    @property
    def bias(self) -> float:
        """The gyro's bias as the filter has learnt it (rad/s)."""
        return self.ekf.gyro_bias

    @property
    def sigma_m(self) -> float:
        p = self.ekf.covariance
        return float(math.sqrt(max(0.0, p[0, 0] + p[1, 1])))

    def update(self, mcu_time_ms: int, enc_l: int, enc_r: int, yaw_rate_rps: float,
               imu_yaw_rad: float | None = None) -> None:
        if self._last is None:
            self._last = (mcu_time_ms, enc_l, enc_r)
            return
        t0, l0, r0 = self._last
        self._last = (mcu_time_ms, enc_l, enc_r)
        dt = ((mcu_time_ms - t0) & 0xFFFFFFFF) / 1000.0
        if dt <= 0 or dt > 5.0:
            return
        dl, dr = (enc_l - l0) / self.ticks_per_m, (enc_r - r0) / self.ticks_per_m
        # the report's own rates carry the pose over its interval, so that the
        # gravity heading taken at its end finds no lag (WallEkf.advance)
        self.sample_s = min(self.sample_s, dt)
        gyro, unseen = interval_rate(self._gyro_prev, yaw_rate_rps, dt, self.sample_s)
        self._gyro_prev = yaw_rate_rps
        self.ekf.advance(dt, dl, dr, gyro, unseen)
        if imu_yaw_rad is not None:
            self.ekf.update_gravity_heading(imu_yaw_rad)
        st = self.ekf.state
        self.v, self.omega = float(st[3]), float(st[5])
        self.t_s = mcu_time_ms / 1000.0

    def seam_seen(self, seams, horizontal: bool, angle_rad: float, lead_m: float,
                  circ_m: float, offset_m: float = 0.0, t_s: float | None = None) -> bool:
        """A camera sighting taken at time ``t_s`` (same clock as the MCU's):
        the estimate is that of the last report, so the offset is carried
        back over the distance the camera moved since (v along the heading,
        lead·ω across it) and the seam's direction in the image over the turn
        made since (ω), else the
        lag would push every fix the way the robot drives or turns. A sighting
        more than MAX_SIGHTING_LAG_S from the estimate (a starved process) is
        not used: the carrying back assumes steady speeds."""
        if t_s is not None and self.t_s is not None:
            lag = t_s - self.t_s
            if abs(lag) > MAX_SIGHTING_LAG_S:
                return False
            th = self.ekf.pose[2]
            # the camera, lead_m ahead of the axle, moves at v along the heading
            # and lead·ω across it
            if horizontal:
                offset_m += lag * (self.v * math.sin(th) + lead_m * self.omega * math.cos(th))
            else:
                offset_m += lag * (self.v * math.cos(th) - lead_m * self.omega * math.sin(th))
            angle_rad += self.omega * lag  # the image's angle is along − θ
        return self.ekf.seam_seen(seams, horizontal, lead_m, circ_m, angle_rad, offset_m)

    def rim_seen(self, discs, fwd_m: float, left_m: float, centre_fwd_m: float,
                 centre_left_m: float, lead_m: float, circ_m: float,
                 t_s: float | None = None) -> bool:
        """A rim sighting taken at ``t_s``: the offsets (body frame) to the rim's
        nearest point and to its centre carried back to the estimate's time as
        in :meth:`seam_seen` (the camera moves v forward and lead·ω to the left;
        the body turns by ω·lag), then :meth:`WallEkf.rim_seen`."""
        pts = [(fwd_m, left_m), (centre_fwd_m, centre_left_m)]
        if t_s is not None and self.t_s is not None:
            lag = t_s - self.t_s
            if abs(lag) > MAX_SIGHTING_LAG_S:
                return False
            a = self.omega * lag  # the body at t_s is turned by a from the estimate's
            c, s = math.cos(a), math.sin(a)
            pts = [(c * f - s * lf + lag * self.v, s * f + c * lf + lag * lead_m * self.omega)
                   for f, lf in pts]
        return self.ekf.rim_seen(discs, lead_m, circ_m, *pts[0], *pts[1])


class Sightings:
    """Camera sightings waiting for the estimate to reach their time.

    The camera shows the body as it is now; the estimate is that of the last
    MCU report folded in, which a busy link or host leaves behind by more than
    :data:`MAX_SIGHTING_LAG_S`. A sighting used at once would then be dropped
    (or, carried back over seconds, wrong), and a starved relay would drive on
    dead reckoning alone: the climber's slip on climbs puts its belief 0.3 m
    above the truth within a few lanes. So each sighting waits here until the
    estimate is within MAX_SIGHTING_LAG_S of its time (:meth:`due`, called
    after every report and every navigation step); one the estimate has passed
    by more than that is dropped and counted. A frame with the time of the one
    before it is the same picture and is not queued again."""

    def __init__(self, capacity: int = MAX_WAITING) -> None:
        self._q: deque[tuple[float, str, tuple]] = deque()
        self._last_t: dict[str, float] = {}
        self.capacity = capacity
        self.dropped = 0  # passed by the estimate before they could be used, or overflowed

    def __len__(self) -> int:
        return len(self._q)

    def add(self, kind: str, t_s: float, items) -> None:
        """One camera frame's sightings of ``kind`` ("seam" or "rim"), taken at ``t_s``."""
        if self._last_t.get(kind) == t_s:
            return
        self._last_t[kind] = t_s
        for it in items:
            if len(self._q) >= self.capacity:
                self._q.popleft()
                self.dropped += 1
            self._q.append((t_s, kind, tuple(it)))

    def due(self, t_est: float | None) -> list[tuple[float, str, tuple]]:
        """The sightings the estimate at ``t_est`` (None: no report yet) can use
        now, oldest first; those it has passed by more than MAX_SIGHTING_LAG_S are
        dropped."""
        out = []
        q = self._q
        while q and (t_est is None or q[0][0] <= t_est + MAX_SIGHTING_LAG_S):
            item = q.popleft()
            if t_est is not None and item[0] < t_est - MAX_SIGHTING_LAG_S:
                self.dropped += 1
            else:
                out.append(item)
        return out
