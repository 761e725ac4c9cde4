"""EKF odometry fusion of wheel encoders and an IMU yaw rate (seed 003 §2.2).

State (seed 003 eq. 5): X = [x, y, θ, v_x, v_y, ω_z]ᵀ — world position and
heading, body-frame velocities and yaw rate. Motion model (eqs. 1, 6), the
velocities held constant over Δt (driven by process noise):

    x_k = x_{k−1} + Δt (cos θ v_x − sin θ v_y)
    y_k = y_{k−1} + Δt (sin θ v_x + cos θ v_y)
    θ_k = θ_{k−1} + Δt ω_z

Its Jacobian A = ∂f/∂X (eq. 7), written out in ``jacobian``:

    ∂x/∂θ = −Δt (sin θ v_x + cos θ v_y)   ∂x/∂v_x = Δt cos θ   ∂x/∂v_y = −Δt sin θ
    ∂y/∂θ =  Δt (cos θ v_x − sin θ v_y)   ∂y/∂v_x = Δt sin θ   ∂y/∂v_y =  Δt cos θ
    ∂θ/∂ω_z = Δt,                          ones on the diagonal.

Predict (eqs. 8–9): X̂⁻ = f(X̂), P⁻ = A P Aᵀ + Q. Update (eqs. 10–13):
K = P⁻Hᵀ(H P⁻ Hᵀ + R)⁻¹, X̂ = X̂⁻ + K (Z − H X̂⁻), P = (I − K H) P⁻.

Measurements are linear in the state (eq. 4, Z = h(X) + V):

- encoders: (v_x, v_y, ω_z) = ((Δs_R + Δs_L)/2Δt, 0, (Δs_R − Δs_L)/(W Δt));
  the zero lateral speed is the non-holonomic constraint. Because a
  skid-steer base slips when it turns (seed 003 §2.2), the encoder yaw rate's
  variance grows with the turn rate: σ² = σ₀² + (k_slip ω)²;
- IMU: ω_z, the gyro's yaw rate (bias removed by the caller, e.g. a
  standstill average).

Beyond the paper, ``gyro_bias=True`` appends a seventh state b, the gyro's
bias (a random walk): the IMU then measures ω_z + b (H = [0 … 1 1]), and
stretches where the wheels do not slip (driving straight) make b observable.
Without it the fused heading inherits the gyro's bias drift.

Kept general (a planar EKF with ``predict``, ``update``, ``update_encoders``,
``update_imu_yaw_rate``, ``state`` and ``covariance``) so that other bases —
the wall climber too — can reuse it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _ekf_kernels as _kernels
from .dead_reckoning import arcs_to_motion


@dataclass(frozen=True)
class EkfNoise:
    accel_mps2: float = 0.5  # process noise of v_x, v_y (per √s)
    yaw_accel_rps2: float = 1.0  # process noise of ω_z (per √s)
    pose_m: float = 1e-4  # small process noise on x, y (per √s)
    encoder_speed_mps: float = 0.01
    encoder_lateral_mps: float = 0.01
    encoder_yaw_rate_rps: float = 0.005
    encoder_slip_per_rps: float = 0.3  # extra encoder yaw-rate σ per rad/s of turning
    gyro_yaw_rate_rps: float = 0.005
    gyro_bias_walk_rps: float = 0.0002  # per √s, for the optional bias state
    gyro_bias_initial_rps: float = 0.005  # prior σ of the bias


X, Y, TH, VX, VY, WZ, BIAS = range(7)


def interval_rate(prev_rps: float | None, last_rps: float, dt: float,
                  sample_s: float) -> tuple[float, float]:
    """The mean yaw rate over a report's interval ``dt`` from a gyro whose
    report carries one sample, the rate over the board's last sampling period
    ``sample_s``: when reports are lost or thinned (dt > sample_s) the rest of
    the interval was not seen. There the rate went from the previous report's
    sample to this one's; taken as a step at an unknown (uniform) time, its
    mean over the unseen part is their midpoint, ±|Δ|/√12. Returns the
    interval's mean rate and the σ that the unseen part adds to it (0 when
    every sample is reported or the rate did not change). Holding the last
    sample over the whole interval instead puts the heading off by up to
    |Δ|·(dt − sample_s) on every change of the rate: 30–60 mrad at a turn's
    start or reversal with one report in four (docs/climber.md, "Lost
    reports in the turns in place")."""
    unseen = dt - sample_s
    if prev_rps is None or unseen <= 0.0 or dt <= 0.0:
        return last_rps, 0.0
    mean = (sample_s * last_rps + unseen * (prev_rps + last_rps) / 2) / dt
    return mean, unseen * abs(last_rps - prev_rps) / (dt * math.sqrt(12.0))


def _is_f8(a, ndim: int) -> bool:
    """Whether ``a`` is a writeable C-contiguous float64 array of ``ndim`` dimensions
    (what the compiled kernels take)."""
    return (type(a) is np.ndarray and a.ndim == ndim and a.dtype == np.float64
            and a.flags.c_contiguous and a.flags.writeable)


def _as_f8(a, ndim: int) -> np.ndarray:
    """``a`` as a C-contiguous float64 array of ``ndim`` dimensions (itself when
    it is one already: the filter's own callers pass such arrays)."""
    if _is_f8(a, ndim):
        return a
    a = np.atleast_1d(a) if ndim == 1 else np.atleast_2d(a)
    return np.ascontiguousarray(a, dtype=np.float64)


class OdometryEkf:
    """Six-state planar EKF (seed 003 eqs. 4–13)."""

    def __init__(self, x: float = 0.0, y: float = 0.0, theta: float = 0.0,
                 noise: EkfNoise = EkfNoise(), track_m: float | None = None,
                 gyro_bias: bool = False) -> None:
        self.noise = noise
        self.track_m = track_m
        self.n = 7 if gyro_bias else 6
        self._x = np.zeros(self.n)
        self._x[:3] = x, y, theta
        p0 = [1e-6, 1e-6, 1e-6, 1e-2, 1e-2, 1e-2]
        self._p = np.diag(p0 + [noise.gyro_bias_initial_rps ** 2] * (self.n - 6))
        self._q_dt: float | None = None  # the dt of _q_split (_split_noise)

    @property
    def state(self) -> np.ndarray:
        return self._x.copy()

    @property
    def covariance(self) -> np.ndarray:
        return self._p.copy()

    @property
    def pose(self) -> tuple[float, float, float]:
        return float(self._x[X]), float(self._x[Y]), float(self._x[TH])

    # -- predict (eqs. 6–9) -------------------------------------------------------------
    @staticmethod
    def motion(state: np.ndarray, dt: float) -> np.ndarray:
        x, y, th, vx, vy, wz = state[:6]
        c, s = math.cos(th), math.sin(th)
        out = state.copy()
        out[X] = x + dt * (c * vx - s * vy)
        out[Y] = y + dt * (s * vx + c * vy)
        out[TH] = (th + dt * wz + math.pi) % (2 * math.pi) - math.pi
        return out

    @property
    def gyro_bias(self) -> float:
        return float(self._x[BIAS]) if self.n == 7 else 0.0

    @staticmethod
    def jacobian(state: np.ndarray, dt: float) -> np.ndarray:
        th, vx, vy = state[TH], state[VX], state[VY]
        c, s = math.cos(th), math.sin(th)
        a = np.eye(len(state))
        a[X, TH] = -dt * (s * vx + c * vy)
        a[X, VX] = dt * c
        a[X, VY] = -dt * s
        a[Y, TH] = dt * (c * vx - s * vy)
        a[Y, VX] = dt * s
        a[Y, VY] = dt * c
        a[TH, WZ] = dt
        return a

    def process_noise(self, dt: float) -> np.ndarray:
        n = self.noise
        q = [n.pose_m ** 2, n.pose_m ** 2, 0.0, n.accel_mps2 ** 2, n.accel_mps2 ** 2,
             n.yaw_accel_rps2 ** 2] + [n.gyro_bias_walk_rps ** 2] * (self.n - 6)
        return np.diag(q) * dt

    def predict(self, dt: float) -> None:
        if dt <= 0:
            return
        a = self.jacobian(self._x, dt)
        self._x = self.motion(self._x, dt)
        self._own_arrays()
        self._p = _kernels.propagate(self._p, a, self.process_noise(dt))  # eq. 9

    def advance(self, dt: float, ds_left_m: float, ds_right_m: float,
                gyro_rps: float | None = None, gyro_unseen_rps: float = 0.0) -> None:
        """One odometry interval with its own rates: the wheel arcs and the gyro's
        rate measured over the ``dt`` just driven carry the pose over that same
        interval. :meth:`predict` then the updates carries the pose with the
        rates of the interval before (eq. 6 with the last estimate of v and ω),
        so while the yaw rate changes the heading lags by Δω·dt — at the start
        of a 0.5 rad/s turn 25 mrad for a 20 Hz report — and an absolute
        heading taken at the end of the interval (the wall climber's gravity
        heading) sees that lag as an error on every turn, one way for a left
        turn and the other for a right one. Here the rates' random walk (Q's velocity part) comes
        first, then the encoders' and the gyro's updates, then the pose's
        propagation (eqs. 6–9) with the rates just updated and Q's pose part.
        ``gyro_unseen_rps``: the σ the part of the interval the gyro's sample
        did not see adds to its white noise (:func:`interval_rate`)."""
        if dt <= 0:
            return
        q_rates, q_pose = self._split_noise(dt)
        self._p += q_rates
        self.update_encoders(ds_left_m, ds_right_m, dt)
        if gyro_rps is not None:
            sigma = math.hypot(self.noise.gyro_yaw_rate_rps, gyro_unseen_rps)
            self.update_imu_yaw_rate(gyro_rps, sigma)
        a = self.jacobian(self._x, dt)
        self._x = self.motion(self._x, dt)
        self._own_arrays()
        self._p = _kernels.propagate(self._p, a, q_pose)  # eq. 9

    def _split_noise(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Q(dt) as its rates' block and its pose's block (each zero elsewhere),
        kept for the last dt (the reports come at a steady rate; the noise
        settings are frozen)."""
        if self._q_dt != dt:
            q = self.process_noise(dt)
            pose = np.zeros(self.n, bool)
            pose[[X, Y, TH]] = True
            self._q_split = (np.where(~pose[:, None] & ~pose[None, :], q, 0.0),
                             np.where(pose[:, None] & pose[None, :], q, 0.0))
            self._q_dt = dt
        return self._q_split

    # -- update (eqs. 10–13) --------------------------------------------------------------
    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Linear measurement Z = H X + V, V ~ N(0, R); returns the innovation.
        K = P⁻Hᵀ(H P⁻ Hᵀ + R)⁻¹ (eq. 10), X̂ = X̂⁻ + K (Z − H X̂⁻) (eq. 11), and
        eq. 13 in Joseph form multiplied out (:func:`._ekf_kernels.update`)."""
        z, h, r = _as_f8(z, 1), _as_f8(h, 2), _as_f8(r, 2)
        self._own_arrays()
        return _kernels.update(self._x, self._p, z, h, r, TH)

    def _own_arrays(self) -> None:
        """State and covariance as contiguous float64 arrays of this filter's own
        (the kernels write into them; a caller may have set either)."""
        if not _is_f8(self._x, 1):
            self._x = np.array(self._x, dtype=np.float64)
        if not _is_f8(self._p, 2):
            self._p = np.array(self._p, dtype=np.float64)

    def update_body_velocity(self, v_mps: float, omega_rps: float) -> np.ndarray:
        """Encoder-derived forward speed and yaw rate, with v_y = 0."""
        n = self.noise
        h = np.zeros((3, self.n))
        h[0, VX] = h[1, VY] = h[2, WZ] = 1.0
        s_w2 = n.encoder_yaw_rate_rps ** 2 + (n.encoder_slip_per_rps * omega_rps) ** 2
        r = np.diag([n.encoder_speed_mps ** 2, n.encoder_lateral_mps ** 2, s_w2])
        return self.update(np.array([v_mps, 0.0, omega_rps]), h, r)

    def update_encoders(self, ds_left_m: float, ds_right_m: float, dt: float) -> np.ndarray:
        """Wheel arcs over dt (seed 002 eqs. 2–3) as body velocities."""
        if self.track_m is None:
            raise ValueError("update_encoders needs track_m (the effective wheel track)")
        if dt <= 0:
            raise ValueError(f"dt must be positive, got {dt}")
        ds, dth = arcs_to_motion(ds_left_m, ds_right_m, self.track_m)
        return self.update_body_velocity(ds / dt, dth / dt)

    def update_imu_yaw_rate(self, omega_rps: float, sigma_rps: float | None = None) -> np.ndarray:
        h = np.zeros((1, self.n))
        h[0, WZ] = 1.0
        if self.n == 7:
            h[0, BIAS] = 1.0  # the gyro reads ω_z + b
        s = self.noise.gyro_yaw_rate_rps if sigma_rps is None else sigma_rps
        return self.update(np.array([omega_rps]), h, np.array([[s * s]]))
