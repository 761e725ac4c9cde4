"""The needle's axis to a fraction of a pixel: a weighted line fit to its shaft.

The skeleton line of :mod:`.pointer` (eq. 19 on Zhang-Suen's one-pixel skeleton) is
quantised to whole pixels and bends where the pointer's region has grown into a numeral
or tick; near the hub a degree or two of its direction is noise.  Here the shaft itself
is fitted: every pixel of the pointer's region (dilated by one pixel, so both anti-aliased
edges count alike) in a corridor about a first guess of the axis, on the tip's side, away
from the hub and short of the tip, weighted by its darkness.  The weighted principal axis
(eq. 19's orthogonal least squares with weights: the direction is the eigenvector of the
weighted scatter matrix with the larger eigenvalue) is the shaft's centre line; a shaft
is symmetric about it, so its edges' grey levels pull both ways alike and the fit reaches
well below a pixel.  The corridor narrows twice about the line found, so a numeral or a
tick touching the shaft cannot tilt it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .geometry import angle_cw_from_up, principal_axis

__all__ = ["ShaftFit", "fit_shaft"]

INNER_FRAC = 0.3  # the fit starts this far out along the needle (hub and its collar excluded)
OUTER_FRAC = 0.92  # ... and stops short of the tip (its point is not symmetric when blurred)
MIN_PIXELS = 25  # fewer weighted pixels than this: no fit
_K3 = np.ones((3, 3), np.uint8)


@dataclass(frozen=True)
class ShaftFit:
    """The shaft's axis: ``angle_deg`` clockwise from up (pivot -> tip) of the line through
    ``point``; ``rms_px`` the weighted spread across it (about the shaft's half-width);
    ``n`` the pixels fitted."""

    angle_deg: float
    point: tuple[float, float]
    rms_px: float
    n: int

    def angle_at(self, centre, r: float) -> float | None:
        """Angle about ``centre`` (clockwise from up) where the axis crosses the circle of
        radius ``r`` on the tip's side; None when it misses the circle."""
        a = math.radians(self.angle_deg)
        ux, uy = math.sin(a), -math.cos(a)
        px, py = self.point[0] - centre[0], self.point[1] - centre[1]
        b = px * ux + py * uy
        disc = b * b - (px * px + py * py - r * r)
        if disc < 0:
            return None
        t = -b + math.sqrt(disc)  # the far crossing along the tip's direction
        return angle_cw_from_up(px + t * ux, py + t * uy) % 360.0


def fit_shaft(mask: np.ndarray, weight: np.ndarray, pivot, angle_deg: float, length_px: float,
              half_width_px: float = 6.0) -> ShaftFit | None:
    """Fit the shaft's axis near the line from ``pivot`` at ``angle_deg`` (clockwise from
    up), ``length_px`` long.  ``mask`` is the pointer's region (0/1), ``weight`` a darkness
    image of the same shape (the needle bright).  Returns None when too few pixels fit."""
    h, w = mask.shape
    a = math.radians(angle_deg)
    u = np.array([math.sin(a), -math.cos(a)])
    p0 = np.asarray(pivot, float) + INNER_FRAC * length_px * u
    p1 = np.asarray(pivot, float) + OUTER_FRAC * length_px * u
    pad = half_width_px + 2.0
    x0 = max(0, int(math.floor(min(p0[0], p1[0]) - pad)))
    x1 = min(w, int(math.ceil(max(p0[0], p1[0]) + pad)) + 1)
    y0 = max(0, int(math.floor(min(p0[1], p1[1]) - pad)))
    y1 = min(h, int(math.ceil(max(p0[1], p1[1]) + pad)) + 1)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    m = cv2.dilate(np.ascontiguousarray(mask[y0:y1, x0:x1]), _K3)
    ys, xs = np.nonzero(m)
    if len(xs) < MIN_PIXELS:
        return None
    wts = weight[y0:y1, x0:x1][ys, xs].astype(float)
    pts = np.column_stack([xs + x0, ys + y0]).astype(float)
    centre = np.asarray(pivot, float)
    direction = u
    fit = None
    for band in (half_width_px, 0.75 * half_width_px, 0.6 * half_width_px):
        along = (pts - np.asarray(pivot, float)) @ direction  # from the pivot
        across = np.abs((pts - centre) @ np.array([-direction[1], direction[0]]))
        sel = ((along > INNER_FRAC * length_px) & (along < OUTER_FRAC * length_px)
               & (across < max(band, 2.0)))
        ww = wts[sel]
        if sel.sum() < MIN_PIXELS or ww.sum() <= 0:
            return fit
        q = pts[sel]
        mean = (q * ww[:, None]).sum(axis=0) / ww.sum()
        d = q - mean
        sxx = float((ww * d[:, 0] ** 2).sum())
        sxy = float((ww * d[:, 0] * d[:, 1]).sum())
        syy = float((ww * d[:, 1] ** 2).sum())
        ux, uy, lam = principal_axis(sxx, sxy, syy)  # the larger eigenvalue's direction
        direction = np.array([ux, uy])
        if direction @ u < 0:
            direction = -direction
        centre = mean
        fit = ShaftFit(angle_cw_from_up(float(direction[0]), float(direction[1])) % 360.0,
                       (float(mean[0]), float(mean[1])),
                       float(math.sqrt(max(lam, 0.0) / ww.sum())), int(sel.sum()))
    return fit
