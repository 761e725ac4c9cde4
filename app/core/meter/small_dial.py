"""A dial small in its input: found by a finer search, cut out of the input and read as a crop.

The whole-frame search (:func:`.search.full_search`) looks for a rim at least 22 % of the
frame's shorter side across, on a copy reduced to 320 px: a camera aimed at the dial from
its inspection point.  A photograph taken from farther off, or a wide frame with the gauge
in a corner of it, holds the dial at a tenth of that: the search does not consider it, and
its copy would hold the dial at some 30 px anyway.  Where the reading is refused and the
search found no rim at all, the rims down to :data:`SMALL_FILL` of the shorter side are
searched on a copy of :data:`SEARCH_PX`; each (at most :data:`TRIES`, the one the camera is
aimed at first) is cut out of the full-size input with a margin and read as a crop, which
brings it to the crop's working size from the input's own pixels.  A square input is
taken for a crop, its rim searched down to half its side; there only rims from
:data:`CROP_FILLS` are tried (a smaller one would as likely be the dial's hub cap).

Where the search found a rim, a smaller one beside it is another gauge (a station's frames
hold several), and nothing more is tried: a small rim's reading of the wrong gauge would be
confidently wrong.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import cv2
import numpy as np

from .dial import DialEllipse, find_dial_candidates
from .reading import Reading

__all__ = ["SEARCH_PX", "SMALL_FILL", "TRIES", "read_small_dial", "shifted", "small_dial_crops"]

SMALL_FILL = 0.08  # a rim down to this share of the frame's shorter side across
LARGE_FILL = 0.22  # ... below the whole-frame search's own (search.full_search)
# a square input is taken for a crop, its rim searched down to half its side: a rim from
# this share up to that is a dial photographed from a little farther; a smaller one would
# as likely be the dial's own hub cap or a ring of its face
CROP_FILLS = (0.22, 0.5)
SEARCH_PX = 640.0  # the frame searched on a copy this long (the whole-frame search: 320)
TRIES = 2  # rims cut out and read, at most
MARGIN = 1.15  # the crop's side, in the rim's major axis (the crops the reader is made for)
MIN_SIDE_PX = 48  # a rim smaller than this in the input holds too few pixels to read


def small_dial_crops(image: np.ndarray, gray: np.ndarray, k: float,
                     fills: tuple[float, float] = (SMALL_FILL, LARGE_FILL)):
    """``(crop, (x0, y0))`` for each small rim worth reading: ``gray`` is the frame at its
    working size, shrunk from ``image`` by ``k`` (≤ 1).  The crop is cut from ``image`` and
    (x0, y0) is its corner in ``image``'s pixels (the crop may reach past the input's edges,
    which are repeated there).  ``fills``: the rims' least and largest share of the
    shorter side."""
    h, w = gray.shape[:2]
    cands = find_dial_candidates(gray, min_fill=fills[0], search_px=SEARCH_PX)
    out = 0
    for e in cands:
        if out >= TRIES:
            return
        minor, major = sorted((e.width, e.height))
        if minor >= fills[1] * min(h, w) or major / k < MIN_SIDE_PX:
            continue  # the whole-frame search's to judge, or too few pixels
        side = int(math.ceil(MARGIN * major / k))
        cx, cy = (e.cx + 0.5) / k - 0.5, (e.cy + 0.5) / k - 0.5
        x0, y0 = int(round(cx - side / 2.0)), int(round(cy - side / 2.0))
        out += 1
        yield _cut(image, x0, y0, side), (x0, y0)


def _cut(image: np.ndarray, x0: int, y0: int, side: int) -> np.ndarray:
    """The ``side`` × ``side`` square at (x0, y0), the input's edge pixels repeated beyond
    it."""
    h, w = image.shape[:2]
    top, left = max(0, -y0), max(0, -x0)
    bottom, right = max(0, y0 + side - h), max(0, x0 + side - w)
    inner = image[max(0, y0):min(h, y0 + side), max(0, x0):min(w, x0 + side)]
    if top or left or bottom or right:
        inner = cv2.copyMakeBorder(inner, top, bottom, left, right, cv2.BORDER_REPLICATE)
    return np.ascontiguousarray(inner)


def shifted(r: Reading, dx: float, dy: float) -> Reading:
    """The reading made on a crop whose corner lies at (dx, dy) of the input, with its
    geometry in the input's pixels."""

    def pt(p):
        return None if p is None else (float(p[0] + dx), float(p[1] + dy))

    def pair(q):
        return None if q is None else (pt(q[0]), pt(q[1]))

    ell = r.dial_ellipse
    if ell is not None:
        ell = (float(ell[0] + dx), float(ell[1] + dy), *ell[2:])
    return replace(r, dial_ellipse=ell, dial_centre_xy=pt(r.dial_centre_xy),
                   pointer_tip_xy=pt(r.pointer_tip_xy), pointer_line_xy=pair(r.pointer_line_xy),
                   scale_ends_xy=pair(r.scale_ends_xy))


def read_small_dial(image: np.ndarray, gray: np.ndarray, k: float,
                    larger: tuple[DialEllipse, ...],
                    read_crop: Callable[[np.ndarray], Reading],
                    crop_like: bool = False) -> Reading | None:
    """The first small rim's crop that ``read_crop`` reads, in the input's pixels; None
    when none is read.  ``larger``: the rims the whole-frame search found; where it found
    any, nothing is tried: a dial of the frame's size is there, and a small rim beside it
    is another gauge (a station's frames hold several), not the one described."""
    if larger:
        return None
    fills = CROP_FILLS if crop_like else (SMALL_FILL, LARGE_FILL)
    for crop, (x0, y0) in small_dial_crops(image, gray, k, fills):
        r = read_crop(crop)
        if r.value is not None:
            return shifted(r, x0, y0)
    return None
