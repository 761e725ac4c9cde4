"""Reading a gauge through its calibration (issue 11, section 1).

The operator's three clicks (pivot, minimum and maximum end marks) are the reader's
knowledge of the gauge.  With a reference frame the new frame is first registered to it
(:mod:`.register`) and the points are carried over (an end mark the reference could not
place on its tick is placed on the frame, :func:`.mark_points.frame_marks`); without one
the points are refined on the frame itself (:func:`.mark_points.refine_points`).  The
needle is found around the pivot (:mod:`.needle`), and the reading is the needle's angle
from the minimum mark along the scale's direction, as a fraction of the arc from the
minimum to the maximum mark, turned into a value by the profile (linear, or the tick
table's eq. 21).

Angles about the pivot are measured on the dial's plane when the view is oblique
(:mod:`.oblique`: the face's rim ellipse gives the affine map back to a circle); with a
reference frame that map is found once on the reference (its rim kept however round, and
where few rays support it weighed against no correction and the other edges by the dial's
circles, :mod:`.rim_focus`) and carried over by the registration's local linear part at
the pivot.  The less the rim is supported (the share of
rays with a step on its ellipse), the more of the correction it makes counts as the
reading's uncertainty.  The end marks are a second, independent witness of the tilt
(:func:`end_mark_tilt`): both lie on the scale circle, so on the dial their ticks' ends are
equally far from the pivot, and the ratio of their image distances in their two directions
is set by the tilt.  Where the rim's correction makes them equal (and no correction does
not), the share of the correction in doubt narrows to what the marks can tell; where they
disagree with the rim, it stays as wide as the rim's support leaves it, and where the
correction makes them far less equal than none does, it widens to the share they say is
wrong, however well supported the rim (an ellipse fitted to another edge).

An end mark the needle's tip hides is placed on the needle's line (:mod:`.hidden_mark`),
known to the half-width of the needle's band less the other end's tick's, when no tick like
the other end's shows beyond the needle: the click's error no longer blurs a reading at
that end.

A needle resting on the stop pin, at or a little below the minimum (``PIN_TOL_DEG``), or a
little beyond the maximum (``STOP_TOL_DEG``), reads as that end; farther outside the scale
is a refusal.  Where the scale leaves a wide gap between its ends, a needle in that gap
near the minimum can only be resting on the stop pin (real gauges' pins sit up to 10-15 deg
below the zero mark): out to :func:`pin_tolerance` it reads the minimum, with a confidence
score ``stop_pin`` that falls from 1 at ``PIN_TOL_DEG`` to ``PIN_SURE`` at that limit (both
in :mod:`.stop_pin`, shared with the reading against the profile's angles).
A needle surely past the end (by more than ``SIGMAS`` times the reading's
uncertainty) reads the end's value whatever the end mark's uncertainty: the stop pin lies
a few degrees below the minimum, where the needle hides the end mark from its refinement.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import replace

import cv2
import numpy as np

from .clicks import CLICK_SIGMA_PX, FIT_SIGMA_PX, Refined, fraction_sigma, refine_pivot, tick_ends
from .denoise import quieten
from .gappy_line import gappy_line_score
from .mark_points import frame_marks, refine_points
from .needle import angle_cw, find_needle
from .oblique import Rectifier, find_rectifier
from .profile import Calibration, GaugeProfile, load_profile
from .reader import MIN_CONFIDENCE, Reading
from .ref_tip import find_needle_told, reference_strip, tip_teller
from .register import carry_points, implausible, jacobian, reference_image, register
from .register_dense import check_landmarks, dense_register, needle_mask, polish
from .rim_focus import sharpest_rim
from .rim_witness import second_edge
from .rivals import choose_needle, needle_hue, reference_lines
from .solid_channel import find_solid_needle
from .stop_pin import PIN_TOL_DEG, pin_score, pin_tolerance

__all__ = ["PIN_TOL_DEG", "STOP_TOL_DEG", "end_mark_tilt", "pin_tolerance", "prepare",
           "read_calibrated", "refine_points", "scale_fraction"]

log = logging.getLogger(__name__)

STOP_TOL_DEG = 5.0  # a needle this far outside an end mark reads as that end

_REASONS = {
    "needle_contrast": "needle contrast too low",
    "needle_unique": "another needle-like line (a second pointer?)",
    "needle_length": "needle not fully visible",
    "line_through_pivot": "needle does not pass through the pivot",
    "needle_straight": "needle is not a clean straight line",
    "needle_solid": "the needle has gaps along it (print, glare?)",
    "gappy_line": "the needle has gaps along it and its line misses the pivot (glare?)",
    "tip_vs_tail": "cannot tell the needle's tip from its tail",
    "registration": "weak registration",
    "points": "the calibration's points are too uncertain for this scale",
    "tilt": "the dial's tilt is uncertain (its rim is unclear)",
    "stop_pin": "the needle lies far below the minimum",
}
REGISTRATION_FAILED = "registration failed"
TOL_PCT_FS = 2.0  # a reading this far off is wrong: its uncertainty must stay well inside
SIGMAS = 2.0  # ... by this many standard deviations
REG_SIGMA_PX = 0.4  # a point carried by the registration gains this much uncertainty
RIM_DOUBT = 3.0  # a rim with a step on only 2 in 3 rays leaves all its tilt correction in doubt
MARKS_WRONG_SIGMAS = 4.0  # end marks this far from the rim's tilt say the rim is wrong
MARKS_WRONG_MAX = 1.0  # ... and leave at most its whole correction in doubt
REF_ROUND = 1.0  # a reference's rim is not taken as head-on however round it is


def scale_fraction(a_min: float, a_max: float, a: float, clockwise: bool) -> tuple[float, float]:
    """(fraction of the arc, span in degrees) of image angle ``a`` on the scale from
    ``a_min`` to ``a_max`` in the given direction; below the minimum is negative, beyond the
    maximum above 1 (whichever end is nearer)."""
    sign = 1.0 if clockwise else -1.0
    span = (sign * (a_max - a_min)) % 360.0
    rel = (sign * (a - a_min)) % 360.0
    if rel <= span:
        return rel / span, span
    over, under = rel - span, 360.0 - rel
    return (1.0 + over / span if over < under else -under / span), span


def end_mark_tilt(gray: np.ndarray, rect: Rectifier, pivot, marks, sig: np.ndarray,
                  sig_pivot_px: float) -> tuple[float, float]:
    """The end marks' evidence on the rim's tilt correction ``rect`` (found on ``gray``
    about ``pivot``): (the 1-sigma share of the correction in doubt they leave, or infinity
    when they cannot tell or disagree with the rim; the share of it they say is wrong when
    they disagree with the rim, else 0).

    Both end marks (``marks``: min, max; refined ones only, ``sig`` at most
    ``FIT_SIGMA_PX``) are major ticks of one print, so on the dial their inner ends lie on
    one circle about the pivot, and so do their outer ends (:func:`.clicks.tick_ends`).
    Seen through a map ``M`` of image vectors onto the dial, the log-ratio of the two
    marks' distances, ``rho(M) = ln |M w_min| - ln |M w_max|``, is then zero.  Under
    perspective the image of a circle of radius r is centred off the pivot's image by a
    shift that grows as r^2; the rim's ellipse (radius R) shows it, so the marks' distances
    are measured from ``pivot + (rim centre - pivot) (r / R)^2``.  The rim's map gives
    ``rho_rim``, no correction (``rect.base``) ``rho_0``; a share ``lam`` of the correction
    left out gives about ``rho_rim + lam (rho_0 - rho_rim)``, so the marks estimate
    ``lam = rho_rim / (rho_rim - rho_0)`` to ``sigma_rho / |rho_rim - rho_0|``.  Each tick
    end's place along its ray is known to ``FIT_SIGMA_PX``; the pivot's error moves both
    distances.  The marks agree with the rim when ``|rho_rim| <= SIGMAS sigma_rho`` (and
    their inner and outer ends agree with each other: the same print); only then is their
    sigma returned.  A tilt the marks cannot see (both marks foreshortened alike) gives a
    large sigma, which narrows nothing.  Where the rim's correction makes the two marks'
    distances less equal than no correction does, well beyond their sigma
    (``|rho_rim| - |rho_0| > MARKS_WRONG_SIGMAS sigma_rho``), their inner and outer ends
    agreeing, the marks say the rim's ellipse is wrong (another edge, a bracket, glare): the
    share ``|lam|`` of its correction they say is wrong (at most ``MARKS_WRONG_MAX``) is
    returned, for the reading's tilt doubt to cover, whatever the rim's support.  (Marks
    unequal alike with and without the correction say nothing of it: the print's own
    difference, or a pivot off the dial's centre.)"""
    nothing = (math.inf, 0.0)
    if rect.identity or rect.ellipse is None or max(sig[1], sig[2]) > FIT_SIGMA_PX:
        return nothing
    px, py = float(pivot[0]), float(pivot[1])
    ends = []
    for mark in marks:
        e = tick_ends(gray, (px, py), mark)
        if e is None:
            return nothing
        d = np.array([mark[0] - px, mark[1] - py], float)
        ends.append((d / max(np.linalg.norm(d), 1e-9), e))
    (ex, ey), (w_, h_), _ = rect.ellipse
    rim_r = 0.25 * (w_ + h_)
    shift = np.array([ex - px, ey - py], float)

    def rho(m: np.ndarray, k: int) -> float:  # k: 0 the ticks' inner ends, 1 their outer
        out = []
        for u, e in ends:
            r = e[k]
            out.append(np.linalg.norm(m @ (u * r - shift * (r / rim_r) ** 2)))
        return math.log(max(out[0], 1e-9) / max(out[1], 1e-9))

    (u0, (a0, b0)), (u1, (a1, b1)) = ends
    r0, r1 = 0.5 * (a0 + b0), 0.5 * (a1 + b1)
    s_one = FIT_SIGMA_PX * math.hypot(1.0 / r0, 1.0 / r1)  # one pair of ends' rho
    if abs(rho(rect.base, 0) - rho(rect.base, 1)) > SIGMAS * math.sqrt(2.0) * s_one:
        return nothing  # the inner and outer ends disagree: not two ticks of one print
    s_rho = math.hypot(s_one / math.sqrt(2.0),
                       sig_pivot_px * float(np.linalg.norm(u0 / r0 - u1 / r1)))
    rho_rim = 0.5 * (rho(rect.a, 0) + rho(rect.a, 1))
    rho_0 = 0.5 * (rho(rect.base, 0) + rho(rect.base, 1))
    log.debug("end marks' tilt test: rho rim %.4f, none %.4f, sigma %.4f", rho_rim, rho_0,
              s_rho)
    gap = max(abs(rho_rim - rho_0), 1e-9)
    if abs(rho_rim) - abs(rho_0) > MARKS_WRONG_SIGMAS * s_rho:
        return math.inf, min(abs(rho_rim) / gap, MARKS_WRONG_MAX)
    if abs(rho_rim) > SIGMAS * s_rho or rect.support >= 1.0:
        return nothing  # (a rim on every ray is not in doubt: nothing to narrow)
    return s_rho / gap, 0.0


_REFERENCES: dict[tuple, tuple] = {}


def _reference_geometry(cal: Calibration, prof: GaugeProfile) -> tuple:
    """On the reference frame, once per file, mtime and clicks: the rim's rectification,
    the refined points with their uncertainties, the frame in colour (grey when it cannot
    be read so), the hue of its needle when that is one clear coloured line and its
    polarity ("dark" or "light") when it is one clear line (else None), and the strip
    along its needle (:mod:`.ref_tip`) when its tip is sure (else None)."""
    st = cal.image_path.stat()
    key = (cal.image_path, st.st_mtime_ns, st.st_size, cal.center, cal.min_point,
           cal.max_point, cal.clockwise, prof.needle, prof.ignore_colour)
    hit = _REFERENCES.get(key)
    if hit is None:
        if len(_REFERENCES) > 64:
            _REFERENCES.clear()
        ref = reference_image(cal.image_path)
        piv = refine_pivot(ref, cal.center, cal.radius_px)
        nf = find_needle(ref, piv.xy, cal.radius_px, needle=prof.needle)
        pts, sig = refine_points(ref, cal, piv, nf, bool(prof.ticks))
        bgr = cv2.imread(str(cal.image_path), cv2.IMREAD_COLOR)
        bgr = ref if bgr is None or bgr.shape[:2] != ref.shape[:2] else bgr
        # the rim about the clicked pivot: the rim's accept / reject decision is sensitive
        # to sub-pixel moves of its rays' origin (see docs/gauge-profiles.md).  Fitted once
        # on the reference, it is kept however round (``REF_ROUND``: a dial 8 deg off
        # head-on is round to 0.99, and its view otherwise left in every reading), and
        # looked for in the colour channels where grey shows none (a face of the
        # background's grey in another colour)
        rect = second_edge(ref, cal.center, cal.radius_px,
                           find_rectifier(ref, cal.center, cal.radius_px,
                                          bgr if bgr.ndim == 3 else None,
                                          round_ratio=REF_ROUND),
                           round_ratio=REF_ROUND)
        # a rim on few of its rays may mix two edges: the dial's circles, sharpest through
        # the right view, weigh it against no correction and the other edges (:mod:`.rim_focus`)
        rect = sharpest_rim(ref, pts[0], cal.center, cal.radius_px, rect)
        rect.marks_sigma, rect.marks_wrong = end_mark_tilt(ref, rect, pts[0], pts[1:], sig,
                                                           float(sig[0]))
        hue = polarity = None
        nfc = find_needle(bgr, piv.xy, cal.radius_px, needle=prof.needle,
                          ignore_colour=prof.ignore_colour)
        if nfc.ok and min(nfc.scores.values(), default=0.0) >= 0.999:
            hue = needle_hue(bgr, nfc)
            polarity = nfc.polarity if nfc.polarity in ("dark", "light") else None
        hit = _REFERENCES[key] = (rect, pts, sig, bgr, hue, polarity,
                                  _reference_tip(ref, pts, cal, prof))
    return hit


def prepare(profile) -> str | None:
    """Find a calibrated profile's reference geometry now (:func:`_reference_geometry`,
    kept in-process while the reference file and clicks are unchanged), so that the
    point's first frame does not pay it (a few tenths of a second).  ``profile``: as
    :func:`read_calibrated` takes it.  Returns None (done, or nothing to do: no reference
    frame), or why it could not be done; never raises for a bad profile or file."""
    try:
        prof = load_profile(profile)
        cal = prof.calibration
        if cal is None or cal.image_path is None:
            return None
        _reference_geometry(cal, prof)
    except (OSError, ValueError) as e:
        return str(e)
    except Exception as e:  # noqa: BLE001 - a bad reference is the reader's to refuse
        log.warning("reference geometry not prepared: %s", e)
        return f"reference geometry not prepared: {e}"
    return None


def _scale_test(pts, clockwise: bool):
    """Whether an image angle about ``pts[0]`` lies on the scale from ``pts[1]`` to
    ``pts[2]``, allowing the stop pin below the minimum and a little beyond the maximum."""
    (cx, cy), pmin, pmax = (tuple(map(float, p)) for p in pts)
    a_min, a_max = angle_cw(pmin[0] - cx, pmin[1] - cy), angle_cw(pmax[0] - cx, pmax[1] - cy)

    def on_scale(a: float) -> bool:
        f, span = scale_fraction(a_min, a_max, a, clockwise)
        return -pin_tolerance(span) / span <= f <= 1.0 + STOP_TOL_DEG / span
    return on_scale


def _reference_tip(ref: np.ndarray, pts, cal: Calibration, prof: GaugeProfile):
    """The strip along the reference frame's needle (:func:`.ref_tip.reference_strip`) when
    its tip is sure: the needle found about the reference's pivot with its ends weighed as
    in any frame, no doubt about which end is the tip, and the tip on the clicked scale;
    else None."""
    radius = _radius(pts)
    on_scale = _scale_test(pts, cal.clockwise)
    nf = find_needle(ref, tuple(pts[0]), radius, needle=prof.needle, on_scale=on_scale,
                     weigh_ends=True)
    if not nf.ok or nf.scores.get("tip_vs_tail", 1.0) < 1.0 or not on_scale(nf.angle_deg):
        log.debug("the reference needle's tip is not sure: not carried over")
        return None
    return reference_strip(ref, pts[0], radius, nf.angle_deg)


def _radius(pts) -> float:
    """The scale ring's radius: the mean distance of the end marks from the pivot."""
    (cx, cy), (x0, y0), (x1, y1) = (tuple(map(float, p)) for p in pts)
    return 0.5 * (math.hypot(x0 - cx, y0 - cy) + math.hypot(x1 - cx, y1 - cy))


def _ramp(x: float, bad: float, good: float) -> float:
    return float(min(1.0, max(0.0, (x - bad) / (good - bad))))


def _refuse(unit, reason, t0, **kw) -> Reading:
    return Reading(value=None, unit=unit, confidence=0.0, error=reason,
                   elapsed_ms=round((time.perf_counter() - t0) * 1000.0, 3), **kw)


def read_calibrated(image: np.ndarray, profile, *,
                    min_confidence: float = MIN_CONFIDENCE) -> Reading:
    """Read a BGR (or grey) frame with a calibrated profile; never raises for bad content."""
    t0 = time.perf_counter()
    prof: GaugeProfile = load_profile(profile)
    cal = prof.calibration
    unit = prof.unit
    method = "calibrated-reference" if cal.image_path is not None else "calibrated"
    if not isinstance(image, np.ndarray) or image.ndim not in (2, 3) or image.size == 0 \
            or min(image.shape[:2]) < 32:
        return _refuse(unit, "not a usable image", t0, method=method)
    if image.dtype != np.uint8:
        image = np.clip(image, 0, 255).astype(np.uint8)
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    elif image.ndim == 3 and image.shape[2] != 3:
        image = np.ascontiguousarray(image[:, :, 0])
    gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    # a noisy frame is median filtered first (:mod:`.denoise`): its specks otherwise pull
    # the needle's fit, and the clicked geometry accepts what it finds there
    image, gray, _ = quieten(image, gray)
    if cal.image_path is None:
        return _read(image, gray, prof, None, t0, min_confidence)
    # keypoints first (their warp polished by the dial's picture where it agrees); where
    # they fail, or their warp does not carry the end marks onto the frame's, the dial's
    # picture itself (a plain dial has few keypoints)
    reg = register(gray, cal)
    first = None
    if reg.ok:  # the keypoints' warp made closer by the dial's picture, where it agrees
        h = polish(gray, cal, reg.homography)
        if h is not None and implausible(h, cal.center, cal.radius_px, gray.shape, carry_points(
                h, [cal.center, cal.min_point, cal.max_point])) is None:
            reg = replace(reg, homography=h)
        first = _read(image, gray, prof, reg, t0, min_confidence)
        if not (first.error or "").startswith(REGISTRATION_FAILED):
            return first
    dense = dense_register(gray, cal)
    if dense.ok:
        return _read(image, gray, prof, dense, t0, min_confidence)
    why = first.error if first is not None else reg.error
    log.debug("dense registration refused too: %s", dense.error)
    return _refuse(unit, f"{why}; by the dial's picture: "
                         f"{dense.error.removeprefix(REGISTRATION_FAILED).lstrip(': ')}",
                   t0, method=method)


def _read(image: np.ndarray, gray: np.ndarray, prof: GaugeProfile, reg, t0: float,
          min_confidence: float) -> Reading:
    """The reading of a prepared frame (BGR or grey, and its grey) with the calibrated
    profile ``prof``, registered to its reference frame by ``reg`` (None: no reference)."""
    cal = prof.calibration
    unit = prof.unit
    method = "calibrated-reference" if cal.image_path is not None else "calibrated"
    scores: dict[str, float] = {}
    hom = None
    static = ()
    ref_hue = ref_polarity = None
    tip_of = None
    if reg is not None:
        hom = reg.homography
        scores["registration"] = round(reg.score, 4)
        try:
            rect, pts, sig, ref_bgr, ref_hue, ref_polarity, ref_strip = \
                _reference_geometry(cal, prof)
        except (OSError, ValueError):
            rect = Rectifier()
            pts = np.array([cal.center, cal.min_point, cal.max_point], float)
            sig = np.full(3, CLICK_SIGMA_PX)
            ref_bgr, ref_hue, ref_strip = None, None, None
        j = jacobian(hom, *pts[0])
        rect = rect.carried(j)
        ref_pivot, ref_radius = tuple(pts[0]), _radius(pts)
        ref_pts = pts.copy()
        kept = sig >= CLICK_SIGMA_PX  # points the reference showed no clearer than clicked
        pts = carry_points(hom, pts)
        if ref_strip is not None:  # the reference needle's tip, carried over
            tip_of = tip_teller(ref_strip, ref_pivot, ref_radius, hom, gray, tuple(pts[0]),
                                _radius(pts))

        def static(h=hom, frame_pivot=tuple(pts[0])):  # the reference's lines, carried over
            if ref_bgr is None:
                return []
            return reference_lines(ref_bgr, ref_pivot, ref_radius,
                                   lambda q: carry_points(h, q), frame_pivot)
        sig = np.hypot(sig * math.sqrt(abs(np.linalg.det(j))), REG_SIGMA_PX)
    else:
        piv = refine_pivot(gray, cal.center, cal.radius_px)
        pts = np.array([piv.xy, cal.min_point, cal.max_point], float)
        sig = None  # the end marks are refined once the needle is known
    (cx, cy), pmin, pmax = (tuple(map(float, p)) for p in pts)
    hh, ww = gray.shape[:2]
    if not (0 <= cx < ww and 0 <= cy < hh):
        return _refuse(unit, "the calibrated pivot lies outside this image", t0, method=method)
    geo = {"method": method, "homography": None if hom is None else hom.tolist(),
           "dial_centre_xy": (cx, cy), "scale_ends_xy": (pmin, pmax)}
    radius = _radius(pts)
    geo["dial_radius_px"] = radius
    if hom is None:
        rect = find_rectifier(gray, (cx, cy), radius, image if image.ndim == 3 else None)
        if rect.ellipse is not None:
            (ex, ey), (ew, eh), ea = rect.ellipse
            geo["dial_ellipse"] = (float(ex), float(ey), float(ew), float(eh), float(ea))
    on_scale = _scale_test(pts, cal.clockwise)
    nf = find_needle_told(image, (cx, cy), radius, tip_of, find=find_solid_needle,
                          needle=prof.needle, ignore_colour=prof.ignore_colour,
                          on_scale=on_scale, weigh_ends=True)
    # a second pointer: what the calibration knows may tell which line is the needle
    nf = choose_needle(image, (cx, cy), radius, nf, needle=prof.needle,
                       ignore_colour=prof.ignore_colour, on_scale=on_scale,
                       static_angles=static, reference_hue=ref_hue,
                       reference_polarity=ref_polarity)
    scores.update({k: round(v, 4) for k, v in nf.scores.items()})
    if hom is not None:  # the end marks must line up with the reference's (its needle aside)
        why, shifts = check_landmarks(gray, cal, hom, needle_mask(gray.shape, nf, radius))
        if why is not None:
            return _refuse(unit, why, t0, scores=scores, **geo)
        for i, (dx, dy) in enumerate(shifts, start=1):  # a mark found a little off the warp
            if dx or dy:
                pts[i] = carry_points(hom, ref_pts[i:i + 1] + (dx, dy))[0]
                sig[i] = math.hypot(sig[i], 0.5 * math.hypot(dx, dy))
        if nf.ok and not prof.ticks:  # marks the reference could not place: on this frame
            frame_marks(gray, cal, pts, sig, kept, nf)
        pmin, pmax = (tuple(map(float, p)) for p in pts[1:])
        geo["scale_ends_xy"] = (pmin, pmax)
    if not nf.ok:
        return _refuse(unit, nf.error, t0, scores=scores, **geo)
    if hom is not None:  # a needle with gaps whose line misses the carried pivot
        scores["gappy_line"] = round(gappy_line_score(nf.scores, nf.pivot_xy, (cx, cy),
                                                      radius), 4)
    geo["pointer_tip_xy"] = nf.tip_xy
    geo["pointer_line_xy"] = (nf.pivot_xy, nf.tip_xy)
    # the end marks' angles about the pivot moved onto the needle's line, on the dial plane
    qx, qy = nf.pivot_xy
    if sig is None:  # the clicked end marks placed on their ticks, clear of the needle
        piv = Refined((qx, qy), piv.ok, piv.moved_px, piv.sigma_px, piv.why)
        pts, sig = refine_points(gray, cal, piv, nf, bool(prof.ticks))
        pmin, pmax = (tuple(map(float, p)) for p in pts[1:])
        geo["scale_ends_xy"] = (pmin, pmax)
        rect.marks_sigma, rect.marks_wrong = end_mark_tilt(gray, rect, (qx, qy), (pmin, pmax),
                                                           sig, float(sig[0]))
    a_min = rect.angle(pmin[0] - qx, pmin[1] - qy)
    a_max = rect.angle(pmax[0] - qx, pmax[1] - qy)
    t = math.radians(nf.angle_deg)
    a_needle = rect.angle(math.sin(t), -math.cos(t))
    frac, span = scale_fraction(a_min, a_max, a_needle, cal.clockwise)
    # a rim that not every ray agrees with may have mixed two edges and misjudged the tilt:
    # the less it is supported, the more of its correction is uncertain
    sig_rect = 0.0
    if not rect.identity:
        # (with a reference frame, the rim's part only: the registration's is sure)
        f_img, _ = scale_fraction(rect.base_angle(pmin[0] - qx, pmin[1] - qy),
                                  rect.base_angle(pmax[0] - qx, pmax[1] - qy),
                                  rect.base_angle(math.sin(t), -math.cos(t)), cal.clockwise)
        doubt = min(1.0, max(0.0, RIM_DOUBT * (1.0 - rect.support)))
        if doubt > 0.0 and math.isfinite(rect.marks_sigma):  # two witnesses of the tilt
            doubt = 1.0 / math.hypot(1.0 / doubt, 1.0 / max(rect.marks_sigma, 1e-9))
        # end marks that contradict the rim: its correction is in doubt as far as they say
        doubt = max(doubt, rect.marks_wrong)
        sig_rect = 100.0 * abs(frac - f_img) * doubt
    pin_tol = pin_tolerance(span)
    if frac < -pin_tol / span or frac > 1.0 + STOP_TOL_DEG / span:
        below = frac < 0
        deg = (-frac if below else frac - 1.0) * span
        return _refuse(unit, f"pointer outside the scale ({deg:.0f} deg "
                             f"{'below the minimum' if below else 'beyond the maximum'})",
                       t0, scores=scores, **geo)
    # the points' uncertainty (after refinement) against the tolerance of a wrong reading
    r_min = math.hypot(pmin[0] - qx, pmin[1] - qy)
    r_max = math.hypot(pmax[0] - qx, pmax[1] - qy)
    sig_needle = math.degrees(max(nf.rms_px, 0.3) / max(nf.length_px, 1.0))
    # the pivot was moved onto the needle's line: only its error along the line is left
    off_min = angle_cw(pmin[0] - qx, pmin[1] - qy) - nf.angle_deg
    off_max = angle_cw(pmax[0] - qx, pmax[1] - qy) - nf.angle_deg
    sigma_pts = 100.0 * fraction_sigma(frac, span, r_min, r_max, sig[1], sig[2], sig[0],
                                       sig_needle, off_min, off_max)
    sigma = math.hypot(sigma_pts, sig_rect)
    # a needle surely past an end (resting on the stop pin) reads that end's value, however
    # uncertain the end mark's exact place is
    past = max(-frac, frac - 1.0) * 100.0
    if past > 0 and past >= SIGMAS * sigma:
        log.debug("needle %.2f %% FS past the scale's end: reads the end", past)
        sigma = sigma_pts = sig_rect = 0.0
    below_deg = -frac * span
    if below_deg > PIN_TOL_DEG:  # in the gap below the minimum: on the stop pin, surely?
        scores["stop_pin"] = pin_score(below_deg, span)
    log.debug("reading uncertainty %.2f %% FS (points %s px, tilt %.2f)", sigma,
              np.round(sig, 2), sig_rect)
    # named for the larger share of the uncertainty: the points, or the dial's tilt
    scores["tilt" if sig_rect > sigma_pts else "points"] = _ramp(SIGMAS * sigma, TOL_PCT_FS,
                                                                 0.75 * TOL_PCT_FS)
    frac = min(max(frac, 0.0), 1.0)  # at the stop pin: the end mark's value
    raw = prof.value_at_fraction(frac)
    conf = float(np.prod(list(scores.values()))) if scores else 0.0
    worst = min(scores, key=scores.get)
    band = prof.in_normal_band(raw)
    ok = conf >= min_confidence
    return Reading(
        value=float(raw) if ok else None, unit=unit, confidence=round(conf, 4),
        error=None if ok else f"low confidence ({_REASONS.get(worst, worst)})",
        raw_value=float(raw),
        angle_deg=prof.min_angle_deg + frac * (prof.max_angle_deg - prof.min_angle_deg),
        in_normal_band=band if ok else None, scores=scores,
        elapsed_ms=round((time.perf_counter() - t0) * 1000.0, 3), **geo,
    )
