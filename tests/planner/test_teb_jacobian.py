"""The TEB's analytic Jacobian (teb_jacobian.py) against central differences
of the penalties themselves, on random bands beside an obstacle, on and off
the global path, reversing, fast and turning, for the optimised and the
plain TEB; a hinge exactly at its kink contributes nothing; the obstacle
field's gradient is the bilinear interpolation's own."""

import math

import numpy as np
import pytest

from app.core.planner.fws_navigator import _WithObstacles
from app.core.planner.teb import ObstacleField, Teb, TebConfig
from app.core.planner.teb_scenes import RES_M, make_scene

BLOCKS = ("time", "kin", "radius", "vmax", "back", "wmax", "acc", "obs", "mid", "path")


def _block_of(rows, n):
    """The penalty each residual row belongs to (Teb._residuals' order)."""
    m, q = n - 1, n - 2
    ends = np.cumsum([m, m, m, m, m, m, m, q, m, q])
    return np.array(BLOCKS)[np.searchsorted(ends, rows, side="right")]


def _central(teb, z, args, h=1e-6):
    """Central, forward and backward differences on the pattern's entries."""
    rows, cols, *_ = teb._sparsity(args[0], args[4] is not None)
    r0 = teb._residuals(z, *args)
    C, Fw, Bw = (np.empty(len(rows)) for _ in range(3))
    for j in range(z.size):
        e = np.zeros_like(z)
        e[j] = h
        rp, rm = teb._residuals(z + e, *args), teb._residuals(z - e, *args)
        sel = cols == j
        C[sel] = (rp - rm)[rows[sel]] / (2 * h)
        Fw[sel] = (rp - r0)[rows[sel]] / h
        Bw[sel] = (r0 - rm)[rows[sel]] / h
    return rows, C, Fw, Bw


def _band(rng, kind: str, n: int = 10):
    """Poses along y = 1.62 beside the box of the obstacle-at-goal scene
    (x 6.4–7.1, y 2.0–4.0; clearance 0.5 m), perturbed at random."""
    x = np.linspace(5.4, 8.2, n)
    th = np.zeros(n)
    dts = rng.uniform(0.35, 0.6, n - 1)
    if kind == "reversing":
        th += math.pi  # facing back along the band: v < 0
    elif kind == "fast":
        dts = rng.uniform(0.08, 0.2, n - 1)
    elif kind == "turning":
        th = np.cumsum(rng.choice([-1.0, 1.0], n)) * 0.9
    P = np.column_stack([x, np.full(n, 1.62), th])
    P[:, :2] += rng.normal(scale=0.04, size=(n, 2))
    P[:, 2] += rng.normal(scale=0.08, size=n)
    z = np.concatenate([P[1:-1].ravel(), dts])
    path = np.column_stack([np.linspace(5.0, 8.6, 7), 1.62 + 0.1 * np.sin(np.arange(7))])
    return P[0], P[-1], z, path


KINDS = ("near", "reversing", "fast", "turning")
FIELD = ObstacleField(make_scene("obstacle_at_goal").blocked, RES_M)


@pytest.mark.parametrize("optimised", [True, False])
@pytest.mark.parametrize("with_path", [True, False])
@pytest.mark.parametrize("kind", KINDS)
def test_analytic_jacobian_equals_central_differences(optimised, with_path, kind):
    """Entries whose one-sided differences disagree (a hinge or a cell edge
    of the distance field within the step) are left out; they must be few.
    Every penalty the scenario is built for must be active somewhere."""
    teb = Teb(TebConfig(optimised=optimised))
    rng = np.random.default_rng([optimised, with_path, KINDS.index(kind)])
    active = set()
    for _ in range(3):
        start, goal, z, path = _band(rng, kind)
        n = 10
        args = (n, start, goal, FIELD, path if with_path and optimised else None, 0.3)
        got = teb._jacobian_values(z, teb._residuals(z, *args), *args)
        rows, C, Fw, Bw = _central(teb, z, args)
        smooth = np.abs(Fw - Bw) <= 1e-3 * (1.0 + np.abs(C))
        assert smooth.mean() > 0.97
        assert np.allclose(got[smooth], C[smooth], rtol=1e-6, atol=1e-5)
        active |= set(_block_of(rows[np.abs(got) > 1e-9], n))
    need = {"time", "kin", "obs", "mid", "acc"}
    need |= {"path"} if with_path and optimised else set()
    need |= {"reversing": {"back"}, "fast": {"vmax"},
             "turning": {"wmax", "radius"}}.get(kind, set())
    assert need <= active


def test_fd_jacobian_stays_selectable_and_agrees():
    teb_fd, teb_an = Teb(TebConfig(jacobian="fd")), Teb(TebConfig())
    start, goal, z, path = _band(np.random.default_rng(1), "near")
    args = (10, start, goal, FIELD, path, 0.3)
    r = teb_an._residuals(z, *args)
    fd, an = teb_fd._jacobian_values(z, r, *args), teb_an._jacobian_values(z, r, *args)
    assert np.max(np.abs(fd - an)) <= 1e-3 * np.max(np.abs(an))
    assert not np.array_equal(fd, an)  # forward differences: not exact


