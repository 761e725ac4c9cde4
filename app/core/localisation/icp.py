"""2-D scan matching: point-to-line ICP with a correlative search seed.

The seed's matcher is ICP (seed 002 §2.3, ref. [9], Besl & McKay): iterate
nearest neighbours and a rigid fit. Here each reference point carries the
normal n_j of the line through its neighbours (a local PCA), and a source
point p_i moved by T = (t, θ) has the point-to-line residual

    e_i = n_j · (R(θ) p_i + t − q_j)                                  (ICP-1)

with Jacobian row J_i = [n_x, n_y, n_j · R'(θ) p_i]. One Gauss-Newton step
solves (Jᵀ W J) δ = −Jᵀ W e (ICP-2). Outliers: pairs further than a gate
(shrinking from ``max_corr_dist_m`` to ``min_corr_dist_m``) are dropped, the
worst (1 − trim_fraction) of the rest are trimmed, and Huber weights
w_i = min(1, k / |e_i|) soften the remainder.

Visibility (a map reference only): a map's wall has two faces, and a scan
point on the near face of a thin wall also lies a wall's thickness from its
far face — a second, equally tight fit that many points agree with. When the
reference knows which way each surface point faces (``facing``, pointing into
free space), a pair is only allowed when the face looks towards the sensor:
f_j · (p_i − o) / |p_i − o| ≤ cos 75°, o the sensor's position; each source
point takes the nearest such reference point among its ``VISIBLE_K`` nearest.

Covariance (Hessian approximation): Σ = σ̂² (Jᵀ W J)⁻¹ with
σ̂² = Σ w e² / (m − 3) (ICP-3). Along a featureless corridor Jᵀ W J has no
information in the corridor's direction and Σ becomes large there.

A poor guess: ``correlative_search`` scores a grid of poses against a
likelihood field of the reference (Olson's correlative scan matching, at one
resolution) and hands its best pose to ICP when ICP alone fails.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .icp_kernel import best_shift, icp_loop, stamp_field
from .nearest import BucketGrid
from .se2 import rotation, transform_points, wrap


@dataclass(frozen=True)
class IcpConfig:
    max_iterations: int = 30
    max_corr_dist_m: float = 1.0
    min_corr_dist_m: float = 0.2
    trim_fraction: float = 0.85
    huber_m: float = 0.05
    normal_neighbours: int = 6
    inlier_dist_m: float = 0.1  # a source point this close to a line is an inlier
    min_points: int = 20
    min_sigma_m: float = 0.01  # floor of σ̂, so a perfect fit is not over-trusted
    damping: float = 1e-4  # Levenberg term, relative to the largest Hessian entry
    bucket_m: float = 0.25  # mapping's references: bucket size of the compiled search


@dataclass
class IcpResult:
    pose: np.ndarray  # (x, y, θ) moving source points into the reference frame
    covariance: np.ndarray  # 3×3
    rmse_m: float
    inlier_fraction: float
    iterations: int
    converged: bool

    @property
    def ok(self) -> bool:
        return self.converged and self.inlier_fraction > 0.0


VISIBLE_K = 16  # nearest reference points searched for one whose face is seen
FACING_MAX_COS = math.cos(math.radians(75))


class Reference:
    """Reference points with their line normals and a k-d tree; ``facing``
    (optional, unit or zero vectors): the side each point's surface is seen
    from (a map's wall faces its free side; zero: seen from anywhere).
    ``bucket_m``: also sort the points into buckets of that size, answered by
    a compiled search (nearest.py) and the compiled ICP loop (icp_kernel.py)
    instead of the k-d tree and NumPy steps; without ``facing`` every point
    is seen from anywhere (zero facing vectors), as with the k-d tree."""

    def __init__(self, points: np.ndarray, neighbours: int = 6,
                 facing: np.ndarray | None = None, bucket_m: float | None = None,
                 normals: np.ndarray | None = None, planar: np.ndarray | None = None) -> None:
        self.points = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
        if facing is None and bucket_m:
            facing = np.zeros_like(self.points)
        self.facing = (None if facing is None
                       else np.ascontiguousarray(facing, dtype=float).reshape(-1, 2))
        self.tree = cKDTree(self.points) if len(self.points) else None
        self.buckets = (BucketGrid(self.points, bucket_m)
                        if bucket_m and len(self.points) else None)
        self._field: LikelihoodField | None = None
        if normals is not None and planar is not None:  # given (see ``scan_normals``)
            self.normals = np.ascontiguousarray(normals, dtype=float).reshape(-1, 2)
            self.planar = np.ascontiguousarray(planar, dtype=bool)
        else:
            self.normals, self.planar = scan_normals(self.points, neighbours, self.tree)

    def likelihood_field(self) -> LikelihoodField:
        """The reference's likelihood field for the correlative search, built
        on first use and kept (a reference may be searched more than once)."""
        if self._field is None:
            self._field = LikelihoodField(self.points, margin_m=1.0, stamped=True)
        return self._field


def scan_normals(points: np.ndarray, neighbours: int = 6,
                 tree: cKDTree | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Unit normal of the line through each point's ``neighbours`` nearest
    points (a local PCA) and whether that neighbourhood is line-like (small
    spread across the line, not a blob).

    Computed on *one* scan: in a reference stacked from several scans
    (a local map of keyframes, a loop-closure place) the nearest neighbours of
    a point are the same spot seen by the other scans, a blob a few
    centimetres wide whose PCA says nothing about the wall; with ten
    keyframes nearly every point failed the line test and ICP found no pairs.
    So a multi-scan reference takes each scan's own normals, turned by its
    pose (``Reference(..., normals=, planar=)``)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    normals = np.zeros_like(pts)
    planar = np.zeros(len(pts), bool)
    k = min(neighbours, len(pts))
    if k < 3:
        return normals, planar
    tree = tree if tree is not None else cKDTree(pts)
    _, idx = tree.query(pts, k=k)
    nb = pts[idx]  # (N, k, 2)
    d = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", d, d) / k
    w, v = np.linalg.eigh(cov)  # ascending eigenvalues
    normals = np.ascontiguousarray(v[:, :, 0])
    planar = (w[:, 0] < 0.1 * np.maximum(w[:, 1], 1e-12)) | (w[:, 0] < 1e-4)
    return normals, planar


def stacked_reference(scans, neighbours: int = 6, bucket_m: float | None = None,
                      faces: bool = False) -> Reference:
    """One reference from several scans, each (pose, points, normals, planar)
    in its own sensor frame (``scan_normals``): points moved and normals
    turned by the pose, so that every normal is its own scan's.

    ``faces``: each line-like point also knows the side its surface was seen
    from (its normal turned towards its own scan's sensor; the reference's
    ``facing``), so a point seen from the other side is not paired with it:
    the two faces of a thin wall, a few decimetres apart, seen by scans on
    either side, are different surfaces, and pairing them pulls a match
    across the wall's thickness. Points without a line normal are seen from
    anywhere."""
    scans = list(scans)
    if not scans:
        return Reference(np.zeros((0, 2)), neighbours, bucket_m=bucket_m)
    pts = np.vstack([transform_points(pose, p) for pose, p, _, _ in scans])
    nrm = np.vstack([n @ rotation(pose[2]).T for pose, _, n, _ in scans])
    planar = np.concatenate([pl for _, _, _, pl in scans])
    facing = None
    if faces:
        sensor = np.vstack([np.broadcast_to(np.asarray(pose, float)[:2], (len(p), 2))
                            for pose, p, _, _ in scans])
        towards = np.einsum("ij,ij->i", nrm, sensor - pts)
        facing = np.where(planar[:, None], nrm * np.where(towards < 0, -1.0, 1.0)[:, None], 0.0)
    return Reference(pts, neighbours, facing, bucket_m=bucket_m, normals=nrm, planar=planar)


def warm_up(ref: Reference) -> None:
    """Load (or compile, once per install) the pairing of points the matching's
    Python steps use, so a first scan does not compile it: a compile holds the
    interpreter for about a second, and the robot's MCU link watchdog (0.5 s) starves."""
    _correspond(ref, ref.points[:2], 0.5, np.zeros(2))


def _correspond(ref: Reference, moved: np.ndarray, gate: float,
                origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest reference point of each moved source point within ``gate``
    (distance inf and index len(points) where none), seen from ``origin``
    when the reference knows its faces (see the module docstring)."""
    if ref.buckets is not None:
        return ref.buckets.nearest_visible(ref.points, ref.facing, moved, origin, gate,
                                           min(VISIBLE_K, len(ref.points)), FACING_MAX_COS)
    dist, j = ref.tree.query(moved, distance_upper_bound=gate)
    if ref.facing is None:
        return dist, j
    ray = moved - origin
    ray /= np.maximum(np.hypot(ray[:, 0], ray[:, 1]), 1e-9)[:, None]
    found = np.isfinite(dist)
    back = np.zeros(len(moved), bool)
    back[found] = np.einsum("nd,nd->n", ref.facing[j[found]], ray[found]) > FACING_MAX_COS
    if not back.any():
        return dist, j
    # the nearest point's face looks away: the nearest one that is seen, if any
    k = min(VISIBLE_K, len(ref.points))
    d2, i2 = ref.tree.query(moved[back], k=k, distance_upper_bound=gate)
    d2, i2 = d2.reshape(-1, k), i2.reshape(-1, k)
    ok = np.isfinite(d2)
    f = ref.facing[np.where(ok, i2, 0)]  # (M, k, 2)
    seen = ok & (np.einsum("mkd,md->mk", f, ray[back]) <= FACING_MAX_COS)
    first = np.argmax(seen, axis=1)  # the nearest seen one (k-d results are sorted)
    rows = np.arange(len(first))
    hit = seen[rows, first]
    dist, j = dist.copy(), j.copy()
    dist[back] = np.where(hit, d2[rows, first], np.inf)
    j[back] = np.where(hit, i2[rows, first], len(ref.points))
    return dist, j


def icp(source: np.ndarray, ref: Reference, guess, cfg: IcpConfig = IcpConfig(),
        origin=(0.0, 0.0)) -> IcpResult:
    """Point-to-line ICP of source points onto ``ref``, from pose ``guess``;
    eqs. ICP-1..3 in the module docstring. ``origin``: where the sensor stood,
    in the source points' frame (used with a reference's ``facing``)."""
    x = np.array(guess, dtype=float)
    src = np.asarray(source, dtype=float)
    org = np.asarray(origin, dtype=float).reshape(1, 2)
    if ref.tree is None or len(src) < cfg.min_points or len(ref.points) < cfg.min_points:
        return IcpResult(x, np.eye(3) * 1e6, math.inf, 0.0, 0, False)
    if ref.buckets is not None:  # the same iterations, compiled (icp_kernel.py)
        b = ref.buckets
        x, H, sigma2, it, converged, failed = icp_loop(
            np.ascontiguousarray(src), x, org[0].copy(), ref.points, ref.normals, ref.planar,
            ref.facing, b.starts, b.order, float(b.lo[0]), float(b.lo[1]), b.cell, b.nx, b.ny,
            min(VISIBLE_K, len(ref.points)), FACING_MAX_COS, cfg.max_iterations,
            cfg.max_corr_dist_m, cfg.min_corr_dist_m, cfg.trim_fraction, cfg.huber_m,
            cfg.min_points, cfg.damping)
        if failed:
            return IcpResult(x, np.eye(3) * 1e6, math.inf, 0.0, it, False)
        return _finish(src, ref, x, org, H, sigma2, it, converged, cfg)
    gate = cfg.max_corr_dist_m
    converged = False
    H = np.eye(3) * 1e-9
    sigma2 = 1.0
    it = 0
    for it in range(1, cfg.max_iterations + 1):
        moved = transform_points(x, src)
        dist, j = _correspond(ref, moved, gate, transform_points(x, org)[0])
        sel = np.isfinite(dist)
        sel[sel] &= ref.planar[j[sel]]
        if np.count_nonzero(sel) < cfg.min_points:
            return IcpResult(x, np.eye(3) * 1e6, math.inf, 0.0, it, False)
        n = ref.normals[j[sel]]
        p = src[sel]
        e = np.einsum("ij,ij->i", n, moved[sel] - ref.points[j[sel]])
        ae = np.abs(e)
        kth = min(int(cfg.trim_fraction * len(ae)), len(ae) - 1)
        keep = ae <= np.partition(ae, kth)[kth]
        n, p, e = n[keep], p[keep], e[keep]
        w = np.minimum(1.0, cfg.huber_m / np.maximum(np.abs(e), 1e-12))
        dr = p @ (rotation(x[2]) @ np.array([[0.0, -1.0], [1.0, 0.0]])).T  # R'(θ) p
        J = np.column_stack((n[:, 0], n[:, 1], np.einsum("ij,ij->i", n, dr)))
        H = (J * w[:, None]).T @ J
        g = (J * w[:, None]).T @ e
        try:
            # Levenberg damping: a direction without information (a corridor)
            # stays where the guess put it instead of wandering on noise
            damp = cfg.damping * max(float(np.max(np.diag(H))), 1e-9)
            delta = -np.linalg.solve(H + np.eye(3) * damp, g)
        except np.linalg.LinAlgError:
            break
        x += delta
        x[2] = float(wrap(x[2]))
        sigma2 = float(np.sum(w * e * e) / max(len(e) - 3, 1))
        gate = max(cfg.min_corr_dist_m, 0.7 * gate)
        tiny = np.hypot(delta[0], delta[1]) < 1e-4 and abs(delta[2]) < 1e-5
        # or a step that barely lowers the cost (sliding along a corridor)
        flat = float(delta @ H @ delta) < 1e-4 * float(np.sum(w * e * e))
        if (tiny or flat) and gate <= cfg.min_corr_dist_m + 1e-9:
            converged = True
            break
    return _finish(src, ref, x, org, H, sigma2, it, converged, cfg)


def _finish(src: np.ndarray, ref: Reference, x: np.ndarray, org: np.ndarray, H: np.ndarray,
            sigma2: float, it: int, converged: bool, cfg: IcpConfig) -> IcpResult:
    """Inliers and RMS at the final gate, and the covariance (ICP-3)."""
    moved = transform_points(x, src)
    dist, j = _correspond(ref, moved, cfg.min_corr_dist_m, transform_points(x, org)[0])
    found = np.isfinite(dist)
    e_all = np.full(len(src), np.inf)
    e_all[found] = np.abs(np.einsum("ij,ij->i", ref.normals[j[found]],
                                    moved[found] - ref.points[j[found]]))
    inlier = e_all < cfg.inlier_dist_m
    rmse = float(np.sqrt(np.mean(e_all[inlier] ** 2))) if inlier.any() else math.inf
    sigma2 = max(sigma2, cfg.min_sigma_m ** 2)
    cov = sigma2 * np.linalg.inv(H + np.eye(3) * 1e-9)
    return IcpResult(x, cov, rmse, float(np.mean(inlier)), it, converged)


def pair_information(source: np.ndarray, ref: Reference, pose, cfg: IcpConfig = IcpConfig(),
                     origin=(0.0, 0.0)) -> np.ndarray:
    """Σ n_j n_jᵀ (2×2) over the inlier pairs at ``pose`` (as ``_finish``
    counts them: the nearest line-like reference point within the final
    gate, closer than ``inlier_dist_m`` along its normal): the translation
    block of Jᵀ J (ICP-2) in units of points. An eigenvalue says how many
    points' worth of pairs hold the fit along its eigenvector; a small one
    is a direction the fit hardly sees (a corridor's axis, held only by a
    few points on small objects), however small ICP-3's σ̂ is there."""
    src = np.asarray(source, dtype=float).reshape(-1, 2)
    if ref.tree is None or len(src) == 0:
        return np.zeros((2, 2))
    moved = transform_points(pose, src)
    org = transform_points(pose, np.asarray(origin, dtype=float).reshape(1, 2))[0]
    dist, j = _correspond(ref, moved, cfg.min_corr_dist_m, org)
    found = np.isfinite(dist)
    found[found] &= ref.planar[j[found]]
    n = ref.normals[j[found]]
    e = np.abs(np.einsum("ij,ij->i", n, moved[found] - ref.points[j[found]]))
    n = n[e < cfg.inlier_dist_m]
    return n.T @ n

# ---- correlative search: a seed for a poor guess -----------------------------------


class LikelihoodField:
    """exp(−d²/2σ²) of the distance d to the nearest reference point, on a grid.

    By default d is the distance between cell centres (a Euclidean distance
    transform of the cells that hold points). ``stamped``: d from each cell's
    centre to the nearest point itself, zero beyond 3σ (where the field is
    below 0.012), built by stamping each point's disc of 3σ into the grid
    (icp_kernel.stamp_field), which costs what the points cost, not what the
    grid's area does; the mapping's references, built anew for nearly every
    scan, use this one."""

    def __init__(self, ref_points: np.ndarray, res_m: float = 0.1, sigma_m: float = 0.2,
                 margin_m: float = 3.0, stamped: bool = False) -> None:
        pts = np.ascontiguousarray(ref_points, dtype=float).reshape(-1, 2)
        self.res = res_m
        if stamped:
            margin_m = max(margin_m, 3 * sigma_m + res_m)
        self.lo = pts.min(axis=0) - margin_m
        shape = np.ceil((pts.max(axis=0) + margin_m - self.lo) / res_m).astype(int) + 1
        if stamped:
            self.field = np.zeros((shape[1] + 2, shape[0] + 2))  # [row = y, col = x]
            self.lo = self.lo - res_m  # a zero border: points outside score 0
            stamp_field(pts, float(self.lo[0]), float(self.lo[1]), res_m, sigma_m, self.field)
            return
        occ = np.ones((shape[1], shape[0]), bool)  # [row = y, col = x]; True = free
        c = np.floor((pts - self.lo) / res_m).astype(int)
        occ[c[:, 1], c[:, 0]] = False
        # imported here: scipy.ndimage alone costs ≈ 0.6 s at start
        from scipy.ndimage import distance_transform_edt

        d = distance_transform_edt(occ) * res_m
        self.field = np.exp(-0.5 * (d / sigma_m) ** 2)
        self.field = np.pad(self.field, 1)  # zero border: points outside score 0
        self.lo = self.lo - res_m

    def score(self, pts: np.ndarray) -> np.ndarray:
        """Sum of field values at points (..., N, 2) → (...)."""
        c = np.floor((pts - self.lo) / self.res).astype(int)
        h, w = self.field.shape
        cx = np.clip(c[..., 0], 0, w - 1)
        cy = np.clip(c[..., 1], 0, h - 1)
        return self.field[cy, cx].sum(axis=-1)


def correlative_search(source: np.ndarray, field: LikelihoodField, guess, window_xy_m: float,
                       window_theta_rad: float, step_xy_m: float = 0.15,
                       step_theta_rad: float = math.radians(2.0),
                       max_points: int = 90) -> tuple[np.ndarray, float]:
    """Best pose on the grid guess ± window and its mean field score (0..1)."""
    src = np.asarray(source, float).reshape(-1, 2)
    if len(src) == 0:
        return np.array(guess, float), 0.0
    if len(src) > max_points:
        src = src[np.linspace(0, len(src) - 1, max_points).astype(int)]
    offs = np.arange(-window_xy_m, window_xy_m + 1e-9, step_xy_m)
    dx, dy = np.meshgrid(offs, offs, indexing="ij")
    shifts = np.column_stack((dx.ravel(), dy.ravel()))  # (S, 2)
    best, best_score = np.array(guess, float), -1.0
    for dth in np.arange(-window_theta_rad, window_theta_rad + 1e-9, step_theta_rad):
        th = guess[2] + dth
        base = transform_points((guess[0], guess[1], th), src)  # (N, 2)
        k, score = best_shift(base, shifts, field.field, float(field.lo[0]),
                              float(field.lo[1]), float(field.res))
        if score > best_score:
            best_score = float(score)
            best = np.array([guess[0] + shifts[k, 0], guess[1] + shifts[k, 1], float(wrap(th))])
    return best, best_score / len(src)


def match(source: np.ndarray, ref: Reference, guess, cfg: IcpConfig = IcpConfig(),
          window_xy_m: float = 0.0, window_theta_rad: float = 0.0,
          min_inlier_fraction: float = 0.5, always_search: bool = False) -> IcpResult:
    """ICP from ``guess``; if it fails or fits poorly (or ``always_search``)
    and a window is given, seed ICP again from the correlative search's best
    pose and keep the better fit (more inliers)."""
    r = icp(source, ref, guess, cfg)
    good = r.converged and r.inlier_fraction >= min_inlier_fraction and not always_search
    if good or window_xy_m <= 0 \
            or len(ref.points) < cfg.min_points or len(source) < cfg.min_points:
        return r
    seed, _ = correlative_search(source, ref.likelihood_field(), guess, window_xy_m,
                                 window_theta_rad)
    r2 = icp(source, ref, seed, cfg)
    return r2 if r2.inlier_fraction > r.inlier_fraction else r
