"""The full reading pipeline (seed 000 section 3 plus field robustness) -> :class:`Reading`.

Step 0 (where the dial is) lives in :mod:`.search`, steps 2-8 on the normalised crop in
:mod:`.pointer`; this module runs them, judges the result and builds the :class:`Reading`.
"""

from __future__ import annotations

import logging
import math
import time

import cv2
import numpy as np

from . import learned as _learned
from .angles import (
    BOUND_BAD,
    BOUND_GOOD,
    DARK_FACE_GREY,
    NEEDLES_AGREE_DEG,
    hub_is_perspective_centre,
    median_face_grey,
    read_by_angles,
)
from .denoise import quieten
from .dial import (
    FACE_RADIUS,
    NORM_SIZE,
    normalise_size,
    projective_homography,
    rectify_projective,
    same_warp,
)
from .hidden_root import pointer_about_ring
from .learned import crop_keypoints, keypoint_fallback, learned_once
from .other_dials import check_rival
from .pivot_checks import (
    HUB_FIRM_RMS_PX,
    hub_moved,
    negative_pass,
    scale_pivot_doubt,
    second_look_allowed,
)
from .pointer import CENTRE as _C
from .pointer import read_normalised
from .profile import GaugeProfile, load_profile
from .reading import MIN_CONFIDENCE, REASONS, Reading
from .reading import elapsed_ms as _ms
from .reading import ramp as _ramp
from .reading import refuse as _refuse
from .rim import find_crop_rim
from .rivals import erase_colour
from .scale import ARC_MISMATCH, angle_diff
from .scale_checks import needle_doubt, restored_ends, turned_scale
from .search import affine_pass as _affine_pass
from .search import ellipse_in_input as _ellipse_in_input
from .search import full_search as _full_search
from .search import hub_consistent, read_vote_rims, rim_pass
from .small_dial import read_small_dial
from .working_size import shrink, to_input

__all__ = ["Reading", "read_gauge", "MIN_CONFIDENCE"]

log = logging.getLogger(__name__)


def read_gauge(image: np.ndarray, profile, *, min_confidence: float = MIN_CONFIDENCE,
               learned_fallback: bool = True, learned_confirm: bool = False) -> Reading:
    """Read a pointer gauge in a BGR (or grey) image: a dial crop or a whole camera frame.

    Returns a :class:`Reading`; when the confidence is below ``min_confidence`` the value
    is None and ``error`` holds the reason.  Never raises for bad image content.

    Where the dial's own scale is not found (or is in doubt), the reading is made against
    the profile's angles about the pivot found (:mod:`.angles`, ``method="profile-angles"``),
    accepted only where independent estimates of the pivot, the needle and the dial's turn
    agree.

    ``learned_confirm``: let the learned keypoints (:mod:`.keypoints`) confirm what the
    classical estimates of the angles path leave open (a turn resting on one end mark, a
    needle the skeleton cannot confirm); they are never the only estimate.
    ``learned_fallback`` (on by default): that, and where everything classical refuses, the
    keypoints on their own, accepted only when the error bound they state (from the
    heatmaps' spread, two views' disagreement and the needle's fit) is under 2 % FS with
    margin.  On the project's generated gauges, unseen family included, it reads about a
    third more at field and hard level and made no confident wrong reading
    (docs/meter-bench.md); ``learned_fallback=False`` gives the classical reader alone.
    """
    learned = learned_confirm or learned_fallback
    t0 = time.perf_counter()
    prof = load_profile(profile)
    if prof.calibration is not None:  # a calibrated inspection point: read through it
        from .calibrated import read_calibrated

        return read_calibrated(image, prof, min_confidence=min_confidence)
    unit = prof.unit
    if not isinstance(image, np.ndarray) or image.ndim not in (2, 3) or image.size == 0 \
            or min(image.shape[:2]) < 32:
        return _refuse(unit, "not a usable image")
    if image.dtype != np.uint8:
        image = np.clip(image, 0, 255).astype(np.uint8)
    # a large photograph is read at the sizes the reader samples at (:mod:`.working_size`)
    small, k = shrink(image)
    frame: dict = {}
    r = _read_uncalibrated(small, prof, min_confidence, learned, learned_fallback, t0, frame)
    if r.value is None and "gray" in frame:
        # refused, and no rim found: a dial too small in the input for its search, cut
        # out of the input and read as a crop (:mod:`.small_dial`)
        def read_crop(crop: np.ndarray) -> Reading:
            c_small, c_k = shrink(crop)
            got = _read_uncalibrated(c_small, prof, min_confidence, learned, learned_fallback,
                                     t0)
            return to_input(got, c_k, crop.shape[:2])

        got = read_small_dial(image, frame["gray"], k, frame["larger"], read_crop,
                              frame["crop_like"])
        if got is not None:
            return got
    return to_input(r, k, image.shape[:2])


