"""The needle around a known pivot (calibrated inspection points).

With the pivot and the scale ring's radius R known from the calibration, the needle is the
one thin line that runs radially from the hub out towards the scale.  The method:

1. **Contrast against the local face**, in a crop of about 2.3 R around the pivot: a dark
   needle on a light face by a closing minus the grey (a black top-hat) with the veiling-
   glare gain of :func:`app.core.meter.reader.dark_features`; a light needle on a dark face
   by a white top-hat; a coloured needle by a top-hat of the chroma (max - min of B, G,
   R).  A pointer of the
   profile's ``ignore_colour`` (a set-point pointer) is masked out of all three.  A dark
   face has no dark-needle channel and a light face no light-needle one (there they only
   ring the print and the glare).  The channel that sets its best line apart from the
   second-best direction most clearly is the needle's; a second pointer is looked for in
   the others too (a red set-point pointer is alone in the colour channel but beside the
   black needle in the dark one).
2. **Polar unwrap** about the pivot (0.5 deg columns, radii 0.2 R .. 1.05 R, the hub
   skipped).  Each ray's evidence is a low percentile of the response along it between the
   hub and 0.75 R: high only when the line is covered over most of that length.  Text,
   logos and tick marks cover a short range of radii and do not win; glare that washes out
   part of the needle does not lose it.
3. **Axis, then tip**: the best ray gives the needle's axis.  Along it and along the opposite
   ray the needle's extent is measured (gaps up to 0.15 R are bridged; the opposite end also
   against its own strength at its root without gaps, since a thin tip is fainter than a
   wide tail and would fade under the tail's threshold); the tip is the long
   end, or, for two ends of similar length, the thinner one (two-ended needles, arrow tails;
   the reaches and the other end's ray: :mod:`.needle_reach`).
   The calibrated reader (``weigh_ends``) weighs ends of nearly the same reach by their width
   near the hub, the width of their outer halves (a tip tapers, a tail ends in a weight or
   feathers) and the scale's arc, and refuses when these cues disagree.  A longer end that
   is also much the wider and has gaps along it, opposite an end that runs out past its
   root, is no sure tip either (a weight with print beyond it, a thin tip that faded).
4. **Sub-degree refinement**: per radius, the response-weighted centroid across the needle
   gives a point; the line most of the points of both ends agree with (a consensus,
   :func:`_fit_needle`), refitted by weighted total least squares through them, is the
   needle's axis (a stop pin, a numeral or a set-point's hub touching the needle leaves
   the line).  It is not forced through the clicked pivot (clicks are good to a few
   pixels only): the pivot is moved onto the line, which removes the click error across the
   needle.
5. **Confidence** from the evidence: contrast, length, how much stronger the needle is than
   the second-best direction (another pointer), and how near the line passes to the pivot.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .dial import _median, median_u8
from .needle_ends import (
    BOTH_LONG,
    WEIGH_REACH,
    WIDER_TIP,
    outer_width,
    runs_on,
    side_width,
    tail_in_gap,
    weigh_end_cues,
)
from .needle_line import N_TH, R_IN, _centroids, _fit_needle, _needle_points
from .needle_reach import GAP, ROOT_R, _extent, other_end
from .profile import COLOUR_HUES
from .rival_rays import pointer_like, strongest_pointer

__all__ = ["NeedleFit", "find_needle", "angle_cw", "WEIGH_REACH"]

log = logging.getLogger(__name__)

_TH = np.arange(N_TH) * (2.0 * np.pi / N_TH)
_SIN = np.sin(_TH).astype(np.float32)
_COS = np.cos(_TH).astype(np.float32)
R_EVID = 0.75  # rays are judged between R_IN and this
R_OUT = 1.05
R_FIT = 0.85  # the needle's axis is fitted inside the tick ring
COVER_PCT = 35  # percentile of the response along a ray: covered over 65 % of its length
DARK_FACE = 90.0  # grey level of the face below which it is dark (no dark needle on it)
LIGHT_FACE = 170.0  # above which it is light (no light needle on it)
COLOUR_FACE = 110.0  # the face's median chroma (max - min of B, G, R) above which it is
# strongly coloured (no colour channel: white, cream and yellowed faces lie under 90)
# another channel checks for a second pointer where it sees the needle this well (of its
# best line), and its rival has this share of the needle's contrast in the chosen channel
RIVAL_SEEN = 0.5
MASKED_SHARE = 0.15  # a ray crossing the ignored colour over this share of its radii ...
MASKED_MARGIN_DEG = 4.0  # ... and this far either side of it is no second pointer's
HUB_PX = 0.15  # the needle's axis may start this much farther out (units of R): a wide hub
# weighing the ends, a short end this many times the long end's width near the hub is a
# counterweight (a thin tip that faded or was cut short is no wider than the long end)
COUNTERWEIGHT = WIDER_TIP


def angle_cw(dx: float, dy: float) -> float:
    """Angle in degrees clockwise from up of an image vector (y down), in [0, 360)."""
    return math.degrees(math.atan2(dx, -dy)) % 360.0


@dataclass
class NeedleFit:
    """The needle found by :func:`find_needle`, in the input image's pixel coordinates."""

    ok: bool
    error: str | None = None
    angle_deg: float | None = None  # image angle clockwise from up, pivot -> tip
    pivot_xy: tuple[float, float] | None = None  # the clicked pivot moved onto the needle
    tip_xy: tuple[float, float] | None = None
    length_px: float = 0.0
    tail_px: float = 0.0
    polarity: str = ""
    rms_px: float = 0.0  # spread of the needle's centre points about its fitted axis
    width_px: float = 0.0  # the widest of its two ends near the hub
    agree: float = 1.0  # share of the needle's centres on its fitted line
    scores: dict = field(default_factory=dict)


