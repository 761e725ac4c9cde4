"""A submap's likelihood grid that knows which way each wall faces.

The submap's grid (submap_match.py) stamps every keyframe point alike. A
thin wall (an office's 0.1–0.2 m partition) seen from both rooms is two
lines a wall's thickness apart, and a scan of one face fits the other face
almost as well: the grid fit of the final pass took one for the other on
drawn logs of identical rooms (docs/localisation.md, section (g)). The ICP
references already know the side each wall point was seen from
(icp.stacked_reference's ``faces``); this is the same idea for the grid.

1. **Facing** (``join_facing``): in a keyframe's own frame (the sensor at the
   origin), each pair of neighbouring beams closer than the join gap is a
   piece of wall whose normal is turned towards the sensor; a point's
   facing is the normalised sum of the pieces within two beams of it,
   weighted by their length (the normal of the chord over ±2 beams on a
   straight wall). A point with no piece, or whose pieces turn by more
   than about 120° (a corner, a post), has facing zero: seen from anywhere.
   The points the join adds take their piece's facing.
2. **Layers** (``FaceField``): K orientation bins of width 2π/K, centres
   α_k = 2πk/K. Layer k is the likelihood grid (M = exp(−d²/2σ²), stamped
   as submap_match's, one stamp per cell at its points' mean) of the points
   whose facing f has angle(f, α_k) < 90° + π/K, and of the points seen
   from anywhere: neighbouring layers overlap, so a face is in every layer
   whose query it may answer.
3. **Query**: a scan point h (sensor frame) under the pose (t, θ) looks
   back to the sensor along −R(θ) h, angle ψ = atan2(−h_y, −h_x) + θ,
   independent of t: per heading, each point's layer is fixed for every
   shift of the correlative search (Olson 2009, §III) and for a step of the
   refinement (Hess et al. 2016, §IV.C, here the "distance" objective of
   submap_match._refine_distance). The point is scored on the layer whose
   centre is nearest ψ; that layer holds every face at under 90° from ψ
   (the face looks towards the sensor) and none at over 90° + 2π/K. With
   K = 12 the far face of a thin wall (at 180° − i from ψ, i the beam's
   angle of incidence) is left out for i < 60°.

``FaceField.grid`` is the plain grid (the layers' maximum, what
submap_match's _Field holds): code that does not know the layers (the
rivals' score volume, rival_match.py; the residual covariance) reads it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .grid_interp import _bicubic, _bicubic_hessian
from .icp_kernel import stamp_field


def join_facing(pts: np.ndarray, gap_m: float, step_m: float) -> np.ndarray:
    """Points (in beam order, sensor frame) joined as submap_match._join
    joins them (neighbours closer than ``gap_m``, a point every ``step_m``),
    with each point's facing (1. of the module docstring): rows (x, y, fx, fy)."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    if len(pts) < 2 or gap_m <= 0:
        return np.hstack((pts, np.zeros_like(pts)))
    seg = np.diff(pts, axis=0)
    d = np.hypot(seg[:, 0], seg[:, 1])
    near = (d < gap_m) & (d > 0)
    # each piece's normal times its length, turned towards the sensor (the origin)
    nrm = np.column_stack((-seg[:, 1], seg[:, 0]))
    mid = 0.5 * (pts[:-1] + pts[1:])
    nrm *= np.where(np.einsum("ij,ij->i", nrm, -mid) < 0, -1.0, 1.0)[:, None]
    nrm[~near] = 0.0
    length = np.where(near, d, 0.0)
    # point i's pieces: i − 1 and i touch it; i − 2 and i + 1 when joined to those
    n_seg, idx = len(seg), np.arange(len(pts))

    def piece(k):
        return np.where((k >= 0) & (k < n_seg), np.clip(k, 0, n_seg - 1), -1)

    acc = np.zeros_like(pts)
    tot = np.zeros(len(pts))
    for off, via in ((-1, None), (0, None), (-2, -1), (1, 0)):
        k = piece(idx + off)
        ok = (k >= 0) & near[k]
        if via is not None:
            v = piece(idx + via)
            ok &= (v >= 0) & near[v]
        acc += np.where(ok[:, None], nrm[k], 0.0)
        tot += np.where(ok, length[k], 0.0)
    mag = np.hypot(acc[:, 0], acc[:, 1])
    straight = (tot > 0) & (mag > 0.5 * tot)  # pieces within ≈ 120° of each other
    facing = np.where(straight[:, None], acc / np.maximum(mag, 1e-12)[:, None], 0.0)
    # the joined points: as submap_match._join, each with its piece's facing
    n = np.where(near, np.floor(d / step_m).astype(int), 0)
    i = np.repeat(np.arange(len(d)), n)
    first = np.repeat(np.cumsum(n) - n, n)
    t = (np.arange(len(i)) - first + 1) * step_m / np.where(d > 0, d, 1.0)[i]
    seg_f = nrm / np.maximum(d, 1e-12)[:, None]
    added = np.column_stack((pts[i] + t[:, None] * seg[i], seg_f[i]))
    return np.vstack((np.hstack((pts, facing)), added))


