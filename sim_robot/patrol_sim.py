"""Run a patrol without threads or sockets: the world, the MCU model and the
navigation stack stepped in lock-step on one sim clock, as fast as the host
allows. Motor commands still go to the MCU model as MOTOR_CMD frames (encoded
and decoded as on the serial link), so its acceleration limits and its own
obstacle stop stay in force. Used by tests/sim/test_patrol.py and
bench/patrol_bench.py.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

from .config import SimConfig
from .mcu import McuModel
from .mcu_link import Keepalive, McuDecoder, McuEncoder, MotorCmd
from .navigation import Navigation
from .odometry import Odometry
from .patrol import ACTIVE, PatrolConfig
from .route import Route
from .world import World

log = logging.getLogger(__name__)


@dataclass
class OfflinePatrol:
    cfg: SimConfig = field(default_factory=SimConfig)
    # no camera stream to wait for when running in lock-step
    patrol: PatrolConfig = field(default_factory=lambda: PatrolConfig(inspect_min_wall_s=0.0))
    world: World | None = None

    def __post_init__(self) -> None:
        self.t = 0.0
        self.world = self.world or World(self.cfg.station_file, self.cfg.seed)
        self.world.clock = lambda: self.t
        r = self.cfg.robot
        self.mcu = McuModel(self.world, r, self.cfg.limits, self.cfg.seed,
                            link_clock=lambda: self.t)
        p = self.world.pose
        self.odom = Odometry(r.ticks_per_rev / (2 * math.pi * r.wheel_radius_m), r.track_m,
                             p.x, p.y, p.theta)
        self.events: list[tuple[float, str, dict]] = []
        self.published: list[object] = []
        self.camera_target: str | None = None
        self.nav = Navigation(self.world, self.cfg.seed, self._emit, self.published.append,
                              self._look_at, self.patrol, self.cfg.lidar_beams,
                              self.cfg.lidar_range_m, initial_pose=(p.x, p.y, p.theta))
        self._enc = McuEncoder()
        self._dec = McuDecoder()
        self.min_clearance_m = math.inf

    def _emit(self, level: str, code: str, text: str, **data) -> None:
        log.debug("%s: %s", code, text)
        self.events.append((self.t, code, data))

    def _look_at(self, gauge: str | None) -> None:
        self.camera_target = gauge

    def _send(self, msg) -> None:
        for fr in self._dec.feed(self._enc.encode(msg)):
            self.mcu.handle(fr)

    def pause(self, reason: str = "operator") -> tuple[bool, str]:
        """Pause the mission and stop the motors, as the relay does for pause_patrol."""
        out = self.nav.executor.pause(reason)
        self._send(MotorCmd(0.0, 0.0))
        return out

    def codes(self, code: str) -> list[dict]:
        return [d for _, c, d in self.events if c == code]

    def step(self) -> None:
        """One control period: the MCU samples (20 Hz), then the navigation decides."""
        mcu_dt = 1.0 / self.cfg.mcu_rate_hz
        n = max(1, round(self.patrol.control_dt_s / mcu_dt))
        for _ in range(n):
            self.t += mcu_dt
            rep = self.mcu.step(self.t, mcu_dt)
            self.odom.update(rep.mcu_time_ms, rep.enc_left_ticks, rep.enc_right_ticks,
                             rep.yaw_rate_rps, rep.imu_yaw_rad)
        o = self.odom
        v, w, send = self.nav.step(self.t, n * mcu_dt, (o.x, o.y, o.theta), (o.v, o.omega))
        self._send(MotorCmd(v, w) if send else Keepalive())
        p = self.world.pose
        self.min_clearance_m = min(self.min_clearance_m, self.world.clearance(p.x, p.y))

    def run(self, route: Route | None = None, max_sim_s: float = 1800.0) -> str:
        """Start ``route`` (if given) and step until the mission ends or time runs
        out; returns the executor's final state."""
        ex = self.nav.executor
        if route is not None:
            ok, why = ex.start(route, self.t)
            if not ok:
                raise ValueError(why)
        end = self.t + max_sim_s
        while self.t < end:
            self.step()
            if ex.state not in ACTIVE:
                break
        return ex.state