def _read_uncalibrated(image: np.ndarray, prof: GaugeProfile, min_confidence: float,
                       learned: bool, learned_fallback: bool, t0: float,
                       frame: dict | None = None) -> Reading:
    """:func:`read_gauge` on a uint8 image of a working size, with a profile that has no
    calibration.  ``frame`` (optional) receives the grey image searched (``"gray"``, before
    a crop's size normalisation), the rims its search found (``"larger"``) and whether it
    was taken for a crop (``"crop_like"``)."""
    unit = prof.unit
    colour = image  # for the keypoint fallback, which looks at colour
    # the whole pipeline works on grey: one conversion here, and every resize and warp
    # after it moves one channel instead of three
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY)
    elif image.ndim == 3 and image.shape[2] == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    elif image.ndim == 3:
        image = np.ascontiguousarray(image[:, :, 0])
    # a noisy camera's specks break the thin lines everything below follows: median
    # filtered where the image is measured to be noisy (:mod:`.denoise`)
    colour, image, _ = quieten(colour, image)
    if prof.ignore_colour and colour.ndim == 3 and colour.shape[2] >= 3:
        image = erase_colour(image, colour[:, :, :3], prof.ignore_colour)
    h, w = image.shape[:2]
    crop_like = abs(h - w) <= 0.12 * max(h, w)
    if crop_like and (h, w) != (NORM_SIZE, NORM_SIZE) and \
            max(h, w) <= 1.25 * NORM_SIZE and min(h, w) >= 0.9 * NORM_SIZE:
        # step 1 for a crop near 300 px: the rectifying warp below scales it to 300 x 300
        # anyway, so it is not resampled twice (the one warp is the size normalisation)
        base = image
        to_base = np.eye(3)
    elif crop_like:  # step 1: size normalisation
        base = normalise_size(image)
        to_base = np.array([[NORM_SIZE / w, 0, 0], [0, NORM_SIZE / h, 0], [0, 0, 1.0]])
    else:
        base = image
        to_base = np.eye(3)
    quick = find_crop_rim(base) if crop_like else None
    seen = r_seen = None  # the fast path's pass and its refusal
    # a crop's learned reading needs nothing of the classical paths (its keypoints look at
    # the whole crop): made at most once, it is asked before any classical retry
    learned_first = learned_once(colour, prof, min_confidence, t0) \
        if crop_like and learned_fallback and _learned.LEARNED_BEFORE_RETRIES else None
    if quick is not None:
        # fast path for a ready crop: its rim found on rays around the crop's face edge (a
        # tight ellipse all round it); its reading is kept if the checks of the reading
        # accept it (the hub's offset from the rim's centre among them), otherwise the full
        # search runs.  A hub off the rim's centre is not refused here: a dark face's hub
        # is found only in its negative, by the profile's angles, and an eccentric pivot
        # is the angles path's to judge
        norm, m_aff, r_aff = _affine_pass(base, quick, face_edge=True)
        seen = (quick, norm, m_aff, r_aff, read_normalised(norm, prof))
        r_seen = r = _finish(seen, base, to_base, prof, min_confidence, t0, colour, learned,
                             learned_first)
        if r.value is not None:
            return r
        # refused on the crop's own rim: the dial search's other views are a retry, made
        # only where the learned keypoints cannot read the crop either
        got = learned_first() if learned_first is not None else None
        if got is not None and got.value is not None:
            return got
    found: dict = {}  # the dial search's rims, which the keypoint fallback may reuse
    cur = _full_search(base, crop_like, prof, found, seen)
    if frame is not None:
        frame.update(gray=image, larger=found["dial_candidates"][2], crop_like=crop_like)
    if cur is None:
        r = _refuse(unit, "dial not found", elapsed_ms=_ms(t0))
    elif cur is seen:
        # the search's rim gives the view the fast path read (within
        # :data:`.search.SAME_VIEW_PX`): the same view resampled is no new evidence, and
        # reading it again would only give a borderline refusal a second draw
        r = r_seen
        r.elapsed_ms = _ms(t0)
    else:
        r = _finish(cur, base, to_base, prof, min_confidence, t0, colour, learned,
                    learned_first)
        if not crop_like:  # another gauge in the frame, as likely the one described
            r = check_rival(r, cur[0], found["dial_candidates"][2], base.shape,
                            lambda e: _finish(rim_pass(base, e, prof), base, to_base, prof,
                                              min_confidence, t0, colour, learned),
                            prof.full_scale)
    if r.value is None and cur is not None and not crop_like and not hub_consistent(cur[4]):
        # the rim chosen holds no pointer's hub at its centre: the circle vote's rims,
        # each read in full (:func:`.search.read_vote_rims`); in a whole frame only, where
        # a backdrop's straight edges can hide the dial's rim from the search (a crop is
        # the dial, and on crops the vote found no rim the search had missed)
        r = read_vote_rims(found, cur[0], lambda e: _finish(
            rim_pass(base, e, prof), base, to_base, prof, min_confidence, t0, colour,
            learned)) or r
    if r.value is not None or not learned_fallback:
        return r
    return keypoint_fallback(colour, prof, r, min_confidence, t0,
                             found.get("dial_candidates"), learned_first)