def stamp_means(pts: np.ndarray, lo: np.ndarray, width: int, res_m: float, sigma_m: float,
                grid: np.ndarray) -> None:
    """Stamp ``pts`` into ``grid`` as submap_match's _Field does: one stamp
    per occupied cell, at the mean of its points."""
    if len(pts) == 0:
        return
    c = np.floor((pts - lo) / res_m).astype(np.int64)
    cells, inv = np.unique(c[:, 1] * width + c[:, 0], return_inverse=True)
    cnt = np.bincount(inv, minlength=len(cells))
    centres = np.column_stack((np.bincount(inv, pts[:, 0], len(cells)) / cnt,
                               np.bincount(inv, pts[:, 1], len(cells)) / cnt))
    stamp_field(np.ascontiguousarray(centres), float(lo[0]), float(lo[1]), res_m, sigma_m, grid)


class FaceField:
    """K likelihood layers by the faces' orientation (2. of the module
    docstring): ``layers`` [k, row = y, col = x]; ``grid``, their maximum."""

    def __init__(self, pts: np.ndarray, facing: np.ndarray, res_m: float, sigma_m: float,
                 bins: int) -> None:
        self.res = res_m
        self.bins = bins
        margin = 3 * sigma_m + 2 * res_m
        if len(pts) == 0:
            self.lo = np.zeros(2)
            self.layers = np.zeros((bins, 2, 2))
            self.grid = np.zeros((2, 2))
            return
        self.lo = pts.min(axis=0) - margin
        shape = np.ceil((pts.max(axis=0) + margin - self.lo) / res_m).astype(int) + 1
        self.layers = np.zeros((bins, shape[1], shape[0]))
        anywhere = (facing[:, 0] == 0.0) & (facing[:, 1] == 0.0)
        cos_max = math.cos(math.pi / 2 + math.pi / bins)
        for k in range(bins):
            a = 2 * math.pi * k / bins
            keep = anywhere | (facing[:, 0] * math.cos(a) + facing[:, 1] * math.sin(a) > cos_max)
            stamp_means(pts[keep], self.lo, int(shape[0]), res_m, sigma_m, self.layers[k])
        self.grid = self.layers.max(axis=0)


def back_bearings(src: np.ndarray) -> np.ndarray:
    """Each scan point's direction back to the sensor in its own frame,
    atan2(−h_y, −h_x) (3. of the module docstring)."""
    return np.arctan2(-src[:, 1], -src[:, 0])


@njit(cache=True)
def _layer(beta, th, bins):
    """The layer whose centre is nearest the bearing beta + th."""
    k = int(math.floor((beta + th) * bins / (2.0 * math.pi) + 0.5)) % bins
    return k + bins if k < 0 else k


@njit(cache=True)
def face_search_kernel(src, beta, gx, gy, gth, dths, layers, lox, loy, res, n, step_xy):
    """Olson's exhaustive search (2009, §III) over the (2n + 1)² shifts
    ((ix − n)·step_xy, (iy − n)·step_xy) and the headings gth + dths[j],
    each point read from its layer (k = ix·(2n + 1) + iy, as
    submap_match._grid_search lays shifts out; cells clamped to the grid);
    the first highest (k, j, score)."""
    bins, h, w = layers.shape
    side = 2 * n + 1
    tot = np.empty(side * side)
    cxs = np.empty(side, np.int64)
    cys = np.empty(side, np.int64)
    best_k, best_j, best = -1, -1, -1.0
    for j in range(dths.shape[0]):
        th = gth + dths[j]
        c, s = math.cos(th), math.sin(th)
        tot[:] = 0.0
        for i in range(src.shape[0]):
            lay = layers[_layer(beta[i], th, bins)]
            bx = c * src[i, 0] - s * src[i, 1] + gx
            by = s * src[i, 0] + c * src[i, 1] + gy
            for t in range(side):
                cxs[t] = min(max(int(math.floor((bx + (t - n) * step_xy - lox) / res)), 0), w - 1)
                cys[t] = min(max(int(math.floor((by + (t - n) * step_xy - loy) / res)), 0), h - 1)
            for ix in range(side):
                for iy in range(side):
                    tot[ix * side + iy] += lay[cys[iy], cxs[ix]]
        for k in range(side * side):
            if tot[k] > best:
                best_k, best_j, best = k, j, tot[k]
    return best_k, best_j, best


