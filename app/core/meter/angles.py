"""Reading against the profile's angles when the dial's own scale is not (fully) found.

The profile's ``min_angle_deg`` / ``max_angle_deg`` are knowledge: on the upright dial the
scale runs between them.  What the image must still tell is (a) the needle's angle about
the pivot and (b) how far the dial is turned in the picture (a rolled camera, a gauge
turned in its mounting).  Each comes from two estimates that do not share a step, and a
reading is returned only when they agree:

* **the needle**: the skeleton line of :mod:`.pointer` (eq. 19 through the hub) and the
  polar ray evidence of :func:`.needle.find_needle` about the same hub.  They differ in
  how they find the needle (a thresholded region's skeleton against the covered length
  of rays), so an agreement within a few degrees says they found the same line; a
  disagreement, or a tip/tail choice they do not share, is a refusal that says so.  The
  skeleton is coarse, so the angle is then measured to a fraction of a degree by a line
  through the shaft's cross-sections near the scale (:mod:`.needle_axis`); the reading
  takes the middle of it and the ray evidence, and half their difference is its error.
* **the turn of the dial** (:func:`.arc_fit.fit_profile_arc`): the scale's printed marks (ticks,
  arcs, zones) lie on a ring, over the profile's arc and not in its gap.  The profile's
  arc is slid round that ring's evidence; where it holds the most evidence is the dial's
  turn.  The two end marks bound the slide from either side, so the set of turns that
  hold (nearly) the most evidence is narrow only when the evidence agrees with the
  profile's span at both ends: its width is the turn's uncertainty.  A span that does not
  match, a hidden end mark, a ring with no gap, or a turn beyond what a camera rolls all
  widen it, and the reading is refused.  The polar image is unwrapped about the centre of
  the ring of scale marks (:mod:`.ring_centre`); where the arc is refused about it, it is
  tried once more about the centre that makes the ticks an even comb (:mod:`.comb_centre`),
  whose standard error then widens the bound (also where only the end marks turned it and
  the ticks form a comb about that centre: :func:`_comb_arc`), and then about the hub,
  whose place along the gap's axis (where a short ring's centre slides) the end marks must
  verify (:func:`_hub_arc`), and last about the point of the needle's line from which the
  end marks lie the profile's span apart, which the learned end marks must confirm
  (:mod:`.span_pivot`).

The confidence says what was verified: the needle finders' agreement and the bound on
the error that the turn's uncertainty leaves, in % of full scale (plus the usual pointer
checks).  The reading is refused when that bound is too large for the confidence that a
returned reading claims.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .arc_fit import (
    MAX_ROLL_DEG,
    NEAR_MISS_DEG,
    SPAN_MISS,
    STEP,
    ArcFit,
    fit_profile_arc,
    mark_level,
    percentile,
)
from .comb_centre import comb_centre
from .dial import FACE_RADIUS
from .learned_checks import keypoint_tip_diff as _keypoint_tip_diff
from .learned_checks import keypoint_turn as _keypoint_turn
from .learned_checks import learned_tip_opposes as _learned_tip_opposes
from .needle import WEIGH_REACH, find_needle
from .needle_axis import INNER_FRAC, OUTER_FRAC, ShaftFit, fit_shaft
from .pointer import CENTRE, FACE_MASK
from .profile import GaugeProfile
from .ring_centre import (
    CENTRES_AGREE_PX,
    hub_is_perspective_centre,
    pass_images,
    ring_centre,
)
from .scale import angle_diff
from .span_pivot import span_arc
from .stop_pin import gap_is_bare, pin_score, pin_tolerance, widest_space

__all__ = ["ArcFit", "fit_profile_arc", "read_by_angles", "MAX_ROLL_DEG",
           "hub_is_perspective_centre", "ring_centre"]

NEEDLES_AGREE_DEG = 6.0  # the skeleton's axis confirms the ray evidence's within this
SKELETON_TILT_DEG = 15.0  # ... or, this far off, a shaft fit that agrees (below) overrules it
SHAFT_CONFIRMS_DEG = 1.5  # the shaft's fit and the ray evidence agree within this
SHAFT_COVER = 0.7  # share of the shaft's cross-sections the fit must keep to overrule
# % FS: the error bound's confidence ramp, 0.5 at a bound of 0.625 % FS. A ramp reaching 0.5
# at 1 % FS (half the 2 % FS that makes a reading wrong; stated bounds were seen exceeded by
# up to 1.4x) read 4-5 % more dials but returned confident wrong readings on dials of a
# style family it was not tuned on, so the bound stays this strict.
BOUND_GOOD, BOUND_BAD = 0.35, 0.9
DARK_FACE_GREY = 100  # a face whose median grey is below this carries light marks
KP_TURN_TOL_DEG = 2.5  # the learned end marks' turn confirms a one-end fit within this
KP_TIP_TOL_DEG = 6.0  # the learned tip confirms the ray finder's needle within this
STRIP_MARGIN_PX = 2.0  # the needle's strip reaches this far beyond its shaft
STOP_TOL_DEG = 5.0  # a needle this far outside an end mark reads as that end (a stop pin)
SAME_START_PX = 1.5  # the ring's fit from the hub and from the rim's centre start alike
LINE_AT_CENTRE_PX = 2.5  # or the needle's line passes the ring's centre within this
CENTRE_SE_K = 3.0  # the comb's centre is known to this many standard errors
COMB_MOVES_PX = 0.2  # the comb's centre is a second try only this far from the ring's
HUB_RMS_PX = 1.5  # the hub's circle fits its boundary this closely to be a third try ...
HUB_TRY_PX = 1.0  # ... when it lies this far from the ring's centre, and no further than
HUB_TRY_MAX_PX = 8.0  # this
MIN_END_LEVER = 0.5  # sin(half the span) below this: the end marks barely fix the pivot


def median_face_grey(grey: np.ndarray) -> float:
    """Median grey of the normalised crop's face."""
    h = cv2.calcHist([grey], [0], FACE_MASK, [256], [0, 256]).ravel()
    return float(np.searchsorted(np.cumsum(h), h.sum() / 2.0))


