"""An end mark hidden under the needle's tip (calibrated inspection points).

A needle resting at an end of the scale (on the stop pin, or just above the minimum) lies
over that end's mark, and :func:`.clicks.refine_end_mark` cannot place the mark's tick: it
keeps the click, whose error across the arc (``CLICK_SIGMA_PX``, about +-3 px) is as large
on a small dial as the whole tolerance of a reading.  Yet the image says more than the
click.  The end mark is the outermost tick of the scale; none as strong lies beyond it.
Where no tick like the other end's shows outward of the needle's tip (off the scale) out to
the whole window around the click, the mark is either

* under the needle: its tick lies inside the needle's dark band at the mark's radius, so
  its angle is the needle's to within the half-width of that band as seen in the image
  (measured there, not the needle's mean width: a tapered tip is narrower, a lance's head
  wider), or
* a visible tick inward of the needle (on the scale's side): then the needle lies off the
  scale beyond its end, and the reading is that end's value whichever tick it is.

In both cases a mark placed on the needle's line gives the right reading to within the
band's half-width ``h``: the mark is known to a uniform +-h about the needle, 1 sigma
``h / sqrt(3)``, in place of the click's.  Where a tick like the other end's shows beyond
the needle, or the needle does not reach across the tick ring, or the band is not a
needle's (wider than ``BAND_MAX`` of the needle's own width, a tick touching it), nothing is
claimed and the click is kept; so too where the band is so wide that it says less than the
click does.  A tick beyond is looked for in the top-hat and against the face itself: print
beside the needle's tip (a numeral, the dots between diamond marks) merges with a mark
beyond it into one patch wider than the top-hat's closing, which then shows no tick there.
"""

from __future__ import annotations

import logging
import math

import cv2
import numpy as np

from .clicks import (
    CLICK_SIGMA_PX,
    END_MATCH,
    MARK_BAND,
    MAX_SHIFT_PX,
    MIN_TICK_CONTRAST,
    TICK_MAX_PX,
    Refined,
)

__all__ = ["mark_under_needle"]

log = logging.getLogger(__name__)

STEP_PX = 0.25  # samples along the arc
BLUR_PX = 1.5  # the band's edge is blurred this far: a tick this near it may hide in it
BAND_MAX = 1.6  # the band at the mark is at most this much wider than the needle's width
BAND_MIN_PX = 1.0  # the smallest band half-width claimed (the edges' own placing)


def _no(why: str) -> None:
    log.debug("end mark not placed under the needle: %s", why)


