"""The covariance of a scan matched on a submap's grid (match_covariance.py)."""

import math

import numpy as np

from app.core.localisation.mapping import MappingConfig
from app.core.localisation.match_covariance import _residual_terms, residual_covariance
from app.core.localisation.submap_match import Submap, SubmapConfig, covariance, match_submap

CFG = SubmapConfig()


def _room(step_m=0.05):
    """A closed 8 m × 5 m room as wall points, wall by wall (in beam-like order)."""
    corners = [(-4.0, -2.5), (4.0, -2.5), (4.0, 2.5), (-4.0, 2.5), (-4.0, -2.5)]
    walls = []
    for (x1, y1), (x2, y2) in zip(corners[:-1], corners[1:], strict=True):
        n = int(round(math.hypot(x2 - x1, y2 - y1) / step_m))
        t = np.arange(n) / n
        walls.append(np.column_stack((x1 + t * (x2 - x1), y1 + t * (y2 - y1))))
    return walls


def _normals(wall):
    d = wall[-1] - wall[0]
    return np.array([-d[1], d[0]]) / math.hypot(*d)


def test_a_corridor_keeps_its_direction_weak():
    """Two long parallel walls: nothing fixes the pose along them, and the
    residual covariance says so (no damping term hides it)."""
    x = np.linspace(-10, 10, 400)
    walls = np.r_[np.column_stack((x, np.full_like(x, 1.0))),
                  np.column_stack((x, np.full_like(x, -1.0)))]
    sub = Submap([(np.zeros(3), walls)])
    rng = np.random.default_rng(3)
    src = walls[::3] + rng.normal(0, 0.01, walls[::3].shape)
    cov = residual_covariance(src, sub.fine, np.zeros(3), CFG.sigma_m, CFG.join_gap_m)
    assert np.all(np.linalg.eigvalsh(cov) > 0)
    sx, sy = math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1])
    assert sx > 100 * sy
    assert sy < 0.02


def _segments(step_m=0.05):
    """Four walls of a room, apart (no corner joins two of them)."""
    ends = [((-4.0, -2.5), (4.0, -2.5)), ((4.0, -2.0), (4.0, 2.0)),
            ((3.0, 2.5), (-3.0, 2.5)), ((-4.0, 2.0), (-4.0, -1.0))]
    walls = []
    for (x1, y1), (x2, y2) in ends:
        n = int(round(math.hypot(x2 - x1, y2 - y1) / step_m))
        t = np.arange(n) / n
        walls.append(np.column_stack((x1 + t * (x2 - x1), y1 + t * (y2 - y1))))
    return walls


def _smooth_noise(rng, n, sigma, rho):
    """AR(1) along a wall: each beam's error mostly its neighbour's."""
    e = np.empty(n)
    e[0] = rng.normal(0, sigma)
    for i in range(1, n):
        e[i] = rho * e[i - 1] + rng.normal(0, sigma * math.sqrt(1 - rho * rho))
    return e


def test_errors_shared_by_neighbouring_beams_count_as_fewer_measurements():
    """Smooth errors along each wall (neighbouring beams' errors 0.95
    correlated): over many draws the matched pose spreads far more than
    σ² H⁻¹ of independent beams claims; the residual covariance, which
    counts a wall's correlated beams as fewer measurements, states a spread
    of the right size."""
    walls = _segments()
    sub = Submap([(np.zeros(3), np.vstack(walls))])
    rng = np.random.default_rng(5)
    poses, stated, naive, rhos = [], [], [], []
    for _ in range(30):
        src = np.vstack([w + _smooth_noise(rng, len(w), 0.015, 0.95)[:, None] * _normals(w)
                         for w in walls])[::2]
        r = match_submap(src, sub, np.zeros(3))
        poses.append(r.pose)
        stated.append(np.sqrt(np.diag(residual_covariance(src, sub.fine, r.pose, CFG.sigma_m,
                                                          CFG.join_gap_m))))
        J, _, sigma2, rho, _, _ = _residual_terms(src, sub.fine, r.pose, CFG.sigma_m,
                                               CFG.join_gap_m)
        naive.append(np.sqrt(np.diag(sigma2 * np.linalg.inv(J.T @ J))))
        rhos.append(rho)
    spread = np.sqrt(np.mean(np.array(poses) ** 2, axis=0))
    stated, naive = np.mean(stated, axis=0), np.mean(naive, axis=0)
    assert np.mean(rhos) > 0.7
    assert np.all(naive < spread / 2.5)  # independent beams: far too confident
    assert np.all(stated > spread / 2) and np.all(stated < spread * 2.5)


