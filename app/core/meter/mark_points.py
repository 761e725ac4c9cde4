"""The calibration's end marks placed on an image's own ticks (calibrated inspection points).

:func:`refine_points` moves the clicked end marks onto their ticks (:mod:`.clicks`), clear of
the needle, the ends matched as one print; a mark the needle's tip hides is placed on the
needle's line (:mod:`.hidden_mark`).  Without a reference frame this runs on every frame;
with one, once on the reference, and the points are carried into each frame by the
registration.  :func:`frame_marks`: where the reference could not place an end mark (the
needle lay on it, glare crossed it), each frame is asked instead, where the needle and the
light have moved.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np

from .clicks import CLICK_SIGMA_PX, Refined, matched_ends, refine_end_mark
from .hidden_mark import mark_under_needle
from .profile import Calibration

__all__ = ["WIDTH_MATCH", "frame_marks", "refine_points"]

log = logging.getLogger(__name__)

# an end mark placed on a frame is a tick at most this much wider across the arc than the
# other end's (+ 1 px): both are one print, and a view 45 deg off widens one 1.41 times
WIDTH_MATCH = 1.5


def _needle_ends(nf) -> tuple:
    """(image angle, reach, half-width) of both ends of a found needle, for :mod:`.clicks`."""
    if not nf.ok:
        return ()
    hw = 0.5 * nf.width_px
    return ((nf.angle_deg, nf.length_px, hw), ((nf.angle_deg + 180.0) % 360.0, nf.tail_px, hw))


def _under_needle(gray, pivot, click, outward: int, nf, other: Refined) -> Refined | None:
    return mark_under_needle(gray, pivot, click, outward, nf.angle_deg, nf.length_px,
                             0.5 * nf.width_px, other.contrast, other.width_px)


def refine_points(gray: np.ndarray, cal: Calibration, pivot, nf,
                  ticks: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The clicked end marks refined on ``gray`` about ``pivot`` (:mod:`.clicks`), clear of
    the needle ``nf`` (kept as clicked for a profile with a tick table, ``ticks``): points
    (pivot, min, max; 3 x 2) and their uncertainties in px (3,)."""
    lo, hi = _refine_ends(gray, cal, pivot, nf, ticks)
    return (np.array([pivot.xy, lo.xy, hi.xy], float),
            np.array([pivot.sigma_px, lo.sigma_px, hi.sigma_px], float))


def _refine_ends(gray: np.ndarray, cal: Calibration, pivot, nf,
                 ticks: bool = False) -> tuple[Refined, Refined]:
    """:func:`refine_points`' end marks (min, max) as :class:`.clicks.Refined`."""
    out_min, out_max = (-1, 1) if cal.clockwise else (1, -1)
    ends = _needle_ends(nf)
    if ticks:  # the table's angles were measured from the clicked marks: they stay
        lo, hi = (Refined(tuple(map(float, p)), False, why="a tick table's end marks stay")
                  for p in (cal.min_point, cal.max_point))
    else:
        lo = refine_end_mark(gray, pivot.xy, cal.min_point, out_min, ends)
        hi = refine_end_mark(gray, pivot.xy, cal.max_point, out_max, ends)
        # one print: a ring at one end and a tick whose inner side the needle hides at the
        # other is a ring there too
        if lo.ring_px > 0 and hi.ok and not hi.ring_px and hi.side_hidden:
            hi = refine_end_mark(gray, pivot.xy, cal.max_point, out_max, ends, lo.ring_px)
        elif hi.ring_px > 0 and lo.ok and not lo.ring_px and lo.side_hidden:
            lo = refine_end_mark(gray, pivot.xy, cal.min_point, out_min, ends, hi.ring_px)
        lo, hi = matched_ends(lo, hi, cal.min_point, cal.max_point)
        # an end mark the needle's tip hides: the needle's band bounds it better than the
        # click (both ends' marks are ticks of one print: the other end's shows how strong)
        if nf.ok and not lo.ok and hi.ok:
            lo = _under_needle(gray, pivot.xy, cal.min_point, out_min, nf, hi) or lo
        elif nf.ok and not hi.ok and lo.ok:
            hi = _under_needle(gray, pivot.xy, cal.max_point, out_max, nf, lo) or hi
    for name, r in (("pivot", pivot), ("min mark", lo), ("max mark", hi)):
        if not r.ok:
            log.debug("calibration %s kept as clicked: %s", name, r.why)
    return lo, hi


def frame_marks(gray: np.ndarray, cal: Calibration, pts: np.ndarray, sig: np.ndarray,
                 kept: np.ndarray, nf) -> None:
    """End marks the reference frame could not place on their ticks (kept as clicked
    there: the needle lay on them, a glare streak crossed them), refined on this frame
    instead, where the needle and the light have moved: about the carried pivot, from the
    carried clicks, clear of this frame's needle ``nf``, as a frame without a reference is
    (:func:`refine_points`).  ``pts`` and ``sig`` (carried; pivot, min, max) are updated
    in place where ``kept`` (the reference's) and this frame places the mark more surely
    than the carried click, with a tick like the other end's: what kept the reference's
    mark from its tick is often still beside it (the needle a few degrees off, a colour
    band's end), and a tick run together with it is wider than the other end's, which is
    the same print (``WIDTH_MATCH``, + 1 px)."""
    if not kept[1:].any():
        return
    piv = Refined((float(pts[0][0]), float(pts[0][1])), True, 0.0, float(sig[0]))
    carried = replace(cal, min_point=tuple(map(float, pts[1])),
                      max_point=tuple(map(float, pts[2])))
    ends = _refine_ends(gray, carried, piv, nf)
    for i in (1, 2):
        here, other = ends[i - 1], ends[2 - i]
        if not kept[i] or here.sigma_px >= min(sig[i], CLICK_SIGMA_PX):
            continue
        if here.width_px > WIDTH_MATCH * other.width_px + 1.0 > 1.0:
            log.debug("%s mark on this frame much wider than the other end's (%.1f, %.1f px)",
                      ("min", "max")[i - 1], here.width_px, other.width_px)
            continue
        log.debug("%s mark placed on this frame (%.1f px from the carried click)",
                  ("min", "max")[i - 1], math.hypot(here.xy[0] - pts[i][0],
                                                    here.xy[1] - pts[i][1]))
        pts[i], sig[i] = here.xy, here.sigma_px