def mark_under_needle(gray: np.ndarray, pivot, mark, outward: int, needle_deg: float,
                      reach_px: float, half_width_px: float, other_contrast: float,
                      other_width_px: float = 0.0) -> Refined | None:
    """The end mark near the clicked ``mark`` placed on the needle's tip line, when the
    needle hides it (see the module's text), or None.  ``outward``: +1 when the side off the
    scale at this mark is clockwise, -1 otherwise; ``needle_deg``, ``reach_px`` and
    ``half_width_px``: the needle's tip direction (image angle, degrees clockwise from up),
    reach from ``pivot`` and mean half-width; ``other_contrast``: the other end mark's tick
    height (``Refined.contrast``; a tick like it would show) and width across the arc at
    half height (``Refined.width_px``; 0 when unknown): a tick that wide hidden in the band
    has its middle at least half its width inside the band's edges."""
    if other_contrast < MIN_TICK_CONTRAST:
        return _no("the other end's tick is faint")
    px, py = float(pivot[0]), float(pivot[1])
    mx0, my0 = float(mark[0]), float(mark[1])
    rm = math.hypot(mx0 - px, my0 - py)
    band = max(2.0, MARK_BAND * rm)
    if rm < 12.0 or reach_px < rm + 0.5 * band:
        return _no("the tip is short of the tick ring")  # it cannot hide a tick there
    a0 = math.atan2(mx0 - px, -(my0 - py))
    an = math.radians(needle_deg)
    d_n = ((an - a0 + math.pi) % (2 * math.pi) - math.pi) * rm  # needle off the click, px
    near = MAX_SHIFT_PX + 2.0
    if abs(d_n) > near:
        return _no(f"the needle is {d_n:.1f} px from the click")
    half = int(math.ceil((near + TICK_MAX_PX + 2.0) / STEP_PX))
    step = STEP_PX / rm
    ang = a0 + step * np.arange(-half, half + 1, dtype=np.float64)
    # the tick ring's radii that the needle crosses
    rs = np.linspace(rm - band, min(rm + band, reach_px - 1.0), max(5, int(2 * band)))
    mx = (px + np.sin(ang)[None, :] * rs[:, None]).astype(np.float32)
    my = (py - np.cos(ang)[None, :] * rs[:, None]).astype(np.float32)
    hgt, wid = gray.shape[:2]
    if mx.min() < 0 or my.min() < 0 or mx.max() > wid - 1 or my.max() > hgt - 1:
        return _no("near the image's edge")
    v = cv2.remap(gray, mx, my, cv2.INTER_LINEAR).astype(np.float32)
    ker = np.ones((1, int(round(TICK_MAX_PX / STEP_PX)) | 1), np.uint8)
    i_n = half + int(round(d_n / STEP_PX))
    hats = [cv2.morphologyEx(v, cv2.MORPH_CLOSE, ker) - v,
            v - cv2.morphologyEx(v, cv2.MORPH_OPEN, ker)]
    # the needle's polarity: whichever shows it at its own line
    dark = max((0, 1), key=lambda q: float(hats[q].mean(axis=0)[max(i_n - 4, 0):i_n + 5].max()))
    hat = hats[dark]
    prof = cv2.GaussianBlur(hat.mean(axis=0)[None, :].astype(np.float32), (5, 1), 0)[0]
    # the needle's band: the run above half its height around its line
    w = max(2, int(round(half_width_px / STEP_PX)))
    lo_s, hi_s = max(i_n - w, 1), min(i_n + w, len(prof) - 2)
    k = lo_s + int(np.argmax(prof[lo_s:hi_s + 1]))
    top = float(prof[k])
    if top < MIN_TICK_CONTRAST:
        return _no("the needle does not show at the mark")
    lo = hi = k
    while lo > 0 and prof[lo - 1] >= 0.5 * top:
        lo -= 1
    while hi < len(prof) - 1 and prof[hi + 1] >= 0.5 * top:
        hi += 1
    if lo == 0 or hi == len(prof) - 1:
        return _no("the needle's band runs out of the window")
    log.debug("needle's line at %.1f px, band %.1f to %.1f px from the click", d_n,
              (lo - half) * STEP_PX, (hi - half) * STEP_PX)
    if not lo <= i_n <= hi:
        return _no("the band found is beside the needle's line, not on it")
    width_px = (hi - lo) * STEP_PX
    if width_px > BAND_MAX * 2.0 * half_width_px + 2.0 * BLUR_PX:
        return _no(f"band {width_px:.1f} px: not the needle alone")  # a tick beside it
    # nothing like the other end's tick off the scale beyond the band, out to the window
    m = int(round(BLUR_PX / STEP_PX))
    # (also against the face itself: print beside the needle's tip, a numeral, merges with
    # a mark beyond it under the top-hat's closing, as one wide dark patch)
    col = v.mean(axis=0)
    raw = np.percentile(col, 90) - col if dark == 0 else col - np.percentile(col, 10)
    for p in (prof, raw):
        beyond = p[hi + m:] if outward > 0 else p[:max(lo - m, 0)]
        if len(beyond) and float(beyond.max()) >= END_MATCH * other_contrast:
            return _no(f"a tick beyond the needle ({float(beyond.max()):.0f} of "
                       f"{other_contrast:.0f})")
    centre = 0.5 * (lo + hi)
    a = a0 + step * (centre - half)
    h = max(0.5 * (width_px - other_width_px), BAND_MIN_PX)
    if h / math.sqrt(3.0) >= CLICK_SIGMA_PX:
        return _no(f"band {width_px:.1f} px: it says less than the click")
    log.debug("end mark under the needle: band %.1f px, tick %.1f px, +-%.1f px", width_px,
              other_width_px, h)
    shift = rm * abs(a - a0)
    return Refined((px + rm * math.sin(a), py - rm * math.cos(a)), True, shift,
                   h / math.sqrt(3.0), why="under the needle", under_needle=True)