def _needle_strip(pmask: np.ndarray, point, angle_deg: float, tail_px: float) -> np.ndarray:
    """A strip along the needle, from the end of its tail out past its tip, as wide as its
    shaft plus a margin: the evidence it covers is unknown.  The shaft's half-width is
    measured on the pointer's region."""
    u = np.array([math.sin(math.radians(angle_deg)), -math.cos(math.radians(angle_deg))])
    nz = cv2.findNonZero(pmask)
    v = (nz.reshape(-1, 2).astype(float) if nz is not None else np.zeros((0, 2))) \
        - np.asarray(point, float)
    along = v @ u
    across = np.abs(v @ np.array([-u[1], u[0]]))
    mid = (along > 0.25 * FACE_RADIUS) & (along < 0.5 * FACE_RADIUS) & (across < 12.0)
    half = percentile(across[mid], 90) if mid.sum() >= 5 else 4.0
    half = min(half, 8.0) + STRIP_MARGIN_PX
    out = np.zeros_like(pmask)
    p0 = np.asarray(point, float) - u * (tail_px + 3.0 * half)
    p1 = np.asarray(point, float) + u * 1.2 * FACE_RADIUS
    cv2.line(out, (int(round(p0[0] * 16)), int(round(p0[1] * 16))),
             (int(round(p1[0] * 16)), int(round(p1[1] * 16))), 1,
             max(1, int(round(2 * half))), cv2.LINE_8, 4)
    return out


def _profile_arc(prof: GaugeProfile) -> tuple[float, float]:
    """(clockwise start, span) of the profile's arc on the upright dial."""
    return (min(prof.min_angle_deg, prof.max_angle_deg) % 360.0, prof.span_deg)