def test_a_hinge_exactly_at_its_kink_gives_zero():
    """A straight band at exactly the top speed (0.4 m in 0.5 s = 0.8 m/s)
    with one zero-length segment: the speed limit's hinge sits at its kink on
    every segment, and on the empty segment so do the reverse hinge (v = 0)
    and the radius (|Δθ| = 0 = chord). Their rows are exactly zero, while a
    forward step does change those penalties (the kinks are real)."""
    teb = Teb(TebConfig())
    x = np.array([1.0, 1.5, 2.0, 2.0, 2.5, 3.0])
    P = np.column_stack([x, np.full(6, 3.0), np.zeros(6)])
    dts = np.full(5, 0.625)
    z = np.concatenate([P[1:-1].ravel(), dts])
    open_field = ObstacleField(np.zeros((80, 80), dtype=bool), RES_M)
    args = (6, P[0], P[-1], open_field, None, 0.8)
    vals = teb._jacobian_values(z, teb._residuals(z, *args), *args)
    rows, _c, Fw, _b = _central(teb, z, args)
    blk = _block_of(rows, 6)
    assert np.all(vals[blk == "vmax"] == 0.0)
    assert np.any(np.abs(Fw[blk == "vmax"]) > 1.0)
    empty = rows == 4 * 5 + 2  # the reverse hinge of segment 2 (m = 5 segments)
    assert np.all(vals[empty] == 0.0) and np.any(np.abs(Fw[empty]) > 1.0)
    radius2 = rows == 2 * 5 + 2  # its radius
    assert np.all(vals[radius2] == 0.0) and np.any(np.abs(Fw[radius2]) > 1.0)


def test_field_gradient_is_the_bilinear_interpolations_own():
    """distance_and_grad's value is distance()'s (map_coordinates, order 1,
    constant mode: 0 outside the samples) anywhere, its gradient the central
    difference of distance() inside a cell."""
    rng = np.random.default_rng(5)
    blocked = rng.random((30, 40)) < 0.08
    f = ObstacleField(blocked, 0.05, origin_xy=(-0.3, 0.2))
    pts = np.column_stack([rng.uniform(-0.5, 1.9, 400), rng.uniform(0.0, 1.8, 400)])
    d, g = f.distance_and_grad(pts.reshape(20, 20, 2))
    assert g.shape == (20, 20, 2)
    assert np.allclose(d.ravel(), f.distance(pts), rtol=0, atol=1e-12)
    h = 1e-7
    cx = (f.distance(pts + [h, 0]) - f.distance(pts - [h, 0])) / (2 * h)
    cy = (f.distance(pts + [0, h]) - f.distance(pts - [0, h])) / (2 * h)
    cell = (pts - f.origin) / f.res - 0.5
    frac = cell - np.floor(cell)
    away = np.all((frac > 1e-4) & (frac < 1 - 1e-4), axis=1)
    assert away.sum() > 300
    assert np.allclose(g.reshape(-1, 2)[away], np.column_stack([cx, cy])[away], atol=1e-6)
    assert np.any(np.abs(g) > 0.5)


def test_moving_obstacles_gradient_and_fields_without_one():
    """The navigator's field with people's discs folded in, and a field that
    only has distance() (its gradient then by central differences): the
    analytic Jacobian still equals the penalties' central differences."""
    discs = np.array([[6.0, 1.9, 0.25], [7.4, 1.2, 0.25]])
    crowd = _WithObstacles(FIELD, discs)

    class DistanceOnly:
        def distance(self, xy):
            return crowd.distance(xy)

    teb = Teb(TebConfig())
    start, goal, z, path = _band(np.random.default_rng(2), "near")
    for fld in (crowd, DistanceOnly()):
        args = (10, start, goal, fld, path, 0.3)
        got = teb._jacobian_values(z, teb._residuals(z, *args), *args)
        rows, C, Fw, Bw = _central(teb, z, args)
        smooth = np.abs(Fw - Bw) <= 1e-3 * (1.0 + np.abs(C))
        assert smooth.mean() > 0.97
        assert np.allclose(got[smooth], C[smooth], rtol=1e-5, atol=1e-4)
    p = np.array([[6.0, 2.3], [7.4, 1.2], [5.0, 1.0]])
    d, g = crowd.distance_and_grad(p)
    assert np.allclose(d, crowd.distance(p))
    assert np.allclose(g[0], [0.0, 1.0])  # the disc's outward normal
    assert np.allclose(g[1], 0.0)  # at a disc's centre: inside, distance 0


def test_a_pose_on_the_path_keeps_the_paths_stiffness():
    """Poses exactly on the path (distance 0, the |·| kink of the distance):
    the path rows are the segment's normal times w_path, as the one-sided
    differences' magnitude across the path, so JᵀJ keeps w² n nᵀ (the exact
    curvature of the squared penalty) instead of losing the path's pull."""
    teb = Teb(TebConfig())
    n = 6
    P = np.column_stack([np.linspace(1.0, 3.0, n), np.full(n, 3.0), np.zeros(n)])
    z = np.concatenate([P[1:-1].ravel(), np.full(n - 1, 0.5)])
    path = np.array([[0.5, 3.0], [2.0, 3.0], [3.5, 3.0]])
    open_field = ObstacleField(np.zeros((80, 80), dtype=bool), RES_M)
    args = (n, P[0], P[-1], open_field, path, 0.0)
    vals = teb._jacobian_values(z, teb._residuals(z, *args), *args)
    rows, _c, Fw, Bw = _central(teb, z, args)
    on = _block_of(rows, n) == "path"
    w = teb.cfg.w_path
    assert np.allclose(np.abs(vals[on]).reshape(-1, 2), [0.0, w])  # ∂/∂x 0, |∂/∂y| = w
    assert np.allclose(np.abs(Fw[on]).reshape(-1, 2), [0.0, w], atol=1e-6)
    assert np.allclose(Fw[on], -Bw[on], atol=1e-6)  # a kink: the sides disagree
