"""A circle fitted to the points that lie on it, trimming the others (compiled).

The scale ring's centre (:func:`.angles.ring_centre`) fits a circle to the outer or inner
ends of the scale's marks, several times per reading: ring candidates x two ends x two
starts x two refits, each fit trimmed up to four times.  On a few hundred points each, the
work is small and numpy's per-call overhead was most of it; this is the same fit as a
compiled loop.

The fit is the algebraic least-squares circle of :func:`.geometry.fit_circle` (eq. 20's
form, solved in closed form about the points' mean), then the points further than
max(1 px, 2 rms) from it are dropped and the circle refitted, until the kept set stops
changing (at most four fits).  Sums are taken in order here, not pairwise as numpy takes
them, so its fits may differ from :func:`.geometry.fit_circle`'s in the last bits: the
loop only decides which points are kept, and the circle returned is fitted to them by
:func:`.geometry.fit_circle` itself.  The result is the same as fitting with numpy
throughout (a ring whose points lie exactly on a circle about the start has an rms of
rounding error only, and two such fits are compared by it).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .geometry import fit_circle

__all__ = ["trimmed_circle"]

MAX_FITS = 4
MIN_POINTS = 20
KEEP_SHARE = 0.4  # the circle must keep this share of the points


# explicit signatures: compiled (or loaded from numba's cache) when the module is imported,
# not on the first reading
@njit("Tuple((boolean, float64, float64, float64, float64))(float64[::1], float64[::1], "
      "boolean[::1])", cache=True)
def _fit_kept(x: np.ndarray, y: np.ndarray, keep: np.ndarray):
    """(ok, m, n, r, rms) of the least-squares circle through the kept points; ok is False
    when they are (nearly) collinear (the caller then fits them with numpy's lstsq)."""
    cnt = 0
    ox = 0.0
    oy = 0.0
    for i in range(len(x)):
        if keep[i]:
            ox += x[i]
            oy += y[i]
            cnt += 1
    ox /= cnt
    oy /= cnt
    sxx = sxy = syy = sxz = syz = sz = 0.0
    for i in range(len(x)):
        if keep[i]:
            u = x[i] - ox
            v = y[i] - oy
            z = u * u + v * v
            sxx += u * u
            sxy += u * v
            syy += v * v
            sxz += u * z
            syz += v * z
            sz += z
    sxz *= 0.5
    syz *= 0.5
    det = sxx * syy - sxy * sxy
    if det <= 1e-12 * max(sxx * syy, 1e-300):
        return False, 0.0, 0.0, 0.0, 0.0
    m0 = (sxz * syy - syz * sxy) / det
    n0 = (syz * sxx - sxz * sxy) / det
    c = sz / cnt
    m = m0 + ox
    n = n0 + oy
    r = math.sqrt(max(c + m0 * m0 + n0 * n0, 0.0))
    ss = 0.0
    for i in range(len(x)):
        if keep[i]:
            d = math.hypot(x[i] - m, y[i] - n) - r
            ss += d * d
    return True, m, n, r, math.sqrt(ss / cnt)


@njit("int64(float64[::1], float64[::1], boolean[::1])", cache=True)
def _trim(x: np.ndarray, y: np.ndarray, fitted: np.ndarray) -> int:
    """The trimming loop: 1 when a circle is found (``fitted``: the points of its last
    fit), 0 when too few points are kept, -1 when collinear points were met (the caller
    then redoes it all with numpy)."""
    npts = len(x)
    keep = np.ones(npts, np.bool_)
    new = np.empty(npts, np.bool_)
    for _ in range(MAX_FITS):
        if keep.sum() < MIN_POINTS:
            return 0
        ok, m, n, r, rms = _fit_kept(x, y, keep)
        if not ok:
            return -1
        fitted[:] = keep
        thr = max(1.0, 2.0 * rms)
        same = True
        for i in range(npts):
            new[i] = abs(math.hypot(x[i] - m, y[i] - n) - r) < thr
            if new[i] != keep[i]:
                same = False
        if same:
            break
        keep[:] = new
    if keep.sum() < max(MIN_POINTS, KEEP_SHARE * npts):
        return 0
    return 1


def trimmed_circle(pts: np.ndarray):
    """((x, y), rms, radius) of a circle fitted to the points (N x 2) that lie on it, or
    None when fewer than 20 points, or under 40 % of them, lie on one."""
    p = np.asarray(pts, np.float64)
    x = np.ascontiguousarray(p[:, 0])
    y = np.ascontiguousarray(p[:, 1])
    fitted = np.zeros(len(p), np.bool_)
    status = _trim(x, y, fitted)
    if status == -1:  # a degenerate set on the way: the numpy path handles it
        return _trimmed_circle_numpy(p)
    if status == 0:
        return None
    m, n, r, rms = fit_circle(p[fitted])
    return (m, n), rms, r


def _trimmed_circle_numpy(pts: np.ndarray):
    """The same trimmed fit with :func:`.geometry.fit_circle` (numpy; handles collinear
    points by least squares)."""
    keep = np.ones(len(pts), bool)
    for _ in range(MAX_FITS):
        if keep.sum() < MIN_POINTS:
            return None
        m, n, r, rms = fit_circle(pts[keep])
        res = np.abs(np.hypot(pts[:, 0] - m, pts[:, 1] - n) - r)
        new = res < max(1.0, 2.0 * rms)
        if (new == keep).all():
            break
        keep = new
    if keep.sum() < max(MIN_POINTS, KEEP_SHARE * len(pts)):
        return None
    return (m, n), rms, r