def _fraction(prof: GaugeProfile, theta: float, rho: float) -> float:
    """Fraction of the scale at image angle ``theta`` with the profile's arc turned by
    ``rho``; below the minimum negative, beyond the maximum above 1 (nearer end)."""
    a_min = prof.min_angle_deg + rho
    sign = 1.0 if prof.clockwise else -1.0
    span = prof.span_deg
    rel = (sign * (theta - a_min)) % 360.0
    if rel <= span:
        return rel / span
    over, under = rel - span, 360.0 - rel
    return 1.0 + over / span if over < under else -under / span


def read_by_angles(res: dict, prof: GaugeProfile, crop: np.ndarray, keypoints=None) -> dict:
    """The reading of one normalised crop against the profile's angles.

    ``res`` is :func:`.pointer.read_normalised`'s result (it must hold the pointer; for a
    dark face, of the crop's negative, so that its marks are dark) and ``crop`` the
    normalised crop itself (in colour when the profile ignores a colour).  ``keypoints``
    (optional) is a callable giving the learned keypoints (:mod:`.keypoints`) on this crop,
    or None; they are asked only to settle what the classical estimates leave open: the
    turn when one end mark is under the needle, and which line is the needle when the
    skeleton's axis is too coarse to confirm it.  Returns a dict with ``frac``, ``theta``,
    ``rho``, ``bound_fs`` and ``scores``, or with ``error``."""
    hub = res["centre"]
    start, span = _profile_arc(prof)
    # the pivot twice: the hub's circle, and the centre of the ring of scale marks
    # (from the rim's centre only when that is a different start: the fit converges alike)
    # (or the hub is the ring's own centre, fitted from the rim's: :mod:`.hidden_root`)
    starts = [hub] if math.hypot(hub[0] - CENTRE, hub[1] - CENTRE) < SAME_START_PX or \
        res.get("hub_from") == "ring" else [hub, (CENTRE, CENTRE)]
    darkf, hidden = pass_images(res)  # (made once per pass result)
    fits = [f for f in (ring_centre(darkf, res["otsu_t"], start_c, FACE_RADIUS, hidden)
                        for start_c in starts)
            if f is not None]
    if not fits:
        return {"error": "scale marks do not form a ring about the hub"}
    c, ring_rms = min(fits, key=lambda f: f[1])  # from the hub or from the rim's centre
    out: dict = {"centre": c, "ring_rms_px": ring_rms, "ring_centre": c}
    # the needle by its ray evidence about that pivot (tip: the longer, thinner end) ...
    r_guess = 0.8 * FACE_RADIUS
    nf = find_needle(crop, c, r_guess, needle=prof.needle, ignore_colour=prof.ignore_colour,
                     straight_rivals=True)
    if not nf.ok:
        out["error"] = f"second needle finder: {nf.error}"
        return out
    # the scale's turn, with only a strip along the needle's line hidden
    strip = _needle_strip(res["pmask"], nf.pivot_xy, nf.angle_deg, nf.tail_px)
    arc = fit_profile_arc([(darkf, res["otsu_t"])], c, FACE_RADIUS, strip, start, span)
    centre_se = 0.0
    if arc.rho_deg is None or arc.method != "comb":
        # the ring's centre may have slid along the gap's axis with its radius (which turns
        # both end marks inward or outward together); the ticks' comb, where they form one,
        # places the centre by their angles instead (:mod:`.comb_centre`): a second try
        # where the arc is refused, and where only its end marks turned it (see
        # :func:`_comb_arc`)
        tried = _comb_arc(darkf, res["otsu_t"], c, hidden, strip, start, span)
        if tried is not None and (arc.rho_deg is None or tried[0].method == "comb"):
            arc, c, centre_se = tried
            out.update(centre=c, centre_se_px=centre_se)
    d_c = math.hypot(c[0] - hub[0], c[1] - hub[1])
    hub_across_px = None
    if arc.rho_deg is None and res.get("hub_rms", 99.0) < HUB_RMS_PX and d_c > HUB_TRY_PX:
        # a third try, about the hub: see :func:`_hub_arc`
        tried = _hub_arc(darkf, res, prof, crop, hub, c, start, span)
        if tried is not None:
            arc, hub_across_px, nf = tried
            c = (float(hub[0]), float(hub[1]))
            out.update(centre=c, hub_across_px=hub_across_px)
    span_px = 0.0
    if arc.rho_deg is None and arc.ends == 2 and keypoints is not None and \
            0.0 < abs(arc.mismatch_deg) <= NEAR_MISS_DEG and str(arc.error).startswith(SPAN_MISS):
        # a fourth try: the pivot on the needle's line from which the two end marks lie
        # the profile's span apart, confirmed by the learned end marks (:mod:`.span_pivot`)
        tried = span_arc(darkf, res["otsu_t"], prof, crop, c, nf, arc, start, span,
                         keypoints(), lambda n: _needle_strip(res["pmask"], n.pivot_xy,
                                                              n.angle_deg, n.tail_px),
                         KP_TURN_TOL_DEG, STEP)
        if tried is not None:
            arc, c, nf, span_px = tried
            d_c = math.hypot(c[0] - hub[0], c[1] - hub[1])
            out.update(centre=c, span_pivot_px=span_px)
    out["arc"] = arc
    if arc.rho_deg is None:
        out["error"] = arc.error
        _candidate(out, prof, nf.angle_deg, arc.candidate_rho)
        return out
    kp_turn = None
    if arc.ends < 2 and arc.method != "comb":
        # one end mark under the needle: the turn rests on that one mark and on the
        # profile's span; only the learned end marks can check it
        kp = keypoints() if keypoints is not None else None
        kp_turn = _keypoint_turn(kp, c, prof) if kp is not None else None
        if kp_turn is None or abs(angle_diff(kp_turn, arc.rho_deg)) > KP_TURN_TOL_DEG:
            out["error"] = "an end mark is hidden by the needle; the dial's turn is unverified"
            if kp_turn is not None:
                out["error"] += f" (learned end marks: {kp_turn - arc.rho_deg:+.1f} deg off)"
            _candidate(out, prof, nf.angle_deg, arc.rho_deg)
            return out
        out["keypoints_turn_deg"] = kp_turn
    r_ring = arc.radius if arc.radius > 0 else r_guess
    turned = prof.min_angle_deg + arc.rho_deg, prof.max_angle_deg + arc.rho_deg
    # a two-ended needle whose ends reach alike far: the stronger end is no sure tip
    two_alike = prof.needle == "two-ended" and nf.tail_px > nf.length_px - WEIGH_REACH * r_guess
    if "tip_vs_tail" in nf.scores or two_alike:
        # two ends alike: the one on the scale is the tip (now that the scale is placed);
        # for a two-ended needle also the thinner end near the hub and the end whose outer
        # half tapers (a tail ends in a fin, a disc or a weight), each where it is clear,
        # and a refusal where they disagree (:func:`.needle_ends.weigh_end_cues`)
        def on_scale(a: float) -> bool:
            f = _fraction(prof, a, arc.rho_deg)
            return -STOP_TOL_DEG / span <= f <= 1.0 + STOP_TOL_DEG / span

        nf_any = nf
        nf = find_needle(crop, c, r_ring, needle=prof.needle,
                         ignore_colour=prof.ignore_colour, on_scale=on_scale,
                         weigh_ends=two_alike, straight_rivals=True)
        if not nf.ok:
            out["error"] = f"second needle finder: {nf.error}"
            _candidate(out, prof, nf_any.angle_deg, arc.rho_deg)
            return out
        if two_alike and keypoints is not None:
            # the cues that chose between two ends alike may all be one (a tip pointing
            # at an end mark leaves the scale's cue silent, and a tapering tail then looks
            # like the tip): the learned tip, a third estimate, must not point at the
            # other end
            if _learned_tip_opposes(keypoints, c, nf.angle_deg):
                out["error"] = ("cannot tell the needle's tip from its tail (its two ends "
                                "reach alike, and the learned tip points at the other)")
                _candidate(out, prof, nf.angle_deg, arc.rho_deg)
                return out
    if keypoints is not None and abs(angle_diff(nf.angle_deg, res["theta"])) > 90.0:
        # the skeleton's far end lies on the other side of the hub (common for a two-ended
        # needle, whose skeleton runs both ways, and for a long counterweight): the learned
        # tip, a third estimate, must not point there too (a hairline tip that faded beside
        # a finned tail bridged on to the numerals beyond it)
        if _learned_tip_opposes(keypoints, c, nf.angle_deg):
            out["error"] = ("cannot tell the needle's tip from its tail (the learned tip and "
                            "the skeleton point at the other end)")
            _candidate(out, prof, nf.angle_deg, arc.rho_deg)
            return out
    perp = math.hypot(nf.pivot_xy[0] - c[0], nf.pivot_xy[1] - c[1])
    if d_c > CENTRES_AGREE_PX:  # the hub is off the ring's centre: the needle's line decides
        if perp > LINE_AT_CENTRE_PX:
            out["error"] = (f"pivot unclear (hub {d_c:.0f} px from the scale ring's centre, "
                            f"needle line {perp:.0f} px from it)")
            _candidate(out, prof, nf.angle_deg, arc.rho_deg)
            return out
    # ... whose axis the skeleton's line (eq. 19) must confirm, as a line through the hub:
    # it is the coarser of the two (a region grown into a numeral or tick tilts it), so it
    # vouches for which line is the needle, and the ray evidence's sub-degree fit is read
    d = (angle_diff(nf.angle_deg, res["theta"]) + 90.0) % 180.0 - 90.0
    out["needle_diff_deg"] = d
    # the shaft's line through its cross-sections measures the same axis to a fraction of a
    # pixel: once the skeleton has said which line is the needle, the fit's disagreement
    # with the ray evidence is what the bound carries.  A skeleton tilted a little further
    # by a merged numeral is overruled only by a shaft that the pointer's region shows
    # straight along the ray line over most of its length, in agreement with it
    shaft = fit_shaft(res["pmask"], res["dark"], nf.pivot_xy, nf.angle_deg, nf.length_px)
    if shaft is not None and arc.ends == 2 and \
            _line_miss(shaft, nf.pivot_xy) > LINE_AT_CENTRE_PX:
        # a needle's axis passes through its pivot, which the ray evidence's line (fitted
        # over both ends, out to short of the ticks) places; a shaft's line that misses it
        # is tilted by print against the shaft's outer part (a numeral the needle crosses),
        # so its direction is fitted again as a line through that pivot.  (Not where the
        # turn rests on one verified end: a comb that verified one end may be a whole
        # tooth out, which the bound does not carry, and the needle estimates' doubt is
        # then left as it was; a small, far `process` dial read a pitch off without it)
        shaft = fit_shaft(res["pmask"], res["dark"], nf.pivot_xy, nf.angle_deg,
                          nf.length_px, through=True)
    a_fit = shaft.angle_at(c, r_ring) if shaft is not None else None
    # both lines are read where they cross the scale ring, about the ring's centre: what
    # the needle points at on the scale, even where its line misses that centre a little
    a_ray = ShaftFit(nf.angle_deg, nf.pivot_xy, 0.0, 0).angle_at(c, r_ring)
    if a_ray is None:
        a_ray = nf.angle_deg
    whole = shaft is not None and shaft.n >= SHAFT_COVER * (OUTER_FRAC - INNER_FRAC) \
        * nf.length_px
    if (a_fit is not None and abs(d) <= SKELETON_TILT_DEG and whole
            and abs(angle_diff(a_fit, a_ray)) <= SHAFT_CONFIRMS_DEG):
        d_skel = d
    else:
        d_skel = None
    if a_fit is not None and (abs(d) <= NEEDLES_AGREE_DEG or d_skel is not None):
        out["skeleton_diff_deg"] = d
        d = angle_diff(a_fit, a_ray)
        out["needle_diff_deg"] = d
    if abs(d) > NEEDLES_AGREE_DEG:
        kp = keypoints() if keypoints is not None else None
        d_kp = _keypoint_tip_diff(kp, c, nf.angle_deg) if kp is not None else None
        if d_kp is None or abs(d_kp) > KP_TIP_TOL_DEG:
            out["error"] = f"the needle finders disagree by {abs(d):.1f} deg"
            _candidate(out, prof, a_ray, arc.rho_deg)
            return out
        d = 0.0  # the learned tip confirms the ray finder's needle
        out["needle_diff_deg"] = d
        out["keypoints_tip_deg"] = d_kp
    # between the two estimates: the bound's half of their disagreement then covers either
    theta = (a_ray + d / 2.0) % 360.0 if a_fit is not None else a_ray
    frac = _fraction(prof, theta, arc.rho_deg)
    below = -frac * span  # deg below the minimum mark
    if below > pin_tolerance(span) or frac > 1.0 + STOP_TOL_DEG / span:
        out["error"] = "pointer outside the scale"
        out["frac"] = out["candidate_frac"] = frac
        return out
    if below > STOP_TOL_DEG:
        # resting on the stop pin, or on a scale turned towards its maximum, among the
        # ticks the turn left out? Only a bare gap round the needle says the first
        bare, why = _on_the_pin(arc, prof, theta)
        if not bare:
            out["error"] = f"pointer outside the scale ({below:.1f} deg below the minimum: {why})"
            out["frac"] = out["candidate_frac"] = frac
            return out
        out["stop_pin"] = pin_score(below, span, STOP_TOL_DEG)
    # the error bound: half the end marks' disagreement, half the needle finders'
    # disagreement, the pivot's uncertainty (seen at the ring), the
    # evidence's own resolution (half a polar column), more when one end mark was hidden
    # (with the ticks' comb: the comb's own error bound in place of the ends'); the needle's
    # angle is where its line crosses the scale ring, but how far its line misses the
    # ring's centre (or the ring fit's rms, if larger) still says how well the pivot is
    # known: a rectified view's residual perspective shows there
    pivot_deg = math.degrees(max(perp, ring_rms, CENTRE_SE_K * centre_se,
                                 hub_across_px or 0.0, span_px) / r_ring)
    pivot_deg *= pivot_lever(arc, span, angle_diff(theta, start + arc.rho_deg + span / 2.0))
    # (the end marks' mismatch shows them off in opposite ways; off the same way, by up to
    # what their placing leaves in doubt, they turn the scale unseen)
    ends_deg = max(abs(arc.mismatch_deg) / 2.0, arc.ends_err_deg)
    if hub_across_px is not None and span > 180.0:
        # about the hub, the end marks' mismatch may be the pivot's slide along the gap's
        # axis: it turns the ends by sin(span / 2) of what it turns a needle across it
        ends_deg /= math.sin(math.radians(span / 2.0))
    bound_deg = ends_deg + arc.turn_err_deg + abs(d) / 2.0 + pivot_deg + STEP / 2.0
    if kp_turn is not None:
        # the span is the profile's, checked only by the learned end marks, which confirm
        # the one end mark's turn within their tolerance: all of it may be error (a field
        # frame read 2 % FS off where the two turns agreed within 2.2 deg)
        bound_deg += KP_TURN_TOL_DEG
    out["bound_parts_deg"] = (ends_deg + arc.turn_err_deg, abs(d) / 2.0,
                              pivot_deg, STEP / 2.0)
    out.update(frac=min(max(frac, 0.0), 1.0), theta=theta, rho=arc.rho_deg,
               bound_fs=_clamped_bound(frac, bound_deg, span), turned=turned, r_ring=r_ring,
               needle_scores=nf.scores, needle_len=nf.length_px)
    return out


