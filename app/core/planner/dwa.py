"""Dynamic window approach (seed 003 §3.3, with its Table 3 kinematic limits).

1. Sample (v, ω) in the dynamic window (seed 003's window equations):
   V_s = [v_min, v_max] × [−ω_max, ω_max]                speed limits
   V_d = [v_c − a·Δt, v_c + a·Δt] × [ω_c − α·Δt, ω_c + α·Δt]  reachable in Δt
   with n_v × n_ω samples (Table 3: 10 × 10).
2. Roll each sample out as arcs (x += v cos θ Δt, y += v sin θ Δt, θ += ω Δt)
   over the horizon, against the static clearance field and each moving
   obstacle's constant-velocity prediction.
3. Admissible: no contact over the horizon and v ≤ √(2 · d(v, ω) · a_brake),
   so the robot can stop before the nearest obstacle (the V_a condition).
4. G(v, ω) = σ(α·heading + β·dist + γ·velocity), each term normalised over
   the admissible samples; the best pair is commanded.
Table 3: v ∈ [0, 0.15] m/s, |ω| ≤ 0.5 rad/s (min 0.1 rad/s when turning in
place), a = 0.5 m/s², α = 3.5 rad/s², 10 × 10 samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .grid import GridMap


@dataclass
class Kinematics:
    """Seed 003, Table 3."""

    v_max_mps: float = 0.15
    v_min_mps: float = 0.0
    omega_max_rps: float = 0.5
    omega_min_rps: float = 0.1  # smallest |ω| commanded for an in-place turn
    accel_mps2: float = 0.5
    alpha_rps2: float = 3.5
    v_samples: int = 10
    omega_samples: int = 10


@dataclass
class DWAConfig:
    horizon_s: float = 5.0
    sim_dt_s: float = 0.1
    heading_weight: float = 0.8  # α
    clearance_weight: float = 0.3  # β
    velocity_weight: float = 0.2  # γ
    clearance_cap_m: float = 1.0
    safety_margin_m: float = 0.05  # static obstacles
    moving_margin_m: float = 0.05  # moving obstacles


@njit(cache=True)
def _clearance_at(dist, res, ox, oy, x, y):
    c = int(math.floor((x - ox) / res))
    r = int(math.floor((y - oy) / res))
    h, w = dist.shape
    if r < 0 or r >= h or c < 0 or c >= w:
        return 0.0
    return dist[r, c]


@njit(cache=True)
def dwa_kernel(x0, y0, th0, vc, wc, dt, gx, gy, dist, res, ox, oy, obs, robot_r, lim, wts):
    """Best (v, ω) and its score. When no sample is admissible the score is
    −inf and (v, ω) is the sample whose contact comes latest.
    lim = [v_min, v_max, w_max, a, alpha, n_v, n_w, horizon, sim_dt, margin,
    moving_margin];
    wts = [heading, clearance, velocity, clearance_cap]."""
    v_lo = max(lim[0], vc - lim[3] * dt)
    v_hi = min(lim[1], vc + lim[3] * dt)
    w_lo = max(-lim[2], wc - lim[4] * dt)
    w_hi = min(lim[2], wc + lim[4] * dt)
    nv = int(lim[5])
    nw = int(lim[6])
    steps = int(lim[7] / lim[8] + 0.5)
    sdt = lim[8]
    margin = lim[9]
    mmargin = lim[10]
    n = nv * nw
    heads = np.empty(n)
    clears = np.empty(n)
    vels = np.empty(n)
    ws = np.empty(n)
    ok = np.zeros(n, dtype=np.bool_)
    fb_key = -np.inf
    fb_v = 0.0
    fb_w = 0.0
    # Static obstacles: the margin, or half the clearance left when the robot
    # is already inside it (so it is never frozen next to a wall).
    smargin = min(margin, 0.5 * max(_clearance_at(dist, res, ox, oy, x0, y0) - robot_r, 0.0))
    k = 0
    for i in range(nv):
        v = v_lo + (v_hi - v_lo) * i / (nv - 1) if nv > 1 else v_hi
        for j in range(nw):
            w = w_lo + (w_hi - w_lo) * j / (nw - 1) if nw > 1 else 0.0
            x = x0
            y = y0
            th = th0
            dmin = 1e9
            hit = False
            for s in range(1, steps + 1):
                x += v * math.cos(th) * sdt
                y += v * math.sin(th) * sdt
                th += w * sdt
                d = _clearance_at(dist, res, ox, oy, x, y) - robot_r
                if d <= smargin:
                    hit = True
                t = s * sdt
                for m in range(obs.shape[0]):
                    px = obs[m, 0] + obs[m, 2] * t
                    py = obs[m, 1] + obs[m, 3] * t
                    dd = math.hypot(x - px, y - py) - obs[m, 4] - robot_r
                    if dd <= mmargin:
                        hit = True
                    if dd < d:
                        d = dd
                if d < dmin:
                    dmin = d
                if hit:
                    break
            if hit:
                # Least bad fallback: the sample that keeps contact furthest off.
                if s * 1000.0 + dmin > fb_key:
                    fb_key = s * 1000.0 + dmin
                    fb_v = v
                    fb_w = w
                k += 1
                continue
            if v > math.sqrt(2.0 * max(dmin, 0.0) * lim[3]):
                if steps * 1000.0 + dmin > fb_key:
                    fb_key = steps * 1000.0 + dmin
                    fb_v = v
                    fb_w = w
                k += 1
                continue
            dx = gx - x
            dy = gy - y
            err = math.atan2(dy, dx) - th
            err = (err + math.pi) % (2.0 * math.pi) - math.pi
            heads[k] = math.pi - abs(err)
            clears[k] = min(dmin, wts[3])
            vels[k] = v
            ws[k] = w
            ok[k] = True
            k += 1
    best = -1
    best_score = -np.inf
    hs = 0.0
    cs = 0.0
    vs = 0.0
    for k in range(n):
        if ok[k]:
            hs += heads[k]
            cs += clears[k]
            vs += vels[k]
    if hs <= 0:
        hs = 1.0
    if cs <= 0:
        cs = 1.0
    if vs <= 0:
        vs = 1.0
    for k in range(n):
        if ok[k]:
            sc = wts[0] * heads[k] / hs + wts[1] * clears[k] / cs + wts[2] * vels[k] / vs
            if sc > best_score:
                best_score = sc
                best = k
    if best < 0:
        return fb_v, fb_w, -np.inf
    i = best // nw
    j = best - i * nw
    v = v_lo + (v_hi - v_lo) * i / (nv - 1) if nv > 1 else v_hi
    return v, ws[best], best_score


class DynamicWindow:
    """DWA local planner over a GridMap's clearance field plus moving discs."""

    def __init__(
        self,
        grid: GridMap,
        robot_radius_m: float,
        kin: Kinematics | None = None,
        config: DWAConfig | None = None,
    ):
        self.grid = grid
        self.kin = kin or Kinematics()
        self.cfg = config or DWAConfig()
        self.robot_radius_m = float(robot_radius_m)
        self._dist = np.ascontiguousarray(grid.distance_m, dtype=np.float64)

    def step(self, pose, velocity, goal_xy, obstacles=(), dt: float = 0.1):
        """(v, ω, admissible) for pose (x, y, θ), velocity (v, ω), a local goal
        and obstacles [(x, y, vx, vy, r), ...]."""
        k, c = self.kin, self.cfg
        obs = np.asarray(list(obstacles), dtype=np.float64).reshape(-1, 5)
        lim = np.array(
            [
                k.v_min_mps,
                k.v_max_mps,
                k.omega_max_rps,
                k.accel_mps2,
                k.alpha_rps2,
                k.v_samples,
                k.omega_samples,
                c.horizon_s,
                c.sim_dt_s,
                c.safety_margin_m,
                c.moving_margin_m,
            ]
        )
        wts = np.array([c.heading_weight, c.clearance_weight, c.velocity_weight, c.clearance_cap_m])
        ox, oy = self.grid.origin_xy
        v, w, score = dwa_kernel(
            float(pose[0]),
            float(pose[1]),
            float(pose[2]),
            float(velocity[0]),
            float(velocity[1]),
            float(dt),
            float(goal_xy[0]),
            float(goal_xy[1]),
            self._dist,
            self.grid.resolution_m,
            ox,
            oy,
            obs,
            self.robot_radius_m,
            lim,
            wts,
        )
        return float(v), float(w), bool(np.isfinite(score))
