"""The relay's navigation thread ("relay-nav").

Steps localisation, perception and the mission executor once per control period
of sim time, turns the executor's speeds into motor commands (unless the e-stop
is latched), and publishes the patrol status, the tracked obstacles and the
local path to the desks. The executor's own callbacks (events, published
messages, where the camera should look) and the world's collision report come
through here too.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from app.comm.protocol import Obstacles, Path, RobotMode

log = logging.getLogger(__name__)

NAV_STATUS_S = 0.5  # PatrolStatus at 2 Hz (and on every change), wall time
NAV_OBSTACLES_S = 0.2  # Obstacles at 5 Hz
NAV_LOCAL_S = 0.2  # the LOCAL path at 5 Hz while a mission drives
NAV_MAPPING_S = 2.0  # the growing map while mapping, wall time
NAV_YIELD_S = 0.001  # the least sleep between two steps (wall time)


class NavigationThread:
    """The navigation loop and the executor's callbacks."""

    # told the sim time of every navigation step (the simulation paces its
    # clock by it: :meth:`sim_robot.sim.SimClock.control_step`)
    on_control_step: Callable[[float], None] | None = None

    def _nav_publish(self, msg) -> None:
        self.server.broadcast(msg)

    def _look_at(self, gauge: str | None) -> None:
        if self.camera is not None:
            try:
                self.camera.set_target(gauge)
            except ValueError as e:
                log.warning("camera: %s", e)

    def _on_collision(self, rec: dict) -> None:
        self.event("alarm", "collision", f"the robot touched {rec['what']} at "
                   f"({rec['x_m']:.2f}, {rec['y_m']:.2f})", **rec)

    def _publish_growing_map(self) -> None:
        """The map while mapping: its landmarks are taken under the lock and
        the image is drawn and sent on a thread of its own (about a second of
        CPU on a station-sized map, which held the lock, and so the odometry
        and the keep-alives, for as long); one drawing at a time."""
        busy = getattr(self, "_map_drawer", None)
        if busy is not None and busy.is_alive():
            return
        with self._lock:
            view = self.nav.mapping.view()
        if view is None:
            return

        def draw() -> None:
            self.server.broadcast(view.image())

        self._map_drawer = threading.Thread(target=draw, name="relay-map", daemon=True)
        self._map_drawer.start()

    def _nav_loop(self) -> None:
        """Localisation, perception and the mission executor, one step per
        control period of sim time (``control_dt_s``), paced in wall time: at a
        time scale X the loop runs X times as often (5 ms at 20x)."""
        nav = self.nav
        if self.cfg.patrol:
            self._auto_patrol(self.cfg.patrol)
        dt_sim = nav.executor.cfg.control_dt_s
        period = min(0.1, max(0.004, dt_sim / self.cfg.time_scale))
        t_prev = self.sim_time()
        nxt = time.monotonic()
        due = {"status": nxt, "obstacles": nxt, "local": nxt, "map": nxt}
        version = -1
        idle_scan_s = 0.2  # sim time between scans while no mission drives (the pose
        # stays fixed to the map, tracks stay alive)
        # Always a short sleep between steps: a step that overran its period
        # used to take the lock again at once, and the threads waiting for it
        # (the MCU reports that carry the odometry, the publishers that send
        # the MCU's keepalive) waited seconds of sim time at 20x.
        while not self._stop.wait(max(NAV_YIELD_S, nxt - time.monotonic())):
            now = time.monotonic()
            nxt = max(nxt + period, now)
            t = self.sim_time()
            dt = min(max(t - t_prev, 1e-3), 0.5)
            t_prev = t
            ex = nav.executor
            with self._lock:
                odom = (self.odom.x, self.odom.y, self.odom.theta)
                # the report's time is the sim's only with the built-in MCU model
                rep = self.report
                builtin = self.cfg.serial_device is None
                odom_t = rep.mcu_time_ms / 1000.0 if rep is not None and builtin else None
                trail = list(self.odom_trail) if builtin else None
                self.odom_trail.clear()
                nav.docked = rep is not None and rep.mode == RobotMode.DOCKED
                v, w, send = nav.step(t, dt, odom, (self.odom.v, self.odom.omega), odom_t,
                                      trail)
                if self.on_control_step is not None:
                    self.on_control_step(t)
                if send and not self.estop:
                    self._set_cmd(v, w)
                self.counters["nav_steps"] += 1
                driving = ex.owns_motors
                changed = ex.version != version
                version = ex.version
                status = ex.status() if changed or now >= due["status"] else None
            # standing, the robot still localises and tracks, desk or no desk:
            # scans matched only while a desk listened left an idle robot on
            # its gyro alone (tests/sim/test_idle_localisation.py)
            if not driving and (nav.scan_t is None or t - nav.scan_t >= idle_scan_s):
                with self._lock:
                    nav.perceive(t)
            if not self.server.clients:
                continue
            if status is not None:
                due["status"] = now + NAV_STATUS_S
                self.server.broadcast(status)
            if now >= due["obstacles"]:
                due["obstacles"] = now + NAV_OBSTACLES_S
                with self._lock:
                    rows = nav.obstacles.astype("float32")
                self.server.broadcast(Obstacles(rows))
            if nav.mapping is not None and nav.mapping.active and now >= due["map"]:
                due["map"] = now + NAV_MAPPING_S
                self._publish_growing_map()
            if driving and now >= due["local"]:
                due["local"] = now + NAV_LOCAL_S
                with self._lock:
                    traj = ex.local_trajectory(nav.localiser.pose)
                self.server.broadcast(Path(Path.LOCAL, traj))

