"""Recovery: a robot that touches, or stands too close to, an obstacle backs
away from it before it plans again (nav2's BackUp and Spin behaviours, steered
by the static map).

The robot knows it is too close from its own estimate and the station map
(the planner's clearance field), never from the simulator's ground truth. The
way out is towards the nearest point the planner may start from with room to
spare (free on the inflated map by ``SPARE_M`` more): the robot turns on the
spot (a round body turns without sweeping anything) until that point lies
straight ahead or straight behind, whichever needs the smaller turn, then
drives there slowly — backwards when it lies behind, so the MCU's front
ranger, which stops forward motion beside a wall, does not pin it. It is done
once the estimate stands free on the inflated map (a plan starts there), or
gives up after ``TIMEOUT_S`` of sim time.

The command still goes through the planner's safety governor, so a person
walking by is respected while backing away.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

TOUCH_M = 0.0  # the map's clearance beyond the body at or under which the robot touches
SPARE_M = 0.1  # the way out ends this far inside the free space of the inflated map
SEARCH_M = 2.0  # ... searched for within this distance of the robot
SPEED_MPS = 0.15
TURN_RPS = 0.6
ALIGNED_RAD = 0.3  # drive once the way out is this close to straight ahead (or behind)
TIMEOUT_S = 20.0  # sim time


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


@dataclass
class Escape:
    x: float  # the free point the robot backs away to
    y: float
    reverse: bool  # it lies behind the robot: drive backwards
    started_t: float
    clearance_m: float  # the clearance beyond the body where it started (by the map)


class Recovery:
    """``dist_m``: the planner's clearance field (metres from each cell centre
    to the nearest obstacle surface); ``inflated``: its inflated map (True =
    blocked) on the same grid."""

    def __init__(self, dist_m: np.ndarray, inflated: np.ndarray, resolution_m: float,
                 origin_xy: tuple[float, float], robot_radius_m: float,
                 inflation_m: float) -> None:
        self.dist = dist_m
        self.inflated = inflated
        self.res = resolution_m
        self.origin = origin_xy
        self.radius = robot_radius_m
        self.inflation_m = inflation_m
        self.escape: Escape | None = None

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        return (int(math.floor((y - self.origin[1]) / self.res)),
                int(math.floor((x - self.origin[0]) / self.res)))

    def clearance_m(self, x: float, y: float) -> float:
        """Clearance between the body and the nearest mapped obstacle (negative:
        the body overlaps it by the map; -1 off the map)."""
        r, c = self._cell(x, y)
        h, w = self.dist.shape
        if not (0 <= r < h and 0 <= c < w):
            return -1.0
        return float(self.dist[r, c]) - self.radius

    def touching(self, x: float, y: float) -> bool:
        return self.clearance_m(x, y) <= TOUCH_M

    def free(self, x: float, y: float) -> bool:
        """Free on the inflated map: a plan may start here."""
        r, c = self._cell(x, y)
        h, w = self.inflated.shape
        return 0 <= r < h and 0 <= c < w and not self.inflated[r, c]

    def way_out(self, x: float, y: float) -> tuple[float, float] | None:
        """The nearest cell centre with clearance to spare (free on the map
        inflated by ``SPARE_M`` more), within ``SEARCH_M``; else the nearest
        free one; None when there is none."""
        r, c = self._cell(x, y)
        n = int(math.ceil(SEARCH_M / self.res))
        h, w = self.dist.shape
        r0, r1 = max(r - n, 0), min(r + n + 1, h)
        c0, c1 = max(c - n, 0), min(c + n + 1, w)
        if r0 >= r1 or c0 >= c1:
            return None
        rows, cols = np.mgrid[r0:r1, c0:c1]
        cx = self.origin[0] + (cols + 0.5) * self.res
        cy = self.origin[1] + (rows + 0.5) * self.res
        d2 = (cx - x) ** 2 + (cy - y) ** 2
        free = ~self.inflated[r0:r1, c0:c1]
        roomy = free & (self.dist[r0:r1, c0:c1] >= self.radius + self.inflation_m + SPARE_M)
        for ok in (roomy, free):
            if ok.any():
                i = int(np.argmin(np.where(ok, d2, np.inf)))
                return float(cx.flat[i]), float(cy.flat[i])
        return None

    def begin(self, pose, t_s: float) -> Escape | None:
        """Start backing away from where the robot is; None when the map has
        no way out near it."""
        x, y, th = pose
        out = self.way_out(x, y)
        if out is None:
            self.escape = None
            return None
        bearing = math.atan2(out[1] - y, out[0] - x)
        self.escape = Escape(out[0], out[1], abs(_wrap(bearing - th)) > math.pi / 2, t_s,
                             self.clearance_m(x, y))
        return self.escape

    def command(self, pose, t_s: float) -> tuple[float, float, str]:
        """(v, ω, status): status "recovering", "done" (free on the inflated map)
        or "timeout"."""
        e = self.escape
        x, y, th = pose
        if e is None:
            return 0.0, 0.0, "done"
        if self.free(x, y) and self.clearance_m(x, y) > TOUCH_M:
            return 0.0, 0.0, "done"
        if t_s - e.started_t > TIMEOUT_S:
            return 0.0, 0.0, "timeout"
        d = math.hypot(e.x - x, e.y - y)
        if d < 0.05:  # at the way out, yet not free (the estimate moved): done too
            return 0.0, 0.0, "done"
        bearing = math.atan2(e.y - y, e.x - x)
        facing = th + math.pi if e.reverse else th
        err = _wrap(bearing - facing)
        w = max(-TURN_RPS, min(TURN_RPS, 1.5 * err))
        if abs(err) > ALIGNED_RAD:
            return 0.0, w if abs(w) >= 0.2 else math.copysign(0.2, err), "recovering"
        v = min(SPEED_MPS, max(0.05, d)) * math.cos(err)
        return (-v if e.reverse else v), w, "recovering"
