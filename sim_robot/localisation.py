"""Map-based localisation — a STAND-IN for a scan matcher (seeds 002/003 replace it).

A real robot corrects its drifting odometry by matching lidar scans against the
station map (ICP + EKF, seed 002). Until that exists, this module delivers what
such a matcher would: the odometry increment predicts the pose, and a
correction pulls the estimate toward the true pose plus bounded noise
(σ 3 cm, 0.5°, clipped at 3σ), as a scan-matcher fix would. The error is
therefore bounded and does not drift. It reads ground truth, so it exists only
in the simulator; the desk sees only its output (the published Pose).
"""

from __future__ import annotations

import math

import numpy as np


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class Localiser:
    def __init__(self, x: float, y: float, theta: float, seed: int = 0,
                 sigma_xy_m: float = 0.03, sigma_theta_rad: float = math.radians(0.5),
                 gain: float = 0.5) -> None:
        self.x, self.y, self.theta = x, y, theta
        self.v = 0.0
        self.omega = 0.0
        self.sigma_xy_m = sigma_xy_m
        self.sigma_theta_rad = sigma_theta_rad
        self.gain = gain  # weight of each fix against the odometry prediction
        self.rng = np.random.default_rng(seed + 3000)
        self._odom: tuple[float, float, float] | None = None
        self.fixes = 0

    def _noise(self, sigma: float) -> float:
        return float(np.clip(self.rng.standard_normal(), -3.0, 3.0)) * sigma

    def predict(self, odom_xytheta: tuple[float, float, float]) -> None:
        """Apply the odometry increment since the last call (in the odometry frame,
        rotated into the estimate's frame, so odometry drift does not leak in)."""
        ox, oy, oth = odom_xytheta
        if self._odom is not None:
            px, py, pth = self._odom
            dx, dy = ox - px, oy - py
            # the increment in the robot's frame at the previous odometry pose ...
            c, s = math.cos(pth), math.sin(pth)
            fwd, left = c * dx + s * dy, -s * dx + c * dy
            # ... applied from the estimate
            c, s = math.cos(self.theta), math.sin(self.theta)
            self.x += c * fwd - s * left
            self.y += s * fwd + c * left
            self.theta = _wrap(self.theta + _wrap(oth - pth))
        self._odom = (ox, oy, oth)

    def correct(self, true_xytheta: tuple[float, float, float],
                velocity: tuple[float, float] = (0.0, 0.0)) -> tuple[float, float, float]:
        """One 'scan-matcher fix': pull toward the truth plus bounded noise."""
        tx, ty, tth = true_xytheta
        zx = tx + self._noise(self.sigma_xy_m)
        zy = ty + self._noise(self.sigma_xy_m)
        zth = tth + self._noise(self.sigma_theta_rad)
        g = self.gain
        self.x += g * (zx - self.x)
        self.y += g * (zy - self.y)
        self.theta = _wrap(self.theta + g * _wrap(zth - self.theta))
        # whatever the odometry did, the fix keeps the error within a few sigma
        lim = 4 * self.sigma_xy_m
        self.x = tx + float(np.clip(self.x - tx, -lim, lim))
        self.y = ty + float(np.clip(self.y - ty, -lim, lim))
        lim_th = 4 * self.sigma_theta_rad
        self.theta = _wrap(tth + float(np.clip(_wrap(self.theta - tth), -lim_th, lim_th)))
        self.v, self.omega = velocity
        self.fixes += 1
        return self.pose

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.x, self.y, self.theta
