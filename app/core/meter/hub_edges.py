"""The pointer's hub from the face's grey edges, where the pointer's region has none.

Section 3.2 of seed 000 fits the hub's circle to the boundary of the pointer's region
(:func:`.pointer.read_normalised`).  A hub cap lighter than the threshold (a grey cap on
a white face, a light cap on a dark face's negative, a domed cap shaded across) is not in
that region: the region is the needle alone, and its thickest point near the centre is the
tapered needle's base, up to a cap's radius from the pivot along the needle.

Here the cap is looked for in the grey image itself, whatever the sign of its contrast:
a circle about a point on the needle's line (the needle turns about the pivot, so its
axis passes through it), near the line's root, whose circumference crosses an edge all
the way round, away from where the needle itself crosses it.  Each sample's evidence is
the gradient across the circle less the gradient along it, so a circle is scored by how
much it looks like the edge of a disc at that sample, not merely by edges nearby; the
sign may change round the circle (a domed cap lit from one side is lighter than the face
on one side and darker on the other).  The circle's score is a low quantile of its
samples' evidence, so an edge along part of the circle (the needle's side, a tick, a
numeral) does not make one.  The best circle is then refined by a circle fit (eq. 20) to
the strongest edge on each ray and accepted only when

* the fit is as close as the region's hub fit must be (:data:`HUB_RMS_PX`),
* edges were found on most rays (:data:`MIN_COVER`),
* its evidence stands out from the face's own gradients (:data:`MIN_CONTRAST`: the
  quantile's evidence against the median gradient of the face's centre, a ratio with no
  grey level in it), and
* the needle's line (refitted to the skeleton outside the cap) passes within
  :data:`LINE_PX` of its centre.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .geometry import Line, fit_circle, fit_line
from .order_stats import median

__all__ = ["HUB_RMS_PX", "find_hub_edges"]

HUB_RMS_PX = 1.5  # as the region's hub fit (.angles.HUB_RMS_PX)
N_RAYS = 48  # samples round each circle
R_MIN = 4.0  # the smallest cap, px in the 300 x 300 crop
QUANTILE = 0.25  # the circle's evidence: this quantile of its samples' (edge all round)
MIN_COVER = 0.7  # share of the rays off the needle on which an edge was found
MIN_CONTRAST = 2.0  # the circle's evidence against the face centre's median gradient
LINE_PX = 2.0  # the needle's line passes this close to the cap's centre
_ANG = np.linspace(0.0, 2.0 * math.pi, N_RAYS, endpoint=False)
_COS, _SIN = np.cos(_ANG), np.sin(_ANG)
N_SEARCH = 32  # samples round each circle while searching
_COS_S = np.cos(np.linspace(0.0, 2.0 * math.pi, N_SEARCH, endpoint=False)).astype(np.float32)
_SIN_S = np.sin(np.linspace(0.0, 2.0 * math.pi, N_SEARCH, endpoint=False)).astype(np.float32)


def _bilinear(img: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    h, w = img.shape
    x = np.clip(x, 0.0, w - 1.001)
    y = np.clip(y, 0.0, h - 1.001)
    x0, y0 = x.astype(np.int32), y.astype(np.int32)
    fx, fy = x - x0, y - y0
    a = img[y0, x0] * (1 - fx) + img[y0, x0 + 1] * fx
    b = img[y0 + 1, x0] * (1 - fx) + img[y0 + 1, x0 + 1] * fx
    return a * (1 - fy) + b * fy


def find_hub_edges(gray: np.ndarray, line: Line, root, half_w: float, r_max: float,
                   centre_zone: tuple[float, float, float],
                   skel: np.ndarray | None = None) -> dict | None:
    """The hub's circle from the grey image's edges (module docstring), or None.

    ``line`` is the needle's axis, ``root`` the pointer region's thickest point near the
    centre (the needle's base where the cap is not in the region), ``half_w`` the needle's
    half width, ``r_max`` the largest cap radius looked for, ``centre_zone`` (x, y, radius)
    where the pivot may be, ``skel`` the needle's skeleton points (x, y): the line is refitted
    to those outside the cap before it is tested against the cap's centre (the line's first
    fit may have been pulled by the cap's own pixels in the region).
    Returns ``{"centre", "r", "rms", "contrast", "cover"}``."""
    zx, zy, zr = centre_zone
    # the gradients in a window about the centre zone (every circle looked at lies in it),
    # in window coordinates: the zone's centre, the line and the root are shifted alike
    h, w = gray.shape
    x0, x1 = max(int(zx - zr - r_max) - 6, 0), min(int(zx + zr + r_max) + 7, w)
    y0, y1 = max(int(zy - zr - r_max) - 6, 0), min(int(zy + zr + r_max) + 7, h)
    g = cv2.GaussianBlur(gray[y0:y1, x0:x1], (0, 0), 1.0).astype(np.float32)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=0.125)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)
    # the face's own gradients about the centre: the yardstick of the cap's evidence
    noise = float(median(cv2.magnitude(gx, gy))) + 0.5  # (np.median's value)
    zx, zy = zx - x0, zy - y0
    line = Line((line.point[0] - x0, line.point[1] - y0), line.direction)
    root = (root[0] - x0, root[1] - y0)
    ux, uy = line.direction
    nx, ny = -uy, ux
    # candidate centres: on the needle's line (the refinement finds a centre beside it),
    # either way from its root, within the centre zone
    rx, ry = float(root[0]), float(root[1])
    t0 = (rx - line.point[0]) * ux + (ry - line.point[1]) * uy
    fx, fy = line.point[0] + t0 * ux, line.point[1] + t0 * uy  # the root's foot on the line
    ts = np.arange(-r_max, r_max + 0.5, 1.0)
    ss = np.array([0.0])
    cx = (fx + ts[:, None] * ux + ss[None, :] * nx).ravel()
    cy = (fy + ts[:, None] * uy + ss[None, :] * ny).ravel()
    inz = np.hypot(cx - zx, cy - zy) < zr
    cx, cy = cx[inz], cy[inz]
    if len(cx) == 0:
        return None
    # every (centre, radius) pair at once: circles near the root (the needle's base lies
    # under the cap or leaves it at its edge, and its thickest point may lie a little
    # further out along the needle)
    radii = np.arange(R_MIN, r_max + 0.5, 1.0, dtype=np.float32)
    dc = np.hypot(cx - rx, cy - ry)
    ci, ri = np.nonzero(dc[:, None] <= 1.5 * radii[None, :] + half_w + 3.0)
    if len(ci) == 0:
        return None
    pcx, pcy, pr = cx[ci].astype(np.float32), cy[ci].astype(np.float32), radii[ri]
    px = pcx[:, None] + pr[:, None] * _COS_S[None, :]
    py = pcy[:, None] + pr[:, None] * _SIN_S[None, :]
    ex = cv2.remap(gx, px, py, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    ey = cv2.remap(gy, px, py, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    ev = np.abs(ex * _COS_S + ey * _SIN_S) - np.abs(ey * _COS_S - ex * _SIN_S)
    # samples where the needle (either end) crosses the circle carry the needle's edges
    off = np.abs((px - line.point[0]) * nx + (py - line.point[1]) * ny) > half_w + 2.5
    n_off = off.sum(axis=1)
    # the QUANTILE of each circle's samples off the needle (the needle's sort last)
    ev = np.sort(np.where(off, ev, np.inf), axis=1)
    kq = np.floor(QUANTILE * (np.maximum(n_off, 1) - 1)).astype(np.intp)
    score = np.where(n_off >= 0.6 * N_SEARCH, ev[np.arange(len(ev)), kq], -np.inf)
    k = int(np.argmax(score))
    best = None if not np.isfinite(score[k]) else \
        (float(score[k]), float(pcx[k]), float(pcy[k]), float(pr[k]))
    if best is None or best[0] < MIN_CONTRAST * noise:
        return None
    fit = _refine(gx, gy, best[1], best[2], best[3], line, half_w)
    if fit is None:
        return None
    m, n, r, rms, cover = fit
    m, n = m + x0, n + y0
    zx, zy = zx + x0, zy + y0
    line = Line((line.point[0] + x0, line.point[1] + y0), line.direction)
    if rms >= HUB_RMS_PX or cover < MIN_COVER:
        return None
    if skel is not None:
        out = skel[(np.hypot(skel[:, 0] - m, skel[:, 1] - n) > r + 2.0)
                   & (line.distance(skel) < 3.0)]
        if len(out) >= 8:
            line = fit_line(out)
    if float(line.distance((m, n))[0]) > LINE_PX or math.hypot(m - zx, n - zy) >= zr:
        return None
    if not R_MIN - 1.0 <= r <= r_max + 1.0:
        return None
    return {"centre": (m, n), "r": r, "rms": rms, "contrast": best[0] / noise, "cover": cover}


def _refine(gx, gy, cx, cy, r, line: Line, half_w: float):
    """Circle fit (eq. 20) to the strongest radial edge on each ray within 3 px of the
    circle found, off the needle, trimmed twice; (m, n, r, rms, cover) or None."""
    ux, uy = line.direction
    nx, ny = -uy, ux
    dr = np.arange(-3.0, 3.01, 0.5)
    rr = r + dr[None, :]
    px = cx + rr * _COS[:, None]
    py = cy + rr * _SIN[:, None]
    ex, ey = _bilinear(gx, px, py), _bilinear(gy, px, py)
    g_r = np.abs(ex * _COS[:, None] + ey * _SIN[:, None])
    off = np.abs((cx + r * _COS - line.point[0]) * nx + (cy + r * _SIN - line.point[1]) * ny) \
        > half_w + 2.5
    j = np.argmax(g_r, axis=1)
    peak = g_r[np.arange(N_RAYS), j]
    # an edge on the ray: its peak is inside the window (not at its ends) and is a real one
    ok = off & (j > 0) & (j < len(dr) - 1) & (peak > 0.5 * np.median(peak[off]))
    if ok.sum() < 12:
        return None
    # sub-sample peak (parabola through the three samples about it)
    jj = np.clip(j, 1, len(dr) - 2)
    a, b, c = (g_r[np.arange(N_RAYS), jj - 1], g_r[np.arange(N_RAYS), jj],
               g_r[np.arange(N_RAYS), jj + 1])
    den = a - 2 * b + c
    sub = np.where(np.abs(den) > 1e-6, 0.5 * (a - c) / np.where(den == 0, 1, den), 0.0)
    rad = r + dr[jj] + 0.5 * np.clip(sub, -1.0, 1.0)
    pts = np.column_stack([cx + rad * _COS, cy + rad * _SIN])[ok]
    m, n, rf, rms = fit_circle(pts)
    for _ in range(2):
        keep = np.abs(np.hypot(pts[:, 0] - m, pts[:, 1] - n) - rf) < max(1.0, 2.0 * rms)
        if keep.sum() < 12 or keep.all():
            break
        pts = pts[keep]
        m, n, rf, rms = fit_circle(pts)
    cover = len(pts) / max(int(off.sum()), 1)
    return m, n, rf, rms, cover
