"""What the relay sends the desks on its own: the first messages a desk gets on
connecting, then telemetry, pose, lidar scans and heartbeats at their rates.

:meth:`Publishers._control` is the relay's periodic thread ("relay-control"):
it runs each job when it falls due (the MCU keep-alive and limits from
:mod:`.serial_bridge`, the publishers below, the stats log), never bursting to
catch up, and after every wake the watchdogs (:meth:`Relay._watchdogs`).
"""

from __future__ import annotations

import logging
import time

from app.comm.protocol import Event, Heartbeat, Path, RobotMode, Telemetry

from ..server import Client
from .serial_bridge import CONFIG_PERIOD_S

log = logging.getLogger(__name__)

STATS_LOG_S = 60.0


class Publishers:
    """The periodic thread and the streams it publishes."""

    def _on_connect(self, c: Client) -> None:
        """A new desk gets a heartbeat, who holds control, the map, the patrol
        status and the running mission's global path at once."""
        self.event("info", "client_connected", f"desk {c.name} connected", client=c.name,
                   clients=len(self.server.clients))
        c.send(Heartbeat(Heartbeat.ROLE_ROBOT, 0, 0, 0))
        c.send(Event("info", "lease", self._lease_text(), self.lease_info()))
        c.send(self.map_msg)
        with self._lock:
            ex = self.nav.executor
            c.send(ex.status())
            if ex.running and len(ex.planner.path):
                c.send(Path(Path.GLOBAL, ex.planner.path.astype("float32")))

    def _control(self) -> None:
        cfg = self.cfg
        t = time.monotonic()
        nxt = {"keepalive": t, "config": t, "telemetry": t, "pose": t, "scan": t,
               "heartbeat": t, "log_stats": t + STATS_LOG_S}
        period = {"keepalive": cfg.keepalive_s, "config": CONFIG_PERIOD_S,
                  "telemetry": 1 / cfg.telemetry_hz, "pose": 1 / cfg.pose_hz,
                  "scan": 1 / cfg.scan_hz, "heartbeat": 1 / cfg.heartbeat_hz,
                  "log_stats": STATS_LOG_S}
        while not self._stop.wait(max(0.0, self._next_wake(min(nxt.values()))
                                      - time.monotonic())):
            now = time.monotonic()
            due = [k for k, v in nxt.items() if v <= now]
            for k in due:
                nxt[k] = max(nxt[k] + period[k], now)  # never burst to catch up
                getattr(self, "_tick_" + k)()
            self._watchdogs(now)

    def _tick_telemetry(self) -> None:
        with self._lock:
            r = self.report
            if r is None or self.mcu_silent:
                return
            mode = RobotMode.ESTOP if self.estop else r.mode
            if not self.estop and self.nav.executor.owns_motors:
                mode = RobotMode.PATROL
        self.counters["telemetry"] += 1
        self.server.broadcast(Telemetry(
            r.mcu_time_ms, r.gas_lel_pct, r.temp_c, r.humidity_pct, r.obstacle_left_m,
            r.obstacle_front_m, r.obstacle_right_m, r.battery_v, r.wheel_left_mps,
            r.wheel_right_mps, r.yaw_rate_rps, r.cmd_linear_mps, r.cmd_angular_rps,
            r.alarm_flags, int(mode), self.counters["telemetry"]))

    def _tick_pose(self) -> None:
        with self._lock:
            p = self.nav.pose_message(self.odom.v, self.odom.omega)
        self.server.broadcast(p)
        self.counters["pose"] += 1

    def _tick_scan(self) -> None:
        if not self.server.clients:
            return
        self.server.broadcast(self.lidar.scan(*self.camera_pose()))
        self.counters["scan"] += 1

    def _tick_heartbeat(self) -> None:
        now_m = time.monotonic()
        for c in self.server.clients:
            hb = c.last_heartbeat
            echo_ts, hold = (hb[0], int((now_m - hb[1]) * 1e6)) if hb else (0, 0)
            c.send(Heartbeat(Heartbeat.ROLE_ROBOT, echo_ts, hold, c.rx_frames))
        self.counters["heartbeat"] += 1
        with self._lock:
            counts = dict(self.rejections)
            # the table starts with every reason at 0: only a refusal is news
            changed = (any(counts.values())
                       and {k: v for k, v in counts.items() if v}
                       != {k: v for k, v in self._rejections_reported.items() if v})
            self._rejections_reported = counts
        if changed:
            self.event("warning", "rejections", "refusals so far: " + ", ".join(
                f"{k} {v}" for k, v in counts.items() if v), counts=counts)

    def _tick_log_stats(self) -> None:
        log.info("stats: %s", self.stats())

