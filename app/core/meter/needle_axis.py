"""The needle's axis to a fraction of a pixel: a line through its shaft's cross-sections.

The skeleton line of :mod:`.pointer` (eq. 19 on Zhang-Suen's one-pixel skeleton) is
quantised to whole pixels and bends where the pointer's region has grown into a numeral
or tick; a degree or more of its direction is noise.  Here the shaft itself is measured:
the pointer's region (dilated by one pixel, so both anti-aliased edges count alike) is cut
into cross-sections one pixel long across a first guess of the axis, on the tip's side
between :data:`INNER_FRAC` and :data:`OUTER_FRAC` of the needle's length.  Each section's
darkness-weighted centre lies on the shaft's centre line to a fraction of a pixel (a
shaft is symmetric about it); a section much wider than the shaft's median width has a
numeral or tick against it and is dropped, and a straight line is fitted to the centres
by least squares (eq. 19's form, in the guess's frame) with far outliers trimmed.  The
guess is then replaced by that line and the corridor narrowed to the shaft, twice.

Only the outer part of the shaft is used: it is where the needle crosses the scale, and a
lens's distortion bends the image of a long straight needle, so its direction near the
hub is not its direction at the scale.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .geometry import angle_cw_from_up
from .order_stats import median

__all__ = ["ShaftFit", "fit_shaft"]

INNER_FRAC = 0.45  # the fit starts this far out along the needle: its outer part, near the scale
OUTER_FRAC = 0.92  # ... and stops short of the tip (its point is not symmetric when blurred)
MIN_PIXELS = 25  # fewer weighted pixels than this: no fit
MIN_SECTIONS = 12  # fewer cross-sections than this: no fit
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
              half_width_px: float = 6.0, through: bool = False) -> ShaftFit | None:
    """Fit the shaft's axis near the line from ``pivot`` at ``angle_deg`` (clockwise from
    up), ``length_px`` long.  ``mask`` is the pointer's region (0/1), ``weight`` a darkness
    image of the same shape (the needle bright).  Returns None when too few pixels fit.
    ``through``: the axis is a line through ``pivot`` (a needle turns about its pivot), and
    only its direction is fitted."""
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
    rel = np.column_stack([xs + x0, ys + y0]).astype(float) - np.asarray(pivot, float)
    direction, offset = u, 0.0  # the axis: pivot + offset * normal + t * direction
    band = half_width_px
    fit = None
    for _ in range(3):
        nrm = np.array([-direction[1], direction[0]])
        t = rel @ direction
        s = rel @ nrm - offset
        sel = (t > INNER_FRAC * length_px) & (t < OUTER_FRAC * length_px) & (np.abs(s) < band)
        if sel.sum() < MIN_PIXELS:
            return fit
        # cross-sections one pixel long: their weighted centres and their widths
        k = np.floor(t[sel]).astype(int)
        k -= k.min()
        ww = wts[sel]
        sw = np.bincount(k, ww)
        sws = np.bincount(k, ww * s[sel])
        width = np.bincount(k).astype(float)
        ok = sw > 0
        if ok.sum() < MIN_SECTIONS:
            return fit
        med_w = float(median(width[ok]))  # (np.median's value)
        # a section much wider than the shaft has a numeral or a tick against it
        ok &= width <= 1.5 * med_w + 1.0
        tk = np.flatnonzero(ok) + float(np.floor(t[sel]).min()) + 0.5
        ck = sws[ok] / sw[ok]
        keep = np.ones(len(tk), bool)
        for _ in range(3):  # a straight line through the centres, far outliers trimmed
            if keep.sum() < MIN_SECTIONS:
                return fit
            if through:  # s = b t through the pivot: the sections' median direction
                b, a = float(median(ck[keep] / tk[keep])), 0.0
            else:
                b, a = np.polyfit(tk[keep], ck[keep], 1)
            res = ck - (a + b * tk)
            mad = float(median(np.abs(res[keep]))) + 0.05
            new = np.abs(res) < 3.0 * 1.4826 * mad + 0.25
            if (new == keep).all():
                break
            keep = new
        # the line s = a + b t in the current frame, turned into a new frame
        ang = math.atan(b)
        direction = math.cos(ang) * direction + math.sin(ang) * nrm
        offset = (offset + a) * math.cos(ang)
        rms = float(np.sqrt(np.mean(res[keep] ** 2)))
        nrm2 = np.array([-direction[1], direction[0]])
        point = np.asarray(pivot, float) + offset * nrm2 + float(np.mean(tk)) * direction
        fit = ShaftFit(angle_cw_from_up(float(direction[0]), float(direction[1])) % 360.0,
                       (float(point[0]), float(point[1])), rms, int(keep.sum()))
        band = max(2.0, 0.5 * med_w + 1.5)
    return fit
