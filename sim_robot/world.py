"""The station: layout, occupancy, gas plume, climate, gauges and the robot's true pose.

Coordinates are metres in the station frame (x east, y north, origin at the
south-west corner); headings are radians counter-clockwise from +x. The layout
is read from ``app/resources/station/station.json``. Everything here is ground
truth: the desk never sees it, the simulated sensors sample it. The people and
the vehicle that move through the station are in :mod:`sim_robot.movers`
(re-exported here).
"""

from __future__ import annotations

import json
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from app.core.localisation import map_io

from . import raycast
from .config import DEFAULT_STATION
from .movers import DEFAULT_VEHICLES, Vehicle, Walker

FREE = 0


@dataclass
class Gauge:
    id: str
    type: str
    x: float
    y: float
    facing_rad: float
    min: float
    max: float
    unit: str
    mean: float
    amp: float
    period_s: float
    height_m: float = 1.3
    size_m: float = 0.35

    def value(self, t_s: float) -> float:
        v = self.mean + self.amp * math.sin(2 * math.pi * t_s / self.period_s)
        return min(self.max, max(self.min, v))


@dataclass
class TruePose:
    x: float
    y: float
    theta: float
    v: float = 0.0
    omega: float = 0.0


CONTACT_REARM_S = 2.0  # a contact with the same thing within this is the same collision