def test_a_perfect_fit_is_known_to_a_cell_not_better():
    """Points exactly on the map's walls: σ² is held at a cell's res²/12."""
    walls = _room()
    pts = np.vstack(walls)
    sub = Submap([(np.zeros(3), pts)])
    src = pts[::4]
    t = _residual_terms(src, sub.fine, np.zeros(3), CFG.sigma_m, CFG.join_gap_m)
    J, _, sigma2, _, _, _ = t
    assert sigma2 >= CFG.res_m ** 2 / 12 - 1e-12
    cov = residual_covariance(src, sub.fine, np.zeros(3), CFG.sigma_m, CFG.join_gap_m)
    floor = CFG.res_m ** 2 / 12 * np.linalg.inv(J.T @ J)
    assert np.all(np.linalg.eigvalsh(cov - floor) > -1e-12)


def test_the_submap_covariance_kind_and_its_scale_in_the_mapper():
    """Olson's covariance is scaled by the mapper (it counts every beam as
    independent); the residual one is fused as it is."""
    walls = _room()
    sub = Submap([(np.zeros(3), np.vstack(walls))])
    src = np.vstack(walls)[::3]
    olson = covariance(src, sub, np.zeros(3), 2, "olson")
    resid = covariance(src, sub, np.zeros(3), 2, "residual")
    assert not np.allclose(olson, resid)
    assert MappingConfig().cov_scale(True) == MappingConfig().icp_cov_scale
    cfg = MappingConfig(submap_cfg=SubmapConfig(covariance="residual"))
    assert cfg.cov_scale(True) == 1.0 and cfg.cov_scale(False) == cfg.icp_cov_scale


def test_olsons_pose_grid_is_bicubics_likelihood_at_every_pose_to_the_last_bit():
    """Olson's likelihood over the small pose grid, read with the weights of
    each x and each y translation computed once (match_covariance), equals
    the field interpolated afresh at every pose (grid_interp._bicubic) bit
    for bit, also where a pose's nodes leave the grid (a point at the
    field's edge), for steps of one cell, two cells and no whole cell."""
    from app.core.localisation.grid_interp import _bicubic
    from app.core.localisation.match_covariance import _pose_grid_logl

    rng = np.random.default_rng(5)
    walls = np.vstack(_room())
    sub = Submap([(np.zeros(3), walls)])
    f = sub.fine
    lox, loy = float(f.lo[0]), float(f.lo[1])
    src = walls[::9] + rng.normal(0, 0.01, walls[::9].shape)
    src = np.ascontiguousarray(np.vstack((src, [[lox + 0.07, 0.0]])))
    pose = np.array([0.03, -0.02, math.radians(0.4)])
    th = CFG.fine_step_theta_rad
    for m, step in ((2, f.res), (3, 2 * f.res), (2, 0.037)):
        fast = _pose_grid_logl(src, pose, f.grid, lox, loy, f.res, step, th, m)
        side = 2 * m + 1
        slow = np.zeros((side, side, side))
        for a in range(side):
            c, s = math.cos(pose[2] + (a - m) * th), math.sin(pose[2] + (a - m) * th)
            for b in range(side):
                for d in range(side):
                    tx, ty = pose[0] + (b - m) * step, pose[1] + (d - m) * step
                    tot = 0.0
                    for x, y in src:
                        v, _, _ = _bicubic(f.grid, lox, loy, f.res, c * x - s * y + tx,
                                           s * x + c * y + ty)
                        tot += math.log(max(v, 0.01))
                    slow[a, b, d] = tot
        assert np.array_equal(fast, slow)
        # the edge point leaves the grid at the leftmost shifts (ln 0.01 there)
        assert np.ptp(slow) > 1.0