SCALE_AGREE_FS = 0.01  # the scale path and the profile's angles agree within 1 % FS
SCALE_SURE_FS = 0.005  # tick positions off their uniform fit by this share of the span


def _finish(cur, base: np.ndarray, to_base: np.ndarray, prof: GaugeProfile,
            min_confidence: float, t0: float, colour: np.ndarray | None = None,
            learned: bool = False, learned_first=None) -> Reading:
    """From the chosen rim and its first pass: the perspective pass for an oblique view,
    the confidence checks and the :class:`Reading` in input-image coordinates.
    ``learned_first`` (a crop's, :func:`.learned.learned_once`): asked before the second look
    about the scale ring's centre, a retry; its reading, if any, is returned instead."""
    unit = prof.unit
    ell, norm, m_aff, r_aff, res = cur
    crop = norm
    full = np.vstack([m_aff, [0, 0, 1.0]]) @ to_base  # input -> normalised crop
    if "centre" not in res and learned and median_face_grey(norm) >= DARK_FACE_GREY:
        # no hub placed: a needle's root hidden at the hub (:mod:`.hidden_root`)
        res = pointer_about_ring(norm, prof, res, crop_keypoints(colour, full,
                                                                 not prof.clockwise))
    inv = np.linalg.inv(full)

    def back(p):
        v = inv @ np.array([p[0], p[1], 1.0])
        return (float(v[0] / v[2]), float(v[1] / v[2]))

    ell_in = _ellipse_in_input(ell, to_base)
    agree = None
    # the hub sits near the rim ellipse's centre (perspective shifts it only a little); far off
    # means the "rim" was something else
    hub_offset = math.hypot(res["centre"][0] - _C, res["centre"][1] - _C) if "centre" in res \
        else None
    if ("centre" in res and res["hub_rms"] < HUB_FIRM_RMS_PX and res["line_centre_dist"] < 2.0
            and min(ell.width, ell.height) < 0.985 * max(ell.width, ell.height)
            and ("dark" not in res or hub_is_perspective_centre(res, r_aff))):
        # oblique view: second pass with the perspective removed around the found hub, if
        # the scale ring does not say the hub is something else (rectified about a wrong
        # hub, the ring would be concentric with it, and the angles path's check of the
        # pivot against the ring's centre could no longer fail)
        hm = np.vstack([m_aff, [0, 0, 1.0]])
        c_base = np.linalg.inv(hm) @ np.array([*res["centre"], 1.0])
        pr = rectify_projective(base, ell, c_base[:2] / c_base[2], r_aff)
        if pr is not None:
            norm2, h2 = pr
            res2 = read_normalised(norm2, prof)
        if pr is not None and not hub_moved(res2):
            if "frac" in res2 and "frac" in res and \
                    abs(res["span_obs"] - prof.span_deg) < 0.01 * prof.span_deg:
                agree = abs(res2["frac"] - res["frac"])  # two clean passes must agree
            if "frac" in res2 or ("frac" not in res and "centre" in res2):
                res, full, crop = res2, h2 @ to_base, norm2
                inv = np.linalg.inv(full)
    scores: dict[str, float] = {"dial": _ramp(ell.support, 0.35, 0.65) if ell.support else 0.7}
    geo = {"dial_ellipse": ell_in}
    if "centre" in res:
        c = res["centre"]
        lp = res["line"]
        ux, uy = lp.direction
        geo.update(
            dial_centre_xy=back(c),
            dial_radius_px=float(FACE_RADIUS / math.sqrt(abs(np.linalg.det(full[:2, :2])))),
            pointer_tip_xy=back(res["tip"]),
            pointer_line_xy=(back(c), back(res["point"])),
        )
        del ux, uy
    oblique = min(ell.width, ell.height) < 0.985 * max(ell.width, ell.height)
    negative = negative_pass(crop, prof)  # (a dark face's, read once by the steps below)
    if "frac" in res:
        r = _scale_reading(res, prof, dict(scores), geo, back, hub_offset, agree,
                           min_confidence, t0)
        if r.value is not None:
            doubt = needle_doubt(res, crop, prof) or scale_pivot_doubt(res)
            sc = res["scale"]
            restored = restored_ends(res["theta"], sc) or turned_scale(sc, prof)
            sure = (sc.residual_deg / res["span_obs"] <= SCALE_SURE_FS
                    and r.scores.get("scale_span", 1.0) >= 1.0 and restored is None)
            if doubt is None and sure:
                return r
            # the scale path's needle, its ticks (their fit's rms over 0.5 % of the span) or
            # its span (over 1 % off the profile's) is in doubt: the profile's angles must
            # confirm it
            ra = _angles_reading(res, crop, full, prof, colour, scores, geo, min_confidence,
                                 t0, learned, negative)
            ra.scores.pop("_centre", None)
            if ra.scores.pop("_span_centre", None) is not None and oblique:
                ra = _unlooked(unit, ra)  # (no second look here: see below)
            if ra.value is not None and doubt is None and \
                    abs(ra.value - r.value) <= SCALE_AGREE_FS * prof.full_scale:
                return r
            if ra.value is not None and doubt is not None:
                return ra
            # the reason that decided comes first: the profile's angles' refusal, or their
            # disagreement with the scale; what put the scale in doubt follows it
            doubted = doubt or restored or "the scale found is irregular or off the " \
                "profile's span"
            if ra.value is None:
                why = _deciding_first(f"profile angles: {ra.error}", doubted)
            else:
                why = _deciding_first("the scale found and the profile's angles disagree",
                                      doubt or restored)
            raw = ra.raw_value if ra.value is None and ra.raw_value is not None else r.raw_value
            r = _refuse(unit, why, r.scores, raw_value=raw, elapsed_ms=_ms(t0), **geo)
            return r
    else:
        r = _refuse(unit, res.get("error", "no reading"), scores, elapsed_ms=_ms(t0), **geo)
    if r.value is not None or ("dark" not in res and median_face_grey(crop) >= DARK_FACE_GREY):
        # (a dark face's pointer is light: where its first pass found none, the profile's
        # angles still read its negative)
        return r
    if oblique and learned_first is not None and _learned.FORESEE_ARC_REFUSAL and \
            str(res.get("scale_error")).startswith(ARC_MISMATCH):
        # an oblique view whose ticks span another arc than the profile's: the profile's
        # angles refuse most of these (26 of 36 crops of the tuning rows, seeds 1-3), so
        # the learned keypoints read it first, and the profile's angles only where they
        # refuse (a refusal foreseen, docs/meter-bench.md)
        got = learned_first()
        if got.value is not None:
            return got
    # the dial's own scale was not (fully) found: the profile's angles about the pivot found
    ra = _angles_reading(res, crop, full, prof, colour, scores, geo, min_confidence, t0,
                         learned, negative)
    c = ra.scores.pop("_centre", None)
    moved = ra.scores.pop("_span_centre", None)
    # read about the pivot on the needle's line (:mod:`.span_pivot`) in a view still
    # oblique: the perspective left about that pivot bends the scale's middle against its
    # ends, which no part of the bound carries, so the second look, with the perspective
    # removed about that pivot, decides (read there, or refused)
    held = moved is not None and oblique and ra.value is not None
    c = moved if moved is not None and oblique else c
    if ra.value is None and oblique and c is not None and learned_first is not None:
        got = learned_first()  # the retry below only where the learned keypoints refuse
        if got.value is not None:
            return got
    if (ra.value is None or held) and oblique and c is not None:
        # a second look with the perspective removed about the pivot the scale ring gave
        crop_to_base = to_base @ np.linalg.inv(full)
        cb = crop_to_base @ np.array([c[0], c[1], 1.0])
        cb = cb[:2] / cb[2]
        # (not when that warp is the crop's own, within dial.SAME_WARP_PX: the pivot the
        # ring gave is the point the crop was rectified about, or the rim's centre of an
        # affine crop, then no oblique view to the ring; the same crop, read again, would
        # give the same refusal)
        h_cb = projective_homography(ell, cb, r_aff)
        same = h_cb is not None and same_warp(h_cb @ to_base, full)
        held = held and not same  # (the crop is that view already)
        # (and not about a point that a ring of marks says is not the dial's centre: the
        # warp would make the scale concentric with it, and the second look's own checks
        # of the pivot could no longer fail, see :func:`.pivot_checks.second_look_allowed`)
        allowed = same or second_look_allowed(res, crop, prof, c, r_aff, negative)
        if not allowed and ra.value is None:
            ra.error = f"{ra.error} (no second look about the scale ring's centre: " \
                "another ring of marks says it is not the dial's centre)"
        pr = None if same or not allowed else rectify_projective(base, ell, cb, r_aff)
        if pr is not None:
            norm2, h2 = pr
            res2 = read_normalised(norm2, prof)
            if "dark" in res2:
                ra2 = _angles_reading(res2, norm2, h2 @ to_base, prof, colour, scores, geo,
                                      min_confidence, t0, learned)
                ra2.scores.pop("_centre", None)
                ra2.scores.pop("_span_centre", None)
                if ra2.value is not None:
                    return ra2
    if held:
        ra = _unlooked(unit, ra)
    if ra.value is not None:
        return ra
    # the profile's angles were the last path tried, so their reason decided the refusal
    r.error = _deciding_first(f"profile angles: {ra.error}", r.error)
    if ra.raw_value is not None:  # the deciding path's candidate, and its stated bound
        r.raw_value, r.error_bound_fs = ra.raw_value, ra.error_bound_fs
    return r


