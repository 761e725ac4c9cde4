"""The mission executor's control step, one phase at a time (a mixin of
:class:`sim_robot.patrol.PatrolExecutor`, which holds the state and the
operator's commands).

- plan: a global plan from the estimate to the target, retried every
  ``no_path_retry_s`` and skipped after ``no_path_retries``;
- drive: the planner's step (pure pursuit, local avoidance); an ``avoiding``
  event per episode; no progress for ``stuck_s`` replans (event ``blocked``)
  or, within the map's inflation, backs away first;
- recover: back away from a touched obstacle (:mod:`sim_robot.recovery`);
- face: turn to the gauge, the tank or the given heading;
- dwell: hold still ``dwell_s`` (and, for a gauge, ``inspect_min_wall_s`` of
  wall time for the desk to read it), then the next target.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from app.comm.protocol import Path

from .patrol_types import AVOIDING, DOCKING, DRIVING, MAX_PATH_POINTS, Target, _wrap

log = logging.getLogger(__name__)


class PhaseSteps:
    """The per-phase steps of :class:`~sim_robot.patrol.PatrolExecutor`."""

    def _plan(self, pose) -> bool:
        t = self.mission.targets[self.ti]
        try:
            path = self.planner.plan((pose[0], pose[1]), (t.x, t.y))
        except ValueError as e:
            path = []
            log.warning("plan to %s: %s", t.name, e)
        self.stats.plans += 1
        if path:
            self._publish_path()
            self._best_d = math.hypot(t.x - pose[0], t.y - pose[1])
            self._best_t = self._t
        return bool(path)

    def _publish_path(self) -> None:
        p = self.planner.path
        if p is self._published_path or len(p) == 0:
            return
        self._published_path = p
        self.stats.path_length_m += float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
        pts = np.asarray(p, np.float32)
        if len(pts) > MAX_PATH_POINTS:
            keep = np.linspace(0, len(pts) - 1, MAX_PATH_POINTS).round().astype(int)
            pts = pts[keep]
        self.publish(Path(Path.GLOBAL, pts))

    def _begin_recovery(self, t_s: float, pose, why: str) -> bool:
        """Back away from a touched obstacle (phase ``recover``); False when
        this leg has had its ``max_recoveries`` or the map has no way out.
        Only with a planner whose safety governor can vet the manoeuvre (the
        skid-steer robot's; a 4WS body's corners sweep wider when it turns)."""
        if self._recoveries >= self.cfg.max_recoveries or not hasattr(self.planner, "govern"):
            return False
        e = self.recovery.begin(pose, t_s)
        if e is None:
            return False
        self._recoveries += 1
        self.stats.recoveries += 1
        self.phase = "recover"
        self._set_state_for_phase()
        t = self.mission.targets[self.ti]
        how = "backing" if e.reverse else "driving"
        self.emit("warning", "recovering",
                  f"{why} at ({pose[0]:.2f}, {pose[1]:.2f}) on the way to {t.name}: "
                  f"{how} away to ({e.x:.2f}, {e.y:.2f})", point=t.name,
                  x_m=round(pose[0], 2), y_m=round(pose[1], 2),
                  clearance_m=round(e.clearance_m, 3), to_x_m=round(e.x, 2),
                  to_y_m=round(e.y, 2), reverse=e.reverse)
        return True

    def _recover_step(self, t_s, dt, pose, velocity, obstacles) -> tuple[float, float]:
        v, w, status = self.recovery.command(pose, t_s)
        if status == "recovering":
            return self.planner.govern(pose, velocity, v, w, obstacles, dt)
        if status == "timeout":
            log.warning("recovery toward %s timed out at (%.2f, %.2f)",
                        self.mission.targets[self.ti].name, pose[0], pose[1])
        else:
            log.info("recovered at (%.2f, %.2f)", pose[0], pose[1])
        self.phase = "plan"  # from where it stands now, at once
        self._last_try_t = -math.inf
        self._set_state_for_phase()
        return 0.0, 0.0

    def _face_heading(self, t: Target, pose) -> float | None:
        if t.heading is not None:
            return t.heading
        if t.gauge and t.gauge in self.gauges:
            gx, gy = self.gauges[t.gauge]
            return math.atan2(gy - pose[1], gx - pose[0])
        if t.kind == "tank_wall" and self.tanks:
            tx, ty = min(self.tanks, key=lambda c: math.hypot(c[0] - t.x, c[1] - t.y))
            return math.atan2(ty - pose[1], tx - pose[0])
        return None

    def _step(self, t_s, dt, pose, velocity, obstacles) -> tuple[float, float]:
        t = self.mission.targets[self.ti]
        if self.phase == "recover":
            return self._recover_step(t_s, dt, pose, velocity, obstacles)
        if self.phase in ("plan", "drive") and self.recovery.touching(pose[0], pose[1]) \
                and self._begin_recovery(t_s, pose, "touching an obstacle"):
            return 0.0, 0.0
        if self.phase == "plan":
            return self._plan_step(t_s, t, pose)
        if self.phase == "drive":
            return self._drive_step(t_s, dt, t, pose, velocity, obstacles)
        if self.phase == "face":
            return self._face_step(t_s, t, pose)
        if self.phase == "dwell":
            return self._dwell_step(t_s, t)
        return 0.0, 0.0

    def _plan_step(self, t_s, t: Target, pose) -> tuple[float, float]:
        cfg = self.cfg
        if t_s - self._last_try_t < cfg.no_path_retry_s:
            return 0.0, 0.0
        self._last_try_t = t_s
        if self._plan(pose):
            self.phase = "drive"
            self._set_state_for_phase()
        else:
            self._no_path_tries += 1
            if self._no_path_tries >= cfg.no_path_retries:
                self._skip(f"no path to {t.name} ({t.x:.1f}, {t.y:.1f})")
        return 0.0, 0.0

    def _drive_step(self, t_s, dt, t: Target, pose, velocity, obstacles) -> tuple[float, float]:
        cfg = self.cfg
        v, w, status = self.planner.step(pose, velocity, obstacles, dt)
        self._publish_path()  # the planner may have replanned by itself
        prev = self.last_status
        self.last_status = status
        if status in ("avoiding", "blocked") and prev not in ("avoiding", "blocked"):
            self.stats.avoid_episodes += 1
            obs = np.asarray(obstacles, float).reshape(-1, 5)
            near = {}
            if len(obs):
                k = int(np.argmin(np.hypot(obs[:, 0] - pose[0], obs[:, 1] - pose[1])))
                near = {"x_m": round(float(obs[k, 0]), 2), "y_m": round(float(obs[k, 1]), 2),
                        "vx_mps": round(float(obs[k, 2]), 2),
                        "vy_mps": round(float(obs[k, 3]), 2),
                        "radius_m": round(float(obs[k, 4]), 2)}
            self.emit("info", "avoiding", f"avoiding an obstacle on the way to {t.name}",
                      obstacle=near, point=t.name)
        st = AVOIDING if status in ("avoiding", "blocked") else (
            DOCKING if t.dock else DRIVING)
        if st != self.state:
            self.state = st
            self._changed()
        if status == "reached":
            if t.point_index is not None:
                self.emit("info", "point_reached", f"reached {t.name}", point=t.name,
                          index=t.point_index)
            self.phase = "face"
            self._phase_t = t_s
            if t.gauge:
                self.look_at(t.gauge)
            self._set_state_for_phase()
            return 0.0, 0.0
        if status == "no_path":
            self.phase = "plan"
            self._set_state_for_phase()
            return 0.0, 0.0
        d = math.hypot(t.x - pose[0], t.y - pose[1])
        if d < self._best_d - cfg.progress_m:
            self._best_d, self._best_t = d, t_s
            self._stuck_replans = 0
        elif t_s - self._best_t > cfg.stuck_s:
            self._stuck_replans += 1
            self._own_replans += 1
            why = f"no progress toward {t.name} for {cfg.stuck_s:.0f} s"
            if self._stuck_replans > cfg.max_stuck_replans:
                self._skip(f"blocked: {why}, {cfg.max_stuck_replans} replans did not help")
                return 0.0, 0.0
            self._best_t = t_s
            if not self.recovery.free(pose[0], pose[1]) and \
                    self._begin_recovery(t_s, pose, f"blocked near an obstacle ({why})"):
                return 0.0, 0.0
            self.emit("warning", "blocked", f"blocked: {why}; replanning", reason=why,
                      point=t.name)
            if not self._plan(pose):
                self.phase = "plan"
                self._set_state_for_phase()
                return 0.0, 0.0
        return v, w

    def _face_step(self, t_s, t: Target, pose) -> tuple[float, float]:
        cfg = self.cfg
        h = self._face_heading(t, pose)
        err = 0.0 if h is None else _wrap(h - pose[2])
        if abs(err) <= cfg.face_tolerance_rad or t_s - self._phase_t > cfg.face_timeout_s:
            self.phase = "dwell"
            self._phase_t = t_s
            self._dwell_wall = time.monotonic()
            if t.gauge:
                self.emit("info", "inspection_started", f"inspecting {t.name}",
                          point=t.name, gauge=t.gauge, kind=t.kind)
            return 0.0, 0.0
        w = max(-0.8, min(0.8, 1.5 * err))
        if abs(w) < 0.15:
            w = math.copysign(0.15, err)
        return 0.0, w

    def _dwell_step(self, t_s, t: Target) -> tuple[float, float]:
        cfg = self.cfg
        m = self.mission
        if t_s - self._phase_t < t.dwell_s:
            return 0.0, 0.0
        if t.gauge and time.monotonic() - self._dwell_wall < cfg.inspect_min_wall_s:
            return 0.0, 0.0
        if t.point_index is not None:
            m.points[t.point_index]["state"] = "done"
            self._changed()
            if t.kind != "waypoint" or t.dwell_s > 0:
                self.emit("info", "inspection_done", f"inspected {t.name}", point=t.name,
                          gauge=t.gauge, kind=t.kind)
        if t.gauge:
            self.look_at(None)
        self._next_target()
        return 0.0, 0.0
