"""The covariance of a scan matched on a submap's grid (submap_match.py).

Two estimates of the uncertainty of the pose ξ = (x, y, θ) that puts the
scan's points h_k on the grid:

1. **Olson's** (E. Olson, "Real-time correlative scan matching", ICRA 2009,
   §III-C "covariance estimation"): the likelihood of each pose in a small
   grid round the optimum, L(ξ) = Π_k M(T_ξ h_k) (normalised), taken as the
   pose's distribution, Σ = K/s − u uᵀ/s² with s = Σ L, u = Σ L ξ,
   K = Σ L ξ ξᵀ: ``olson_covariance``. Each point counts as an independent
   measurement whose spread is the field's width σ (8 cm), whatever the
   scan's real residuals are; neighbouring beams see the same wall, so the
   product over k counts one error many times, and the estimate is
   optimistic (the mapper used to scale it by 4).

2. **From the residuals, with correlated beams** (``residual_covariance``):
   the closed form of A. Censi, "An accurate closed-form
   estimate of ICP's covariance", ICRA 2007: the covariance of the
   minimiser ξ̂ of a cost J(z, ξ) of the data z, to first order,

       Σ = H⁻¹ (∂²J/∂ξ∂z) Σ_z (∂²J/∂ξ∂z)ᵀ H⁻¹,

   for the grid fit's own cost J = ½ Σ_k e_k² (submap_match's "distance"
   objective, point-to-line on the grid: near a wall ½∇²G = n nᵀ, G the
   squared distance of the grid interpolated at the moved point). Per
   point, e_k = √λ_k n_kᵀ (p_k − q_k) with n_k, λ_k the leading eigenvector
   and eigenvalue of ½∇²G there (n_k turned towards the sensor, so that a
   wall's points share a sign), the row J_k = √λ_k n_kᵀ [I | R'(θ) h_k]
   and H = Σ_k J_kᵀ J_k. A change of e_k moves the cost's gradient by
   J_kᵀ, so (∂²J/∂ξ∂z) Σ_z (∂²J/∂ξ∂z)ᵀ = Σ_{k,l} J_kᵀ J_l cov(e_k, e_l) =: M.
   The residuals' covariance Σ_z is not taken as σ² I:

   - σ² = Σ e_k² / (m − 3) from the matched points' own residuals (m
     points within 2.5 σ_field of the grid's walls), at least the variance
     of a cell's quantisation, res²/12 (the map holds one stamp per cell);
   - neighbouring beams on the same surface are correlated (they see the
     same wall, placed by the same keyframes, with the same error): runs of
     consecutive beams less than ``join_gap_m`` apart (what the submap joins
     into one wall), the correlation of two beams of a run i and j beams
     apart ρ^|i−j| (an AR(1) process along the wall, ρ per beam from the
     lag-1 correlation of the residuals along the runs, in [0, 0.95]), none
     between runs: M = σ² Σ_runs Σ_{k,l∈run} ρ^|k−l| J_kᵀ J_l. A smooth
     error along a wall (a misplaced keyframe's wall is shifted *and*
     tilted) turns the heading; a model with one correlation for the whole
     run (an offset only) does not see that;
   - H is inverted by its eigenvalues without a damping term, so a
     direction the points do not constrain (along a corridor) keeps the
     large variance it has (eigenvalues floored only at 1e-9 of the
     largest); where H has no information at all, M has none either and the
     sandwich would say zero, so there the variance is σ² over the floor.

   No factor is fitted. It is right where the errors are in the residuals
   (tests/localisation/test_match_covariance.py: smooth errors along the
   walls, many draws), but not on the real logs: there the matches' errors
   against the reference (2.5–3.9 cm, 0.37–0.43°) are 4–10 times what it
   states (bench/match_covariance_bench.py), because what moves a match
   there barely shows in its residuals: the submap's keyframes placed a few
   centimetres and tenths of a degree off (the fit absorbs the part of
   their error that looks like a pose change) and the reference's own
   error. Olson's estimate times the mapper's 4 comes out about right on
   the same matches (NEES 2.1 on freiburg, 3.3 on edmonton, where 3 is
   right; edmonton's heading 1.4 times too confident, the translations
   1.05–1.4 times too cautious), and fused, the residual covariance makes
   the maps worse (edmonton-every2's ATE 0.19 → 0.27 m, mean of 3 draws), so it is an option
   (SubmapConfig.covariance "residual"), not the default.

3. **The submap's own uncertainty** (``submap_spread``), added to either:
   both estimates above take the submap's walls as exact, but the
   keyframes that drew them were placed by earlier fused steps, each with
   its own error, so the walls of a keyframe several steps from the
   submap's anchor (the keyframe the mapper's step is taken from, the
   newest) are turned and moved relative to the anchor's. Model: each
   fused step m (node m from node m − 1) carries an error δ_m, independent
   between steps (the chain's compounding of relative poses, R. Smith,
   M. Self, P. Cheeseman, "Estimating uncertain spatial relationships in
   robotics", 1990, §3.1, to first order), with the covariance C_m the
   mapper gave it (world frame, θ about node m's position). δ_m moves every
   keyframe on the far side of step m from the anchor rigidly: rotation
   δθ_m about node m's position c_m and translation δt_m. The scan fits
   the submap's walls together, each keyframe with about an equal share of
   the matched points (the keyframes overlap; a cell's stamp is the mean of
   its points), so its pose follows the far side's motion by the share
   W_m of the submap's keyframes beyond step m; a rigid motion about c_m
   is, for a pose at p, the translation δt_m + δθ_m ⊥(p − c_m) with the
   same turn (⊥(d) = (−d_y, d_x): the lever arm). Hence

       Σ_spread = Σ_m W_m² T_m C_m T_mᵀ,  T_m = [[1, 0, −d_y], [0, 1, d_x], [0, 0, 1]],
       d = p − c_m,

   a term that is zero for a one-keyframe submap and grows with the
   keyframes' spread along the path (more steps, larger turns, each step's
   heading error with a longer lever arm). ``part`` "heading" keeps only
   each step's heading variance (and its lever arm), "full" the whole C_m.

   Measured (bench/match_covariance_bench.py, 3 draws, the same matches):
   with the heading part, the matches' e/σ θ against the reference goes
   from 0.98 / 1.39 / 1.63 (freiburg, edmonton, edmonton-every2) to
   0.64 / 0.87 / 1.03, x and y barely move; "full" makes x and y 1.5 times
   too cautious. But fused (MappingConfig.submap_spread), it makes the maps
   worse (edmonton's ATE 0.16 → 0.28 m, edmonton-every2's 0.19 → 0.73 m with
   one failed draw; heading RPE worse on all three logs), so it is off by
   default. The term overstates what it models: the same matches on the
   keyframes at their reference poses ("clean") err almost as much in
   heading (0.38° against 0.43° in situ on edmonton), so the keyframes'
   error is a small part; on a synthetic chain the match turns with about
   half the variance Σ_spread states (tests/localisation/
   test_submap_spread.py); and the heading error left against the reference
   is mostly the reference's own: a scan matched on its past and on its
   future keyframes (``--reference-check``) shares 61 % of its heading
   error variance between the two on edmonton (about 0.32° rms, against the
   matcher's own 0.26°, inside Olson's × 4 σ of 0.36°).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .grid_interp import _bicubic_hessian, _keys

MAX_RHO = 0.95


def submap_spread(position, anchor: int, keyframes, positions, step_covs,
                  part: str = "heading") -> np.ndarray:
    """Σ_spread (3. above) for a scan at world ``position`` (x, y) matched
    on a submap of the nodes ``keyframes`` anchored at node ``anchor``:
    ``positions[m]`` node m's world (x, y), ``step_covs[m]`` the covariance
    of node m's fused step from node m − 1 (world frame); ``part``:
    "heading" or "full"."""
    kf = np.sort(np.asarray(list(keyframes), dtype=np.int64))
    out = np.zeros((3, 3))
    if len(kf) < 2:
        return out
    n = float(len(kf))
    px, py = float(position[0]), float(position[1])
    for m in range(int(kf[0]) + 1, int(kf[-1]) + 1):
        # the keyframes on the far side of step m (between node m − 1 and m)
        far = int(np.sum(kf < m)) if m <= anchor else int(np.sum(kf >= m))
        if far == 0:
            continue
        c = np.asarray(step_covs[m], float)
        if part == "heading":
            c = np.diag([0.0, 0.0, c[2, 2]])
        dx, dy = px - float(positions[m][0]), py - float(positions[m][1])
        t = np.array([[1.0, 0.0, -dy], [0.0, 1.0, dx], [0.0, 0.0, 1.0]])
        out += (far / n) ** 2 * (t @ c @ t.T)
    return out


def olson_covariance(src: np.ndarray, field, pose, step_xy: float, step_th: float,
                     half_steps: int = 2) -> np.ndarray:
    """Olson's covariance (1. above) of points ``src`` at ``pose`` on
    ``field`` (a submap's fine _Field: grid, lo, res): moments of the
    normalised likelihood over ±``half_steps`` steps (M floored at 0.01, as a
    point may be a new object)."""
    return _olson_cov(np.ascontiguousarray(src, dtype=np.float64), np.array(pose, float),
                      field.grid, float(field.lo[0]), float(field.lo[1]), field.res, step_xy,
                      step_th, half_steps)


def _residual_terms(src: np.ndarray, field, pose, sigma_m: float, join_gap_m: float):
    """The matched points' rows J (m×3), residuals e, σ² (floored at a
    cell's res²/12), the correlation ρ of neighbouring beams, and each
    matched point's run and beam index (2. above); None with fewer than 6
    matched points."""
    src = np.ascontiguousarray(src, dtype=np.float64)
    rows, e, ok = _point_rows(src, np.array(pose, float), field.grid, float(field.lo[0]),
                              float(field.lo[1]), field.res, sigma_m, (2.5 * sigma_m) ** 2)
    idx = np.flatnonzero(ok)
    m = len(idx)
    if m < 6:
        return None
    J, e = rows[idx], e[idx]
    sigma2 = max(float(e @ e) / (m - 3), field.res ** 2 / 12.0)
    # runs: consecutive beams the submap would join as one wall (``join_gap_m``)
    run_all = np.concatenate(([0], np.cumsum(np.hypot(*np.diff(src, axis=0).T) >= join_gap_m)))
    run = run_all[idx]
    same = run[1:] == run[:-1]
    rho = 0.0
    if same.any():
        lag = (idx[1:] - idx[:-1])[same]
        a, b = e[:-1][same], e[1:][same]
        den = math.sqrt(float(a @ a) * float(b @ b))
        if den > 0:  # per beam of lag: a pair two beams apart shares ρ²
            r = max(float(a @ b) / den, 0.0)
            rho = min(r ** (1.0 / float(np.mean(lag))), MAX_RHO)
    return J, e, sigma2, rho, run, idx


def residual_covariance(src: np.ndarray, field, pose, sigma_m: float,
                        join_gap_m: float) -> np.ndarray:
    """The residual covariance (2. above) of points ``src`` (in beam order)
    at ``pose`` on ``field``, whose likelihood has width ``sigma_m``."""
    t = _residual_terms(src, field, pose, sigma_m, join_gap_m)
    if t is None:
        return np.eye(3) * 1e6
    J, _, sigma2, rho, run, beam = t
    H = J.T @ J
    M = np.zeros((3, 3))
    for r in np.unique(run):
        k = run == r
        Jr, br = J[k], beam[k].astype(float)
        M += Jr.T @ (rho ** np.abs(br[:, None] - br[None, :])) @ Jr
    M *= sigma2
    w, v = np.linalg.eigh(H)
    low = 1e-9 * max(float(w[-1]), 1e-12)
    flat = w < low  # no point constrains this direction: M is blind there too
    w = np.maximum(w, low)
    Hinv = (v / w) @ v.T
    cov = Hinv @ M @ Hinv + sigma2 * (v[:, flat] / w[flat]) @ v[:, flat].T
    return 0.5 * (cov + cov.T)


@njit(cache=True)
def _point_rows(src, pose, grid, lox, loy, res, sigma, cap2):
    """Per point at ``pose``: the row J_k, the residual e_k (2. above) and
    whether the point is matched (within the cap, with a
    positive curvature across the wall)."""
    n = src.shape[0]
    rows = np.zeros((n, 3))
    e = np.zeros(n)
    ok = np.zeros(n, np.bool_)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for i in range(n):
        px, py = src[i, 0], src[i, 1]
        wx = c * px - s * py + pose[0]
        wy = s * px + c * py + pose[1]
        f = _bicubic_hessian(grid, lox, loy, res, wx, wy, sigma)
        if f[0] >= cap2 or (f[0] == 0.0 and f[1] == 0.0 and f[2] == 0.0 and f[3] == 0.0):
            continue
        a, b, d = 0.5 * f[3], 0.5 * f[4], 0.5 * f[5]
        lam = 0.5 * (a + d) + math.sqrt(0.25 * (a - d) ** 2 + b * b)
        if lam <= 0.1:  # no wall's curvature here (a blob's edge, the cap's bend)
            continue
        if abs(b) > 1e-12:
            vx, vy = lam - d, b
        elif a >= d:
            vx, vy = 1.0, 0.0
        else:
            vx, vy = 0.0, 1.0
        norm = math.hypot(vx, vy)
        vx, vy = vx / norm, vy / norm
        if vx * (pose[0] - wx) + vy * (pose[1] - wy) < 0.0:  # towards the sensor
            vx, vy = -vx, -vy
        k = math.sqrt(lam)
        rx, ry = -s * px - c * py, c * px - s * py  # R'(θ) h
        rows[i, 0] = k * vx
        rows[i, 1] = k * vy
        rows[i, 2] = k * (vx * rx + vy * ry)
        e[i] = 0.5 * (f[1] * vx + f[2] * vy) / k
        ok[i] = True
    return rows, e, ok


@njit(cache=True)
def _olson_cov(src, pose, grid, lox, loy, res, step_xy, step_th, m):
    """Olson's moments over the (2m + 1)³ poses round ``pose``."""
    logl = _pose_grid_logl(src, pose, grid, lox, loy, res, step_xy, step_th, m)
    return olson_moments(logl, step_xy, step_th, m)


@njit(cache=True)
def olson_moments(logl, step_xy, step_th, m):
    """The covariance of the normalised likelihood exp(logl) over the
    (2m + 1)³ poses round the optimum (logl[θ, x, y]), plus a step's own
    uniform variance (Olson 2009, §III-C)."""
    side = 2 * m + 1
    top = logl.max()
    s_ = 0.0
    u = np.zeros(3)
    kk = np.zeros((3, 3))
    for a in range(side):
        for b in range(side):
            for d in range(side):
                w = math.exp(logl[a, b, d] - top)
                xi = np.array([(b - m) * step_xy, (d - m) * step_xy, (a - m) * step_th])
                s_ += w
                u += w * xi
                kk += w * np.outer(xi, xi)
    cov = kk / s_ - np.outer(u, u) / (s_ * s_)
    # the grid's own resolution: a peak within one cell is known to a cell
    cov[0, 0] += step_xy * step_xy / 12.0
    cov[1, 1] += step_xy * step_xy / 12.0
    cov[2, 2] += step_th * step_th / 12.0
    return cov


@njit(cache=True)
def _pose_grid_logl(src, pose, grid, lox, loy, res, step_xy, step_th, m):
    """log L(ξ) = Σ_k ln max(M(T_ξ h_k), 0.01) at each pose of the small grid,
    M read by ``_bicubic``'s interpolant. A pose's x translation moves only
    the x interpolation, its y translation only the y: per heading and point,
    the weights and nodes of each x and of each y translation (computed as
    ``_bicubic`` computes them at that pose), then each pose's 4 × 4 nodes
    summed as ``_bicubic`` sums them, to the last bit — 2(2m + 1) weight sets
    per point and heading instead of (2m + 1)², and no gradient."""
    side = 2 * m + 1
    logl = np.zeros((side, side, side))
    h, w = grid.shape
    wxs = np.empty((side, 4))
    wys = np.empty((side, 4))
    xs = np.empty(side, np.int64)
    ys = np.empty(side, np.int64)
    n = src.shape[0]
    for a in range(side):
        th = pose[2] + (a - m) * step_th
        c, s = math.cos(th), math.sin(th)
        for i in range(n):
            rx = c * src[i, 0] - s * src[i, 1]
            ry = s * src[i, 0] + c * src[i, 1]
            for b in range(side):
                u = (rx + (pose[0] + (b - m) * step_xy) - lox) / res - 0.5
                xs[b] = int(math.floor(u))
                wx, _ = _keys(u - xs[b])
                for q in range(4):
                    wxs[b, q] = wx[q]
                v = (ry + (pose[1] + (b - m) * step_xy) - loy) / res - 0.5
                ys[b] = int(math.floor(v))
                wy, _ = _keys(v - ys[b])
                for q in range(4):
                    wys[b, q] = wy[q]
            for b in range(side):
                x0 = xs[b]
                for d in range(side):
                    y0 = ys[d]
                    val = 0.0
                    if x0 >= 1 and y0 >= 1 and x0 + 2 < w and y0 + 2 < h:
                        for j in range(4):
                            for q in range(4):
                                val += wys[d, j] * wxs[b, q] * grid[y0 - 1 + j, x0 - 1 + q]
                    logl[a, b, d] += math.log(max(val, 0.01))
    return logl


def fused_step(q: np.ndarray, rc_fit: np.ndarray, rc: np.ndarray, d: np.ndarray | None,
               mode: str, gate_chi2: float) -> tuple[np.ndarray, np.ndarray]:
    """The mapper's Kalman fusion of a step (seed 002 eqs. 11–14: K = Q (Q + R)⁻¹,
    P = (I − K) Q): (gain, the step's covariance). ``rc_fit``: the match's
    covariance; ``rc``: the same with the matchers' disagreement d
    (MappingConfig.match_disagreement); ``mode`` "fusion" or "position": the
    gain of ``rc``; "edge": the gain of ``rc_fit`` and the covariance that gain
    leaves when the match is as unsure as ``rc`` says (Joseph form,
    (I − K) Q (I − K)ᵀ + K R Kᵀ), unless d is outside the fit's own spread
    (dᵀ rc_fit⁻¹ d > ``gate_chi2``: one fit is in a rival minimum), where the
    gain of ``rc`` hands the step to odometry."""
    if mode == "edge" and d is not None and float(d @ np.linalg.solve(rc_fit, d)) <= gate_chi2:
        gain = q @ np.linalg.inv(q + rc_fit)
        i_k = np.eye(3) - gain
        return gain, i_k @ q @ i_k.T + gain @ rc @ gain.T
    gain = q @ np.linalg.inv(q + rc)
    return gain, (np.eye(3) - gain) @ q