def _unlooked(unit: str, ra: Reading) -> Reading:
    """The refusal of a reading about the pivot on the needle's line (:mod:`.span_pivot`) in
    an oblique view that no second look, with the perspective removed about that pivot,
    has read (see :func:`_finish`)."""
    return _refuse(unit, "read about the pivot on the needle's line, not with the "
                   "perspective removed about it", ra.scores, raw_value=ra.raw_value,
                   error_bound_fs=ra.error_bound_fs, method="profile-angles")


def _deciding_first(deciding: str, earlier: str | None) -> str:
    """A refusal's message: the reason that decided it first (an operator, or a tally of
    reasons, reads the first one), then the reasons of the paths tried before it."""
    return f"{deciding}; also: {earlier}" if earlier else deciding


def _angles_reading(res: dict, crop: np.ndarray, full: np.ndarray, prof: GaugeProfile,
                    colour, scores: dict, geo: dict, min_confidence: float,
                    t0: float, learned: bool = False, negative=None) -> Reading:
    """The reading against the profile's angles (:mod:`.angles`) on one normalised crop
    (``full``: input image -> crop), with the pointer checks of the scale path and the ones
    that say what was verified: the needle finders' agreement and the error bound left by
    the dial's turn.  A dark face's marks are light: its negative is read, where they are
    dark (``negative``: the caller's :func:`.pivot_checks.negative_pass` of ``crop``, which
    the second look's check reads too).  The pivot found, if any, rides in
    ``scores["_centre"]`` of a refusal."""
    if median_face_grey(crop) < DARK_FACE_GREY:
        neg = (negative or negative_pass(crop, prof))()
        if "dark" not in neg:
            return _refuse(prof.unit, f"(dark face) {neg.get('error')}", dict(scores),
                           elapsed_ms=_ms(t0), method="profile-angles", **geo)
        res = neg
    if prof.ignore_colour and colour is not None:
        crop = cv2.warpPerspective(colour, full, (NORM_SIZE, NORM_SIZE), flags=cv2.INTER_LINEAR,
                                   borderMode=cv2.BORDER_REPLICATE)
    inv = np.linalg.inv(full)

    def back(p):
        v = inv @ np.array([p[0], p[1], 1.0])
        return (float(v[0] / v[2]), float(v[1] / v[2]))

    unit = prof.unit
    kp = (res.get("keypoints") or crop_keypoints(colour, full, not prof.clockwise)) \
        if learned else None
    out = read_by_angles(res, prof, crop, kp)
    if "error" in out:
        sc = dict(scores)
        if "centre" in out:
            sc["_centre"] = out["centre"]
        cand = out.get("candidate_frac")
        raw = prof.value_at_fraction(min(max(cand, 0.0), 1.0)) if cand is not None else None
        return _refuse(unit, out["error"], sc, elapsed_ms=_ms(t0), method="profile-angles",
                       raw_value=raw, **geo)
    scores = dict(scores)
    c, r_ring, theta = out["centre"], out["r_ring"], out["theta"]
    scores["pointer_length"] = _ramp(out["needle_len"] / r_ring, 0.55, 0.8)
    scores["line_fit"] = _ramp(res["line"].rms, 1.8, 0.8)
    scores["line_through_hub"] = _ramp(res["line_centre_dist"], 8.0, 3.0)
    scores["hub_centred"] = _ramp(math.hypot(c[0] - _C, c[1] - _C), 16.0, 10.0)
    for k in ("needle_unique", "tip_vs_tail"):
        scores[k] = float(out["needle_scores"].get(k, 1.0))
    scores["needles_agree"] = _ramp(abs(out["needle_diff_deg"]), NEEDLES_AGREE_DEG,
                                    0.5 * NEEDLES_AGREE_DEG)
    scores["error_bound"] = _ramp(out["bound_fs"], BOUND_BAD, BOUND_GOOD)
    if "stop_pin" in out:  # far below the minimum, in a bare gap: on the stop pin, surely?
        scores["stop_pin"] = out["stop_pin"]

    def ring_xy(a):
        return back((c[0] + r_ring * math.sin(math.radians(a)),
                     c[1] - r_ring * math.cos(math.radians(a))))

    geo = dict(geo, scale_ends_xy=(ring_xy(out["turned"][0]), ring_xy(out["turned"][1])),
               pointer_line_xy=(back(c), ring_xy(theta)), dial_centre_xy=back(c),
               pointer_tip_xy=ring_xy(theta))
    frac = out["frac"]
    raw = prof.value_at_fraction(frac)
    conf = float(np.prod(list(scores.values())))
    worst = min(scores, key=scores.get)
    ok = conf >= min_confidence
    if "span_pivot_px" in out:
        scores["_span_centre"] = out["centre"]
    return Reading(
        value=float(raw) if ok else None, unit=unit, confidence=round(conf, 4),
        error=None if ok else f"low confidence ({REASONS.get(worst, worst)})", raw_value=raw,
        angle_deg=prof.min_angle_deg + frac * (prof.max_angle_deg - prof.min_angle_deg),
        in_normal_band=prof.in_normal_band(raw) if ok else None, scores=scores,
        elapsed_ms=_ms(t0), method="profile-angles", error_bound_fs=round(out["bound_fs"], 4),
        **geo)