class World:
    """Static station map plus time-varying fields (all functions of sim time).

    ``clock`` gives the sim time used for things that move by themselves
    (people); the sim wires it to its :class:`~sim_robot.sim.SimClock`."""

    def __init__(self, station_file: str | Path = DEFAULT_STATION, seed: int = 0) -> None:
        with open(station_file, encoding="utf-8") as f:
            self.spec = spec = json.load(f)
        self.rng = np.random.default_rng(seed)
        self.size_m = tuple(spec["size_m"])
        self.res = float(spec["resolution_m"])
        self.origin = (0.0, 0.0)
        self.material_names = ["free", *spec["materials"].keys()]
        self.material_height = np.array(
            [0.0] + [m["height_m"] for m in spec["materials"].values()], np.float32)
        self.material_bgr = np.array(
            [[0, 0, 0]] + [m["bgr"] for m in spec["materials"].values()], np.float32)
        w = int(round(self.size_m[0] / self.res))
        h = int(round(self.size_m[1] / self.res))
        self.labels = np.zeros((h, w), np.uint8)  # row = y index, col = x index
        self._rasterise()
        self.gauges = [Gauge(**{k: g[k] for k in g}) for g in spec["gauges"]]
        for g in self.gauges:  # each gauge stands on a thin post
            self._fill_box("manifold", g.x - 0.08, g.y - 0.08, g.x + 0.08, g.y + 0.08)
        self.occupied = self.labels != FREE
        free = (~self.occupied).astype(np.uint8)
        self.clearance_m = cv2.distanceTransform(free, cv2.DIST_L2, 5) * self.res
        d = spec["dock"]
        self.dock = (d["x"], d["y"], d["theta_rad"], d["radius_m"])
        self.start_time_of_day_s = float(spec.get("start_time_of_day_h", 9.0)) * 3600.0
        self.gas_sources = spec["gas_sources"]
        self.wind = spec["wind"]
        self.climate = spec["climate"]
        # random phases make each seed's weather a little different
        self._phase = self.rng.uniform(0, 2 * math.pi, 8)
        self._lock = threading.Lock()
        self._pose = TruePose(d["x"], d["y"], d["theta_rad"])
        self.pose_time_s: float | None = None  # sim time of the last motion step
        self.clock: Callable[[], float] = lambda: 0.0
        self.walkers = [Walker(p, float(self.rng.uniform(0, 600)))
                        for p in spec.get("people", [])]
        self.vehicles = [Vehicle(v, float(self.rng.uniform(0, 120)))
                         for v in spec.get("vehicles", DEFAULT_VEHICLES)]
        self.robot_radius_m = 0.35  # for the vehicles' drivers; move_robot keeps it current
        # contacts of the robot's body with anything (static map, a person, a vehicle):
        # one record per collision, and an optional callback (the relay's event)
        self.collisions: list[dict] = []
        self.on_collision: Callable[[dict], None] | None = None
        self._last_contact: dict[str, float] = {}
        self._person_mat = self._mat("person") if "person" in self.material_names else 0
        self._runs: np.ndarray | None = None  # raycast.free_runs of the labels
        self._march: dict[tuple[float, float], tuple[np.ndarray, np.ndarray]] = {}
        # people() of the last sim time asked for, while no vehicle has moved since
        self._people_at: tuple[float, tuple, np.ndarray] | None = None

    # ------------------------------------------------------------------ layout

    def _mat(self, name: str) -> int:
        return self.material_names.index(name)

    def _fill_box(self, mat: str, x0: float, y0: float, x1: float, y1: float) -> None:
        c0, r0 = self.to_cell(x0, y0)
        c1, r1 = self.to_cell(x1, y1)
        self.labels[max(r0, 0):max(r1 + 1, 0), max(c0, 0):max(c1 + 1, 0)] = self._mat(mat)

    def _wall_rect(self, mat: str, s: dict, openings: list[dict]) -> None:
        t = s["thickness_m"]
        x0, y0, x1, y1 = s["xmin"], s["ymin"], s["xmax"], s["ymax"]
        sides = {"south": (x0, x1, True, y0), "north": (x0, x1, True, y1 - t),
                 "west": (y0, y1, False, x0), "east": (y0, y1, False, x1 - t)}
        for side, (a0, a1, horizontal, c) in sides.items():
            gaps = sorted((o["from"], o["to"]) for o in openings if o["side"] == side)
            a = a0
            for g0, g1 in [*gaps, (a1, a1)]:
                if g0 > a:
                    if horizontal:
                        self._fill_box(mat, a, c, g0, c + t)
                    else:
                        self._fill_box(mat, c, a, c + t, g0)
                a = max(a, g1)

    def _rasterise(self) -> None:
        s = self.spec
        f = s["fence"]
        self._wall_rect("fence", f, f.get("gates", []))
        for b in s["bunds"]:
            self._wall_rect("bund", b, b.get("openings", []))
        ys, xs = np.mgrid[0:self.labels.shape[0], 0:self.labels.shape[1]]
        cx = (xs + 0.5) * self.res
        cy = (ys + 0.5) * self.res
        for t in s["tanks"]:
            self.labels[(cx - t["x"]) ** 2 + (cy - t["y"]) ** 2 <= t["r"] ** 2] = \
                self._mat("tank")
        for b in s["boxes"]:
            self._fill_box(b["material"], b["xmin"], b["ymin"], b["xmax"], b["ymax"])
        for r in s["pipe_racks"]:
            p = r["pillar_m"] / 2
            x = r["x0"]
            while x <= r["x1"] + 1e-9:
                self._fill_box("rack", x - p, r["y"] - p, x + p, r["y"] + p)
                x += r["spacing_m"]

    def to_cell(self, x: float, y: float) -> tuple[int, int]:
        return int(math.floor(x / self.res)), int(math.floor(y / self.res))

    def occupancy_grid(self) -> tuple[np.ndarray, float, tuple[float, float]]:
        """(occupied[row=y, col=x] bool array, resolution_m, origin_xy of cell (0, 0))."""
        return self.occupied.copy(), self.res, self.origin

    def export_ros_map(self, yaml_path: str | Path) -> Path:
        """Write the occupancy grid as a ROS map_server pair (YAML + PNG, image row 0 =
        north edge) so the desk's planner can load the station's static map."""
        cells = np.where(self.occupied, map_io.OCCUPIED, map_io.FREE).astype(np.int8)
        grid = map_io.OccupancyGrid(cells, self.res, tuple(self.origin))
        return map_io.save_map(grid, yaml_path, ".png")

    def clearance(self, x: float, y: float) -> float:
        c, r = self.to_cell(x, y)
        h, w = self.clearance_m.shape
        if not (0 <= r < h and 0 <= c < w):
            return 0.0
        return float(self.clearance_m[r, c])

    # ------------------------------------------------------------------ robot body

    @property
    def pose(self) -> TruePose:
        with self._lock:
            p = self._pose
            return TruePose(p.x, p.y, p.theta, p.v, p.omega)

    def pose_and_time(self) -> tuple[TruePose, float | None]:
        """The pose and the sim time it was reached at, read together."""
        with self._lock:
            p = self._pose
            return TruePose(p.x, p.y, p.theta, p.v, p.omega), self.pose_time_s

    def pose_facing_gauge(self, gauge_id: str, standoff_m: float = 1.2
                          ) -> tuple[float, float, float]:
        """A pose ``standoff_m`` in front of a gauge's dial, looking at it."""
        for g in self.gauges:
            if g.id == gauge_id:
                x = g.x + standoff_m * math.cos(g.facing_rad)
                y = g.y + standoff_m * math.sin(g.facing_rad)
                theta = (g.facing_rad + 2 * math.pi) % (2 * math.pi) - math.pi
                return x, y, theta
        known = ", ".join(g.id for g in self.gauges)
        raise ValueError(f"no gauge {gauge_id!r} in this station (known: {known})")

    def set_pose(self, x: float, y: float, theta: float) -> None:
        with self._lock:
            self._pose = TruePose(x, y, theta)

    def people(self, t_s: float | None = None) -> np.ndarray:
        """(k, 3) array of x, y, radius of every person and vehicle at sim time ``t_s``
        (default now); rows in the order of :meth:`mover_ids`. Vehicles move on
        to ``t_s`` when it is later than their last update (they react to the robot)."""
        t = self.clock() if t_s is None else t_s
        if self.vehicles:
            p = self._pose  # a plain read: move_robot calls this under self._lock
            for v in self.vehicles:
                v.advance(t, (p.x, p.y), self.robot_radius_m)
        # the same moment again (the lidar, the rangers and the body step ask
        # several times per step): the walkers are functions of time, and the
        # vehicles have not moved since (their clocks say so)
        stamp = (tuple(self.walkers), tuple((v, v.t, v.s) for v in self.vehicles))
        last = self._people_at
        if last is not None and last[0] == t and last[1] == stamp:
            return last[2].copy()
        rows = [(*w.position(t), w.radius) for w in self.walkers]
        rows += [(*v.position(), v.radius) for v in self.vehicles]
        out = np.array(rows) if rows else np.zeros((0, 3))
        self._people_at = (t, stamp, out)
        return out.copy()

    def mover_ids(self) -> list[str]:
        """Names of the rows of :meth:`people`: "person:ID" then "vehicle:ID"."""
        return [f"person:{w.id}" for w in self.walkers] + \
            [f"vehicle:{v.id}" for v in self.vehicles]

    def _contact(self, what: str, x: float, y: float) -> None:
        """The robot's body touches ``what``: record a collision (once per episode)."""
        t = self.clock()
        last = self._last_contact.get(what, -math.inf)
        self._last_contact[what] = t
        if t - last < CONTACT_REARM_S:
            return
        rec = {"t_s": round(t, 2), "what": what, "x_m": round(x, 2), "y_m": round(y, 2)}
        self.collisions.append(rec)
        cb = self.on_collision
        if cb is not None:
            try:
                cb(rec)
            except Exception:  # noqa: BLE001 - a broken listener must not stop physics
                pass

    def _blocker(self, x: float, y: float, radius_m: float, people: np.ndarray,
                 ids: list[str]) -> str:
        if self.clearance(x, y) < radius_m:
            return "static"
        if len(people):
            d2 = (people[:, 0] - x) ** 2 + (people[:, 1] - y) ** 2
            hit = np.flatnonzero(d2 < (people[:, 2] + radius_m) ** 2)
            if len(hit):
                return ids[int(hit[0])] if int(hit[0]) < len(ids) else "person"
        return "static"

    def _free(self, x: float, y: float, radius_m: float, people: np.ndarray) -> bool:
        if self.clearance(x, y) < radius_m:
            return False
        if len(people):
            d2 = (people[:, 0] - x) ** 2 + (people[:, 1] - y) ** 2
            if np.any(d2 < (people[:, 2] + radius_m) ** 2):
                return False
        return True

    def move_robot(self, v: float, omega: float, dt: float, radius_m: float,
                   t_s: float | None = None, lateral_mps: float = 0.0) -> bool:
        """Advance the true pose by a unicycle step (with ``lateral_mps``, a body
        that also slides sideways: the 4WS base's full twist (v, vy, ω)); motion
        stops at contact (slides along a wall when one axis is free). Returns True
        when blocked. ``t_s``: the sim time the step ends at (the MCU model's
        sampling time; default the clock's now, which runs ahead of it while the
        MCU catches up)."""
        contacts: list[tuple[str, float, float]] = []
        with self._lock:
            self.robot_radius_m = radius_m
            p = self._pose
            theta = (p.theta + omega * dt + math.pi) % (2 * math.pi) - math.pi
            dist = math.hypot(v, lateral_mps) * dt
            n = max(1, int(math.ceil(dist / 0.04)))
            slant = math.atan2(lateral_mps, v) if lateral_mps else 0.0  # travel vs heading
            dist = dist if lateral_mps else v * dt
            x, y = p.x, p.y
            blocked = False
            ppl = self.people()
            ids = self.mover_ids()
            if len(ppl):  # someone already overlapping (they walked into us) does not pin us
                keep = (ppl[:, 0] - x) ** 2 + (ppl[:, 1] - y) ** 2 >= (ppl[:, 2] + radius_m) ** 2
                contacts += [(ids[i], x, y) for i in np.flatnonzero(~keep) if i < len(ids)]
                ids = [ids[i] for i in np.flatnonzero(keep) if i < len(ids)]
                ppl = ppl[keep]
            turn = (theta - p.theta + math.pi) % (2 * math.pi) - math.pi  # across ±π too
            for i in range(n):
                a = p.theta + turn * (i + 0.5) / n + slant
                dx, dy = dist / n * math.cos(a), dist / n * math.sin(a)
                if self._free(x + dx, y + dy, radius_m, ppl):
                    x, y = x + dx, y + dy
                    continue
                if not blocked:  # the first clamp of this step names what was touched
                    contacts.append((self._blocker(x + dx, y + dy, radius_m, ppl, ids), x, y))
                if self._free(x + dx, y, radius_m, ppl):
                    x, blocked = x + dx, True
                elif self._free(x, y + dy, radius_m, ppl):
                    y, blocked = y + dy, True
                else:
                    blocked = True
                    break
            moved = math.hypot(x - p.x, y - p.y) / dt if dt > 0 else 0.0
            self._pose = TruePose(x, y, theta, math.copysign(moved, v), omega)
            # when the body was last moved (sim time)
            self.pose_time_s = self.clock() if t_s is None else t_s
        for what, cx, cy in contacts:
            self._contact(what, cx, cy)
        return blocked

    def at_dock(self) -> bool:
        p = self.pose
        return math.hypot(p.x - self.dock[0], p.y - self.dock[1]) <= self.dock[3]

    # ------------------------------------------------------------------ ray casting

    def raycast(self, x: float, y: float, angles: np.ndarray, max_range_m: float,
                step_m: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Cast rays from (x, y) at absolute ``angles``; returns (range_m, material id)
        with range inf / material 0 where nothing is hit within ``max_range_m``.
        Each ray marches in steps of ``step_m`` (half a cell) to its first hit,
        which is then moved back to the first of ten finer samples inside that
        step (the coarse march alone puts a hit up to a whole step behind the
        cell's face, a range bias no lidar has); people and vehicles are circles
        (:mod:`sim_robot.raycast`)."""
        step = step_m or self.res * 0.5
        key = (step, max_range_m)
        steps = self._march.get(key)
        if steps is None:
            steps = self._march[key] = (raycast.march_steps(step, max_range_m),
                                        raycast.fine_offsets(step))
        angles = np.asarray(angles, np.float64)
        c64, s64 = np.cos(angles), np.sin(angles)
        n = len(angles)
        rng = np.empty(n, np.float32)
        mat = np.empty(n, np.uint8)
        ppl = self.people() if self.walkers else None
        if self._runs is None:  # (the labels do not change after construction)
            self._runs = raycast.free_runs(self.labels)
        raycast.cast(self.labels, self._runs, float(x), float(y), c64.astype(np.float32),
                     s64.astype(np.float32), c64, s64, steps[0], steps[1], self.res,
                     float(max_range_m), ppl, self._person_mat, rng, mat)
        return rng, mat

    def _ray_people(self, x: float, y: float, angles: np.ndarray) -> np.ndarray:
        """Distance along each ray to the nearest person (a circle), inf if none."""
        ppl = self.people()
        if not len(ppl):
            return np.full(len(angles), np.inf, np.float32)
        ca, sa = np.cos(angles)[:, None], np.sin(angles)[:, None]
        dx, dy, r = ppl[:, 0] - x, ppl[:, 1] - y, ppl[:, 2]
        b = dx * ca + dy * sa  # along the ray
        d2 = dx * dx + dy * dy - b * b  # squared miss distance
        h = np.sqrt(np.maximum(r * r - d2, 0.0))
        t = np.where((d2 <= r * r) & (b - h > 0), b - h, np.inf)
        return t.min(axis=1).astype(np.float32)

    def _with_people(self, x, y, angles, max_range_m, rng, mat):
        if not self.walkers:
            return rng, mat
        rp = self._ray_people(x, y, angles)
        closer = (rp < rng) & (rp <= max_range_m)
        return np.where(closer, rp, rng), np.where(closer, self._person_mat, mat).astype(np.uint8)

    def raycast_layers(self, x: float, y: float, angles: np.ndarray, max_range_m: float,
                       tall_m: float, step_m: float) -> tuple[np.ndarray, ...]:
        """Like :meth:`raycast` but also returns the first hit taller than ``tall_m``
        (so a camera sees a tank over a low bund wall): (r_near, m_near, r_tall, m_tall)."""
        d = np.arange(step_m, max_range_m + step_m, step_m, dtype=np.float32)
        ca = np.cos(angles).astype(np.float32)[:, None]
        sa = np.sin(angles).astype(np.float32)[:, None]
        cols = np.floor((x + ca * d) / self.res).astype(np.int32)
        rows = np.floor((y + sa * d) / self.res).astype(np.int32)
        h, w = self.labels.shape
        np.clip(cols, 0, w - 1, out=cols)
        np.clip(rows, 0, h - 1, out=rows)
        lab = self.labels[rows, cols]
        idx = np.arange(len(angles))
        out = []
        for hit in (lab != FREE, self.material_height[lab] > tall_m):
            first = hit.argmax(axis=1)
            ok = hit[idx, first]
            out.extend(self._with_people(
                x, y, angles, max_range_m, np.where(ok, d[first], np.inf).astype(np.float32),
                np.where(ok, lab[idx, first], 0).astype(np.uint8)))
        return tuple(out)

    # ------------------------------------------------------------------ fields over time

    def time_of_day_s(self, t_s: float) -> float:
        return (self.start_time_of_day_s + t_s) % 86400.0

    def wind_at(self, t_s: float) -> tuple[float, float]:
        """(direction the wind blows towards, rad; speed m/s), changing slowly."""
        w = self.wind
        ph = self._phase
        d = w["dir_rad"] + w["dir_swing_rad"] * (
            0.7 * math.sin(2 * math.pi * t_s / w["period_s"] + ph[0])
            + 0.3 * math.sin(2 * math.pi * t_s / (w["period_s"] * 0.27) + ph[1]))
        s = w["speed_mps"] * (1.0 + 0.4 * math.sin(2 * math.pi * t_s / 311.0 + ph[2]))
        return d, max(0.3, s)

    def gas_lel_pct(self, x: float, y: float, t_s: float) -> float:
        """Gas concentration (%LEL) from the leak sources: a near-source blob plus a
        Gaussian plume bent down-wind whose width grows with distance."""
        wd, ws = self.wind_at(t_s)
        cw, sw = math.cos(wd), math.sin(wd)
        total = 0.0
        for i, src in enumerate(self.gas_sources):
            q = src["rate_lel"] * (0.65 + 0.35 * math.sin(
                2 * math.pi * t_s / src["period_s"] + self._phase[3 + i % 5]))
            dx, dy = x - src["x"], y - src["y"]
            s = dx * cw + dy * sw  # down-wind distance
            c = -dx * sw + dy * cw  # cross-wind offset
            r2 = dx * dx + dy * dy
            blob = math.exp(-r2 / (2 * 1.5 ** 2))
            plume = 0.0
            if s > 0:
                sigma = 0.8 + 0.25 * s
                plume = (0.8 / (1 + 0.15 * s * ws)) * math.exp(-c * c / (2 * sigma * sigma))
            total += q * max(blob, plume)
        return total

    def ambient(self, t_s: float) -> tuple[float, float]:
        """(temperature degC, relative humidity %) over the day: warmest at 15:00."""
        c = self.climate
        tod = self.time_of_day_s(t_s) / 3600.0
        s = math.sin(2 * math.pi * (tod - 9.0) / 24.0)
        slow = math.sin(2 * math.pi * t_s / 1800.0 + self._phase[7])
        temp = c["temp_mean_c"] + c["temp_amp_c"] * s + 0.4 * slow
        hum = c["humidity_mean_pct"] - c["humidity_amp_pct"] * s - 1.5 * slow
        return temp, min(100.0, max(0.0, hum))


if __name__ == "__main__":  # python -m sim_robot.world [out.yaml]: regenerate the static map
    import sys

    out = sys.argv[1] if len(sys.argv) > 1 else str(DEFAULT_STATION.with_name("station_map.yaml"))
    World().export_ros_map(out)
