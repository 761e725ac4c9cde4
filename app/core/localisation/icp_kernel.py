"""The ICP iterations of icp.py compiled (numba), for a bucketed reference.

Localisation matches every lidar scan against the same map, and the Python
loop of icp.icp spends most of its time in array overhead on ~180 points: a
dozen small NumPy calls per iteration, ~7 iterations per match. This is the
same loop, step for step (eqs. ICP-1..3 of icp.py's module docstring), on
plain floats:

- correspondences: the nearest visible map point within the gate
  (nearest._nearest_one, the bucket search), kept when its neighbourhood is
  line-like (``planar``);
- residual e_i = n_j · (R(θ) p_i + t − q_j) (ICP-1), trimmed to the best
  ``trim_fraction`` (|e| ≤ the k-th smallest, k = ⌊trim·m⌋), Huber weights
  w_i = min(1, k_H / |e_i|);
- Gauss-Newton with Levenberg damping: (Jᵀ W J + λ I) δ = −Jᵀ W e (ICP-2),
  J_i = [n_x, n_y, n_j · R'(θ) p_i], λ = ``damping`` · max diag(Jᵀ W J);
- σ̂² = Σ w e² / (m − 3) (ICP-3), the gate shrinking by 0.7 to its floor, and
  the same stopping tests (a tiny step, or one that barely lowers the cost).

Sums run in another order than NumPy's, so results agree with the Python
loop to rounding, not bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .nearest import _nearest_one


@njit(cache=True)
def _solve3(a, b):
    """a x = b for 3×3 a by Gaussian elimination with partial pivoting (as
    LAPACK's gesv); ok False on an exactly zero pivot (a singular matrix)."""
    m = a.copy()
    v = b.copy()
    for c in range(3):
        p = c
        for r in range(c + 1, 3):
            if abs(m[r, c]) > abs(m[p, c]):
                p = r
        if m[p, c] == 0.0:
            return v, False
        if p != c:
            for q in range(3):
                m[c, q], m[p, q] = m[p, q], m[c, q]
            v[c], v[p] = v[p], v[c]
        for r in range(c + 1, 3):
            f = m[r, c] / m[c, c]
            for q in range(c, 3):
                m[r, q] -= f * m[c, q]
            v[r] -= f * v[c]
    for c in range(2, -1, -1):
        s = v[c]
        for q in range(c + 1, 3):
            s -= m[c, q] * v[q]
        v[c] = s / m[c, c]
    return v, True


@njit(cache=True)
def icp_loop(src, guess, org, pts, normals, planar, facing, starts, order, lox, loy, cell,
             nx, ny, k_visible, max_cos, max_iterations, max_corr, min_corr, trim, huber,
             min_points, damping):
    """Returns (pose, H, σ̂², iterations, converged, failed); ``failed``: too
    few correspondences in some iteration (the pose is where it stopped)."""
    x = guess.copy()
    n = src.shape[0]
    npts = pts.shape[0]
    cand_d = np.empty(npts)
    cand_i = np.empty(npts, np.int64)
    e = np.empty(n)
    jj = np.empty(n, np.int64)
    si = np.empty(n, np.int64)
    H = np.eye(3) * 1e-9
    g = np.zeros(3)
    sigma2 = 1.0
    gate = max_corr
    it = 0
    for it in range(1, max_iterations + 1):
        c, s = math.cos(x[2]), math.sin(x[2])
        ox = org[0] * c - org[1] * s + x[0]
        oy = org[0] * s + org[1] * c + x[1]
        m = 0
        for i in range(n):
            mx = src[i, 0] * c - src[i, 1] * s + x[0]
            my = src[i, 0] * s + src[i, 1] * c + x[1]
            d, j = _nearest_one(mx, my, ox, oy, pts, facing, starts, order, lox, loy, cell,
                                nx, ny, gate, k_visible, max_cos, cand_d, cand_i)
            if d < np.inf and planar[j]:
                e[m] = normals[j, 0] * (mx - pts[j, 0]) + normals[j, 1] * (my - pts[j, 1])
                jj[m], si[m] = j, i
                m += 1
        if m < min_points:
            return x, H, sigma2, it, False, True
        ae = np.abs(e[:m])
        kth = min(int(trim * m), m - 1)
        cut = np.sort(ae)[kth]
        H = np.zeros((3, 3))
        g = np.zeros(3)
        swe2 = 0.0
        kept = 0
        for t in range(m):
            if ae[t] > cut:
                continue
            kept += 1
            j, i = jj[t], si[t]
            w = min(1.0, huber / max(ae[t], 1e-12))
            drx = -s * src[i, 0] - c * src[i, 1]  # R'(θ) p
            dry = c * src[i, 0] - s * src[i, 1]
            row = (normals[j, 0], normals[j, 1], normals[j, 0] * drx + normals[j, 1] * dry)
            for a in range(3):
                g[a] += w * row[a] * e[t]
                for b in range(3):
                    H[a, b] += w * row[a] * row[b]
            swe2 += w * e[t] * e[t]
        damp = damping * max(max(H[0, 0], max(H[1, 1], H[2, 2])), 1e-9)
        delta, ok = _solve3(H + np.eye(3) * damp, g)
        if not ok:
            break
        x -= delta
        x[2] = (x[2] + np.pi) % (2 * np.pi) - np.pi
        delta = -delta
        sigma2 = swe2 / max(kept - 3, 1)
        gate = max(min_corr, 0.7 * gate)
        tiny = math.hypot(delta[0], delta[1]) < 1e-4 and abs(delta[2]) < 1e-5
        flat = delta @ (H @ delta) < 1e-4 * swe2
        if (tiny or flat) and gate <= min_corr + 1e-9:
            return x, H, sigma2, it, True, False
    return x, H, sigma2, it, False, False


@njit(cache=True)
def best_shift(base, shifts, field, lox, loy, res):
    """The correlative search's inner loop (icp.correlative_search): the
    likelihood-field score Σ_i field(p_i + s) of the points ``base`` under
    each shift s, and the first shift with the highest one (as argmax)."""
    h, w = field.shape
    best_k, best = 0, -np.inf
    for k in range(shifts.shape[0]):
        tot = 0.0
        for i in range(base.shape[0]):
            cx = int(math.floor((base[i, 0] + shifts[k, 0] - lox) / res))
            cy = int(math.floor((base[i, 1] + shifts[k, 1] - loy) / res))
            tot += field[min(max(cy, 0), h - 1), min(max(cx, 0), w - 1)]
        if tot > best:
            best_k, best = k, tot
    return best_k, best


@njit(cache=True)
def stamp_field(pts, lox, loy, res, sigma, field):
    """icp.LikelihoodField's grid: each cell (row y, column x) takes
    exp(−d²/2σ²) of its centre's distance d to the nearest point, for d ≤ 3σ;
    each point visits only the cells of its own disc of 3σ. The Gaussian is
    separable, exp(−(dx² + dy²)/2σ²) = exp(−dx²/2σ²)·exp(−dy²/2σ²): one
    exponential per row and per column of the disc, not one per cell."""
    h, w = field.shape
    reach = int(math.ceil(3 * sigma / res)) + 1
    r2 = (3 * sigma) ** 2
    ex = np.empty(2 * reach + 1)
    dxs = np.empty(2 * reach + 1)
    k = -0.5 / (sigma * sigma)
    for i in range(pts.shape[0]):
        px, py = pts[i, 0], pts[i, 1]
        cx = int(math.floor((px - lox) / res))
        cy = int(math.floor((py - loy) / res))
        x_lo, x_hi = max(cx - reach, 0), min(cx + reach + 1, w)
        for x in range(x_lo, x_hi):
            dx = lox + (x + 0.5) * res - px
            dxs[x - x_lo] = dx * dx
            ex[x - x_lo] = math.exp(k * dx * dx)
        for y in range(max(cy - reach, 0), min(cy + reach + 1, h)):
            dy = loy + (y + 0.5) * res - py
            dy2 = dy * dy
            ey = math.exp(k * dy2)
            for x in range(x_lo, x_hi):
                if dxs[x - x_lo] + dy2 <= r2:
                    v = ex[x - x_lo] * ey
                    if v > field[y, x]:
                        field[y, x] = v