def _line_miss(shaft: ShaftFit, c) -> float:
    """How far (px) the shaft's fitted axis passes from the point ``c``."""
    a = math.radians(shaft.angle_deg)
    return abs((c[0] - shaft.point[0]) * math.cos(a) + (c[1] - shaft.point[1]) * math.sin(a))


def pivot_lever(arc: ArcFit, span: float, phi: float) -> float:
    """How much of a pivot's doubt (px / radius, in rad) reaches the reading, for a needle
    ``phi`` deg from the middle of the scale's arc.  The needle and the marks that turn the
    scale are all seen about the same pivot: moved by d, a mark at angle a seems turned by
    d x t(a) / r (t the ring's tangent), and the reading is the needle's angle less the
    turn, the marks' mean turn.  Its worst case over the direction of d is |m - u| d / r,
    with u the needle's unit vector and m the mean unit vector of the marks: the two end
    marks' (cos(span / 2) along the arc's middle), or the ticks' of a comb spread evenly
    over the arc (sin(s) / s, s = span / 2 in rad).  A short arc's marks move with the
    needle and cancel most of the doubt; a long one's (over 180 deg) move against a needle
    near its middle and add to it.  A comb that verified one end only keeps the whole doubt
    (1): its tooth may be a whole pitch out, which its stated error does not cover (a
    small, far `process` dial read one pitch, 1.9 % FS, off, where the lever had let it
    through); a comb a tooth out cannot verify both ends.  One end mark (its side unknown
    here): 1, as before."""
    if arc.ends < 2:
        return 1.0
    half = math.radians(span / 2.0)
    m = math.sin(half) / half if arc.method == "comb" else math.cos(half)
    p = math.radians(phi)
    return math.sqrt(max(m * m - 2.0 * m * math.cos(p) + 1.0, 0.0))