def _odd(v: float, lo: int, hi: int) -> int:
    k = int(round(v))
    k = min(max(k, lo), hi)
    return k if k % 2 else k + 1


def _ramp(x: float, bad: float, good: float) -> float:
    return float(min(1.0, max(0.0, (x - bad) / (good - bad))))


def _ignore_mask(bgr: np.ndarray, colour: str) -> np.ndarray:
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    m = np.zeros(h.shape, bool)
    for lo, hi in COLOUR_HUES[colour]:
        m |= (h >= lo) & (h <= hi)
    m &= (s >= 90) & (v >= 50)
    return cv2.dilate(m.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0


def _responses(crop: np.ndarray, k: int, disc: np.ndarray) -> dict[str, np.ndarray]:
    """Needle-likeness of each pixel: dark, light and (for colour) saturated thin lines."""
    gray = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY) if crop.ndim == 3 else crop
    ker = cv2.getStructuringElement(cv2.MORPH_RECT, (k, k))  # separable: fast
    # medians over the disc from histograms under it as a mask (the same values)
    disc_u8 = disc.view(np.uint8)
    face = median_u8(gray, disc_u8) if disc.any() else 128.0
    # a dark needle on a dark face, or a light one on a light face, is not a needle: there
    # the closing (opening) only rings the face's print and the glass's glare; so only the
    # channels the face allows are made
    out = {}
    if face > DARK_FACE:
        bg = cv2.morphologyEx(gray, cv2.MORPH_CLOSE, ker)
        f0 = median_u8(bg, disc_u8) if disc.any() else 200.0
        # veiling glare I = I0 (1 - a) + 255 a shrinks contrast by (1 - a): undone by the gain
        gain = np.clip((257.0 - f0) / (257.0 - np.arange(256, dtype=np.float32)), 1.0, 4.0)
        out["dark"] = cv2.subtract(bg, gray).astype(np.float32) * cv2.LUT(bg, gain)
    if face < LIGHT_FACE:
        out["light"] = cv2.subtract(gray, cv2.morphologyEx(gray, cv2.MORPH_OPEN, ker)) \
            .astype(np.float32)
    if crop.ndim == 3:
        # chroma (max - min of B, G, R), not HSV's saturation: that divides by the value and
        # makes every dark pixel of a dark face look strongly coloured
        b, g, r = cv2.split(crop)
        chroma = cv2.subtract(cv2.max(cv2.max(b, g), r), cv2.min(cv2.min(b, g), r))
        # on a strongly coloured face the chroma's top-hat rings the face's print and a
        # camera's chroma blocks (JPEG's 8 x 8 and 16 x 16 px, in columns and rows), and a
        # needle shows in the grey channels anyway: the colour channel is made only on faces
        # of little colour
        if (median_u8(chroma, disc_u8) if disc.any() else 0.0) <= COLOUR_FACE:
            out["colour"] = cv2.subtract(chroma, cv2.morphologyEx(chroma, cv2.MORPH_OPEN, ker)) \
                .astype(np.float32)
    return out


