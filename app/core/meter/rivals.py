"""Which of two needle-like lines about a calibrated pivot is the needle (and a set-point
pointer of a known colour erased before the needle is looked for, :func:`erase_colour`).

Real gauges carry more than one pointer about the pivot: a red set-point pointer, a drag
pointer, a flag.  :func:`app.core.meter.needle.find_needle` finds the strongest line and
refuses (its ``needle_unique`` score) when a second one is nearly as strong.  A calibrated
inspection point knows more than a single image does, and this module uses it:

1. **The candidates.**  The polar evidence of every channel (dark, light, colour, as in
   :mod:`.needle`, unmasked) gives the directions with a line over most of the radii
   between the hub and the scale (local maxima of at least ``CAND_SHARE`` of the best, more
   than ``SEPARATE_DEG`` apart, not on the lobe of a stronger one's evidence above
   ``SAME_LINE`` of it (a wide needle) and not one another's opposite end).
2. **Each candidate alone.**  The other candidates' wedges (and their tails') are painted
   over with the face around them (``cv2.inpaint``, Telea's method), but not the corridor
   of the candidate looked at, and the needle is looked for again in that image: each
   candidate gets its own fit, ends, length and width.
3. **What tells the needle.**  In order, each cue used only when it settles the choice:

   * *The profile's colour to ignore* (``ignore_colour``): a candidate mostly of that colour
     is not the needle, when another is not of it.  This cue comes first: a set-point
     pointer's line may pass nearer a pivot clicked a few pixels off than the needle's.
   * *It turns about the calibrated pivot*: its line passes through the pivot and is one
     clean straight line (``GEOMETRY``); a glare streak or a logo's edge does not.
   * *It ends at the pivot*: a line reaching ``THROUGH`` of the scale radius or more on
     both sides of the pivot runs across the dial (a glare streak on the glass); a
     needle's tail or counterweight is far shorter.
   * *It points at the scale* (or the stop pin just below it); a line pointing into the
     gap beyond the scale's ends is not the needle.  A first finding pointing there is
     looked at the same way.
   * *A pointer that did not move.*  With a reference frame, its candidates' directions are
     carried into this frame by the registration.  A set-point or drag pointer stays where
     it was when the operator calibrated; the needle moves with the process.  A candidate
     on a reference line (within ``STATIC_DEG``) is a fixed pointer when another candidate
     is on none; when every candidate is on a reference line the needle may not have
     moved, and this cue says nothing.
   * *The reference needle's colour*: with a reference frame whose needle is coloured, a
     candidate of another hue (or none: glare, print) is not the needle.
   * *A two-ended needle* (``"needle": "two-ended"``): the candidate with a counterweight
     or tail reaching beyond the hub (by at least ``TAIL_BEYOND`` of the scale radius),
     when the others reach less than ``NO_TAIL`` beyond it.  The hub's reach is that of
     the line's own evidence across it (:func:`hub_reach`): a set-point pointer's round
     disc under the hub is no tail.

   With a reference frame whose needle is one clear line, the one left is not settled
   when it is of the other brightness (a glare streak's half), nor when a candidate's fit
   of the other brightness (wherever it was found) runs by its tip, within a wedge's
   half-width (``WEDGE``): a glare streak along the needle washes out its outer part and
   pulls the edges of what is left.

   When no cue settles it, or the one line left is of the colour to ignore while a
   candidate of another colour could not be fitted (the needle's own line, lost on the
   way), the first finding (and its refusal) stands: refusing is
   better than a wrong reading.  A first finding that saw no rival but lies on none of the
   candidate lines (with a colour masked, it may have fitted a line between two pointers)
   is looked at the same way (when the profile names a colour to ignore), and refused when
   nothing settles it.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import cv2
import numpy as np

from .needle import (
    COVER_PCT,
    GAP,
    N_TH,
    R_EVID,
    NeedleFit,
    _extent,
    _ignore_mask,
    _lobe,
    _row_percentile,
    _widen,
    angle_cw,
    find_needle,
    polar_frame,
)
from .profile import COLOUR_HUES

__all__ = ["candidate_angles", "choose_needle", "erase_colour", "needle_hue", "reference_lines"]

log = logging.getLogger(__name__)

UNIQUE_OK = 0.999  # a first finding with a needle_unique score this high stands as it is
AGREE_DEG = 5.0  # ... when it lies this near one of the candidate lines
CAND_SHARE = 0.45  # a candidate line has this share of the best one's evidence
SAME_LINE = 0.8  # a peak on the lobe of a stronger one above this share is on its line
PLATEAU = 0.95  # a candidate's direction: the middle of its evidence above this share
SEPARATE_DEG = 8.0  # candidates closer than this are one line
OPPOSITE_DEG = 16.0  # ... and a line this near another's opposite is its tail
MAX_CANDIDATES = 3
STATIC_DEG = 2.5  # a candidate this near a reference line did not move
WEDGE = 0.06  # half-width of a painted-over wedge, in units of R (plus 3 px)
HUB_R = 0.1  # ... painted from this far out (units of R): just outside a hub
KEEP = 0.035  # half-width of the corridor of the line looked at, never painted (plus 2 px)
TAIL_REACH = 0.5  # a tail or counterweight is painted over out to this (units of R)
TAIL_BEYOND = 0.05  # a counterweight or tail reaches this far beyond the hub (units of R)
NO_TAIL = 0.02  # ... and a line with none, less than this (between the two: in doubt)
THROUGH = 0.75  # a line reaching this far on both sides of the pivot (units of R) crosses it
COLOUR_SHARE = 0.5  # a candidate mostly of the ignored colour
COLOUR_GAP = 0.3  # ... or this much less of it than one that is
SATURATED = 80  # HSV saturation of a coloured needle's pixels
HUE_TOL = 12.0  # a needle's hue this near the reference needle's (OpenCV's 0..180)
GEOMETRY = ("line_through_pivot", "needle_straight", "needle_solid")
_OTHER_POLARITY = {"dark": "light", "light": "dark"}
GEOMETRY_OK = 0.9  # ... a needle's scores for turning about the pivot as one straight line
_TH = np.arange(N_TH) * (2.0 * np.pi / N_TH)
_SIN = np.sin(_TH).astype(np.float32)
_COS = np.cos(_TH).astype(np.float32)


def _adiff(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def candidate_angles(image: np.ndarray, pivot, radius: float) -> list[float]:
    """Directions (image angles, clockwise from up) of the needle-like lines about
    ``pivot``, strongest first; a line's two ends are one candidate (its stronger end)."""
    R = float(radius)
    frame = polar_frame(image, pivot, R)
    if frame is None:
        return []
    _crop, resp, rs, mx, my = frame
    ev = rs <= R_EVID * R
    widen = max(1, int(round(math.degrees(6.0 / R) * N_TH / 360.0)))
    total = np.zeros(N_TH, np.float32)
    for img in resp.values():  # each channel's evidence over its own floor and peak
        pol = cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                        borderValue=0)
        s = _row_percentile(_widen(pol, widen)[:, ev], COVER_PCT)
        s = s - float(np.median(s))
        if s.max() > 4.0:
            total = np.maximum(total, s / float(s.max()) * min(1.0, float(s.max()) / 14.0))
    out: list[float] = []
    taken = np.zeros(N_TH, bool)  # the lobes of the lines found (a wide needle has one)
    order = np.argsort(-total)
    top = float(total[order[0]]) if len(order) else 0.0
    for i in order:
        v = float(total[i])
        if v < CAND_SHARE * top or len(out) >= MAX_CANDIDATES:
            break
        if taken[i] or total[(i - 1) % N_TH] > v or total[(i + 1) % N_TH] > v:
            continue  # on a line found already, or not a local maximum
        # the evidence is widened over the clicks' error: the middle of its plateau
        top_lo, top_hi = _lobe(total, int(i), PLATEAU * v)
        a = (0.5 * (top_lo + top_hi) * 360.0 / N_TH) % 360.0
        if any(_adiff(a, b) < SEPARATE_DEG or _adiff(a, b + 180.0) < OPPOSITE_DEG
               for b in out):
            continue
        lo, hi = _lobe(total, int(i), SAME_LINE * v)
        taken[np.arange(lo, hi + 1) % N_TH] = True
        out.append(a)
    return out


