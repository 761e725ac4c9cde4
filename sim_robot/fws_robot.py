"""``sim-robot --robot 4ws``: the four-wheel independent-steering patrol robot
of seed 004 on the station.

It is the patrol robot with two parts swapped, everything else shared (world,
sensors, camera, lidar, the relay's serial bridge, commands, control lease,
deadman, publishers, the TCP link and its framing):

- the board: :class:`~.fws_mcu.FwsMcu` drives four steering servos and four
  drive motors and reports the wheels (MCU frame ``WHEEL_REPORT``);
- the mission executor's planner: :class:`app.core.planner.FwsNavigator`
  (optimised A* → optimised TEB → pure pursuit) in place of the skid-steer
  robot's JPS + APF/DWA.

To the desks the relay adds, at the pose rate, the wheels (``WHEEL_STATE``,
type 24) and, while a mission drives, the TEB local plan (``TEB_PLAN``, type
25): docs/protocol.md, "4WS patrol robot".

Sideways motion: the navigator closes a small sideways offset at a goal in
CRAB mode (``crab_docking``); while it does, the relay sends the board the
body twist with its sideways speed (MCU ``BODY_CMD``) instead of (v, ω). The
relay's odometry takes forward travel and heading from the sensor report, as
the patrol robot's does, and the sideways travel from the wheel report: the
four wheels' encoder increments along their steering angles, fitted to a
rigid-body motion (:func:`app.core.kinematics.body_twist`, least squares).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

from app.comm.fws_protocol import TebPlan, WheelState
from app.core.kinematics import FwsGeometry, Twist, WheelCommand, body_twist
from app.core.planner.fws_navigator import FwsNavConfig, FwsNavigator

from .fws_base import FwsActuators
from .fws_mcu import FwsMcu, FwsMcuThread
from .mcu_link import BodyCmd, McuType, MotorCmd, WheelReport
from .navigation import Navigation
from .patrol import PatrolExecutor
from .patrol_sim import OfflinePatrol
from .relay import Relay
from .sim import SimRobot
from .world import World

log = logging.getLogger(__name__)

FWS_MARGIN_M = 0.15
# TEB cycles per second of wall time at most: at a high time scale a cycle every
# 0.3 s of sim time would take the relay's whole core (and the GIL from its
# serial thread: the MCU's link watchdog then stops the robot)
TEB_MAX_WALL_HZ = 4.0


def use_fws_navigator(nav: Navigation, world: World, emit, publish, look_at,
                      crab_docking: bool = False) -> FwsNavigator:
    """Give the navigation stack a mission executor planning with the 4WS
    navigator (same callbacks as its own); returns the navigator.
    ``crab_docking``: for a caller that sends the navigator's sideways speed
    (``lateral_mps``) to the board."""
    # the 4WS chassis' corners reach 0.39 m from its centre: 5 cm more margin
    # than the skid-steer robot's (with 0.1 m its arcs touched a gauge post)
    pc = dataclasses.replace(nav.executor.cfg, local_planner="teb",
                             inflation_margin_m=FWS_MARGIN_M)
    fws = FwsNavigator(nav.grid, FwsNavConfig(
        robot_radius_m=pc.robot_radius_m, inflation_margin_m=pc.inflation_margin_m,
        v_max_mps=pc.v_max_mps, goal_tolerance_m=pc.goal_tolerance_m,
        detect_range_m=pc.detect_range_m, crab_docking=crab_docking))
    tanks = [(t["x"], t["y"]) for t in world.spec.get("tanks", [])]
    d = world.dock
    nav.executor = PatrolExecutor(nav.grid, (d[0], d[1], d[2]),
                                  {g.id: (g.x, g.y) for g in world.gauges}, tanks, emit,
                                  publish, look_at, pc, planner=fws)
    return fws


def wheel_travel(geom: FwsGeometry, prev: WheelReport, cur: WheelReport,
                 ticks_per_m: float) -> Twist | None:
    """The body's travel (dx, dy forward and to the left in the body frame, m;
    dθ, rad) between two wheel reports: each wheel's encoder increment along
    its steering angle (the mean of the two reports'), fitted to a rigid-body
    motion by least squares (:func:`app.core.kinematics.body_twist` on
    distances instead of speeds). None across a board reset or a gap over 2 s."""
    dt_ms = (cur.mcu_time_ms - prev.mcu_time_ms) & 0xFFFFFFFF
    if dt_ms == 0 or dt_ms > 2000:
        return None
    d = [(((a - b + 0x80000000) & 0xFFFFFFFF) - 0x80000000) / ticks_per_m
         for a, b in zip(cur.ticks, prev.ticks, strict=True)]
    ang = [(a + b) / 2 for a, b in zip(cur.angles_rad, prev.angles_rad, strict=True)]
    move, _ = body_twist(geom, WheelCommand(tuple(ang), tuple(d)))
    return move


class FwsRelay(Relay):
    """The patrol robot's relay with the 4WS navigator in its mission executor."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        nav = self.nav
        self.fws_nav = use_fws_navigator(nav, self.world, self.event, self._nav_publish,
                                         self._look_at, crab_docking=True)
        fc = self.fws_nav.cfg
        # the TEB cycles off the relay's lock (its serial and keep-alive threads
        # wait on it), at most TEB_MAX_WALL_HZ a second of wall time
        self.fws_nav.cfg = dataclasses.replace(
            fc, teb_period_s=max(fc.teb_period_s, self.cfg.time_scale / TEB_MAX_WALL_HZ),
            background_teb=True)
        self.wheels = None  # the MCU's last WheelReport
        self._wheels_sent = None
        self._teb_sent = None
        self.cmd_vy = 0.0  # the sideways speed sent with (cmd_v, cmd_w)
        act = FwsActuators()
        self.wheel_ticks_per_m = act.ticks_per_rev / (2 * math.pi * act.wheel_radius_m)
        self.slide_m = 0.0  # the odometry's sideways travel, summed
        self.counters.update({"wheel_reports": 0, "wheel_state": 0, "teb_plan": 0})

    # ---- motion: (v, ω), or the body twist while the navigator drives sideways ----
    def _set_cmd(self, v: float, w: float) -> None:
        ex = self.nav.executor
        vy = self.fws_nav.lateral_mps if ex.owns_motors and ex.phase == "drive" else 0.0
        changed = (v, w, vy) != (self.cmd_v, self.cmd_w, self.cmd_vy)
        self.cmd_v, self.cmd_w, self.cmd_vy = v, w, vy
        if changed:
            self._mcu_send(self._motor_msg())

    def _motor_msg(self):
        if self.cmd_vy:
            return BodyCmd(self.cmd_v, self.cmd_vy, self.cmd_w)
        return MotorCmd(self.cmd_v, self.cmd_w)

    def _moving(self) -> bool:
        return bool(self.cmd_v or self.cmd_w or self.cmd_vy)

    # ---- the board's wheels: the desk's wheel state, the odometry's sideways term ----
    def _on_mcu_frame(self, fr) -> None:
        if fr.msg_type == McuType.WHEEL_REPORT:
            with self._lock:
                self._slide_odometry(self.wheels, fr.message)
                self.wheels = fr.message
                self.counters["wheel_reports"] += 1

    def _slide_odometry(self, prev, cur) -> None:
        """Move the odometry by the sideways travel between two wheel reports
        (the sensor report already moved it forward and turned it)."""
        if prev is None:
            return
        move = wheel_travel(self.fws_nav.cfg.geometry, prev, cur, self.wheel_ticks_per_m)
        if move is None or abs(move.vy) < 1e-6:
            return
        self.odom.slide(move.vy)
        self.slide_m += abs(move.vy)
        trail = self.odom_trail
        if trail and abs(trail[-1][0] - cur.mcu_time_ms / 1000.0) < 1e-6:
            trail[-1] = (trail[-1][0], self.odom.x, self.odom.y, self.odom.theta)

    def _tick_pose(self) -> None:
        """The pose, then the wheels (when the MCU reported anew) and the TEB plan
        (when a mission drives and the TEB ran a new cycle)."""
        super()._tick_pose()
        with self._lock:
            w = self.wheels
            teb = self.fws_nav.last_teb if self.nav.executor.owns_motors else None
        if w is not None and w is not self._wheels_sent and not self.mcu_silent:
            self._wheels_sent = w
            self.server.broadcast(WheelState(w.mcu_time_ms, w.mode, w.angles_rad,
                                             w.speeds_mps))
            self.counters["wheel_state"] += 1
        if teb is not None and teb is not self._teb_sent:
            self._teb_sent = teb
            self.server.broadcast(TebPlan(teb.turning_in_place, teb.poses, teb.dts))
            self.counters["teb_plan"] += 1

    def close(self) -> None:
        super().close()
        self.fws_nav.close()

    def stats(self) -> dict:
        out = super().stats()
        out["teb_cycles"] = self.fws_nav.teb_cycles
        out["governor"] = self.fws_nav.governor_count
        out["odometry_slide_m"] = round(self.slide_m, 3)
        return out


class FwsSim(SimRobot):
    """The station with the 4WS robot: its board on the pty, the relay above."""

    mcu_model = FwsMcu
    mcu_thread_class = FwsMcuThread
    relay_class = FwsRelay

    def start(self) -> None:
        t0 = time.monotonic()
        super().start()
        log.info("4WS patrol robot up after %.1f s", time.monotonic() - t0)


class FwsOfflinePatrol(OfflinePatrol):
    """:class:`~.patrol_sim.OfflinePatrol` (lock-step, no threads or sockets) with
    the 4WS board and navigator: for tests and bench/fws_bench.py. It sends
    (v, ω) only, so its navigator docks without crab moves."""

    def __post_init__(self) -> None:
        super().__post_init__()
        self.mcu = FwsMcu(self.world, self.cfg.robot, self.cfg.limits, self.cfg.seed,
                          link_clock=lambda: self.t)
        self.fws_nav = use_fws_navigator(self.nav, self.world, self._emit,
                                         self.published.append, self._look_at)
