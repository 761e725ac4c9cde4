"""The climber's accelerometer, and the heading its board derives from it.

On a vertical wall the body's x (forward) and y (left) axes lie in the wall's
plane, and gravity (0, −g) in the wall frame is seen by the accelerometer
as the specific force f = a − g_vec, in the body frame

    f_x = a_fwd + g sin θ,    f_y = v ω + g cos θ,

with a_fwd the body's forward acceleration and v ω its centripetal one. The
board knows the wheels' speed v_w and the gyro's rate, so it removes
a_fwd ≈ Δv_w/Δt and v_w ω and sends θ_g = atan2(f_x − a_fwd, f_y − v_w ω):
a heading with no drift (the relay's estimator takes it as an absolute
measurement, app/core/localisation/wall_ekf.py). What is left is the
accelerometer's noise and bias and the acceleration the wheels do not
see (slip). Simulated here from the true body state (the board's side).
"""

from __future__ import annotations

import math

import numpy as np

G_MPS2 = 9.81


class WallAccelerometer:
    """Two in-plane axes: white noise ``noise_mps2`` per sample, a constant
    bias per axis (residual after calibration, drawn from ``bias_mps2``)."""

    def __init__(self, rng: np.random.Generator, noise_mps2: float = 0.02,
                 bias_mps2: float = 0.01) -> None:
        self.rng = rng
        self.noise = noise_mps2
        self.bias = rng.normal(0.0, bias_mps2, size=2)
        self._v_true: float | None = None
        self._v_wheel: float | None = None

    def sample(self, dt: float, theta_rad: float, v_true_mps: float, omega_true_rps: float
               ) -> tuple[float, float]:
        """Specific force (f_x, f_y) in m/s² after a step of dt at the true
        heading, body speed and yaw rate."""
        a_fwd = 0.0 if self._v_true is None or dt <= 0 else (v_true_mps - self._v_true) / dt
        self._v_true = v_true_mps
        fx = a_fwd + G_MPS2 * math.sin(theta_rad)
        fy = v_true_mps * omega_true_rps + G_MPS2 * math.cos(theta_rad)
        n = self.noise * self.rng.standard_normal(2)
        return fx + self.bias[0] + n[0], fy + self.bias[1] + n[1]

    def heading(self, dt: float, fx: float, fy: float, v_wheel_mps: float,
                gyro_rps: float) -> float:
        """The board's gravity heading: the wheels' acceleration and the
        centripetal term removed, then atan2 (rad, wrapped to ±π)."""
        a_fwd = 0.0 if self._v_wheel is None or dt <= 0 else (v_wheel_mps - self._v_wheel) / dt
        self._v_wheel = v_wheel_mps
        return math.atan2(fx - a_fwd, fy - v_wheel_mps * gyro_rps)