def _widen(p: np.ndarray, n: int) -> np.ndarray:
    """Max over +-n rays (circular): a needle a little off the clicked pivot still lines up."""
    padded = np.vstack([p[-n:], p, p[:n]])
    return cv2.dilate(padded, np.ones((2 * n + 1, 1), np.uint8))[n:-n]


def _row_percentile(a: np.ndarray, q: float) -> np.ndarray:
    """``np.percentile(a, q, axis=1)`` (its linear method, the same values) from the two
    ranks it interpolates between, without its general machinery.  The rows are sorted
    whole: for some 720 rows of a few dozen radii numpy's sort is several times faster
    than its partition at the two ranks, and puts the same values there."""
    n = a.shape[1]
    vi = (n - 1) * (q / 100.0)
    lo = int(math.floor(vi))
    hi = min(lo + 1, n - 1)
    p = np.sort(a, axis=1)
    x, y = p[:, lo], p[:, hi]
    t = vi - lo
    d = y - x
    # numpy's interpolation: from the nearer of the two ranks
    return y - d * (1 - t) if t >= 0.5 else x + d * t


def _lobe(s: np.ndarray, i: int, thr: float) -> tuple[int, int]:
    """The run of rays around ``i`` (circular, unwrapped indices) where ``s > thr``."""
    q = len(s) // 4
    k = np.arange(1, q + 1)
    # the rays on either side, outward from i, as far as a quarter turn: the run is as long
    # as their leading stretch above thr
    return i - _leading(s.take(i - k, mode="wrap") > thr), \
        i + _leading(s.take(i + k, mode="wrap") > thr)


def _leading(on: np.ndarray) -> int:
    """How many of the first elements of ``on`` (1-D bool) are True without a break."""
    return len(on) if on.all() else int(on.argmin())


def _masked_rays(masked: np.ndarray) -> np.ndarray:
    """Rays that cross the ignored colour over :data:`MASKED_SHARE` of their radii, and
    :data:`MASKED_MARGIN_DEG` either side of them: where a set-point pointer of that colour
    lies, with its fringe."""
    hit = masked.mean(axis=1) > MASKED_SHARE
    m = int(round(MASKED_MARGIN_DEG * N_TH / 360.0))
    if m > 0 and hit.any():
        k = np.ones(2 * m + 1)
        hit = np.convolve(np.concatenate((hit[-m:], hit, hit[:m])).astype(float), k,
                          mode="valid") > 0
    return hit