def _on_the_pin(arc: ArcFit, prof: GaugeProfile, theta: float) -> tuple[bool, str]:
    """Whether a needle at image angle ``theta``, below the minimum of the profile's arc
    turned by ``arc.rho_deg``, lies in the scale's gap (on the stop pin): the ring of marks
    the arc was placed by is bare from the minimum mark to the needle and on past it
    (:func:`.stop_pin.gap_is_bare`).  (bare, why not)."""
    if arc.ring is None:
        return False, "no ring of marks to see the gap on"
    e, seen = arc.ring
    start, span = _profile_arc(prof)
    level = mark_level(e, seen, start + arc.rho_deg, span)
    space = widest_space(e, seen, level, STEP, start + arc.rho_deg, span)
    return gap_is_bare(e, seen, level, STEP, prof.min_angle_deg + arc.rho_deg, theta,
                       -1.0 if prof.clockwise else 1.0, span, space)


def _clamped_bound(frac: float, bound_deg: float, span: float) -> float:
    """The reading's error bound (% FS) for a needle at ``frac`` of the scale whose angle
    against the scale is known within ``bound_deg``.  The reading is ``frac`` clamped to
    the scale (a needle beyond an end mark, on the stop pin, shows that end), and so is
    the truth: only the part of the angle's doubt that reaches inside the scale can make
    the reading wrong.  A needle resting a few degrees below the minimum mark reads the
    minimum however unsure its exact angle is; the evidence's own resolution (half a polar
    column) is kept as the least bound."""
    beyond = max(-frac, frac - 1.0, 0.0) * span  # deg outside the scale
    return 100.0 * max(bound_deg - beyond, STEP / 2.0) / span


