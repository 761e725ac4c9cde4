"""Large inputs brought down to the sizes the reader works at, and its geometry carried back.

A phone's photograph of a gauge is 3000–4000 px across, a dial in it often 1000 px or more.
Every step of the reader that samples the dial onto its own small grid (the 300 × 300
normalised crop, the 128 × 128 view of the learned keypoints, the polar unwraps) then
drops whole pixels between its samples: thin ticks and a hairline tip alias or vanish,
and the search over the whole frame costs several times more.  The input is therefore
first shrunk by area averaging, which keeps what each dropped pixel held:

- a crop (nearly square) to at most :data:`CROP_SIDE` (1.25 × the normalised 300 px, the
  largest crop read without resampling twice);
- a whole frame to at most :data:`FRAME_SIDE` on its longer side (twice the 640 px frames
  the reader's search is measured on, so that a dial filling a tenth of the frame's width
  keeps about 130 px).

The reading's points, ellipse and radius are carried back to the input's pixels.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from .dial import NORM_SIZE
from .reading import Reading

__all__ = ["CROP_SIDE", "FRAME_SIDE", "area_resize", "shrink", "to_input"]

CROP_SIDE = int(1.25 * NORM_SIZE)  # px: a crop's longer side at most
FRAME_SIDE = 1280  # px: a whole frame's longer side at most
CROP_ASPECT = 0.12  # a crop's sides differ by at most this share (as the reader's crops)


def shrink(image: np.ndarray) -> tuple[np.ndarray, float]:
    """``(image, k)``: the image shrunk by the factor ``k`` (≤ 1; 1 when it is small
    enough and returned as it is)."""
    h, w = image.shape[:2]
    side = max(h, w)
    limit = CROP_SIDE if abs(h - w) <= CROP_ASPECT * side else FRAME_SIDE
    if side <= limit:
        return image, 1.0
    k = limit / side
    size = (max(1, round(w * k)), max(1, round(h * k)))
    return area_resize(image, size), k


def area_resize(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``cv2.resize(image, size, interpolation=cv2.INTER_AREA)`` for a shrink, by way of
    OpenCV's path for a whole factor where the shrink is 2 × or more: area averaging by
    any other factor takes 4 times longer (52 ms against 13 ms for a 3600 × 3600 colour
    photograph brought to 375 px, one core).  The input is averaged over f × f blocks (f the
    whole part of the factor; its far edges replicated up to a multiple of f), then by the
    rest of the factor (under 2 ×) on that image, over the padded extent, whose share is cut
    off: each output pixel covers the input pixels it would have, within the rounding of
    the size."""
    h, w = image.shape[:2]
    sw, sh = size
    f = int(min(w / sw, h / sh))
    if f < 2:
        return cv2.resize(image, size, interpolation=cv2.INTER_AREA)
    ph, pw = -h % f, -w % f
    if ph or pw:
        image = cv2.copyMakeBorder(image, 0, ph, 0, pw, cv2.BORDER_REPLICATE)
    blocks = cv2.resize(image, ((w + pw) // f, (h + ph) // f), interpolation=cv2.INTER_AREA)
    rest = (max(sw, round((w + pw) * sw / w)), max(sh, round((h + ph) * sh / h)))
    return cv2.resize(blocks, rest, interpolation=cv2.INTER_AREA)[:sh, :sw]


def to_input(r: Reading, k: float, shape: tuple[int, int]) -> Reading:
    """The reading made on the image shrunk by ``k`` with its geometry in the pixels of the
    input (``shape``: its height and width; the shrunk size was rounded, so each axis is
    carried back by its own factor, pixel centres onto pixel centres)."""
    if k == 1.0:
        return r
    h, w = shape
    sh, sw = round(h * k), round(w * k)
    fx, fy = w / sw, h / sh

    def pt(p):
        return None if p is None else (float((p[0] + 0.5) * fx - 0.5),
                                       float((p[1] + 0.5) * fy - 0.5))

    def pair(q):
        return None if q is None else (pt(q[0]), pt(q[1]))

    ell = r.dial_ellipse
    if ell is not None:
        cx, cy = pt(ell[:2])
        ell = (cx, cy, float(ell[2] * fx), float(ell[3] * fy), float(ell[4]))
    radius = None if r.dial_radius_px is None else float(r.dial_radius_px * 0.5 * (fx + fy))
    return replace(r, dial_ellipse=ell, dial_centre_xy=pt(r.dial_centre_xy),
                   dial_radius_px=radius, pointer_tip_xy=pt(r.pointer_tip_xy),
                   pointer_line_xy=pair(r.pointer_line_xy), scale_ends_xy=pair(r.scale_ends_xy))