def _away(s: np.ndarray, i: int) -> np.ndarray:
    """Rays away from the needle's axis ``i`` and from its opposite (their lobes of evidence
    above half the peak, and 8 / 16 deg more), where a second pointer would show."""
    away = np.ones(N_TH, bool)
    j = (i + N_TH // 2) % N_TH
    lo_i, hi_i = _lobe(s, i, 0.5 * float(s[i]))
    lo_j, hi_j = _lobe(s, j, 0.5 * max(float(s[j]), 1e-6))
    m8, m16 = int(8 * N_TH / 360), int(16 * N_TH / 360)
    away[np.arange(lo_i - m8, hi_i + m8 + 1) % N_TH] = False
    away[np.arange(min(lo_j, j - m16), max(hi_j, j + m16) + 1) % N_TH] = False
    return away


def _line_rays(rs: np.ndarray, foot: np.ndarray, u: np.ndarray, pivot, half: int) -> np.ndarray:
    """The rays (rows of the polar unwrap about ``pivot``) that the line through ``foot``
    (the pivot's foot on it) along ``u`` crosses at the radii ``rs`` on its ``u`` side,
    each with its ``half`` neighbours either side: an array (2 half + 1) x len(rs)."""
    perp = float(np.hypot(foot[0] - pivot[0], foot[1] - pivot[1]))
    t = np.sqrt(np.maximum(rs.astype(np.float64) ** 2 - perp * perp, 0.0))
    dx = foot[0] - pivot[0] + t * u[0]
    dy = foot[1] - pivot[1] + t * u[1]
    k = np.rint(np.degrees(np.arctan2(dx, -dy)) % 360.0 * N_TH / 360.0).astype(int)
    return (k[None, :] + np.arange(-half, half + 1)[:, None]) % N_TH


def polar_frame(image: np.ndarray, pivot, radius: float):
    """The crop about ``pivot`` that holds a needle of scale radius ``radius``, its
    line responses inside the dial, and the maps that sample them along N_TH rays:
    (crop, responses, radii, map_x, map_y), or None when under 8 px of it is in the image."""
    R = float(radius)
    px, py = float(pivot[0]), float(pivot[1])
    h, w = image.shape[:2]
    half = int(math.ceil(R_OUT * R + 0.1 * R + 4))
    x0, y0 = max(0, int(px) - half), max(0, int(py) - half)
    x1, y1 = min(w, int(px) + half + 1), min(h, int(py) + half + 1)
    if x1 - x0 < 8 or y1 - y0 < 8:
        return None
    crop = image[y0:y1, x0:x1]
    cx, cy = px - x0, py - y0
    yy, xx = np.ogrid[0:y1 - y0, 0:x1 - x0]
    disc = (xx - cx) ** 2 + (yy - cy) ** 2 < (0.95 * R) ** 2
    resp = _responses(crop, _odd(0.14 * R, 5, 41), disc)
    rs, ox, oy = _ray_offsets(R)
    # (float32 throughout: the offsets are float32 products, a Python float added to them
    # stays float32, as when they were made here on every call)
    return crop, resp, rs, cx + ox, cy - oy


def _ray_offsets(R: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The radii sampled for a needle of scale radius ``R`` and every ray's offsets from
    the pivot at those radii (x right, y up; float32, read-only), made once per ``R``: the
    reader asks for the same few radii over and over."""
    got = _RAYS.get(R)
    if got is None:
        n_r = int(min(96, max(24, (R_OUT - R_IN) * R / 1.5)))
        rs = np.linspace(R_IN * R, R_OUT * R, n_r).astype(np.float32)
        got = (rs, _SIN[:, None] * rs[None, :], _COS[:, None] * rs[None, :])
        for a in got:
            a.flags.writeable = False
        if len(_RAYS) >= 64:  # radii measured on each dial: keep the table small
            _RAYS.clear()
        _RAYS[R] = got
    return got


_RAYS: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def find_needle(image: np.ndarray, pivot, radius: float, *, needle: str = "single",
                ignore_colour: str | None = None, on_scale=None,
                weigh_ends: bool = False, straight_rivals: bool = False,
                tip_deg: float | None = None, channel: str | None = None) -> NeedleFit:
    """Find the needle turning about ``pivot`` (x, y) in a BGR or grey image.

    ``radius`` is the scale ring's radius in px (pivot to the end marks).  ``on_scale``
    (optional) tells, for an image angle, whether it lies on the scale arc (with a small
    tolerance); it decides between two ends that look alike.  With ``weigh_ends`` (the
    calibrated reader) two ends of alike reach are told apart by all of their width near the
    hub, the width of their outer halves and the scale
    (:func:`.needle_ends.weigh_end_cues`), and refused when these disagree.  With
    ``straight_rivals`` a second pointer is only a straight line about the pivot
    (:mod:`.rival_rays`).  ``tip_deg`` (a tip known otherwise, :mod:`.ref_tip`): the image
    angle of the needle's tip; the end of the axis nearer it is the tip, and the widths' and
    the gaps' doubts about the two ends stand aside.  ``channel`` (one of the responses:
    ``dark``, ``light``, ``colour``): the needle is looked for in that one only (the others
    still show second pointers); None, the channel that sets a line apart best.
    """
    R = float(radius)
    px, py = float(pivot[0]), float(pivot[1])
    frame = polar_frame(image, pivot, R)
    if frame is None:
        return NeedleFit(False, "the pivot is outside the image")
    crop, resp, rs, mx, my = frame
    masked = None  # where the ignored colour lies, in the polar unwrap: neither seen nor not
    if ignore_colour and crop.ndim == 3:
        m = _ignore_mask(crop, ignore_colour)
        for v in resp.values():
            v[m] = 0.0
        masked = cv2.remap(m.astype(np.float32), mx, my, cv2.INTER_LINEAR,
                           borderMode=cv2.BORDER_CONSTANT, borderValue=0) > 0.25
    # the rays' evidence over the radii up to R_EVID (rs rises: a leading slice, no copy)
    n_ev = int(np.count_nonzero(rs <= R_EVID * R))
    widen = max(1, int(round(math.degrees(6.0 / R) * N_TH / 360.0)))  # clicks: a few px
    best = None
    seen = []  # (evidence per ray, its median) of every channel
    for name, img in resp.items():
        pol = cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                        borderValue=0)
        wide = _widen(pol, widen)
        s = _row_percentile(wide[:, :n_ev], COVER_PCT)
        i = int(s.argmax())
        med = _median(s)
        gain = float(s[i] - med)
        # the channel that sets the needle apart best wins: its contrast over the second-
        # best direction (away from the axis and its opposite), not its raw response, which
        # differs between channels (a dark face's closing rings every light print)
        away = _away(s, i)
        sep = gain / max(float(s[away].max()) - med, 0.1 * gain, 1.0) if away.any() else 3.0
        rank = (s[i] > 4.0, min(sep, 3.0), gain)
        seen.append((s, med, pol))
        if channel is not None and name != channel:
            continue
        if best is None or rank > best[0]:
            best = (rank, name, pol, wide, s, i)
    if best is None:
        return NeedleFit(False, f"no {channel} response here")
    _, polarity, pol, wide, s, i = best
    s_best = float(s[i])
    # a wide needle (a lance) makes a plateau: its middle is the axis
    lo_i, hi_i = _lobe(s, i, 0.7 * s_best)
    i = ((lo_i + hi_i) // 2) % N_TH
    scores: dict[str, float] = {"needle_contrast": _ramp(s_best, 4.0, 14.0)}
    if s_best <= 2.0:
        return NeedleFit(False, "needle not found", polarity=polarity, scores=scores)
    # axis found: measure both ends along it
    j = (i + N_TH // 2) % N_TH
    thr = 0.4 * s_best
    gap = GAP * R
    ext_a = _extent(wide[i], rs, thr, gap)
    if ext_a < 0.4 * R:  # the strongest end may start behind a wide hub (a set-point's ring)
        ext_a = _extent(wide[i], rs, thr, gap, HUB_PX * R)
    # the other end also against its own strength at its root, unbroken: a thin tapered tip
    # is fainter than a wide tail (an arrow, a spade) and fades under the tail's threshold
    # (unbroken: bridged over gaps, a faint end would run on into print and ticks)
    # (with weigh_ends, on the ray near the opposite one where it reaches farthest)
    j, ext_b, run_b, thr_b = other_end(wide, rs, R, j, (lo_i, hi_i), thr, s_best, ext_a,
                                       search=weigh_ends)
    thr_b = thr_b if run_b > ext_b else thr  # the threshold that end's reach was found with
    ext_b = max(ext_b, run_b)
    wid_a = side_width(pol, i, rs, R_IN * R, 0.5 * min(max(ext_a, ext_b), R))
    wid_b = side_width(pol, j, rs, R_IN * R, 0.5 * min(max(ext_a, ext_b), R))
    tip_i, tail_i = i, j
    alike = abs(ext_a - ext_b) < 0.1 * R
    log.debug("needle ends: reach %.2f / %.2f R, width %.1f / %.1f px", ext_a / R, ext_b / R,
              wid_a, wid_b)
    if ext_b > ext_a + 0.1 * R or (alike and wid_b < 0.8 * wid_a):
        tip_i, tail_i = j, i
    weighed = weigh_ends and on_scale is not None and abs(ext_a - ext_b) < WEIGH_REACH * R
    slack = widen * 360.0 / N_TH  # an end's ray is its lobe's middle, a few degrees off
    # the tip known (the reference frame's needle, carried over)
    known = tip_deg is not None
    if known:
        near_i = abs((i * 360.0 / N_TH - tip_deg + 180.0) % 360.0 - 180.0) < 90.0
        tip_i, tail_i = (i, j) if near_i else (j, i)
    elif weighed:
        # (a single needle's two long ends: does either run on past the scale ring?)
        both_long = needle == "single" and min(ext_a, ext_b) > BOTH_LONG * R
        centre = (float(mx[0, 0]), float(my[0, 0] + rs[0]))  # the first ray points up
        tip_i, tail_i = weigh_end_cues(
            pol, rs, R, (i, ext_a, wid_a), (j, ext_b, wid_b), on_scale, scores, slack,
            runs_on(resp[polarity], centre, R, (i, j), thr, widen) if both_long else None)
    elif alike and abs(wid_a - wid_b) <= 0.2 * max(wid_a, wid_b) and on_scale is not None:
        a_on = on_scale(i * 360.0 / N_TH)
        b_on = on_scale(j * 360.0 / N_TH)
        if a_on != b_on:
            tip_i, tail_i = (i, j) if a_on else (j, i)
        else:
            scores["tip_vs_tail"] = 0.0
    # a tip is long and thin, a tail short or wide: an end longer by far but also much wider
    # than the other (glare cutting the thin tip short beside a long spade tail) is no sure
    # tip; the scale cannot settle it either, since the cut tip may rest at an end mark.
    # (The widths are measured out to half the longer end: only a shorter end that reaches
    # that far is measured over its whole range.)
    wid_tip, wid_tail = (wid_a, wid_b) if tip_i == i else (wid_b, wid_a)
    # the end taken for the tail points clearly into the scale's gap: no tip does (or the
    # reference needle told the tip)
    settled = known or (on_scale is not None
                              and tail_in_gap(on_scale, tip_i, tail_i, slack))
    if not alike and not weighed and min(ext_a, ext_b) >= 0.5 * max(ext_a, ext_b) \
            and wid_tip > WIDER_TIP * max(wid_tail, 1e-6):
        # ... unless (weighing the ends) their outer halves tell them apart: a tip tapers to
        # its end, a tail ends in its feathers, disc or spade (near the hub a tapered tip is
        # the wider)
        out_tip = out_tail = 0.0
        if weigh_ends:
            out_tip = outer_width(pol, tip_i, rs, ext_a if tip_i == i else ext_b, R)
            out_tail = outer_width(pol, tail_i, rs, ext_b if tip_i == i else ext_a, R)
            log.debug("needle ends' outer halves: %.1f (tip) / %.1f px", out_tip, out_tail)
        if out_tail <= WIDER_TIP * max(out_tip, 1e-6) and not settled:
            scores["tip_vs_tail"] = 0.0
    ext_tail = ext_b if tip_i == i else ext_a
    ext_tip = ext_a if tip_i == i else ext_b
    if needle == "single" and alike and ext_tail > 0.6 * R:
        # a single needle has no long second end: another pointer or a line through the hub
        scores["tip_vs_tail"] = min(scores.get("tip_vs_tail", 1.0),
                                    _ramp(abs(wid_a - wid_b) / max(wid_a, wid_b, 1e-6), 0.1, 0.3))
    # the second-best direction, away from the needle's axis (and from the ignored colour's
    # pointer: its fringe, blurred below the colour's saturation, is no second pointer)
    away = _away(s, i)
    near = ~away
    if masked is not None:
        away &= ~_masked_rays(masked[:, :n_ev])
    r_ev = R_EVID * R

    def pointer(p):
        return (lambda k: pointer_like(p, k, rs, r_ev, R, (px, py))) if straight_rivals \
            else (lambda k: True)

    s2 = strongest_pointer(s, away, 0.55 * s_best, pointer(pol)) if away.any() else 0.0
    rival = s2 / s_best
    # another channel that sees this needle too may see a second pointer (a red set-point
    # pointer is alone in the colour channel, but beside the black needle in the dark one)
    for s_c, med_c, pol_c in seen if away.any() and near.any() else ():
        at = float(s_c[near].max()) - med_c
        other = strongest_pointer(s_c, away, med_c + 0.55 * max(at, 0.0), pointer(pol_c)) \
            - med_c
        if s_c is s or at <= RIVAL_SEEN * (float(s_c.max()) - med_c) or at <= 2.0 \
                or other < RIVAL_SEEN * (s_best - _median(s)):
            continue
        rival = max(rival, other / at)
    scores["needle_unique"] = _ramp(rival, 0.8, 0.55)
    scores["needle_length"] = _ramp(ext_tip / R, 0.4, 0.6)
    # sub-degree: weighted line through the centroids of both ends
    half_px = 0.07 * R + 5.0
    r_fit = R_FIT * R  # the tick ring beyond would pull the centres
    pts, wts, cover = _needle_points([
        _centroids(pol, tip_i, rs, min(0.95 * ext_tip, r_fit), half_px, (px, py)),
        _centroids(pol, tail_i, rs, min(0.95 * ext_tail, r_fit), half_px, (px, py))])
    if len(pts) < 4:
        return NeedleFit(False, "needle too short", polarity=polarity, scores=scores)
    c, u, rms, share = _fit_needle(pts, wts, cover)
    log.debug('needle line: %.2f of the centres agree', share)
    tdir = np.array([math.sin(tip_i * 2 * np.pi / N_TH), -math.cos(tip_i * 2 * np.pi / N_TH)])
    if float(u @ tdir) < 0:
        u = -u
    # the pivot moved onto the needle's line (the click is off by a few pixels)
    off = np.array([px, py]) - c
    along = float(off @ u)
    piv = c + along * u
    perp = float(np.hypot(*(np.array([px, py]) - piv)))
    scores["line_through_pivot"] = _ramp(perp, max(8.0, 0.08 * R), max(4.0, 0.04 * R))
    # a needle is one solid line from the hub out: a column of print (a logo, a word, a
    # numeral and a tick one above the other) has gaps along it.  Measured along the fitted
    # line: about a pivot a few px off it, the line crosses rays as it goes out, and its
    # thin tip leaves the rays of its root (where a set-point pointer's hub or ring of the
    # ignored colour covers it, the needle is not seen, and that is no gap)
    run = (rs >= R_IN * R) & (rs <= 0.9 * ext_tip) & (rs > perp)
    rays = _line_rays(rs, piv, u, (px, py), 2)
    cols = np.arange(len(rs))[None, :]
    if masked is not None:
        run &= ~masked[rays, cols].any(axis=0)
    if run.sum() >= 4:
        near = pol[rays, cols].max(axis=0)[run]
        cover = float(np.mean(near > (thr if tip_i == i else thr_b)))
        log.debug("needle cover %.2f", cover)
        scores["needle_solid"] = _ramp(cover, 0.6, 0.85)
        # (weighing the ends, a short end much the wider near the hub is a counterweight)
        weight = weigh_ends and wid_tail > COUNTERWEIGHT * max(wid_tip, 1e-6)
        if cover < 0.85 and ext_tail >= ROOT_R * R and ext_tip > ext_tail + 0.1 * R \
                and (wid_tip > WIDER_TIP * max(wid_tail, 1e-6)
                     or (needle == "two-ended" and not weight)) and not settled:
            # the longer end has gaps along it, and the other end runs out past its root:
            # the long end's reach may be print beyond a tail's weight, and the other end a
            # thin tip that faded or that glare cut short.  Said so by the long end being
            # also the much wider one, or by the profile: a two-ended needle's tail may be
            # as thin as its tip
            scores["tip_vs_tail"] = 0.0
    # straight: its centres close about the line, and most of them on it
    scores["needle_straight"] = min(_ramp(rms, max(3.0, 0.03 * R), max(1.5, 0.015 * R)),
                                    _ramp(share, 0.4, 0.6))
    ang = angle_cw(float(u[0]), float(u[1]))
    tip = piv + ext_tip * u
    return NeedleFit(True, None, ang, (float(piv[0]), float(piv[1])),
                     (float(tip[0]), float(tip[1])), ext_tip, ext_tail, polarity, rms,
                     max(wid_a, wid_b), share, scores)