def _candidate(out: dict, prof: GaugeProfile, theta: float, rho: float | None) -> None:
    """A refusal's best guess (``out["candidate_frac"]``): the needle at ``theta`` against
    the profile's arc turned by ``rho``, the turn the refused fit came nearest to.  It says
    what a refusal would have read, for benches that tell over-cautious refusals from
    sound ones; it is never returned as a reading."""
    if rho is not None:
        out["candidate_frac"] = _fraction(prof, theta, rho)


def _comb_arc(darkf: np.ndarray, thr: float, c, hidden, strip: np.ndarray, start: float,
              span: float):
    """(arc fit, centre, its standard error px) about the centre that makes the ticks an
    even comb (:mod:`.comb_centre`, started from ``c``) where it lies more than
    :data:`COMB_MOVES_PX` from ``c``, else None.  About a centre off the pivot by d a tick
    at angle a seems turned by d x t(a) / r (t the ring's tangent): the ticks bend by a sine
    of one period, which a long arc's comb cannot carry as a linear drift, while its two end
    marks, turned inward or outward together, still match the span.  The turn then rests
    on the end marks, and the centre's offset reaches the reading through
    :func:`pivot_lever` (up to twice its angle on a long arc).  The caller takes this fit
    where the arc was refused, or where the ticks form a comb about it (the arc's fit
    prefers a comb to the end marks wherever one is found); the comb's standard error then
    enters the pivot's doubt (:data:`CENTRE_SE_K`)."""
    comb = comb_centre(darkf, thr, c, FACE_RADIUS, hidden)
    if comb is None or math.hypot(comb[0][0] - c[0], comb[0][1] - c[1]) <= COMB_MOVES_PX:
        return None
    arc = fit_profile_arc([(darkf, thr)], comb[0], FACE_RADIUS, strip, start, span)
    if arc.rho_deg is None:
        return None
    return arc, comb[0], comb[1]