def _wedges(mask: np.ndarray, pivot, radius: float, angles, r0: float, hw: float,
            value: int) -> None:
    """Draw on ``mask`` the wedges along ``angles`` from ``r0`` out past the scale, and on
    the other side of the hub out to ``TAIL_REACH`` (a tail or counterweight), ``hw`` px
    either side of the line."""
    px, py = float(pivot[0]), float(pivot[1])
    for a in angles:
        for b, r1 in ((a, 1.08 * radius), (a + 180.0, TAIL_REACH * radius)):
            t = math.radians(b)
            ux, uy = math.sin(t), -math.cos(t)
            nx, ny = -uy, ux
            poly = np.array([(px + ux * r + nx * s, py + uy * r + ny * s)
                             for r, s in ((r0, -hw), (r1, -hw), (r1, hw), (r0, hw))],
                            np.float32)
            cv2.fillConvexPoly(mask, np.round(poly).astype(np.int32), value)


def _painted(image: np.ndarray, pivot, radius: float, others, keep: float) -> np.ndarray:
    """``image`` with the lines along ``others`` painted over with the face around them,
    from just outside the hub (their roots would pull the remaining line's fit), except
    along the corridor of the line ``keep``."""
    mask = np.zeros(image.shape[:2], np.uint8)
    _wedges(mask, pivot, radius, others, HUB_R * radius, WEDGE * radius + 3.0, 255)
    _wedges(mask, pivot, radius, [keep], 0.0, KEEP * radius + 2.0, 0)
    return cv2.inpaint(image, mask, 3, cv2.INPAINT_TELEA)


