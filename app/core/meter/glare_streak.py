"""A glare streak across an end mark's patch in one of two images of a dial.

The end marks' check (:func:`.register_dense.check_landmarks`) correlates the reference's
fine print about each end mark with the frame's.  Glare on the glass is light laid over
the dial, ``out = (1 - a) dial + a 255``: a streak of it washes out the print under it
(its contrast times ``1 - a``) and its sides are edges that no print has, so a patch
crossed by a streak in one of the two images correlates poorly however right the warp is.

Such a streak is light in one image that the other does not have: with both windows
blurred over ``BLUR`` px (the print's strokes, a few px wide, fade; a streak, 6-20 px
wide, stays) their difference is level but for it; it is long (a band across most of the
window) and lighter than the face of the image it lies in.  What differs between the two
images because the warp is off (a tick more or less at the scale's end, a numeral
shifted) is print: where one image lacks the other's dark print it shows only its face,
no lighter, and the difference is left in.  :func:`streak_mask` finds the pixels of such
bands, to be left out of both patches.  What is left must still pin the mark along the
scale (:func:`drop_along_arc`): a streak may cover the very tick or dot that ends the
scale, and the arc's line beside it fits however far the warp is turned about the pivot.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["drop_along_arc", "streak_mask"]

BLUR = 2.5  # px: the print's strokes fade, a streak stays
LEVEL = 25.0  # grey levels one image is lighter (or darker) than the other in a streak ...
MADS = 4.0  # ... and at least this many robust deviations of the difference
LONG = 0.6  # a streak runs across at least this share of the window
LIGHTER = 25.0  # grey levels a streak is lighter than the face of its image (the median)
MIN_AREA = 10  # px: smaller specks are noise
GROW = 5  # the streak's mask widened by this square (px): its soft sides


def streak_mask(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Where a band of light lies across the square window ``a`` and not across ``b`` (two
    grey windows of one place, the same size), or across ``b`` and not ``a``: a bool mask,
    all False when there is none."""
    sa, sb = (cv2.GaussianBlur(x.astype(np.float32), (0, 0), BLUR) for x in (a, b))
    d = sa - sb
    d -= float(np.median(d))  # the two exposures' offset
    t = max(LEVEL, MADS * 1.4826 * float(np.median(np.abs(d))))
    side = max(a.shape[:2])
    out = np.zeros(a.shape[:2], np.uint8)
    for sign, lit in ((1.0, sa), (-1.0, sb)):  # the streak in ``a``, then in ``b``
        n, lab, st, _ = cv2.connectedComponentsWithStats((sign * d > t).astype(np.uint8), 8)
        face = float(np.median(lit))
        for k in range(1, n):
            if st[k, cv2.CC_STAT_AREA] < MIN_AREA:
                continue
            band = lab == k
            ys, xs = np.nonzero(band)
            _, (w, h), _ = cv2.minAreaRect(np.stack([xs, ys], 1).astype(np.float32))
            # long, and light over the face of its own image: glare adds light, while
            # dark print the other image has and this one lacks leaves only the face
            if max(w, h) >= LONG * side and float(np.median(lit[band])) - face >= LIGHTER:
                out[band] = 1
    if not out.any():
        return out.astype(bool)
    return cv2.dilate(out, np.ones((GROW, GROW), np.uint8)) > 0


def drop_along_arc(res: np.ndarray, peak, point, pivot, step: float) -> float:
    """How far the correlation ``res`` (over shifts, its peak at ``peak`` (x, y) in its
    cells) falls ``step`` px either way along the scale's arc at ``point`` (about
    ``pivot``) from the peak: the smaller of the two falls (0 or less where the print
    left does not pin the mark along the arc)."""
    gx, gy = point[0] - pivot[0], point[1] - pivot[1]
    norm = max(math.hypot(gx, gy), 1e-9)
    tx, ty = -gy / norm, gx / norm  # along the arc
    top = float(res[int(round(peak[1])), int(round(peak[0]))])
    drop = math.inf
    for k in (-step, step):
        j = min(max(int(round(peak[0] + k * tx)), 0), res.shape[1] - 1)
        i = min(max(int(round(peak[1] + k * ty)), 0), res.shape[0] - 1)
        drop = min(drop, top - float(res[i, j]))
    return drop