def _hub_arc(darkf: np.ndarray, res: dict, prof: GaugeProfile, crop: np.ndarray, hub,
             ring_c, start: float, span: float):
    """The dial's turn about the hub, where it was refused about the scale ring's centre:
    (arc fit, the two centres' disagreement across the gap's axis in px, the needle about
    the hub), or None.

    A ring of marks over a short arc, or of ticks whose major and minor ends lie at
    different radii, fixes its circle's centre poorly along the gap's axis (the centre
    slides with the radius there): both end marks then turn inward (or outward) together
    and miss the profile's span, although the pivot is plain to see.  The hub (the
    pointer's own circle, :mod:`.pointer`) is an estimate of the pivot that shares no step
    with the ring.  About it the end marks must both be found and match the profile's
    span, which verifies its place along the axis; across the axis, where a ring's fit is
    firm, the ring's centre must agree with it (:data:`CENTRES_AGREE_PX`), and their
    disagreement there enters the bound as the pivot's uncertainty."""
    if math.hypot(hub[0] - ring_c[0], hub[1] - ring_c[1]) > HUB_TRY_MAX_PX or \
            math.sin(math.radians(span / 2.0)) < MIN_END_LEVER:
        return None
    c = (float(hub[0]), float(hub[1]))
    nf = find_needle(crop, c, 0.8 * FACE_RADIUS, needle=prof.needle,
                     ignore_colour=prof.ignore_colour, straight_rivals=True)
    if not nf.ok:
        return None
    strip = _needle_strip(res["pmask"], nf.pivot_xy, nf.angle_deg, nf.tail_px)
    arc = fit_profile_arc([(darkf, res["otsu_t"])], c, FACE_RADIUS, strip, start, span)
    if arc.rho_deg is None or arc.ends < 2:
        return None
    mid = math.radians(start + span / 2.0 + arc.rho_deg)
    vx, vy = ring_c[0] - c[0], ring_c[1] - c[1]
    across = abs(vx * -math.cos(mid) - vy * math.sin(mid))
    if across > CENTRES_AGREE_PX:
        return None
    return arc, across, nf