def _colour_share(image: np.ndarray, fit, colour: str) -> float:
    """Share of the pixels along the fit's tip end that are of ``colour`` (``fit``: a
    NeedleFit, or (pivot, angle, length) of a line)."""
    hsv = _tip_hsv(image, fit)
    if len(hsv) == 0:
        return 0.0
    hue, sat, val = hsv[:, 0], hsv[:, 1], hsv[:, 2]
    on = np.zeros(len(hue), bool)
    for lo, hi in COLOUR_HUES[colour]:
        on |= (hue >= lo) & (hue <= hi)
    on &= (sat >= 90) & (val >= 50)
    return float(on.mean())


def _tip_hsv(image: np.ndarray, fit) -> np.ndarray:
    """HSV (OpenCV's ranges) of the pixels along the fit's tip end, N x 3 (``fit``: a
    NeedleFit, or (pivot, angle, length) of a line)."""
    pivot, angle, length = ((fit.pivot_xy, fit.angle_deg, fit.length_px)
                            if isinstance(fit, NeedleFit) else fit)
    if image.ndim != 3 or pivot is None:
        return np.zeros((0, 3), np.uint8)
    t = math.radians(angle)
    rs = np.linspace(0.3, 0.85, 24) * length
    xs = np.round(pivot[0] + np.sin(t) * rs).astype(int)
    ys = np.round(pivot[1] - np.cos(t) * rs).astype(int)
    ok = (xs >= 0) & (ys >= 0) & (xs < image.shape[1]) & (ys < image.shape[0])
    if not ok.any():
        return np.zeros((0, 3), np.uint8)
    return cv2.cvtColor(image[ys[ok], xs[ok]][None, :, :], cv2.COLOR_BGR2HSV)[0]


def needle_hue(image: np.ndarray, fit: NeedleFit) -> float | None:
    """The hue of a coloured needle (most of its tip end saturated), else None."""
    hsv = _tip_hsv(image, fit)
    sat = hsv[:, 1] >= SATURATED
    if len(hsv) == 0 or sat.mean() < COLOUR_SHARE:
        return None
    ang = hsv[sat, 0].astype(float) * (2.0 * np.pi / 180.0)
    return float(np.degrees(np.arctan2(np.sin(ang).mean(), np.cos(ang).mean())) / 2.0) % 180.0


