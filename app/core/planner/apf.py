"""Improved artificial potential field (seed 000 §4.2.3–4.2.4, eqs. 28–40).

Attraction    U_att = ½ K_att p²(q, q_g)                        (eq. 28)
              F_att = K_att p(q, q_g), towards the goal          (eq. 29)
Repulsion     U_rep = ½ K_rep (1/p − 1/p0)²  for p ≤ p0, else 0  (eq. 30)
              F_rep = −∇U_rep = K_rep (1/p − 1/p0) / p² · n      (eq. 31)
              (p: distance between the robot's and the obstacle's surfaces,
              n: unit vector from the obstacle to the robot)
Total         F = F_att + Σ F_rep                                 (eqs. 32–33)
Velocity terms (moving obstacles):
              U_att(q, v) = ½K_att p² + ½K_attv V²(v, v_g)        (eq. 34)
              F_att(q, v) = F_att(q) + K_attv (v_g − v)           (eq. 35)
              U_rep(v) = K_repv V_rep(v, v_obs)                  (eq. 36)
              V_rep = (v − v_obs)·(−n), the closing speed; the velocity term
              acts only while closing (V_rep ≥ 0), eqs. 37–38. Its force
              F_rep(v) = K_repv V_rep · m, where m is the unit vector normal
              to the relative velocity that points away from the obstacle:
              it steers the robot off the collision course instead of only
              braking (the paper gives no direction for it).
              F(q, v) = F_att(q, v) + Σ F_rep(q, v)               (eqs. 39–40)

Local minima: when the net force vanishes or the distance to the goal has
not shrunk by ``stuck_progress_m`` over ``stuck_window_s``, the field gets a
tangential term along the obstacle boundary (wall following, one side held)
until the robot is closer to the goal than where it got stuck.

Static obstacles come from the map's clearance field (GridMap.distance_m):
the nearest obstacle direction is its gradient.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from .grid import GridMap


@dataclass
class APFConfig:
    k_att: float = 1.0  # eqs. 28–29
    k_att_v: float = 0.5  # eqs. 34–35
    k_rep: float = 0.15  # eqs. 30–31
    k_rep_v: float = 1.5  # eqs. 36–38
    p0_m: float = 1.0  # repulsion range p0
    attract_saturation_m: float = 1.5  # |F_att| ≤ K_att · this
    rep_cap: float = 20.0  # bound on one obstacle's |F_rep| (p → 0)
    stuck_window_s: float = 3.0
    stuck_progress_m: float = 0.05
    escape_gain: float = 1.5


class PotentialField:
    """The improved field of eqs. 28–40 over a static map plus moving discs."""

    def __init__(
        self, grid: GridMap | None, robot_radius_m: float, config: APFConfig | None = None
    ):
        self.cfg = config or APFConfig()
        self.grid = grid
        self.robot_radius_m = float(robot_radius_m)
        if grid is not None:
            d = grid.distance_m
            gy, gx = np.gradient(d, grid.resolution_m)
            self._dist, self._gx, self._gy = d, gx, gy
        self._progress: deque[tuple[float, float]] = deque()
        self._escape_side = 0.0
        self._escape_until_m = math.inf
        self._t = 0.0

    def reset(self) -> None:
        self._progress.clear()
        self._escape_side = 0.0
        self._escape_until_m = math.inf
        self._t = 0.0

    @property
    def escaping(self) -> bool:
        return self._escape_side != 0.0

    # -- the field -----------------------------------------------------------------
    def _rep_static(self, q: np.ndarray) -> tuple[np.ndarray, float]:
        if self.grid is None:
            return np.zeros(2), math.inf
        r, c = self.grid.world_to_cell(q[0], q[1])
        h, w = self._dist.shape
        if not (0 <= r < h and 0 <= c < w):
            return np.zeros(2), 0.0
        p = self._dist[r, c] - self.robot_radius_m
        n = np.array([self._gx[r, c], self._gy[r, c]])
        nn = np.hypot(*n)
        if nn < 1e-9:
            return np.zeros(2), p
        return self._rep(p, n / nn), p

    def _rep(self, p: float, n: np.ndarray) -> np.ndarray:
        """Eq. 31 for one obstacle at surface distance p along unit n."""
        cfg = self.cfg
        if p > cfg.p0_m:
            return np.zeros(2)
        p = max(p, 1e-3)
        mag = cfg.k_rep * (1.0 / p - 1.0 / cfg.p0_m) / (p * p)
        return min(mag, cfg.rep_cap) * n

    def force(self, q, v, goal, obstacles=(), v_goal=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
        """(F_total, F_rep_total) at position q with velocity v (eq. 40)."""
        cfg = self.cfg
        q = np.asarray(q, float)
        v = np.asarray(v, float)
        to_goal = np.asarray(goal, float) - q
        dist = float(np.hypot(*to_goal))
        sat = min(dist, cfg.attract_saturation_m)
        f_att = cfg.k_att * sat * (to_goal / dist) if dist > 1e-9 else np.zeros(2)  # eq. 29
        f_att = f_att + cfg.k_att_v * (np.asarray(v_goal, float) - v)  # eq. 35
        f_rep, _ = self._rep_static(q)
        for ox, oy, ovx, ovy, orad in obstacles:
            d = q - (ox, oy)
            cd = float(np.hypot(*d))
            if cd < 1e-9:
                continue
            n = d / cd
            p = cd - orad - self.robot_radius_m
            if p > cfg.p0_m:
                continue  # eqs. 37–38, third case
            f_rep = f_rep + self._rep(p, n)  # eq. 31
            rel = v - (ovx, ovy)
            closing = float(rel @ -n)  # V_rep
            if closing >= 0.0:  # eqs. 37–38, first case
                m = np.array([-rel[1], rel[0]])
                mn = np.hypot(*m)
                if mn > 1e-9:
                    m = m / mn
                    if m @ n < 0:
                        m = -m
                else:
                    m = n
                f_rep = f_rep + cfg.k_rep_v * closing / max(p, 0.05) * m
        return f_att + f_rep, f_rep

    # -- one control step ------------------------------------------------------------
    def desired_velocity(self, q, v, goal, obstacles=(), dt: float = 0.1, v_goal=(0.0, 0.0)):
        """The direction to move (unit vector times |F|), with the local-minimum
        escape applied."""
        q = np.asarray(q, float)
        f, f_rep = self.force(q, v, goal, obstacles, v_goal)
        dist = float(np.hypot(*(np.asarray(goal, float) - q)))
        self._t += dt
        self._progress.append((self._t, dist))
        while self._progress and self._progress[0][0] < self._t - self.cfg.stuck_window_s:
            self._progress.popleft()
        window_full = self._t - self._progress[0][0] >= 0.95 * self.cfg.stuck_window_s
        best_old = self._progress[0][1]
        stalled = window_full and best_old - dist < self.cfg.stuck_progress_m
        rep_n = float(np.hypot(*f_rep))
        if (
            not self.escaping
            and dist > 0.2
            and rep_n > 1e-6
            and (stalled or np.hypot(*f) < 0.05 * self.cfg.k_att)
        ):
            to_goal = np.asarray(goal, float) - q
            cross = to_goal[0] * f_rep[1] - to_goal[1] * f_rep[0]
            self._escape_side = 1.0 if cross >= 0 else -1.0
            self._escape_until_m = dist - 0.3
        if self.escaping:
            if dist < self._escape_until_m:
                self._escape_side = 0.0
                self._progress.clear()
            elif rep_n > 1e-6:
                n = f_rep / rep_n
                t = self._escape_side * np.array([-n[1], n[0]])
                # Slide along the boundary: tangent, plus enough push to hold
                # the distance at which the field balances.
                f = self.cfg.escape_gain * self.cfg.k_att * t + 0.5 * f_rep
        return f
