"""The rims of manholes and nozzles in the climber's downward camera frame:
round landmarks of known radius (the wall's drawing) that fix the crawler's
position across the lanes where no vertical seam is near (the geometry of the
fix is :meth:`.wall_ekf.WallEkf.rim_seen`'s).

A rim of radius r in a frame of ``m_per_px`` metres a pixel is an arc of a
circle of r / m_per_px pixels whose centre usually lies outside the frame.
It is found by a Hough transform for circles of known radius:

1. edge pixels (Canny, as for the seams) and their grey-level gradients;
2. each edge pixel votes for the centre r along its gradient — against it
   for a rim darker inside (an opening, the gradient pointing outwards),
   along it for one lighter inside — one accumulator per radius and polarity,
   in cells of ``BIN_PX``;
3. the strongest cell, smoothed over its neighbours, is refined by least
   squares on the pixels within ``INLIER_PX`` of its circle whose gradient
   agrees with the polarity (the radius kept: it is the map's);
4. it is a rim when those pixels cover ``MIN_ARC`` of the frame's width, sit
   on the circle within ``MAX_RMS_PX`` and bow away from a straight line
   (a seam's edge, which a large circle fits over a short chord);
5. where one rim is found with both polarities (an opening, darker inside,
   ringed by a lighter neck weld whose outer edge is a wider circle), the
   darker-inside edge is the rim: the map's radius is the opening's.

What the EKF takes, for rims within ``RANGE_M``, is the offset from the image
centre to the rim's nearest point and to its centre, in the body frame
(forward, left). The nearest point alone does not tell which side of the rim
the camera is on (inside the opening or outside it: the two points a rim's
width apart see it at the same offset, mirrored), nor, on a short arc, which
way round the rim; the centre's offset does (:meth:`.wall_ekf.WallEkf.rim_seen`).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .seam_camera import edge_map, grey

BIN_PX = 2.0
INLIER_PX = 2.5
MIN_ARC = 0.5  # inlier pixels, as a share of the frame's width
MAX_RMS_PX = 1.2
RANGE_M = 0.08
ALIGN = 0.8  # cos of the largest angle between a pixel's gradient and the radius
MIN_BOW_PX = 1.5  # an arc's pixels lie at least this far (rms) from a straight line,
BOW_RATIO = 3.0  # and this many times further than from their circle
SAME_RIM_M = 0.02  # nearest points closer than this are one rim


def _gradients(img: np.ndarray):
    """The edge pixels (:func:`.seam_camera.edge_map`) and their unit gradients."""
    edges, gx, gy = edge_map(img)
    mag = cv2.magnitude(gx, gy)
    ys, xs = np.nonzero(edges)
    m = mag[ys, xs]
    keep = m > 1e-3
    xs, ys, m = xs[keep], ys[keep], m[keep]
    return (xs.astype(np.float64), ys.astype(np.float64),
            gx[ys, xs] / m, gy[ys, xs] / m)


def _refine(xs, ys, ux, uy, cx, cy, r, sign):
    """Least-squares centre for the circle of radius ``r`` through the pixels
    near it whose gradient points ``sign`` · outwards; (cx, cy, inliers, rms)."""
    n_in, rms = 0, math.inf
    for _ in range(6):
        dx, dy = xs - cx, ys - cy
        rho = np.hypot(dx, dy) + 1e-9
        res = rho - r
        along = sign * (ux * dx + uy * dy) / rho
        near = (np.abs(res) < INLIER_PX) & (along > ALIGN)
        n_in = int(near.sum())
        if n_in < 5:
            return cx, cy, n_in, math.inf, 0.0
        # Gauss-Newton on Σ (‖p − c‖ − r)²: ∂res/∂c = −(p − c)/‖p − c‖
        jx, jy = -dx[near] / rho[near], -dy[near] / rho[near]
        a = np.array([[jx @ jx, jx @ jy], [jx @ jy, jy @ jy]])
        b = -np.array([jx @ res[near], jy @ res[near]])
        try:
            step = np.linalg.solve(a, b)
        except np.linalg.LinAlgError:
            return cx, cy, n_in, math.inf, 0.0
        cx, cy = cx + step[0], cy + step[1]
        rms = float(np.sqrt(np.mean(res[near] ** 2)))
        if abs(step[0]) + abs(step[1]) < 0.05:
            break
    # how far the same pixels are from their best straight line (a seam's edge fits
    # a large circle over a short chord as well as a line)
    pts = np.stack([xs[near], ys[near]], axis=1)
    pts = pts - pts.mean(axis=0)
    line_rms = float(np.sqrt(np.linalg.eigvalsh(pts.T @ pts / len(pts))[0]))
    return cx, cy, n_in, rms, line_rms


def find_rims(img: np.ndarray, m_per_px: float, radii_m
              ) -> list[tuple[float, float, float, float]]:
    """Rims of the given radii in one grey frame: for each, the offsets (forward,
    left, metres) from the image centre to its nearest point and to its centre,
    ``(near_fwd, near_left, centre_fwd, centre_left)``."""
    img = grey(img)
    h, w = img.shape
    xs, ys, ux, uy = _gradients(img)
    if len(xs) < MIN_ARC * w:
        return []
    ox, oy = (w - 1) / 2, (h - 1) / 2
    found: list[tuple[float, float, float, float]] = []  # cx, cy, r (px), support
    for r_m in sorted(set(round(float(r), 4) for r in radii_m)):
        r = r_m / m_per_px
        span = r + RANGE_M / m_per_px + max(w, h) / 2
        nb = int(2 * span / BIN_PX) + 1
        for sign in (1.0, -1.0):  # darker inside (an opening), lighter inside
            cx = xs - sign * r * ux
            cy = ys - sign * r * uy
            bx = np.floor((cx - ox + span) / BIN_PX).astype(np.int64)
            by = np.floor((cy - oy + span) / BIN_PX).astype(np.int64)
            ok = (bx >= 0) & (bx < nb) & (by >= 0) & (by < nb)
            acc = np.zeros((nb, nb), np.float32)
            np.add.at(acc, (by[ok], bx[ok]), 1.0)
            acc = cv2.GaussianBlur(acc, (0, 0), 1.0)
            k = int(np.argmax(acc))
            byk, bxk = divmod(k, nb)
            c0x = (bxk + 0.5) * BIN_PX - span + ox
            c0y = (byk + 0.5) * BIN_PX - span + oy
            ccx, ccy, n_in, rms, line_rms = _refine(xs, ys, ux, uy, c0x, c0y, r, sign)
            if (n_in >= MIN_ARC * w and rms <= MAX_RMS_PX
                    and line_rms >= max(MIN_BOW_PX, BOW_RATIO * rms)):
                found.append((ccx, ccy, r, sign))
    out = []
    # an opening's own edge (darker inside) first: its neck's outer edge (lighter inside)
    # is a circle a few millimetres wider, which a fixed radius fits off centre
    for ccx, ccy, r, _ in sorted(found, key=lambda f: -f[3]):
        dx, dy = ox - ccx, oy - ccy
        rho = math.hypot(dx, dy)
        if rho < 1e-6 or abs(rho - r) * m_per_px > RANGE_M:
            continue
        qx, qy = ccx + dx * r / rho, ccy + dy * r / rho  # the rim's nearest point
        if any(math.hypot(qx - px, qy - py) < SAME_RIM_M / m_per_px for px, py, _, _ in out):
            continue  # the same rim found at another radius or polarity
        out.append((qx, qy, ccx, ccy))
    return [(-(qy - oy) * m_per_px, -(qx - ox) * m_per_px,
             -(ccy - oy) * m_per_px, -(ccx - ox) * m_per_px) for qx, qy, ccx, ccy in out]