def _hue_near(image: np.ndarray, fit: NeedleFit, hue: float) -> bool:
    h = needle_hue(image, fit)
    return h is not None and abs((h - hue + 90.0) % 180.0 - 90.0) <= HUE_TOL


def hub_reach(image: np.ndarray, pivot, radius: float, fit: NeedleFit) -> float:
    """How far out (px) the fit's own evidence reaches across its line, the median over
    rays 60-120 deg either side of it: a round hub, or a set-point pointer's disc under it.
    A counterweight is a tail only where it reaches beyond that."""
    frame = polar_frame(image, pivot, radius)
    if frame is None or fit.polarity not in frame[1]:
        return 0.0
    _crop, resp, rs, mx, my = frame
    pol = cv2.remap(resp[fit.polarity], mx, my, cv2.INTER_LINEAR,
                    borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    wide = _widen(pol, max(1, int(round(math.degrees(6.0 / radius) * N_TH / 360.0))))
    s = _row_percentile(wide[:, rs <= R_EVID * radius], COVER_PCT)
    tip = int(round(fit.angle_deg * N_TH / 360.0)) % N_TH
    thr = 0.4 * float(s[tip])  # as find_needle measures the needle's ends
    rows = [int(round((fit.angle_deg + sd * d) * N_TH / 360.0)) % N_TH
            for sd in (-1, 1) for d in range(60, 121, 10)]
    return float(np.median([_extent(wide[r], rs, thr, GAP * radius) for r in rows]))


def _off_line(fit: NeedleFit, p) -> float:
    """How far (px) point ``p`` lies from the fitted line of ``fit`` (both ways)."""
    t = math.radians(fit.angle_deg)
    dx, dy = p[0] - fit.pivot_xy[0], p[1] - fit.pivot_xy[1]
    return abs(dx * math.cos(t) + dy * math.sin(t))


def _settle(fits: list[NeedleFit], keep: list[bool], why: str) -> tuple[list, str | None]:
    """The fits a cue keeps, when it keeps some but not all of them."""
    if any(keep) and not all(keep):
        return [f for f, k in zip(fits, keep, strict=True) if k], why
    return fits, None


def choose_needle(image: np.ndarray, pivot, radius: float, first: NeedleFit, *,
                  needle: str = "single", ignore_colour: str | None = None, on_scale=None,
                  static_angles=(), reference_hue: float | None = None,
                  reference_polarity: str | None = None) -> NeedleFit:
    """The needle among the candidate lines, when ``first`` (find_needle's finding) saw a
    second pointer; else ``first``.  ``static_angles``: the reference frame's candidate
    directions carried into this image (a fixed pointer lies on one of them), or a callable
    giving them (asked only when needed); ``reference_hue``: the hue (OpenCV's 0..180) of
    a coloured needle in the reference frame; ``reference_polarity``: ``"dark"`` or
    ``"light"`` when the reference frame's needle is one clear line darker or lighter than
    the face (a line left of the other brightness is not settled, nor one with a line of the
    other brightness by its tip)."""
    unique = first.scores.get("needle_unique", 1.0) >= UNIQUE_OK
    off_scale = first.ok and on_scale is not None and not on_scale(first.angle_deg)
    if unique and not ignore_colour and not off_scale:
        return first
    cands = candidate_angles(image, pivot, radius)
    # a first finding that saw no rival stands when it is one of the lines seen here
    # (with a colour masked it may have fitted a line between two pointers)
    # (not a line of the colour to ignore: a first finding along it is that pointer's fringe,
    # its edge blurred below the colour's saturation, left beside the masked pointer)
    lines = [c for c in cands if not ignore_colour
             or _colour_share(image, (pivot, c, R_EVID * radius), ignore_colour) < COLOUR_SHARE]
    agrees = first.ok and any(min(_adiff(first.angle_deg, c), _adiff(first.angle_deg + 180.0, c))
                              <= AGREE_DEG for c in lines)
    if unique and not off_scale and (len(cands) < 2 or agrees):
        return first
    if len(cands) < 2:
        return first
    if not agrees and first.ok:  # unless settled below, a refusal
        first = replace(first, scores=dict(first.scores, needle_unique=0.0))
    fits, tails = [], {}
    fitted = []  # every candidate's fit alone, wherever it was found
    for a in cands:
        alone = _painted(image, pivot, radius, [b for b in cands if b != a], a)
        f = find_needle(alone, pivot, radius, needle=needle, on_scale=on_scale,
                        weigh_ends=True)
        if f.ok:
            fitted.append(f)
        # alone, a candidate must still be found where it was
        if f.ok and min(_adiff(f.angle_deg, a), _adiff(f.angle_deg, a + 180.0)) < SEPARATE_DEG:
            fits.append(f)
            if needle == "two-ended":  # its tail, beyond its hub (or a pointer's disc)
                tails[id(f)] = f.tail_px - hub_reach(alone, pivot, radius, f)
        else:
            fits.append(None)
    lost = [a for a, f in zip(cands, fits, strict=True) if f is None]
    reasons = []
    other_seen = False  # a line not of the colour to ignore was fitted

    def ignored(f: NeedleFit) -> NeedleFit:
        # the answer is never a line of the colour the profile says to ignore when a line of
        # another colour is there (the needle's, judged no clean line): then a refusal
        if other_seen and f.ok and _colour_share(image, f, ignore_colour) >= COLOUR_SHARE:
            log.debug("the line left is %s, the colour to ignore: not settled", ignore_colour)
            return replace(f, scores=dict(f.scores, needle_unique=0.0))
        return f

    # the profile's word first: a pointer of the colour it says to ignore is not the needle
    # (its line may pass nearer a clicked pivot that is a few pixels off than the needle's)
    if ignore_colour:
        shares = [_colour_share(image, f, ignore_colour) if f is not None else 0.0
                  for f in fits]
        # (or by far less of it than another, which is mostly of it: a needle whose root
        # passes over a hub of that colour)
        most = max(shares)
        other = [f is not None and (s < COLOUR_SHARE or (most >= COLOUR_SHARE
                                                          and s <= most - COLOUR_GAP))
                 for f, s in zip(fits, shares, strict=True)]
        if any(other) and not all(o for o, f in zip(other, fits, strict=True) if f is not None):
            fits = [f if o else None for f, o in zip(fits, other, strict=True)]
            reasons.append(f"the other pointer is {ignore_colour}")
            other_seen = True
    # a line that does not turn about the pivot, or is no clean straight line, is not it
    # (a glare streak, a logo's edge)
    about = [f is not None and min(f.scores.get(k, 1.0) for k in GEOMETRY) >= GEOMETRY_OK
             for f in fits]
    if not any(about):
        return ignored(first)
    fits, why = _settle(fits, about, "the other line does not turn about the pivot")
    fits = [f for f in fits if f is not None]
    reasons.append(why)
    # a line as long on both sides of the pivot runs across the dial (glare on the glass)
    if len(fits) > 1:
        fits, why = _settle(fits, [min(f.length_px, f.tail_px) < THROUGH * radius
                                   for f in fits], "the other line runs across the dial")
        reasons.append(why)
    if on_scale is not None and len(fits) > 1:
        on = [on_scale(f.angle_deg) for f in fits]
        fits, why = _settle(fits, on, "the other line points off the scale")
        reasons.append(why)
    static = static_angles() if callable(static_angles) else static_angles
    if static:
        moved = [all(min(_adiff(f.angle_deg, s), _adiff(f.angle_deg + 180.0, s)) > STATIC_DEG
                     for s in static) for f in fits]
        fits, why = _settle(fits, moved, "the other pointer has not moved since the reference")
        reasons.append(why)
    if reference_hue is not None and len(fits) > 1:
        same = [_hue_near(image, f, reference_hue) for f in fits]
        fits, why = _settle(fits, same, "only the needle has the reference needle's colour")
        reasons.append(why)
    if needle == "two-ended" and len(fits) > 1:
        beyond = [tails[id(f)] / radius for f in fits]
        log.debug("tails beyond the hub: %s R", np.round(beyond, 3))
        if all(b >= TAIL_BEYOND or b < NO_TAIL for b in beyond):  # none in doubt
            fits, why = _settle(fits, [b >= TAIL_BEYOND for b in beyond],
                                "only the needle has a counterweight")
        reasons.append(why)
    if len(fits) != 1:
        log.debug("second pointer not settled: %d candidates left", len(fits))
        return ignored(first)
    chosen = fits[0]
    if reference_polarity and chosen.polarity == _OTHER_POLARITY.get(reference_polarity):
        # the reference's needle is one clear line, darker (or lighter) than the face: a
        # line left of the other brightness (a glare streak whose other half was taken for
        # another line) is not settled as the needle
        log.debug("the line left is %s, the reference needle %s: not settled",
                  chosen.polarity, reference_polarity)
        return ignored(first)
    if reference_polarity and any(
            f.polarity == _OTHER_POLARITY.get(reference_polarity)
            and _off_line(f, chosen.tip_xy) <= WEDGE * radius + 3.0 for f in fitted):
        # a line of the other brightness (glare) runs by the needle's tip: a streak along
        # the needle washes out its outer part and pulls the edges of what is left
        log.debug("a %s line runs by the needle's tip: not settled",
                  _OTHER_POLARITY[reference_polarity])
        return ignored(first)
    if first.ok and _adiff(chosen.angle_deg, first.angle_deg + 180.0) <= AGREE_DEG:
        # the first finding's line, its ends the other way round: the other lines painted
        # over (inpainted print beside the needle) may have cut one end short, or their
        # presence have lengthened it; which end is the tip is not settled
        log.debug("the line chosen is the first finding's, its tip at the other end")
        return replace(chosen, scores=dict(chosen.scores, needle_unique=1.0, tip_vs_tail=0.0))
    log.debug("needle chosen among %d lines: %s", len(cands), "; ".join(r for r in reasons if r))
    if ignore_colour and _colour_share(image, chosen, ignore_colour) >= COLOUR_SHARE and any(
            _colour_share(image, (pivot, a, R_EVID * radius), ignore_colour) < COLOUR_SHARE
            for a in lost):
        # the profile says this colour is not the needle's, and a line of another colour
        # was lost on the way (its fit failed, or found another line): the needle's, maybe
        log.debug("the line left is %s, the colour to ignore: not settled", ignore_colour)
        return first
    return replace(chosen, scores=dict(chosen.scores, needle_unique=1.0))


def reference_lines(ref_bgr: np.ndarray, ref_pivot, radius: float, to_frame, frame_pivot):
    """The reference frame's candidate directions carried into the frame: ``to_frame``
    maps reference points (N x 2) to frame points."""
    out = []
    for a in candidate_angles(ref_bgr, ref_pivot, radius):
        t = math.radians(a)
        p = np.array([[ref_pivot[0] + 0.7 * radius * math.sin(t),
                       ref_pivot[1] - 0.7 * radius * math.cos(t)]])
        q = to_frame(p)[0]
        out.append(angle_cw(q[0] - frame_pivot[0], q[1] - frame_pivot[1]))
    return out


def erase_colour(grey: np.ndarray, bgr: np.ndarray, colour: str) -> np.ndarray:
    """A pointer of the profile's ``ignore_colour`` (a set-point pointer) erased from the grey
    image: its pixels take the face's local brightness (a max filter, then a blur), so the
    grey pipeline cannot take it for the needle."""
    m = _ignore_mask(bgr, colour)
    if not m.any():
        return grey
    face = cv2.blur(cv2.dilate(grey, _ERASE_KERNEL), (15, 15))
    out = grey.copy()
    out[m] = face[m]
    return out


_ERASE_KERNEL = cv2.getStructuringElement(cv2.MORPH_RECT, (25, 25))