def _scale_reading(res: dict, prof: GaugeProfile, scores: dict, geo: dict, back, hub_offset,
                   agree, min_confidence: float, t0: float) -> Reading:
    """The reading against the scale found on the dial (its end marks)."""
    unit = prof.unit
    geo = dict(geo)
    sc = res["scale"]
    c = res["centre"]

    def ring_xy(a):
        r = res["r_s"]
        return back((c[0] + r * math.sin(math.radians(a)), c[1] - r * math.cos(math.radians(a))))

    geo["scale_ends_xy"] = (ring_xy(sc.start_deg), ring_xy(sc.end_deg))
    frac = res["frac"]
    r_s = res["r_s"]
    scores["pointer_length"] = _ramp(res["tip_len"] / r_s, 0.55, 0.8)
    scores["line_fit"] = _ramp(res["line"].rms, 1.8, 0.8)
    scores["line_through_hub"] = _ramp(res["line_centre_dist"], 8.0, 3.0)
    scores["tip_agrees"] = _ramp(abs(angle_diff(res["tip_angle"], res["theta"])), 4.0, 1.5)
    scores["scale_fit"] = min(_ramp(sc.residual_deg / sc.step_deg, 0.25, 0.12),
                              _ramp(sc.residual_deg, 1.6, 0.8))
    scores["scale_span"] = _ramp(abs(res["span_obs"] - prof.span_deg) / prof.span_deg, 0.03, 0.01)
    scores["ticks"] = _ramp(sc.n_ticks, 5, 12)
    expected = (sc.end_deg - sc.start_deg) / sc.step_deg + 1.0
    scores["ticks_seen"] = _ramp(sc.n_ticks / expected, 0.3, 0.5)
    if hub_offset is not None:
        scores["hub_centred"] = _ramp(hub_offset, 16.0, 10.0)
    scores["on_scale"] = _ramp(max(-frac, frac - 1.0), 0.03, 0.01)
    if agree is not None:
        scores["passes_agree"] = _ramp(agree, 0.015, 0.006)
    raw = prof.value_at_fraction(frac)
    angle_up = prof.min_angle_deg + min(max(frac, 0.0), 1.0) * (
        prof.max_angle_deg - prof.min_angle_deg)
    # several weak signals together weigh more than one: the product of the checks
    conf = float(np.prod(list(scores.values())))
    worst = min(scores, key=scores.get)
    band = prof.in_normal_band(raw)
    ok = conf >= min_confidence
    return Reading(
        value=float(raw) if ok else None, unit=unit, confidence=round(conf, 4),
        error=None if ok else f"low confidence ({REASONS.get(worst, worst)})", raw_value=raw,
        angle_deg=angle_up, in_normal_band=band if ok else None, scores=scores,
        elapsed_ms=_ms(t0), **geo,
    )

