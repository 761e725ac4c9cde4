"""What moves through the station by itself: people walking their rounds and a
utility vehicle on the main road. The world (:mod:`sim_robot.world`) places
them, casts the lidar's rays against them and stops the robot's body at them;
they are ground truth, which the robot's navigation never reads (it tracks
them from its own scans, :mod:`sim_robot.tracker`).
"""

from __future__ import annotations

import bisect
import math
import threading

import numpy as np


class _PolylineMover:
    """What a walker and a vehicle read from their spec alike: ``id``, the
    polyline ``path`` driven there and back, ``speed_mps``, ``pause_s`` at each
    end and ``radius_m``; and the polyline's arc length at each vertex."""

    def __init__(self, spec: dict) -> None:
        self.id = spec["id"]
        self.pts = np.array(spec["path"], float)
        self.speed = float(spec["speed_mps"])
        self.pause = float(spec["pause_s"])
        self.radius = float(spec["radius_m"])
        seg = np.linalg.norm(np.diff(self.pts, axis=0), axis=1)
        self.cum = np.concatenate([[0.0], np.cumsum(seg)])
        self.length = float(self.cum[-1])
        # the same as plain floats, for the point at an arc length (asked for
        # several times per step of every mover)
        self._cum = [float(c) for c in self.cum]
        self._xs = [float(v) for v in self.pts[:, 0]]
        self._ys = [float(v) for v in self.pts[:, 1]]

    def point(self, s: float) -> tuple[float, float]:
        """The point at arc length ``s``: ``np.interp(s, cum, pts[:, k])`` for
        k = 0, 1, in the same double arithmetic, without numpy's per-call cost."""
        return _interp(s, self._cum, self._xs), _interp(s, self._cum, self._ys)


def _interp(x: float, xp: list[float], fp: list[float]) -> float:
    """numpy's ``interp`` of one value (its C loop, step by step): the last
    knot at or before ``x``, the ends held outside, the knot's value on a knot."""
    if math.isnan(x):
        return x
    n = len(xp)
    if n == 1 or x >= xp[-1]:
        return fp[-1] if x >= xp[-1] else fp[0]
    if x < xp[0]:
        return fp[0]
    j = bisect.bisect_right(xp, x) - 1
    if xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    out = slope * (x - xp[j]) + fp[j]
    if math.isnan(out):  # numpy's second try, from the other knot
        out = slope * (x - xp[j + 1]) + fp[j + 1]
        if math.isnan(out) and fp[j] == fp[j + 1]:
            out = fp[j]
    return out


class Walker(_PolylineMover):
    """A person walking a polyline there and back, pausing at each end (a pure
    function of sim time, so every sensor agrees where they are)."""

    def __init__(self, spec: dict, phase_s: float) -> None:
        super().__init__(spec)
        self.period = 2 * (self.length / self.speed + self.pause)
        self.phase = phase_s

    def position(self, t_s: float) -> tuple[float, float]:
        walk = self.length / self.speed
        u = (t_s + self.phase) % self.period
        if u < walk:
            s = u * self.speed
        elif u < walk + self.pause:
            s = self.length
        elif u < 2 * walk + self.pause:
            s = self.length - (u - walk - self.pause) * self.speed
        else:
            s = 0.0
        return self.point(s)


# A small utility vehicle (a disc standing in for a ~1.8 m wide cart) that runs up
# and down the main east-west road now and then, across the north-south road the
# patrol uses; a station file may list its own under "vehicles".
DEFAULT_VEHICLES = [
    {"id": "cart-1", "path": [[4.0, 25.5], [77.0, 25.5]], "speed_mps": 2.0, "pause_s": 25.0,
     "radius_m": 0.9},
]


class Vehicle(_PolylineMover):
    """A vehicle driving a polyline there and back, pausing at each end. Unlike a
    walker it has state: its driver brakes (stops at once) while the robot's body
    is in its lane within ``stop_gap_m`` ahead, and drives on when it is clear."""

    def __init__(self, spec: dict, phase_s: float) -> None:
        super().__init__(spec)
        self.stop_gap_m = float(spec.get("stop_gap_m", 3.0))
        self.s = 0.0
        self.dir = 1
        self.wait = phase_s % (2 * self.pause + 2 * self.length / self.speed)
        self.t: float | None = None
        self.yielding = False
        self.yield_count = 0
        self._lock = threading.Lock()

    def _at(self, s: float) -> tuple[float, float, float, float]:
        """(x, y, ux, uy): position at arc length s and the unit driving direction."""
        i = int(min(max(np.searchsorted(self.cum, s, side="right") - 1, 0), len(self.pts) - 2))
        d = self.pts[i + 1] - self.pts[i]
        n = float(np.hypot(*d)) or 1.0
        x, y = self.point(s)
        return x, y, self.dir * d[0] / n, self.dir * d[1] / n

    def advance(self, t_s: float, robot_xy: tuple[float, float], robot_r: float) -> None:
        with self._lock:
            if self.t is None:
                self.t = t_s
                return
            if t_s <= self.t:  # another thread asked for a moment already passed
                return
            dt = min(t_s - self.t, 5.0)  # a long gap (a paused sim) jumps, never spins
            self.t = t_s
            while dt > 1e-9:
                h = min(dt, 0.1)
                dt -= h
                if self.wait > 0:
                    self.wait -= h
                    continue
                x, y, ux, uy = self._at(self.s)
                rx, ry = robot_xy[0] - x, robot_xy[1] - y
                along = rx * ux + ry * uy
                lateral = abs(rx * uy - ry * ux)
                reach = self.radius + robot_r
                if 0.0 < along < reach + self.stop_gap_m and lateral < reach + 0.5:
                    if not self.yielding:
                        self.yield_count += 1
                    self.yielding = True
                    continue
                self.yielding = False
                self.s += self.dir * self.speed * h
                if self.s >= self.length:
                    self.s, self.dir, self.wait = self.length, -1, self.pause
                elif self.s <= 0.0:
                    self.s, self.dir, self.wait = 0.0, 1, self.pause

    def position(self) -> tuple[float, float]:
        with self._lock:
            x, y, _, _ = self._at(self.s)
        return x, y
