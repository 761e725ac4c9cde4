"""Mission commands at the relay: start / pause / resume / abort a patrol, goto, dock,
and the operator's ``set_pose`` (missions are refused while localisation is lost).

A route arrives inline in ``start_patrol`` (or, empty, means the default route
file); it is checked by the one route parser both processes share
(:mod:`app.core.route`, through :mod:`sim_robot.route`, which adds the
station's gauge ids and the map's extent) and by the executor (every point
must be a place the robot can stand). ``goto`` takes a point of the running
or default route, a gauge id, or coordinates. Called with the relay's lock held.
"""

from __future__ import annotations

import json
import logging
import math
import pathlib
import threading

from ..route import DEFAULT_ROUTE, Route, RoutePoint, load_route, parse_route

log = logging.getLogger(__name__)


class Missions:
    """Patrol and goto commands, handed to the navigation's mission executor."""

    def _mission_command(self, name: str, args: dict) -> tuple[bool, str]:
        """start_patrol / pause_patrol / resume_patrol / abort_patrol / goto / dock
        (called with the lock held)."""
        ex = self.nav.executor
        if name in ("start_patrol", "resume_patrol", "goto", "dock") and self.estop:
            return False, "estop latched; send reset_estop first"
        if name == "set_pose":
            return self._set_pose(args)
        if name in ("start_mapping", "stop_mapping", "save_map"):
            return self._mapping_command(name, args)
        if self.nav.localiser.lost and name in ("start_patrol", "resume_patrol", "goto", "dock"):
            return False, "localisation lost; set the robot's pose on the map first (set_pose)"
        if name == "start_patrol":
            try:
                route = self._route_from(args.get("route"))
            except ValueError as e:
                return False, str(e)
            ok, why = ex.start(route, self.sim_time())
        elif name == "pause_patrol":
            ok, why = ex.pause("operator")
            self._set_cmd(0.0, 0.0)
        elif name == "resume_patrol":
            ok, why = ex.resume()
        elif name == "abort_patrol":
            ok, why = ex.abort("operator")
            self._set_cmd(0.0, 0.0)
        elif name == "dock":
            ok, why = ex.dock_now()
        else:  # goto
            try:
                x, y, label = self._goto_target(args)
            except ValueError as e:
                return False, str(e)
            ok, why = ex.goto(x, y, label)
        return ok, why

    def _set_pose(self, args: dict) -> tuple[bool, str]:
        """The operator's pose estimate: x_m, y_m, theta_rad (the desk's
        click-and-drag on the map). A mission stays paused: the operator
        resumes it once the estimate looks right."""
        try:
            x, y, th = (float(args[k]) for k in ("x_m", "y_m", "theta_rad"))
        except (KeyError, TypeError, ValueError):
            return False, "set_pose needs numeric x_m, y_m and theta_rad"
        if not all(math.isfinite(v) for v in (x, y, th)):
            return False, "set_pose needs finite numbers"
        if not self.nav.executor.reachable(x, y):
            return False, f"({x:.2f}, {y:.2f}) is not a free place on the map"
        self.nav.set_pose(x, y, th)
        return True, ""

    def _mapping_command(self, name: str, args: dict) -> tuple[bool, str]:
        """Mapping mode: start (the operator then drives by keyboard), stop,
        save the map so far (``name``) on the robot."""
        m = self.nav.mapping
        if name == "start_mapping":
            if self.nav.executor.owns_motors:
                return False, "a mission is running; pause or abort it first"
            m.start()
            self.event("info", "mapping_started", "mapping: drive the robot round the station")
            return True, ""
        if name == "stop_mapping":
            if not m.active:
                return False, "not mapping"
            scans = m.scans
            m.stop()
            self.server.broadcast(self.map_msg)  # the station's map again
            self.event("info", "mapping_stopped", f"mapping stopped after {scans} scans",
                       scans=scans)
            return True, ""
        return self._save_map(m, args)

    def _save_map(self, m, args: dict) -> tuple[bool, str]:
        """save_map: the mapper is copied here (under the lock) and finished and
        written on a thread of its own, since the final solve takes seconds and
        the lock is the robot's: ``map_saving`` at once, ``map_saved`` (or
        ``map_save_failed``) when the file is written."""
        try:
            name = m.check_name(str(args.get("name", "")))
        except ValueError as e:
            return False, str(e)
        busy = getattr(self, "_map_saver", None)
        if busy is not None and busy.is_alive():
            return False, "a map is being saved; wait for map_saved"
        snap = m.snapshot()
        if snap is None:
            return False, "no map yet: start mapping and drive first"
        self.event("info", "map_saving",
                   f"saving map {name}: final solve over {len(snap.mapper.poses)} scans "
                   "(a few seconds)", name=name)
        self._map_saver = threading.Thread(target=self._finish_and_save, args=(m, snap, name),
                                           name="map-save", daemon=True)
        self._map_saver.start()
        return True, ""

    def _finish_and_save(self, m, snap, name: str) -> None:
        try:
            path = m.save(name, snap.finish())
        except Exception as e:  # reported to the operator, never a dead thread
            log.exception("saving map %s failed", name)
            self.event("warning", "map_save_failed", f"map {name} not saved: {e}", name=name)
            return
        self.event("info", "map_saved", f"map saved as {path}", path=str(path))

    def _route_from(self, obj) -> Route:
        gauges = {g.id for g in self.world.gauges}
        if obj is None or obj == {}:
            route = load_route(DEFAULT_ROUTE, gauges, self.world.size_m)
        else:
            route = parse_route(obj, gauges, self.world.size_m)
        self.nav.executor.check_route(route)
        return route

    def _goto_target(self, args: dict) -> tuple[float, float, str]:
        if args.get("point") is not None:
            name = str(args["point"])
            pts: list[RoutePoint] = []
            m = self.nav.executor.mission
            if m is not None:
                pts += [RoutePoint(p["name"], p["kind"], p["x_m"], p["y_m"]) for p in m.points]
            try:
                pts += load_route(DEFAULT_ROUTE).points
            except ValueError:
                pass
            for p in pts:
                if p.name == name:
                    return p.x_m, p.y_m, name
            if any(g.id == name for g in self.world.gauges):
                x, y, _ = self.world.pose_facing_gauge(name)
                return x, y, name
            raise ValueError(f"no route point or gauge named {name!r}")
        try:
            x, y = float(args["x_m"]), float(args["y_m"])
        except (KeyError, TypeError, ValueError):
            raise ValueError("goto needs numeric x_m and y_m, or a point name") from None
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError("goto needs finite x_m and y_m")
        return x, y, str(args.get("name") or f"({x:.1f}, {y:.1f})")

    def _auto_patrol(self, which: str) -> None:
        """``--patrol``: start a route as soon as navigation is ready."""
        try:
            obj = {} if which == "default" else json.loads(
                pathlib.Path(which).read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            log.error("--patrol %s: %s", which, e)
            return
        with self._lock:
            ok, why = self._mission_command("start_patrol", {"route": obj})
        if not ok:
            log.error("--patrol %s: %s", which, why)

