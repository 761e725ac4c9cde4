"""Scan-to-submap matching: a scan against a smoothed grid of recent keyframes.

Point-to-line ICP (icp.py) pairs each scan point with one reference point and
that point's line normal, fitted over six neighbours of a single sparse scan;
at 180 beams a long-range wall has a beam every 0.2–0.3 m, and the normal and
the pairing are noisy. A *submap* renders the recent keyframes' scans, at
their poses, into one grid, and the scan is matched against the whole grid at
once:

1. **The grid** (``Submap``): a likelihood field M(c) = exp(−d(c)²/2σ²), d(c)
   the distance from cell c's centre to the nearest keyframe point (zero beyond
   3σ), stamped point by point (icp_kernel.stamp_field); a fine grid for the
   refinement and a coarse one, wider σ, for the search.
2. **Coarse-to-fine correlative search** (E. Olson, "Real-time correlative
   scan matching", ICRA 2009, §III: the pose maximising the summed likelihood
   of the scan's points over a 3-D grid of (x, y, θ), found on a coarse grid
   first and then on a fine one round the coarse winner, the multi-resolution
   form of the exhaustive search): ``search``.
3. **Refinement on the smoothed grid** (W. Hess, D. Kohler, H. Rapp,
   D. Andor, "Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, §IV.C,
   problem (CS)): argmin_ξ Σ_k (1 − M_smooth(T_ξ h_k))², M_smooth the grid
   interpolated bicubically (as the paper), solved by
   Gauss-Newton with the interpolant's analytic gradient, plus Cartographer's
   pull towards the initial guess (translation and rotation weights):
   ``refine``.
4. **Covariance** (match_covariance.py): by default Olson's (2009, §III-C)
   moments of the likelihood round the optimum, which takes each point as
   an independent 8 cm measurement and is optimistic per beam (the mapper
   scales it by 4; so scaled, it is about right on the logs); or
   (``covariance`` "residual") Censi's closed form for the grid fit's cost
   with σ² from the matched points' residuals and neighbouring beams
   correlated, fused unscaled, which on the logs claims 4–10 times too
   much: ``covariance``.

With ``face_bins`` > 0 the grids know which way each wall faces
(face_grid.py: one layer per orientation bin, a scan point read from the
layer of faces looking towards the sensor), in the search, the refinement
and Olson's covariance alike.

``match_submap`` runs 2–4 (3 from an ICP fit when one is given) and returns
an icp.IcpResult, so the mapper treats it as it treats an ICP fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .face_grid import (
    FaceField,
    back_bearings,
    face_pose_logl,
    face_refine_kernel,
    face_search_kernel,
    face_values_kernel,
    join_facing,
    stamp_means,
)
from .grid_interp import _bicubic
from .icp import IcpResult
from .icp_kernel import best_shift
from .match_covariance import olson_covariance, olson_moments, residual_covariance
from .se2 import rotation, transform_points, wrap


@dataclass(frozen=True)
class SubmapConfig:
    res_m: float = 0.05  # fine grid
    sigma_m: float = 0.08  # fine field's width
    coarse_res_m: float = 0.1
    coarse_sigma_m: float = 0.2
    coarse_step_theta_rad: float = math.radians(1.0)
    fine_step_theta_rad: float = math.radians(0.25)
    iterations: int = 20
    translation_weight: float = 0.0  # pull towards the guess (Cartographer's weights),
    rotation_weight: float = 0.0  # per point, on metres and radians
    inlier_value: float = 0.3  # a point whose field value is above this is an inlier
    max_points: int = 400
    # neighbouring beams closer than this are joined by a line of points
    # (spaced res/2) before stamping: a wall, not a string of beads
    join_gap_m: float = 0.5
    # the refinement's objective: "cs", Hess et al.'s Σ (1 − M)²; "distance",
    # Σ min(d², cap²), d² read from the likelihood grid (``_refine_distance``)
    objective: str = "distance"
    # the match's covariance (match_covariance.py): "olson", the likelihood's
    # moments (per beam optimistic: the mapper scales it by icp_cov_scale);
    # "residual", Censi's closed form with the residuals' σ and correlated
    # neighbouring beams, fused as it is (3-7 times too confident on the logs:
    # bench/match_covariance_bench.py)
    covariance: str = "olson"
    # the grids' orientation layers (face_grid.py): 0, one plain grid; K > 0,
    # K layers by the way each wall faces, a scan point read only against
    # faces looking towards the sensor (the refinement then always uses the
    # "distance" objective)
    face_bins: int = 0


class Submap:
    """The likelihood fields (fine and coarse) of keyframe scans at their poses."""

    def __init__(self, scans, cfg: SubmapConfig = SubmapConfig(), joined: bool = False) -> None:
        """``scans``: iterable of (pose, points in that pose's frame);
        ``joined``: the points are already joined (``join``)."""
        rows = [(pose, p if joined else join(p, cfg)) for pose, p in scans if len(p)]
        pts = [transform_points(pose, p[:, :2]) for pose, p in rows]
        self.points = np.vstack(pts) if pts else np.zeros((0, 2))
        self.facing = None
        if cfg.face_bins > 0:  # each point's facing turned into the world (face_grid.py)
            fac = [p[:, 2:4] @ rotation(pose[2]).T for pose, p in rows]
            self.facing = np.vstack(fac) if fac else np.zeros((0, 2))
        self.cfg = cfg
        self.fine = self._field(cfg.res_m, cfg.sigma_m)
        self._coarse: _Field | FaceField | None = None

    def _field(self, res_m: float, sigma_m: float) -> _Field | FaceField:
        if self.facing is None:
            return _Field(self.points, res_m, sigma_m)
        return FaceField(self.points, self.facing, res_m, sigma_m, self.cfg.face_bins)

    @property
    def coarse(self) -> _Field | FaceField:
        """The coarse field, built on first use (a narrow search needs none)."""
        if self._coarse is None:
            self._coarse = self._field(self.cfg.coarse_res_m, self.cfg.coarse_sigma_m)
        return self._coarse


class SubmapCache:
    """The submap of a mapper's latest keyframes, rendered again only when
    the set of keyframes or one of their poses changes (a pose-graph solve
    moves them); each keyframe's joined scan (in its own frame) is kept for
    as long as the keyframe stays in the set. ``renders`` counts the grids."""

    def __init__(self, cfg: SubmapConfig = SubmapConfig()) -> None:
        self.cfg = cfg
        self.renders = 0
        self._key: tuple = ()
        self._joined: dict = {}
        self._submap: Submap | None = None

    def get(self, keyframes) -> Submap:
        """``keyframes``: list of (id, pose, points in that pose's frame)."""
        key = tuple((i, *(float(v) for v in pose)) for i, pose, _ in keyframes)
        if self._submap is None or key != self._key:
            self._joined = {i: self._joined[i] if i in self._joined else join(p, self.cfg)
                            for i, _, p in keyframes}
            self._submap = Submap([(pose, self._joined[i]) for i, pose, _ in keyframes],
                                  self.cfg, joined=True)
            self._key = key
            self.renders += 1
        return self._submap


class _Field:
    def __init__(self, pts: np.ndarray, res_m: float, sigma_m: float) -> None:
        self.res = res_m
        margin = 3 * sigma_m + 2 * res_m
        if len(pts) == 0:
            self.lo = np.zeros(2)
            self.grid = np.zeros((2, 2))
            return
        self.lo = pts.min(axis=0) - margin
        shape = np.ceil((pts.max(axis=0) + margin - self.lo) / res_m).astype(int) + 1
        self.grid = np.zeros((shape[1], shape[0]))  # [row = y, col = x]
        # one stamp per occupied cell, at the mean of its points (many points
        # share a cell; the cell's centre would move a wall by up to res/2)
        stamp_means(pts, self.lo, int(shape[0]), res_m, sigma_m, self.grid)


def join(pts: np.ndarray, cfg: SubmapConfig) -> np.ndarray:
    """A keyframe's points as the grid stamps them (``_join``); with
    ``face_bins``, rows (x, y, fx, fy) with each point's facing
    (face_grid.join_facing)."""
    if cfg.face_bins > 0:
        return join_facing(pts, cfg.join_gap_m, cfg.res_m)
    return _join(pts, cfg.join_gap_m, cfg.res_m)


def _join(pts: np.ndarray, gap_m: float, step_m: float) -> np.ndarray:
    """Points (in beam order) with each pair of neighbours closer than
    ``gap_m`` joined by points every ``step_m`` along the segment."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    if gap_m <= 0 or len(pts) < 2:
        return pts
    seg = np.diff(pts, axis=0)
    d = np.hypot(seg[:, 0], seg[:, 1])
    n = np.where(d < gap_m, np.floor(d / step_m).astype(int), 0)
    i = np.repeat(np.arange(len(d)), n)  # segment of each new point
    first = np.repeat(np.cumsum(n) - n, n)
    t = (np.arange(len(i)) - first + 1) * step_m / d[i]  # 0 < t < 1 along it
    return np.vstack((pts, pts[i] + t[:, None] * seg[i]))


def _thin(src: np.ndarray, n: int) -> np.ndarray:
    src = np.asarray(src, float).reshape(-1, 2)
    if len(src) > n:
        src = src[np.linspace(0, len(src) - 1, n).astype(int)]
    return np.ascontiguousarray(src)


def search(source: np.ndarray, sub: Submap, guess, window_xy_m: float,
           window_theta_rad: float) -> tuple[np.ndarray, float]:
    """Olson's search, coarse to fine: the best (x, y, θ) on a grid of the
    coarse field over guess ± window, then on the fine field within one
    coarse step of it; returns the pose and its mean fine-field value. A
    window within two coarse steps is searched on the fine grid alone."""
    c = sub.cfg
    src = _thin(source, 120)
    best = np.array(guess, float)
    win_xy, win_th = window_xy_m, window_theta_rad
    if win_xy > 2 * c.coarse_res_m or win_th > 2 * c.coarse_step_theta_rad:
        best, _ = _grid_search(src, sub.coarse, best, win_xy, c.coarse_res_m, win_th,
                               c.coarse_step_theta_rad)
        win_xy, win_th = c.coarse_res_m, c.coarse_step_theta_rad
    best, score = _grid_search(src, sub.fine, best, win_xy, c.res_m, win_th,
                               c.fine_step_theta_rad)
    return best, score / len(src)


def _grid_search(src, field: _Field | FaceField, guess, win_xy, step_xy, win_th, step_th):
    n = int(round(win_xy / step_xy))
    offs = np.arange(-n, n + 1) * step_xy
    dx, dy = np.meshgrid(offs, offs, indexing="ij")
    shifts = np.column_stack((dx.ravel(), dy.ravel()))
    m = int(round(win_th / step_th))
    guess = np.array(guess, float)
    if isinstance(field, FaceField):  # each point on its layer (face_grid.py)
        src = np.ascontiguousarray(src, dtype=np.float64)
        k, j, score = face_search_kernel(src, back_bearings(src), float(guess[0]),
                                         float(guess[1]), float(guess[2]),
                                         np.arange(-m, m + 1) * step_th, field.layers,
                                         float(field.lo[0]), float(field.lo[1]),
                                         float(field.res), n, float(step_xy))
        if k < 0:
            return guess, -1.0
        th = guess[2] + (j - m) * step_th
        return np.array([guess[0] + shifts[k, 0], guess[1] + shifts[k, 1],
                         float(wrap(th))]), score
    args = (src, float(guess[0]), float(guess[1]), float(guess[2]), shifts,
            np.arange(-m, m + 1) * step_th, field.grid, float(field.lo[0]),
            float(field.lo[1]), float(field.res))
    cells = step_xy / field.res
    if abs(cells - round(cells)) < 1e-9:  # the search steps whole cells (always, as configured)
        k, j, score = _grid_search_cells(*args[:4], *args[5:], n, step_xy, int(round(cells)))
    else:
        k, j, score = _grid_search_kernel(*args)
    if k < 0:
        return guess, -1.0
    th = guess[2] + (j - m) * step_th
    return np.array([guess[0] + shifts[k, 0], guess[1] + shifts[k, 1], float(wrap(th))]), score


@njit(cache=True)
def _grid_search_kernel(src, gx, gy, gth, shifts, dths, grid, lox, loy, res):
    """For each heading guess + dths[j], the points turned and moved to the
    guess, then scored under every shift (icp_kernel.best_shift); the first
    (shift, heading) with the highest score, as (k, j, score)."""
    base = np.empty_like(src)
    best_k, best_j, best = -1, -1, -1.0
    for j in range(dths.shape[0]):
        th = gth + dths[j]
        c, s = math.cos(th), math.sin(th)
        for i in range(src.shape[0]):
            base[i, 0] = c * src[i, 0] - s * src[i, 1] + gx
            base[i, 1] = s * src[i, 0] + c * src[i, 1] + gy
        k, tot = best_shift(base, shifts, grid, lox, loy, res)
        if tot > best:
            best_k, best_j, best = k, j, tot
    return best_k, best_j, best


@njit(cache=True)
def _grid_search_cells(src, gx, gy, gth, dths, grid, lox, loy, res, n, step_xy, q):
    """``_grid_search_kernel``, to the last bit, for the square of shifts
    ``((ix − n)·step_xy, (iy − n)·step_xy)`` of ``q`` whole cells per step
    (k = ix·(2n + 1) + iy, as ``_grid_search`` lays them out). A point's cell
    under a shift is its cell at the guess moved by the shift's cells, so
    each point's cell is found once per heading and the shifts only add
    integers — unless the point lies within 1e-7 of a cell's border, where
    rounding could put the shifted point in the next cell: its cells are
    then found shift by shift, as ``best_shift`` finds them. A point whose
    window lies inside the grid needs no clamping. The scores are the same
    sums in the same order; the first highest wins."""
    h, w = grid.shape
    side = 2 * n + 1
    ns = side * side
    tot = np.empty(ns)
    cxs = np.empty(side, np.int64)
    cys = np.empty(side, np.int64)
    best_k, best_j, best = -1, -1, -1.0
    reach = n * q
    for j in range(dths.shape[0]):
        th = gth + dths[j]
        c, s = math.cos(th), math.sin(th)
        tot[:] = 0.0
        for i in range(src.shape[0]):
            bx = c * src[i, 0] - s * src[i, 1] + gx
            by = s * src[i, 0] + c * src[i, 1] + gy
            fx, fy = (bx - lox) / res, (by - loy) / res
            cx, cy = int(math.floor(fx)), int(math.floor(fy))
            rx, ry = fx - cx, fy - cy
            if min(rx, ry) < 1e-7 or max(rx, ry) > 1.0 - 1e-7:  # at a border: shift by shift
                for t in range(side):
                    cxs[t] = int(math.floor((bx + (t - n) * step_xy - lox) / res))
                    cys[t] = int(math.floor((by + (t - n) * step_xy - loy) / res))
            else:
                for t in range(side):
                    cxs[t] = cx + (t - n) * q
                    cys[t] = cy + (t - n) * q
            inside = cx - reach >= 1 and cx + reach < w - 1 and cy - reach >= 1 and \
                cy + reach < h - 1
            for iy in range(side):
                y = cys[iy] if inside else min(max(cys[iy], 0), h - 1)
                for ix in range(side):
                    x = cxs[ix] if inside else min(max(cxs[ix], 0), w - 1)
                    tot[ix * side + iy] += grid[y, x]
        k_best, t_best = 0, -np.inf
        for k in range(ns):
            if tot[k] > t_best:
                k_best, t_best = k, tot[k]
        if t_best > best:
            best_k, best_j, best = k_best, j, t_best
    return best_k, best_j, best


@njit(cache=True)
def _refine_kernel(src, x0, grid, lox, loy, res, iterations, w_t, w_r):
    """Gauss-Newton on Σ_k (1 − M(T_ξ h_k))² + w_t²‖t − t₀‖² + w_r²(θ − θ₀)²
    (Hess et al. 2016, (CS)); returns (pose, JᵀJ, Σ r², points)."""
    x = x0.copy()
    n = src.shape[0]
    H = np.zeros((3, 3))
    cost = 0.0
    for _ in range(iterations):
        H[:, :] = 0.0
        g = np.zeros(3)
        cost = 0.0
        c, s = math.cos(x[2]), math.sin(x[2])
        for i in range(n):
            px, py = src[i, 0], src[i, 1]
            wx = c * px - s * py + x[0]
            wy = s * px + c * py + x[1]
            val, gx, gy = _bicubic(grid, lox, loy, res, wx, wy)
            r = 1.0 - val
            j0, j1 = -gx, -gy
            j2 = -(gx * (-s * px - c * py) + gy * (c * px - s * py))
            jr = (j0, j1, j2)
            for a in range(3):
                g[a] += jr[a] * r
                for b in range(3):
                    H[a, b] += jr[a] * jr[b]
            cost += r * r
        # the pull towards the guess, scaled by the number of points, and a
        # Levenberg term: a direction without slope (a corridor) stays put
        damp = 1e-4 * max(H[0, 0], H[1, 1], H[2, 2]) + 1e-9
        for a in range(3):
            w = (w_t if a < 2 else w_r) ** 2 * n
            H[a, a] += w + damp
            g[a] += w * (x[a] - x0[a])
        delta = np.linalg.solve(H, -g)
        for a in range(3):
            H[a, a] -= damp
        x += delta
        if abs(delta[0]) + abs(delta[1]) < 1e-5 and abs(delta[2]) < 1e-6:
            break
    return x, H, cost


@njit(cache=True)
def _refine_distance(src, x0, grid, lox, loy, res, iterations, cap2, step_xy, step_th,
                     sigma):
    """Newton (Gauss-Newton in the pose) on ½ Σ_k min(d_k², cap²), d_k the
    distance of the moved point to the nearest keyframe point, from the
    grid of G = d² (from the likelihood grid) interpolated bicubically: gradient
    Σ J_kᵀ ½∇G, Hessian Σ J_kᵀ ½∇²G J_k (J_k = ∂(T_ξ h_k)/∂ξ); points at the
    cap are outliers and drop out. Near a wall ½∇²G = n nᵀ, so this is
    point-to-line ICP with the grid's own normals, and its basin is
    quadratic where (1 − M)² of (CS) is quartic (flat at the optimum)."""
    # (the face-aware kernel with a single layer: every point reads ``grid``)
    layers = grid.reshape((1, grid.shape[0], grid.shape[1]))
    return face_refine_kernel(src, np.zeros(src.shape[0]), x0, layers, lox, loy, res,
                              iterations, cap2, step_xy, step_th, sigma)


def refine(source: np.ndarray, sub: Submap, guess) -> tuple[np.ndarray, float]:
    """Problem (CS) from ``guess``; returns the pose and the mean field
    value of the points there."""
    c = sub.cfg
    src = _thin(source, c.max_points)
    f = sub.fine
    if isinstance(f, FaceField):
        x, _ = face_refine_kernel(src, back_bearings(src), np.array(guess, float), f.layers,
                                  float(f.lo[0]), float(f.lo[1]), f.res, c.iterations,
                                  (2.5 * c.sigma_m) ** 2, c.sigma_m,
                                  c.fine_step_theta_rad * 4, c.sigma_m)
    elif c.objective == "distance":
        x, _ = _refine_distance(src, np.array(guess, float), f.grid, float(f.lo[0]),
                                float(f.lo[1]), f.res, c.iterations, (2.5 * c.sigma_m) ** 2,
                                c.sigma_m, c.fine_step_theta_rad * 4, c.sigma_m)
    else:
        x, _, _ = _refine_kernel(src, np.array(guess, float), f.grid, float(f.lo[0]),
                                 float(f.lo[1]), f.res, c.iterations, c.translation_weight,
                                 c.rotation_weight)
    x[2] = float(wrap(x[2]))
    before, after = float(np.mean(_values(src, guess, f))), float(np.mean(_values(src, x, f)))
    if after < before:  # the local model misled it: the guess stands
        return np.array(guess, float), before
    return x, after


def _values(src: np.ndarray, pose, f: _Field | FaceField) -> np.ndarray:
    """Interpolated fine-field value at each point moved by ``pose`` (on its
    layer, on a face-aware field)."""
    if isinstance(f, FaceField):
        src = np.ascontiguousarray(src, dtype=np.float64)
        return face_values_kernel(src, back_bearings(src), np.asarray(pose, np.float64),
                                  f.layers, float(f.lo[0]), float(f.lo[1]), f.res)
    return _values_kernel(np.ascontiguousarray(src, dtype=np.float64),
                          np.asarray(pose, np.float64), f.grid, float(f.lo[0]),
                          float(f.lo[1]), f.res)


@njit(cache=True)
def _values_kernel(src, pose, grid, lox, loy, res):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    out = np.empty(src.shape[0])
    for i in range(src.shape[0]):
        wx = c * src[i, 0] - s * src[i, 1] + pose[0]
        wy = s * src[i, 0] + c * src[i, 1] + pose[1]
        out[i] = _bicubic(grid, lox, loy, res, wx, wy)[0]
    return out


def covariance(source: np.ndarray, sub: Submap, pose, half_steps: int = 2,
               kind: str | None = None) -> np.ndarray:
    """The covariance of ``pose`` (match_covariance.py) by ``kind`` (default:
    the submap's ``covariance``): "olson", over ±``half_steps`` fine steps
    on 90 of the points; "residual", on up to ``max_points``."""
    c = sub.cfg
    f = sub.fine
    if (kind or c.covariance) == "olson" and isinstance(f, FaceField):
        src = _thin(source, 90)
        logl = face_pose_logl(src, back_bearings(src), np.array(pose, float), f.layers,
                              float(f.lo[0]), float(f.lo[1]), f.res, c.res_m,
                              c.fine_step_theta_rad, half_steps)
        return olson_moments(logl, c.res_m, c.fine_step_theta_rad, half_steps)
    if (kind or c.covariance) == "olson":
        return olson_covariance(_thin(source, 90), sub.fine, pose, c.res_m,
                                c.fine_step_theta_rad, half_steps)
    return residual_covariance(_thin(source, c.max_points), sub.fine, pose, c.sigma_m,
                               c.join_gap_m)


def match_submap(source: np.ndarray, sub: Submap, guess, window_xy_m: float = 0.0,
                 window_theta_rad: float = 0.0, cov_half_steps: int = 2) -> IcpResult:
    """Search (when a window is given) then refine and estimate the
    covariance (over ±``cov_half_steps`` fine steps); ``inlier_fraction``:
    the share of points whose field value is above ``inlier_value`` (about
    1.5σ from the nearest keyframe point)."""
    c = sub.cfg
    src = _thin(source, c.max_points)
    if len(src) < 10 or len(sub.points) < 10:
        return IcpResult(np.array(guess, float), np.eye(3) * 1e6, math.inf, 0.0, 0, False)
    x = np.array(guess, float)
    if window_xy_m > 0 or window_theta_rad > 0:
        x, _ = search(src, sub, x, window_xy_m, window_theta_rad)
    x, _ = refine(src, sub, x)
    vals = _values(src, x, sub.fine)
    inl = vals > c.inlier_value
    # the distance a value stands for: M = exp(−d²/2σ²) → d = σ √(−2 ln M)
    d = c.sigma_m * np.sqrt(-2 * np.log(np.clip(vals[inl], 1e-9, 1.0)))
    rmse = float(np.sqrt(np.mean(d * d))) if inl.any() else math.inf
    cov = covariance(src, sub, x, cov_half_steps)
    return IcpResult(x, cov, rmse, float(np.mean(inl)), 1, True)
