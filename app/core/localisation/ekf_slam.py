"""Seed 002's laser-landmark EKF (§2.3, Fig. 5, eqs. 6–14).

The state holds the robot's pose and the pose of every laser landmark
(eq. 9), with the full covariance and its blocks (eq. 10):

    X = [X_R, X_1, …, X_n]ᵀ,   P = [[P_R, P_R1, …], [P_1R, P_1, …], …]

- ``predict(u, Q)``: dead reckoning moves the robot, X_R ← X_R ⊕ u (eqs. 1–5);
  the error propagation of eq. 11 with A = ∂(X_R ⊕ u)/∂X_R (state error
  transfer) and B = ∂(X_R ⊕ u)/∂u (control error transfer):
  P_R ← A P_R Aᵀ + B Q Bᵀ and P_Ri ← A P_Ri for every landmark i.
- ``add_landmark()``: the n-th landmark is put at the robot's pose; its rows
  and columns copy the robot's (P_n = P_R, P_nR = P_R, P_ni = P_Ri), the
  state of eqs. 9–10 when a landmark joins.
- ``update(n, z, R)``: ICP gives the robot's pose relative to landmark n,
  z = (Δx_n, Δy_n, Δθ_n) (eqs. 6–8 with the sensor offsets a, b zero: the
  scans are taken in the sensor frame), h(X) = X_n ⊖ X_R; the observation
  Jacobians H_R = ∂h/∂X_R and H_n = ∂h/∂X_n (eqs. 12–14) are written out, and
  the Kalman update acts on the whole state, so the cross-covariances carry a
  correction at one landmark to the others — which is also what makes a loop
  closure (an update against an old landmark) straighten the whole map.
"""

from __future__ import annotations

import math

import numpy as np

from .se2 import compose, relative, wrap


class LandmarkEkf:
    def __init__(self, pose=(0.0, 0.0, 0.0), sigma_xy_m: float = 1e-3,
                 sigma_theta_rad: float = 1e-3) -> None:
        self.x = np.array(pose, dtype=float)
        self.p = np.diag([sigma_xy_m ** 2, sigma_xy_m ** 2, sigma_theta_rad ** 2])

    @property
    def robot(self) -> np.ndarray:
        return self.x[:3].copy()

    @property
    def landmark_count(self) -> int:
        return len(self.x) // 3 - 1

    def landmark(self, n: int) -> np.ndarray:
        return self.x[3 + 3 * n:6 + 3 * n].copy()

    # -- eq. 11 ---------------------------------------------------------------------
    @staticmethod
    def motion_jacobians(robot: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c, s = math.cos(robot[2]), math.sin(robot[2])
        a = np.array([[1.0, 0.0, -s * u[0] - c * u[1]],
                      [0.0, 1.0, c * u[0] - s * u[1]],
                      [0.0, 0.0, 1.0]])
        b = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return a, b

    def predict(self, u, q: np.ndarray) -> None:
        u = np.asarray(u, float)
        a, b = self.motion_jacobians(self.x[:3], u)
        self.x[:3] = compose(self.x[:3], u)
        self.p[:3, :] = a @ self.p[:3, :]
        self.p[:, :3] = self.p[:, :3] @ a.T
        self.p[:3, :3] += b @ q @ b.T

    # -- a landmark joins (eqs. 9–10) --------------------------------------------------
    def add_landmark(self) -> int:
        n = self.landmark_count
        m = len(self.x)
        self.x = np.concatenate((self.x, self.x[:3]))
        p = np.zeros((m + 3, m + 3))
        p[:m, :m] = self.p
        p[m:, :m] = self.p[:3, :]
        p[:m, m:] = self.p[:, :3]
        p[m:, m:] = self.p[:3, :3]
        self.p = p
        return n

    # -- eqs. 12–14 --------------------------------------------------------------------
    @staticmethod
    def observation_jacobians(robot: np.ndarray,
                              lm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """H_R = ∂(X_n ⊖ X_R)/∂X_R and H_n = ∂(X_n ⊖ X_R)/∂X_n."""
        c, s = math.cos(lm[2]), math.sin(lm[2])
        dx, dy = robot[0] - lm[0], robot[1] - lm[1]
        h_r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        h_n = np.array([[-c, -s, -s * dx + c * dy],
                        [s, -c, -c * dx - s * dy],
                        [0.0, 0.0, -1.0]])
        return h_r, h_n

    def update(self, n: int, z, r: np.ndarray) -> float:
        """Fuse the robot's pose relative to landmark n; returns the innovation's
        squared Mahalanobis distance."""
        i = 3 + 3 * n
        lm = self.x[i:i + 3]
        h_r, h_n = self.observation_jacobians(self.x[:3], lm)
        innov = np.asarray(z, float) - relative(lm, self.x[:3])
        innov[2] = float(wrap(innov[2]))
        # H is zero except its robot and landmark-n blocks: P Hᵀ from two column blocks
        pht = self.p[:, :3] @ h_r.T + self.p[:, i:i + 3] @ h_n.T
        s = h_r @ pht[:3] + h_n @ pht[i:i + 3] + r
        s_inv = np.linalg.inv(s)
        k = pht @ s_inv
        self.x = self.x + k @ innov
        self.x[2::3] = wrap(self.x[2::3])
        self.p = self.p - k @ pht.T
        self.p = (self.p + self.p.T) / 2
        return float(innov @ s_inv @ innov)
