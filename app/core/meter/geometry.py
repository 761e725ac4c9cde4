"""Line fit (eq. 19), circle fit (eq. 20), line-circle intersection and its choice."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Line",
    "angle_cw_from_up",
    "choose_intersection",
    "fit_circle",
    "fit_line",
    "line_circle_intersections",
    "principal_axis",
]


@dataclass(frozen=True)
class Line:
    """A line through ``point`` along the unit vector ``direction`` (image x right, y down)."""

    point: tuple[float, float]
    direction: tuple[float, float]
    rms: float = 0.0

    @property
    def slope_intercept(self) -> tuple[float, float] | None:
        """(k, c) of eq. 19, y = kx + c; ``None`` for a vertical line."""
        dx, dy = self.direction
        if abs(dx) < 1e-9:
            return None
        k = dy / dx
        return k, self.point[1] - k * self.point[0]

    def distance(self, xy) -> np.ndarray:
        p = np.atleast_2d(np.asarray(xy, float))
        nx, ny = -self.direction[1], self.direction[0]
        return np.abs((p[:, 0] - self.point[0]) * nx + (p[:, 1] - self.point[1]) * ny)


def principal_axis(sxx: float, sxy: float, syy: float) -> tuple[float, float, float]:
    """Eigen-decomposition of the symmetric 2 x 2 scatter [[sxx, sxy], [sxy, syy]] in closed
    form: (ux, uy, lam_min), the unit direction of the larger eigenvalue and the smaller
    eigenvalue (clipped at 0).  The same as ``np.linalg.eigh`` (up to the sign of the
    direction) without its per-call overhead."""
    h = 0.5 * (sxx - syy)
    r = math.hypot(h, sxy)
    lam_max = 0.5 * (sxx + syy) + r
    lam_min = max(0.5 * (sxx + syy) - r, 0.0)
    if r == 0.0:
        return 1.0, 0.0, lam_min
    if h >= 0:  # the better-conditioned of the two forms of the eigenvector
        ux, uy = lam_max - syy, sxy
    else:
        ux, uy = sxy, lam_max - sxx
    n = math.hypot(ux, uy)
    return ux / n, uy / n, lam_min


def fit_line(points) -> Line:
    """Least-squares line of the pointer skeleton (eq. 19, y = kx + c).

    Minimises the perpendicular (orthogonal) distances rather than the vertical ones: for a
    non-vertical pointer it is the same straight line as eq. 19 up to the error model, and it
    stays well defined for a vertical pointer, where k of eq. 19 is infinite.
    """
    p = np.asarray(points, float).reshape(-1, 2)
    if len(p) < 2:
        raise ValueError("need at least two points for a line")
    c = p.mean(axis=0)
    d = p - c
    cov = d.T @ d / len(p)
    ux, uy, lam = principal_axis(float(cov[0, 0]), float(cov[0, 1]), float(cov[1, 1]))
    return Line((float(c[0]), float(c[1])), (ux, uy), float(math.sqrt(lam)))


def fit_circle(points) -> tuple[float, float, float, float]:
    """Algebraic least-squares circle (x - m)^2 + (y - n)^2 = r^2 (the form of eq. 20).

    Returns (m, n, r, rms radial residual).  Used on the boundary of the pointer's hub to get
    the dial centre (m, n) as in section 3.2.
    """
    p = np.asarray(points, float).reshape(-1, 2)
    if len(p) < 3:
        raise ValueError("need at least three points for a circle")
    # eq. 20 expanded: 2 m x + 2 n y + c = x^2 + y^2 with c = r^2 - m^2 - n^2, linear in
    # (m, n, c).  About the points' mean, sum(x) = sum(y) = 0, so the normal equations split:
    # c = mean(x^2 + y^2) and a 2 x 2 system for (m, n), solved in closed form
    # (np.add.reduce(v) / len: the same sums and the same value as v.mean(), without the
    # mean's per-call overhead; this fit runs many times per reading)
    k = len(p)
    ox, oy = float(np.add.reduce(p[:, 0])) / k, float(np.add.reduce(p[:, 1])) / k
    x, y = p[:, 0] - ox, p[:, 1] - oy
    z = x * x + y * y
    sxx, sxy, syy = float(x @ x), float(x @ y), float(y @ y)
    sxz, syz = 0.5 * float(x @ z), 0.5 * float(y @ z)
    det = sxx * syy - sxy * sxy
    if det <= 1e-12 * max(sxx * syy, 1e-300):  # collinear points: the least-squares answer
        a = np.column_stack([2 * x, 2 * y, np.ones(len(p))])
        (m0, n0, _), *_ = np.linalg.lstsq(a, z, rcond=None)
    else:
        m0 = (sxz * syy - syz * sxy) / det
        n0 = (syz * sxx - sxz * sxy) / det
    c = float(np.add.reduce(z)) / k
    m, n = m0 + ox, n0 + oy
    r = math.sqrt(max(c + m0 * m0 + n0 * n0, 0.0))
    res = np.hypot(p[:, 0] - m, p[:, 1] - n) - r
    return float(m), float(n), float(r), math.sqrt(float(np.add.reduce(res * res)) / k)


def line_circle_intersections(line: Line, centre, r: float) -> list[tuple[float, float]]:
    """Solve eq. 19 together with eq. 20: zero, one or two points."""
    px, py = line.point
    dx, dy = line.direction
    fx, fy = px - centre[0], py - centre[1]
    b = fx * dx + fy * dy
    c = fx * fx + fy * fy - r * r
    disc = b * b - c
    if disc < 0:
        return []
    s = math.sqrt(disc)
    ts = (-b - s, -b + s) if s > 0 else (-b,)
    return [(px + t * dx, py + t * dy) for t in ts]


def choose_intersection(points, centre, mass_xy) -> tuple[float, float] | None:
    """The true intersection: the one on the side of the centre where the pointer mass lies.

    The paper (section 3.2) compares the vertical projections of the pointer's centre and the
    dial centre, i.e. left/right only; this generalises it to a dot product with the vector
    from the centre to the pointer's centroid, so it also holds for a vertical pointer.
    """
    if not points:
        return None
    vx, vy = mass_xy[0] - centre[0], mass_xy[1] - centre[1]
    return max(points, key=lambda p: (p[0] - centre[0]) * vx + (p[1] - centre[1]) * vy)


def angle_cw_from_up(dx: float, dy: float) -> float:
    """Angle in degrees, clockwise from 12 o'clock, of an image vector (y down), (-180, 180]."""
    return math.degrees(math.atan2(dx, -dy))
