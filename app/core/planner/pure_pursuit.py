"""Pure pursuit path tracking on the 4WS base (seed 004 §2.1, the tracking
controller it evaluates in Gazebo after Figs. 1–3).

Each cycle: find the path point nearest the robot (searching forward from the
last one, so a path that passes near itself is not short-cut), walk the
look-ahead distance Ld along the path to the target point, and steer onto the
arc through it tangent to the heading:

    κ = 2 sin α / Ld        (α: bearing of the target in the body frame)

The look-ahead is scheduled with the speed, Ld = clip(Ld0 + k·v, Ld_min,
Ld_max): short when slow (tight tracking), longer when fast (no weaving). The
arc is driven in the 4WS COUNTER mode (δr = −δf, ICR on the lateral axis), so
the yaw rate is ω = v·κ and |κ| ≤ 1/R_min of that mode; the speed is reduced
on tight arcs (lateral acceleration limit) and to stop at the path's end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..kinematics import FwsGeometry, Mode, Twist, limit_twist, min_turn_radius

__all__ = ["PurePursuit", "PurePursuitConfig", "cross_track_error"]


@dataclass(frozen=True)
class PurePursuitConfig:
    speed_mps: float = 0.8
    lookahead_base_m: float = 0.15
    lookahead_gain_s: float = 0.3
    lookahead_min_m: float = 0.2
    lookahead_max_m: float = 1.5
    max_lateral_accel_mps2: float = 0.6
    max_decel_mps2: float = 0.5
    geometry: FwsGeometry = field(default_factory=FwsGeometry)

    def lookahead(self, speed_mps: float) -> float:
        return float(np.clip(self.lookahead_base_m + self.lookahead_gain_s * abs(speed_mps),
                             self.lookahead_min_m, self.lookahead_max_m))


class PurePursuit:
    """Tracks one path (N × 2, metres). ``command(pose, speed_now)`` returns
    the twist for this cycle; ``done`` once the end is reached."""

    def __init__(self, path, config: PurePursuitConfig | None = None):
        p = np.asarray(path, dtype=float).reshape(-1, 2)
        keep = np.r_[True, np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-9]
        p = p[keep]
        if len(p) < 2:
            raise ValueError("pure pursuit needs a path of at least two distinct points")
        self.path = p
        self.cfg = config or PurePursuitConfig()
        self.s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        self.k_max = 1.0 / min_turn_radius(self.cfg.geometry, Mode.COUNTER)
        self._i = 0
        self.done = False

    def _nearest(self, xy: np.ndarray) -> tuple[int, float]:
        """Index of the segment nearest xy within a window ahead, and the arc
        length of the foot point."""
        lo = self._i
        hi = min(len(self.path) - 1, lo + 60)
        a = self.path[lo:hi]
        b = self.path[lo + 1:hi + 1]
        ab = b - a
        t = np.clip(np.sum((xy - a) * ab, axis=1) / np.maximum(np.sum(ab * ab, axis=1), 1e-12),
                    0.0, 1.0)
        d = np.linalg.norm(a + t[:, None] * ab - xy, axis=1)
        k = int(np.argmin(d))
        self._i = lo + k
        return lo + k, self.s[lo + k] + t[k] * (self.s[lo + k + 1] - self.s[lo + k])

    def _point_at(self, s: float) -> np.ndarray:
        s = min(s, self.s[-1])
        return np.array([np.interp(s, self.s, self.path[:, 0]),
                         np.interp(s, self.s, self.path[:, 1])])

    def command(self, pose, speed_now: float) -> Twist:
        c = self.cfg
        x, y, th = float(pose[0]), float(pose[1]), float(pose[2])
        _, s_foot = self._nearest(np.array([x, y]))
        left = self.s[-1] - s_foot
        if left < 0.02:
            self.done = True
            return Twist(0.0)
        ld = c.lookahead(max(speed_now, 0.1))
        tx, ty = self._point_at(s_foot + ld)
        dx, dy = tx - x, ty - y
        alpha = math.atan2(dy, dx) - th
        dist = math.hypot(dx, dy)
        kappa = 2.0 * math.sin(alpha) / max(dist, 1e-6)
        kappa = float(np.clip(kappa, -self.k_max, self.k_max))
        v = c.speed_mps
        if abs(kappa) > 1e-9:
            v = min(v, math.sqrt(c.max_lateral_accel_mps2 / abs(kappa)))
        v = min(v, math.sqrt(2.0 * c.max_decel_mps2 * left))  # stop at the end
        return limit_twist(c.geometry, Twist(v, 0.0, v * kappa))


def cross_track_error(path, xy) -> np.ndarray:
    """Distance from each point in xy (k × 2) to the polyline path (metres)."""
    p = np.asarray(path, dtype=float)
    q = np.asarray(xy, dtype=float).reshape(-1, 2)
    a, b = p[:-1], p[1:]
    ab = b - a
    out = np.empty(len(q))
    L2 = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
    for i, pt in enumerate(q):
        t = np.clip(np.sum((pt - a) * ab, axis=1) / L2, 0.0, 1.0)
        out[i] = float(np.min(np.linalg.norm(a + t[:, None] * ab - pt, axis=1)))
    return out


def track(path, config: PurePursuitConfig | None = None, dt_s: float = 0.02,
          max_time_s: float = 600.0, pose0=None) -> tuple[np.ndarray, np.ndarray]:
    """Drive the 4WS model along ``path`` with pure pursuit from ``pose0``
    (default: the path's start, heading along its first segment — the base
    turns in place to it before a leg). Returns the poses (k × 3) and the
    commanded speeds; the pose update is the exact arc of Fig. 3."""
    from ..kinematics import integrate_pose

    pp = PurePursuit(path, config)
    p = pp.path
    if pose0 is None:
        d = p[1] - p[0]
        pose0 = (p[0, 0], p[0, 1], math.atan2(d[1], d[0]))
    pose = tuple(float(v) for v in pose0)
    poses = [pose]
    speeds = []
    v = 0.0
    t = 0.0
    while not pp.done and t < max_time_s:
        tw = pp.command(pose, v)
        # first-order speed response with the drive's acceleration limit
        dv = float(np.clip(tw.vx - v, -pp.cfg.max_decel_mps2 * dt_s, 1.0 * dt_s))
        scale = (v + dv) / tw.vx if abs(tw.vx) > 1e-9 else 0.0
        tw = Twist(v + dv, 0.0, tw.omega * scale)
        pose = integrate_pose(pose, tw, dt_s)
        v = tw.vx
        poses.append(pose)
        speeds.append(v)
        t += dt_s
    return np.array(poses), np.array(speeds)