@njit(cache=True)
def face_refine_kernel(src, beta, x0, layers, lox, loy, res, iterations, cap2, step_xy,
                       step_th, sigma):
    """submap_match._refine_distance (½ Σ min(d², cap²) by Newton on the
    bicubic grid of d², after Hess et al. 2016's problem (CS)) with each
    point's d² read from its layer at the current heading; with one layer
    (``layers.shape[0] == 1``) every point reads it, and this is
    submap_match._refine_distance itself."""
    x = x0.copy()
    n = src.shape[0]
    bins = layers.shape[0]
    H = np.zeros((3, 3))
    for _ in range(iterations):
        H[:, :] = 0.0
        g = np.zeros(3)
        c, s = math.cos(x[2]), math.sin(x[2])
        for i in range(n):
            px, py = src[i, 0], src[i, 1]
            wx = c * px - s * py + x[0]
            wy = s * px + c * py + x[1]
            f = _bicubic_hessian(layers[_layer(beta[i], x[2], bins)], lox, loy, res, wx, wy,
                                 sigma)
            if f[0] >= cap2 or f[0] == 0.0 and f[1] == 0.0 and f[2] == 0.0 \
                    and f[3] == 0.0:
                continue
            rx, ry = -s * px - c * py, c * px - s * py  # ∂p/∂θ
            gx, gy = 0.5 * f[1], 0.5 * f[2]
            hxx, hxy, hyy = 0.5 * f[3], 0.5 * f[4], 0.5 * f[5]
            g[0] += gx
            g[1] += gy
            g[2] += gx * rx + gy * ry
            H[0, 0] += hxx
            H[0, 1] += hxy
            H[1, 1] += hyy
            H[0, 2] += hxx * rx + hxy * ry
            H[1, 2] += hxy * rx + hyy * ry
            H[2, 2] += hxx * rx * rx + 2 * hxy * rx * ry + hyy * ry * ry
        H[1, 0], H[2, 0], H[2, 1] = H[0, 1], H[0, 2], H[1, 2]
        # a Hessian that is not positive (points near the cap, where G bends
        # over) is shifted until it is; a Levenberg term keeps a corridor put
        lo_eig = np.linalg.eigvalsh(H)[0]
        top = max(H[0, 0], H[1, 1], H[2, 2])
        damp = 1e-4 * top + 1e-9 + (0.0 if lo_eig > 1e-6 * top else 1e-6 * top - lo_eig)
        A = H.copy()
        for a in range(3):
            A[a, a] += damp
        delta = np.linalg.solve(A, -g)
        # a step no longer than the grid's reach (σ-sized): the model is local
        big = max(math.hypot(delta[0], delta[1]) / step_xy, abs(delta[2]) / step_th, 1.0)
        x += delta / big
        if abs(delta[0]) + abs(delta[1]) < 1e-5 and abs(delta[2]) < 1e-6:
            break
    return x, H


@njit(cache=True)
def face_values_kernel(src, beta, pose, layers, lox, loy, res):
    """Each point's interpolated value on its layer under ``pose``."""
    bins = layers.shape[0]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    out = np.empty(src.shape[0])
    for i in range(src.shape[0]):
        wx = c * src[i, 0] - s * src[i, 1] + pose[0]
        wy = s * src[i, 0] + c * src[i, 1] + pose[1]
        out[i] = _bicubic(layers[_layer(beta[i], pose[2], bins)], lox, loy, res, wx, wy)[0]
    return out


@njit(cache=True)
def face_pose_logl(src, beta, pose, layers, lox, loy, res, step_xy, step_th, m):
    """log L(ξ) = Σ_k ln max(M_k(T_ξ h_k), 0.01) over the (2m + 1)³ poses
    round ``pose`` (Olson 2009, §III-C), M_k the point's layer: logl[θ, x, y]
    as match_covariance._pose_grid_logl lays it out."""
    side = 2 * m + 1
    bins = layers.shape[0]
    logl = np.zeros((side, side, side))
    for a in range(side):
        th = pose[2] + (a - m) * step_th
        c, s = math.cos(th), math.sin(th)
        for i in range(src.shape[0]):
            lay = layers[_layer(beta[i], th, bins)]
            bx = c * src[i, 0] - s * src[i, 1] + pose[0]
            by = s * src[i, 0] + c * src[i, 1] + pose[1]
            for b in range(side):
                for d in range(side):
                    v = _bicubic(lay, lox, loy, res, bx + (b - m) * step_xy,
                                 by + (d - m) * step_xy)[0]
                    logl[a, b, d] += math.log(max(v, 0.01))
    return logl
