"""The mission executor: drive a route point by point, inspect, return to the dock.

No Qt and no threads: :meth:`PatrolExecutor.tick` is called every control
step (sim time) with the localised pose, the measured velocity and the tracked
moving obstacles, and returns the speed command. The relay runs it from its
navigation loop and sends the command to the MCU like a teleop command; tests
and the bench run it against the world and the MCU model directly
(:mod:`sim_robot.patrol_sim`).

Per route point: plan (HybridPlanner: JPS on the inflated station map,
any-angle, smoothed) → drive (pure pursuit, local avoidance of tracked
obstacles, rejoin) → turn to face the gauge / the tank / the given heading →
aim the camera head at the gauge and dwell ``dwell_s`` → done. After the last
point the robot drives back to the dock and faces the dock's heading.

Blocked: when the distance to the goal has not shrunk by ``progress_m`` for
``stuck_s``, the executor replans from where the robot is (event ``blocked``);
after ``max_stuck_replans`` such replans the point is skipped (the dock leg
fails the patrol instead).

Too close: a robot whose estimate touches a mapped obstacle (a bump, a pose a
few centimetres off) before it plans, while it drives, or when it is blocked
within the map's inflation, first backs away to free space
(:mod:`recovery`; event ``recovering``, once per episode, at most
``max_recoveries`` per leg) and then plans from there.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import numpy as np

from app.comm.protocol import PatrolStatus
from app.core.planner import GridMap, HybridConfig, HybridPlanner, Kinematics

from .patrol_phases import PhaseSteps
from .patrol_types import (  # noqa: F401 - re-exported: the states are part of this API
    ABORTED,
    ACTIVE,
    AVOIDING,
    DOCKING,
    DONE,
    DRIVING,
    FAILED,
    IDLE,
    INSPECTING,
    MAX_PATH_POINTS,
    PAUSED,
    PLANNING,
    Mission,
    PatrolConfig,
    PatrolStats,
    Target,
)
from .recovery import Recovery
from .route import Route

log = logging.getLogger(__name__)


class PatrolExecutor(PhaseSteps):
    """``emit(level, code, text, **data)`` sends an event; ``publish(msg)`` sends
    a protocol message (a GLOBAL path); ``look_at(gauge_or_None)`` aims the camera.

    This class holds the mission's state, the operator's commands and the
    reports; the control step's phases are in :class:`~sim_robot.patrol_phases.PhaseSteps`,
    the states and records in :mod:`sim_robot.patrol_types`."""

    def __init__(self, grid: GridMap, dock_xytheta: tuple[float, float, float],
                 gauges: dict[str, tuple[float, float]], tanks: list[tuple[float, float]],
                 emit: Callable[..., None], publish: Callable[[object], None],
                 look_at: Callable[[str | None], None], config: PatrolConfig | None = None,
                 planner: HybridPlanner | None = None) -> None:
        self.cfg = cfg = config or PatrolConfig()
        self.grid = grid
        self.dock = dock_xytheta
        self.gauges = gauges
        self.tanks = tanks
        self.emit = emit
        self.publish = publish
        self.look_at = look_at
        kin = Kinematics(v_max_mps=cfg.v_max_mps, v_min_mps=cfg.v_min_mps,
                         omega_max_rps=cfg.omega_max_rps,
                         accel_mps2=cfg.accel_mps2, alpha_rps2=cfg.alpha_rps2)
        self.planner = planner or HybridPlanner(grid, HybridConfig(
            robot_radius_m=cfg.robot_radius_m, inflation_margin_m=cfg.inflation_margin_m,
            local_planner=cfg.local_planner, detect_range_m=cfg.detect_range_m,
            goal_tolerance_m=cfg.goal_tolerance_m, slow_grow_mps=cfg.slow_grow_mps,
            slow_grow_cap_m=cfg.slow_grow_cap_m, moving_grow_mps=cfg.moving_grow_mps,
            kin=kin))
        self.recovery = Recovery(grid.distance_m, self.planner.inflated.blocked,
                                 grid.resolution_m, grid.origin_xy, cfg.robot_radius_m,
                                 cfg.inflation_margin_m)
        self._recoveries = 0
        self.state = IDLE
        self.reason = ""
        self.mission: Mission | None = None
        self.ti = 0  # current target
        self.phase = ""  # plan | drive | face | dwell
        self.paused_from = ""
        self.version = 0  # bumped on every status change
        self.stats = PatrolStats()
        self.last_cmd = (0.0, 0.0)
        self.last_status = ""  # the planner's last status
        self._published_path = None
        self._phase_t = 0.0
        self._dwell_wall = 0.0
        self._best_d = math.inf
        self._best_t = 0.0
        self._stuck_replans = 0
        self._no_path_tries = 0
        self._last_try_t = -math.inf
        self._t = 0.0
        self._stop_once = False
        self._replan_base = 0
        self._own_replans = 0

    # ------------------------------------------------------------------ commands
    @property
    def owns_motors(self) -> bool:
        """True while the executor drives the robot (the relay skips teleop failsafes)."""
        return self.state in ACTIVE

    @property
    def running(self) -> bool:
        return self.state in ACTIVE or self.state == PAUSED

    def _standoff_m(self) -> float:
        return self.cfg.robot_radius_m + self.cfg.inflation_margin_m

    def reachable(self, x: float, y: float) -> bool:
        """True when the robot's centre may stand at (x, y): free on the map
        inflated by its radius and margin (where the planner plans)."""
        return self.planner.inflated.is_free_xy(x, y)

    def check_route(self, route: Route) -> None:
        """ValueError naming the first point the robot cannot stand on."""
        for i, p in enumerate(route.points):
            if not self.reachable(p.x_m, p.y_m):
                raise ValueError(f"point {i + 1} ({p.name!r}): "
                                 f"({p.x_m:g}, {p.y_m:g}) is within {self._standoff_m():.2f} m "
                                 "of an obstacle; the robot cannot stand there")

    def _target_for(self, i: int, p) -> Target:
        return Target(p.name, p.kind, p.x_m, p.y_m, p.gauge, p.dwell_s, p.heading_rad, i)

    def _dock_target(self) -> Target:
        x, y, th = self.dock
        return Target("dock", "dock", x, y, None, 0.0, th, None, True)

    def start(self, route: Route, t_s: float | None = None) -> tuple[bool, str]:
        if self.running:
            return False, f"a mission is running ({self.state}); abort_patrol first"
        pts = [{"name": p.name, "kind": p.kind, "x_m": p.x_m, "y_m": p.y_m, "gauge": p.gauge,
                "state": "pending"} for p in route.points]
        targets = [self._target_for(i, p) for i, p in enumerate(route.points)]
        targets.append(self._dock_target())
        self._begin(Mission(route.name, pts, targets, self._t if t_s is None else t_s))
        self.emit("info", "patrol_started", f"patrol {route.name!r} started: "
                  f"{len(pts)} points", route=route.name, points=len(pts))
        return True, ""

    def goto(self, x: float, y: float, name: str = "goal", dock: bool = False
             ) -> tuple[bool, str]:
        if self.running:
            return False, f"a mission is running ({self.state}); abort_patrol first"
        if not self.reachable(x, y):
            return False, (f"({x:.2f}, {y:.2f}) is not free space the robot can stand on "
                           f"(within {self._standoff_m():.2f} m of an obstacle)")
        t = self._dock_target() if dock else Target(name, "waypoint", x, y)
        pts = [] if dock else [{"name": name, "kind": "waypoint", "x_m": x, "y_m": y,
                                "gauge": None, "state": "pending"}]
        if not dock:
            t.point_index = 0
        self._begin(Mission("dock" if dock else "goto", pts, [t], self._t))
        self.emit("info", "dock" if dock else "goto_started",
                  "returning to the dock" if dock else f"driving to {name} ({x:.1f}, {y:.1f})",
                  x_m=t.x, y_m=t.y)
        return True, ""

    def dock_now(self) -> tuple[bool, str]:
        """Stop the route (remaining points skipped) and return to the dock."""
        m = self.mission
        if m is not None and self.running:
            for p in m.points:
                if p["state"] in ("pending", "current"):
                    p["state"] = "skipped"
            self.look_at(None)
            self.ti = len(m.targets) - 1 if m.targets[-1].dock else len(m.targets)
            if self.ti >= len(m.targets):
                m.targets.append(self._dock_target())
            self.state = PLANNING
            self.phase = "plan"
            self.reason = "dock requested"
            self._changed()
            self.emit("info", "docking", "returning to the dock (operator request)")
            return True, ""
        return self.goto(*self.dock[:2], dock=True)

    def pause(self, reason: str) -> tuple[bool, str]:
        """Stop driving (the caller stops the motors, or hands them to the operator)."""
        if self.state == PAUSED:
            return True, ""
        if not self.owns_motors:
            return False, f"no mission running ({self.state})"
        self.paused_from = self.phase
        self.state = PAUSED
        self.reason = reason
        self._changed()
        self.emit("warning" if reason != "operator" else "info", "patrol_paused",
                  f"patrol paused: {reason}", reason=reason)
        return True, ""

    def resume(self) -> tuple[bool, str]:
        if self.state != PAUSED:
            return False, f"nothing to resume ({self.state})"
        # after a pause the robot may stand anywhere: plan the current leg again,
        # unless it was already turning or dwelling at the point
        self.phase = self.paused_from if self.paused_from in ("face", "dwell") else "plan"
        self._phase_t = self._t
        self.reason = ""
        self._set_state_for_phase()
        self.emit("info", "patrol_resumed", "patrol resumed")
        return True, ""

    def abort(self, reason: str = "operator") -> tuple[bool, str]:
        if not self.running:
            return False, f"no mission running ({self.state})"
        self._finish(ABORTED, reason, "warning", "patrol_aborted", f"patrol aborted: {reason}")
        return True, ""

    # ------------------------------------------------------------------ internals
    def _changed(self) -> None:
        self.version += 1

    def _begin(self, m: Mission) -> None:
        self.mission = m
        self.ti = 0
        self.stats = PatrolStats()
        self._replan_base = self.planner.replan_count
        self._own_replans = 0
        self.reason = ""
        self._start_target()

    def _start_target(self) -> None:
        m = self.mission
        t = m.targets[self.ti]
        if t.point_index is not None:
            m.points[t.point_index]["state"] = "current"
        self.phase = "plan"
        self._no_path_tries = 0
        self._stuck_replans = 0
        self._recoveries = 0
        self._last_try_t = -math.inf
        self._set_state_for_phase()

    def _set_state_for_phase(self) -> None:
        t = self.mission.targets[self.ti]
        if self.phase == "plan":
            st = PLANNING
        elif self.phase in ("face", "dwell") and not t.dock:
            st = INSPECTING
        elif t.dock:
            st = DOCKING
        else:
            st = DRIVING
        if st != self.state:
            self.state = st
            self._changed()

    def _finish(self, state: str, reason: str, level: str, code: str, text: str,
                **data) -> None:
        self.state = state
        self.reason = reason
        self.phase = ""
        self._stop_once = True
        self.look_at(None)
        m = self.mission
        if m is not None and state != DONE:
            for p in m.points:
                if p["state"] in ("pending", "current"):
                    p["state"] = "skipped"
        self._changed()
        self.emit(level, code, text, reason=reason, route=m.route if m else "", **data)

    def _next_target(self) -> None:
        m = self.mission
        self.ti += 1
        if self.ti >= len(m.targets):
            done = sum(p["state"] == "done" for p in m.points)
            self._finish(DONE, "", "info", "patrol_done",
                         f"patrol {m.route!r} done: {done}/{len(m.points)} points",
                         points_done=done, skipped=len(m.points) - done,
                         duration_s=round(self._t - m.started_t, 1))
            return
        self._start_target()

    def _skip(self, why: str) -> None:
        m = self.mission
        t = m.targets[self.ti]
        if t.dock or t.point_index is None:
            self._finish(FAILED, why, "alarm", "patrol_failed", f"mission failed: {why}")
            return
        m.points[t.point_index]["state"] = "skipped"
        self.stats.skipped += 1
        self._changed()
        self.emit("warning", "point_skipped", f"{t.name} skipped: {why}", point=t.name,
                  reason=why)
        self._next_target()

    # ------------------------------------------------------------------ the step
    def tick(self, t_s: float, dt: float, pose, velocity, obstacles) -> tuple[float, float, bool]:
        """One control step: (v_mps, omega_rps, send). ``send`` is False when the
        executor does not own the motors (then the command must not be sent)."""
        self._t = t_s
        if not self.owns_motors:
            if self._stop_once:
                self._stop_once = False
                self.last_cmd = (0.0, 0.0)
                return 0.0, 0.0, True
            return 0.0, 0.0, False
        self.stats.driven_m += abs(float(velocity[0])) * dt
        v, w = self._step(t_s, dt, pose, velocity, obstacles)
        if not self.owns_motors:  # the mission ended during this step
            self._stop_once = False
            v, w = 0.0, 0.0
        self.last_cmd = (v, w)
        return v, w, True

    # ------------------------------------------------------------------ reports
    def progress(self) -> float:
        m = self.mission
        if m is None:
            return 0.0
        if self.state == DONE:
            return 1.0
        n = len(m.targets)
        return round(min(1.0, self.ti / n) if n else 0.0, 3)

    def status(self) -> PatrolStatus:
        m = self.mission
        idx = -1
        if m is not None and self.state not in (DONE, ABORTED, FAILED, IDLE) \
                and self.ti < len(m.targets):
            pi = m.targets[self.ti].point_index
            idx = -1 if pi is None else pi
        return PatrolStatus(self.state, m.route if m else "", idx,
                            [dict(p) for p in m.points] if m else [], self.reason,
                            self.progress(), self.cfg.local_planner)

    def local_trajectory(self, pose, steps: int = 15) -> np.ndarray:
        """The predicted trajectory: the last command rolled out for local_horizon_s."""
        v, w = self.last_cmd
        x, y, th = pose
        h = self.cfg.local_horizon_s / steps
        out = [(x, y)]
        for _ in range(steps):
            th += w * h
            x += v * math.cos(th) * h
            y += v * math.sin(th) * h
            out.append((x, y))
        return np.asarray(out, np.float32)

    def counts(self) -> dict:
        return {"replans": self.planner.replan_count - self._replan_base + self._own_replans,
                "avoid_episodes": self.stats.avoid_episodes, "plans": self.stats.plans,
                "path_length_m": round(self.stats.path_length_m, 1),
                "driven_m": round(self.stats.driven_m, 1),
                "skipped": self.stats.skipped, "governor": self.planner.governor_count,
                "recoveries": self.stats.recoveries}
