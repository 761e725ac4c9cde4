"""The full reading pipeline (seed 000 section 3 plus field robustness) -> :class:`Reading`."""

from __future__ import annotations

import logging
import math
import time
from dataclasses import asdict, dataclass, field

import cv2
import numpy as np

from .dial import (
    FACE_RADIUS,
    NORM_SIZE,
    DialEllipse,
    _median,
    face_radius,
    find_crop_rim,
    find_dial_candidates,
    is_head_on_crop,
    normalise_size,
    rectify,
    rectify_projective,
    rim_points_around,
)
from .geometry import (
    Line,
    choose_intersection,
    fit_circle,
    fit_line,
    line_circle_intersections,
    principal_axis,
)
from .otsu import binarize, otsu_threshold
from .profile import GaugeProfile, load_profile
from .scale import angle_diff, find_scale, ring_angle
from .thinning import zhang_suen

__all__ = ["Reading", "read_gauge", "MIN_CONFIDENCE"]

log = logging.getLogger(__name__)

MIN_CONFIDENCE = 0.5
_C = NORM_SIZE / 2.0
_YY, _XX = np.mgrid[0:NORM_SIZE, 0:NORM_SIZE].astype(np.float32)
_RR = np.hypot(_XX - _C, _YY - _C)
_FACE_MASK = (_RR < 0.94 * FACE_RADIUS).astype(np.uint8)
_CENTRE_ZONE = _RR < 0.2 * FACE_RADIUS
_cz_r, _cz_c = np.nonzero(_CENTRE_ZONE)
_CZ_BOX = (slice(int(_cz_r.min()), int(_cz_r.max()) + 1),
           slice(int(_cz_c.min()), int(_cz_c.max()) + 1))
_CZ_ZONE = _CENTRE_ZONE[_CZ_BOX]
_CZ_ZONE_FLAT = _CZ_ZONE.ravel()
_FACE_MASK255 = _FACE_MASK * np.uint8(255)
_LEVELS = np.arange(256, dtype=np.float32)
_BG_KERNEL = cv2.getStructuringElement(cv2.MORPH_RECT, (25, 25))
_K3 = np.ones((3, 3), np.uint8)
_IDENTITY_2X3 = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def _median_hist(h: np.ndarray) -> float:
    """Exact median of the values counted in a 256-bin histogram (as ``np.median``)."""
    c = np.cumsum(h)
    n = int(round(float(c[-1])))
    lo = int(np.searchsorted(c, (n - 1) // 2 + 1))
    hi = int(np.searchsorted(c, n // 2 + 1))
    return 0.5 * (lo + hi)


@dataclass
class Reading:
    """One gauge reading with its confidence and the geometry an overlay needs.

    All ``*_xy`` points and the ellipse are in the input image's pixel coordinates.
    ``value`` is None when the reading is refused; ``error`` then says why.
    """

    value: float | None
    unit: str
    confidence: float
    error: str | None = None
    raw_value: float | None = None  # the candidate value even when refused
    angle_deg: float | None = None  # pointer angle on the upright dial (profile convention)
    dial_ellipse: tuple[float, float, float, float, float] | None = None  # cx, cy, w, h, deg
    dial_centre_xy: tuple[float, float] | None = None  # hub centre
    dial_radius_px: float | None = None
    pointer_tip_xy: tuple[float, float] | None = None
    pointer_line_xy: tuple[tuple[float, float], tuple[float, float]] | None = None
    scale_ends_xy: tuple[tuple[float, float], tuple[float, float]] | None = None
    in_normal_band: bool | None = None
    scores: dict = field(default_factory=dict)
    elapsed_ms: float = 0.0
    # "scale" (found on the dial), "profile-angles", "calibrated", "calibrated-reference",
    # "keypoints" (the learned fallback, :mod:`.keypoints`)
    method: str = "scale"
    homography: list | None = None  # 3 x 3, reference frame -> this image (calibrated)

    @property
    def ok(self) -> bool:
        return self.value is not None

    def to_dict(self) -> dict:
        return asdict(self)


def _ramp(x: float, bad: float, good: float) -> float:
    """1 at ``good``, 0 at ``bad``, linear between (either order)."""
    if good == bad:
        return 1.0 if x == good else 0.0
    return float(min(1.0, max(0.0, (x - bad) / (good - bad))))


def dark_features(gray: np.ndarray) -> np.ndarray:
    """Darkness against the local face brightness, with veiling-glare compensation.

    The face brightness F is estimated by a max filter then a blur.  Glare on the glass acts
    as a veil, I = I0 (1 - a) + 255 a, which shrinks all contrast by (1 - a); with the face's
    unveiled brightness F0 (median over the dial) the loss is undone by the gain
    (255 - F0) / (255 - F), capped at 4.  The result feeds Otsu (eqs. 1-18).
    """
    bg = cv2.blur(cv2.dilate(gray, _BG_KERNEL), (15, 15))
    f0 = _median_hist(cv2.calcHist([bg], [0], _FACE_MASK, [256], [0, 256]).ravel()) \
        if bg.shape == _FACE_MASK.shape else float(np.median(bg[_FACE_MASK > 0]))
    # the gain depends on F alone (uint8): a 256-entry table instead of per-pixel division
    gain_lut = (257.0 - f0) / (257.0 - _LEVELS)
    np.clip(gain_lut, 1.0, 4.0, out=gain_lut)
    d = cv2.subtract(bg, gray).astype(np.float32)
    d *= cv2.LUT(bg, gain_lut)
    np.minimum(d, 255.0, out=d)  # d >= 0: the subtraction saturates at 0 and gain >= 1
    return d.astype(np.uint8)


def segment_pointer(binary: np.ndarray) -> np.ndarray | None:
    """Section 3.1: the largest contour inside the dial, here also required to reach the
    centre zone (where the pointer's hub is), so a long scale arc cannot win."""
    # only regions reaching the centre zone compete: each is flood-filled (8-connected) from
    # a seed in that zone and given its own label 1, 2, ... (254 at most), instead of
    # labelling every tick and numeral of the whole image
    work = binary.copy()
    zone = work[_CZ_BOX]
    best, best_area, label = 0, 0, 0
    while label < 254:
        hit = np.flatnonzero((zone.ravel() == 255) & _CZ_ZONE_FLAT)
        if len(hit) == 0:
            break
        label += 1
        y, x = divmod(int(hit[0]), zone.shape[1])
        area = cv2.floodFill(work, None, (x + _CZ_BOX[1].start, y + _CZ_BOX[0].start), label,
                             0, 0, 8)[0]
        if area > best_area:
            best, best_area = label, area
    if best == 0:
        return None
    return np.equal(work, best).view(np.uint8)  # bool -> 0/1 without a copy


def robust_pointer_line(pts: np.ndarray, hub) -> Line | None:
    """Eq. 19 on the skeleton, made robust to branches (arrow barbs, touching numerals).

    The most common axial direction of the skeleton seen from the hub seeds the fit; the
    axis through the hub is then narrowed to skeleton pixels within 2.5, 1.5 and 1 px of it
    (so a numeral or tick merged with the tip cannot pull it), and eq. 19 (orthogonal least
    squares) is fitted freely to the pixels that remain.
    """
    ang = np.degrees(np.arctan2(pts[:, 1] - hub[1], pts[:, 0] - hub[0])) % 180.0
    hist = np.bincount(ang.astype(int) % 180, minlength=180).astype(float)
    hist = hist + np.roll(hist, 1) + np.roll(hist, -1)
    a0 = math.radians(float(np.argmax(hist)) + 0.5)
    seed = Line((float(hub[0]), float(hub[1])), (math.cos(a0), math.sin(a0)))
    axis = _line_through(pts, hub, seed, bands=(4.0, 2.5, 1.5, 1.0))
    keep = axis.distance(pts) < 1.0
    if keep.sum() < 8:
        keep = axis.distance(pts) < 2.0
        if keep.sum() < 8:
            return None
    return fit_line(pts[keep])


def _line_through(pts: np.ndarray, centre, seed: Line, bands=(2.0, 1.5, 1.0)) -> Line:
    """Eq. 19 constrained through the hub centre: principal axis of the skeleton about it."""
    line = Line((float(centre[0]), float(centre[1])), seed.direction)
    c = np.asarray(centre, float)
    for band in bands:
        keep = line.distance(pts) < band
        if keep.sum() < 8:
            return line
        v = pts[keep] - c
        s = v.T @ v
        ux, uy, lam = principal_axis(float(s[0, 0]), float(s[0, 1]), float(s[1, 1]))
        rms = float(math.sqrt(lam / keep.sum()))
        line = Line((float(c[0]), float(c[1])), (ux, uy), rms)
    return line


def _refuse(unit, reason, scores=None, **kw) -> Reading:
    return Reading(value=None, unit=unit, confidence=0.0, error=reason, scores=scores or {}, **kw)


def read_normalised(norm_bgr: np.ndarray, prof: GaugeProfile) -> dict:
    """Steps 2-8 on the normalised dial crop; returns a dict of results in crop coordinates."""
    gray = cv2.cvtColor(norm_bgr, cv2.COLOR_BGR2GRAY) if norm_bgr.ndim == 3 else norm_bgr
    dark = dark_features(gray)
    t = max(otsu_threshold(dark, mask=_FACE_MASK), 12)  # eqs. 1-17
    binary = binarize(dark, t)  # eq. 18
    binary &= _FACE_MASK255
    pmask = segment_pointer(binary)
    if pmask is None:
        return {"error": "pointer not found"}
    # the pointer steps below work in the pointer's bounding box with 2 px of background
    # around it (the face mask keeps the pointer well inside the crop); point lists are
    # shifted back to crop coordinates
    bx, by, bw, bh = cv2.boundingRect(pmask)
    bx0, by0 = bx - 2, by - 2
    pbox = np.ascontiguousarray(pmask[by0:by + bh + 2, bx0:bx + bw + 2])
    # hub: thickest part of the pointer near the centre
    dt = np.zeros(pmask.shape, np.float32)
    dt[by0:by + bh + 2, bx0:bx + bw + 2] = cv2.distanceTransform(pbox, cv2.DIST_L2, 5)
    dz = np.where(_CZ_ZONE, dt[_CZ_BOX], 0)  # only the centre zone's bounding box
    hy, hx = np.unravel_index(int(np.argmax(dz)), dz.shape)
    hub_r0 = float(dz[hy, hx])
    hy, hx = hy + _CZ_BOX[0].start, hx + _CZ_BOX[1].start
    if hub_r0 < 2:
        return {"error": "pointer hub not found"}
    # erosion, then Zhang-Suen thinning
    allp = cv2.findNonZero(pbox).reshape(-1, 2) + np.array([bx0, by0], np.int32)
    reach = float(np.hypot(allp[:, 0] - hx, allp[:, 1] - hy).max())
    pts = None
    for erode in (True, False):
        er = cv2.erode(pbox, _K3) if erode else pbox.copy()
        # the hub's own skeleton is not used (only the shaft is), so it is not thinned either
        cv2.circle(er, (int(hx) - bx0, int(hy) - by0), int(1.3 * hub_r0), 0, -1)
        skel = zhang_suen(er)
        nz = cv2.findNonZero(skel)
        if nz is None:
            continue
        xs, ys = nz.reshape(-1, 2).T
        xs, ys = xs + bx0, ys + by0
        d_hub = np.hypot(xs - hx, ys - hy)
        sel = d_hub > 1.3 * hub_r0 + 2
        if sel.sum() >= 8:
            pts = np.column_stack([xs[sel], ys[sel]]).astype(float)
            # a thin needle loses its outer part to the erosion: then thin it uneroded
            if d_hub[sel].max() >= 0.75 * reach:
                break
    if pts is None:
        return {"error": "pointer too short"}
    line = robust_pointer_line(pts, (hx, hy))
    if line is None:
        return {"error": "pointer line not found"}
    skel_pts = pts
    pts = pts[line.distance(pts) < 1.5]
    # centre (m, n) from a circle fit of the hub's boundary (section 3.2)
    cnts, _ = cv2.findContours(pbox, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE,
                               offset=(bx0, by0))
    bpts = np.vstack([c.reshape(-1, 2) for c in cnts]).astype(float)
    half_w = _median(dt[pts[:, 1].astype(int), pts[:, 0].astype(int)])
    db = np.hypot(bpts[:, 0] - hx, bpts[:, 1] - hy)
    near = (np.abs(db - hub_r0) < 0.4 * hub_r0 + 1.5) & (line.distance(bpts) > half_w + 2.0)
    m, n, hub_r, hub_rms = float(hx), float(hy), hub_r0, 99.0
    if near.sum() >= 12:
        hp = bpts[near]
        cm, cn, cr, crms = fit_circle(hp)
        for _ in range(2):  # trim boundary points that are not on the hub's circle
            keep = np.abs(np.hypot(hp[:, 0] - cm, hp[:, 1] - cn) - cr) < max(1.0, 2 * crms)
            if keep.sum() < 12 or keep.all():
                break
            hp = hp[keep]
            cm, cn, cr, crms = fit_circle(hp)
        if math.hypot(cm - hx, cn - hy) < 0.5 * hub_r0 + 1 and 0.6 * hub_r0 < cr < 1.6 * hub_r0:
            m, n, hub_r, hub_rms = cm, cn, cr, crms
    centre = (m, n)
    free_dist = float(line.distance(centre)[0])
    if hub_rms < 1.5:
        # the pointer turns about its hub: refit the axis through (m, n), which keeps a numeral
        # or tick touching the shaft from tilting it; the free line's offset stays a check
        line = _line_through(skel_pts, centre, line)
    nz = allp
    pxs, pys = nz[:, 0], nz[:, 1]
    dp = np.hypot(pxs - m, pys - n)
    outer = dp > 1.5 * hub_r + 1
    if outer.sum() < 5:
        return {"error": "pointer too short"}
    mass = (float(pxs[outer].mean()), float(pys[outer].mean()))
    ux, uy = line.direction
    proj = (pxs - m) * ux + (pys - n) * uy
    side = 1.0 if (mass[0] - m) * ux + (mass[1] - n) * uy >= 0 else -1.0
    on_axis = line.distance(np.column_stack([pxs, pys])) < 3.0
    ti = int(np.argmax(np.where(on_axis, proj * side, -np.inf)))
    tip = (float(pxs[ti]), float(pys[ti]))
    tip_len = float(abs(proj[ti]))
    tip_angle = ring_angle(tip[0], tip[1], centre)
    # scale: tick marks and end marks
    sc, why = find_scale(dark, t, centre, FACE_RADIUS, pmask, tip_angle, prof.span_deg,
                         _table_model(prof))
    r_s = sc.radius if sc else 0.8 * FACE_RADIUS
    p = choose_intersection(line_circle_intersections(line, centre, r_s), centre, mass)
    if p is None:
        return {"error": "pointer line misses the scale circle"}
    theta = ring_angle(p[0], p[1], centre)
    out = {
        "centre": centre, "hub_r": hub_r, "hub_rms": hub_rms, "line": line, "tip": tip,
        "tip_len": tip_len, "point": p, "theta": theta, "scale": sc, "scale_error": why,
        "line_centre_dist": free_dist, "n_skel": int(len(pts)),
        "tip_angle": tip_angle, "r_s": r_s, "otsu_t": t,
    }
    if sc is None:
        out["error"] = why
        return out
    span_obs = sc.end_deg - sc.start_deg
    rel = (theta - sc.start_deg) % 360.0
    if rel > span_obs + (360.0 - span_obs) / 2:
        rel -= 360.0
    frac = rel / span_obs if prof.clockwise else 1.0 - rel / span_obs
    out["frac"] = frac
    out["span_obs"] = span_obs
    return out


def _table_model(prof: GaugeProfile) -> np.ndarray | None:
    """Tick angles of a tick-table profile, measured from its first tick along the scale."""
    if not prof.ticks:
        return None
    m, n = prof.table_centre
    a = np.array([math.atan2(x - m, -(y - n)) for _, x, y in prof.ticks])
    a = np.degrees(np.unwrap(a))
    return np.abs(a - a[0])


def read_gauge(image: np.ndarray, profile, *, min_confidence: float = MIN_CONFIDENCE,
               learned_fallback: bool = False) -> Reading:
    """Read a pointer gauge in a BGR (or grey) image: a dial crop or a whole camera frame.

    Returns a :class:`Reading`; when the confidence is below ``min_confidence`` the value
    is None and ``error`` holds the reason.  Never raises for bad image content.

    ``learned_fallback``: where the classical reader refuses, try the learned keypoints
    (:mod:`.keypoints`).  Off by default: on the benchmark's held-out style family it made
    a few confident readings 2-4 % FS off (docs/meter-bench.md), which breaks the first
    rule, so it is for a site that accepts that, not the default.
    """
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
    colour = image  # for the keypoint fallback, which looks at colour
    # the whole pipeline works on grey: one conversion here, and every resize and warp
    # after it moves one channel instead of three
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY)
    elif image.ndim == 3 and image.shape[2] == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    elif image.ndim == 3:
        image = np.ascontiguousarray(image[:, :, 0])
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
    if quick is not None:
        # fast path for a ready crop: its rim found on rays around the crop's face edge; kept
        # only if the hub agrees with it and the reading is accepted, otherwise the full
        # search runs
        norm, m_aff, r_aff = _affine_pass(base, quick, face_edge=True)
        res = read_normalised(norm, prof)
        if _hub_consistent(res):
            r = _finish((quick, norm, m_aff, r_aff, res), base, to_base, prof, min_confidence,
                        t0)
            if r.value is not None:
                return r
    cur = _full_search(base, crop_like, prof)
    if cur is None:
        r = _refuse(unit, "dial not found", elapsed_ms=_ms(t0))
    else:
        r = _finish(cur, base, to_base, prof, min_confidence, t0)
    if r.value is not None or not learned_fallback:
        return r
    return _keypoint_fallback(colour, prof, r, min_confidence, t0)


def _keypoint_fallback(image: np.ndarray, prof: GaugeProfile, refused: Reading,
                       min_confidence: float, t0: float) -> Reading:
    """Where the classical reader refuses: the learned keypoints (:mod:`.keypoints`), whose
    own checks decide; if they refuse too, the classical refusal stands, with their reason
    added."""
    from .keypoints import read_keypoints

    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    elif image.ndim == 3 and image.shape[2] != 3:
        image = np.ascontiguousarray(image[:, :, 0])
    kr = read_keypoints(image, prof, min_confidence=min_confidence, t0=t0)
    if kr.value is not None:
        return kr
    refused.error = f"{refused.error}; {kr.error}"
    refused.elapsed_ms = _ms(t0)
    return refused


def _finish(cur, base: np.ndarray, to_base: np.ndarray, prof: GaugeProfile,
            min_confidence: float, t0: float) -> Reading:
    """From the chosen rim and its first pass: the perspective pass for an oblique view,
    the confidence checks and the :class:`Reading` in input-image coordinates."""
    unit = prof.unit
    ell, norm, m_aff, r_aff, res = cur
    full = np.vstack([m_aff, [0, 0, 1.0]]) @ to_base  # input -> normalised crop
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
    if ("centre" in res and res["hub_rms"] < 1.5 and res["line_centre_dist"] < 2.0
            and min(ell.width, ell.height) < 0.985 * max(ell.width, ell.height)):
        # oblique view: second pass with the perspective removed around the found hub
        hm = np.vstack([m_aff, [0, 0, 1.0]])
        c_base = np.linalg.inv(hm) @ np.array([*res["centre"], 1.0])
        pr = rectify_projective(base, ell, c_base[:2] / c_base[2], r_aff)
        if pr is not None:
            norm2, h2 = pr
            res2 = read_normalised(norm2, prof)
            if "frac" in res2 and "frac" in res and \
                    abs(res["span_obs"] - prof.span_deg) < 0.01 * prof.span_deg:
                agree = abs(res2["frac"] - res["frac"])  # two clean passes must agree
            if "frac" in res2 or "frac" not in res:
                res, full = res2, h2 @ to_base
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
    if "frac" not in res:
        return _refuse(unit, res.get("error", "no reading"), scores, elapsed_ms=_ms(t0), **geo)
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
        error=None if ok else f"low confidence ({_REASONS.get(worst, worst)})", raw_value=raw,
        angle_deg=angle_up, in_normal_band=band if ok else None, scores=scores,
        elapsed_ms=_ms(t0), **geo,
    )


_REASONS = {
    "dial": "dial rim not clear",
    "pointer_length": "pointer not fully visible",
    "line_fit": "pointer is not a clean straight line",
    "line_through_hub": "pointer line misses the hub",
    "tip_agrees": "pointer tip and axis disagree",
    "scale_fit": "tick marks irregular",
    "scale_span": "scale arc does not match the profile",
    "ticks": "too few tick marks",
    "on_scale": "pointer outside the scale",
    "passes_agree": "affine and perspective corrections disagree",
    "ticks_seen": "most tick marks not visible",
    "hub_centred": "hub far from the dial rim's centre",
}


def _hub_consistent(res: dict) -> bool:
    """The hub lies where the rim says the dial's centre is (within 10 px of 300)."""
    return "centre" in res and math.hypot(res["centre"][0] - _C, res["centre"][1] - _C) <= 10


def _full_search(base: np.ndarray, crop_like: bool, prof: GaugeProfile):
    """Step 0 in full: up to three rim candidates, then a rim refitted around the hub.

    Returns (ellipse, normalised crop, affine map, radius, results) or None (no dial)."""
    cands = find_dial_candidates(base, min_fill=0.5 if crop_like else 0.22)
    if not cands:
        if not crop_like:
            return None
        bh, bw = base.shape[:2]
        cands = [DialEllipse(bw / 2.0, bh / 2.0, 0.9 * bw, 0.9 * bh, 0.0, 0.0)]
    first = None
    for ell in cands[:3]:
        norm, m_aff, r_aff = _affine_pass(base, ell)
        res = read_normalised(norm, prof)
        cur = (ell, norm, m_aff, r_aff, res)
        first = first or cur
        if _hub_consistent(res):
            return cur  # the hub is where this rim says the centre is: a consistent dial
    cur = first
    re = _rim_around_hub(base, first)
    if re is not None:
        norm, m_aff, r_aff = _affine_pass(base, re)
        res = read_normalised(norm, prof)
        if _hub_consistent(res):
            cur = (re, norm, m_aff, r_aff, res)
    return cur


def _rim_around_hub(base: np.ndarray, first) -> DialEllipse | None:
    """Re-fit the rim from rays cast out of the hub found in a first, inconsistent pass."""
    ell, norm, m_aff, _, res = first
    if "centre" not in res:
        return None
    pts = rim_points_around(_gray(norm), res["centre"])
    if len(pts) < 40:
        return None
    e = cv2.fitEllipse(pts)
    for _ in range(2):  # drop rays that hit a numeral, the pointer or glare
        (cx, cy), (w, h), ang = e
        t = math.radians(ang)
        dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
        xr = dx * math.cos(t) + dy * math.sin(t)
        yr = -dx * math.sin(t) + dy * math.cos(t)
        res_px = np.abs(np.hypot(xr / (w / 2), yr / (h / 2)) - 1.0) * (w + h) / 4
        keep = res_px < 2.0
        if keep.sum() < 30:
            return None
        pts = pts[keep]
        e = cv2.fitEllipse(pts)
    inv = cv2.invertAffineTransform(m_aff)
    back = cv2.transform(pts.reshape(-1, 1, 2), inv).reshape(-1, 2)
    (cx, cy), (w, h), ang = cv2.fitEllipse(back.astype(np.float32))
    return DialEllipse(cx, cy, w, h, ang, ell.support)


def _affine_pass(base: np.ndarray, ell: DialEllipse, face_edge: bool = False):
    """Affine rectification of the rim ellipse, rescaled so the face edge lands at 135 px.

    ``face_edge``: the ellipse was fitted to the face edge itself (the crop fast path), so
    the face already lands at 135 px and is not measured again; if that rim already is the
    normalised circle (:func:`is_head_on_crop`), the crop is used as it is, without a warp."""
    if face_edge and is_head_on_crop(ell, base.shape):
        return base, _IDENTITY_2X3, FACE_RADIUS
    norm, m_aff = rectify(base, ell)
    if face_edge:
        return norm, m_aff, FACE_RADIUS
    fr = face_radius(_gray(norm))
    r_aff = FACE_RADIUS
    if fr is not None and abs(fr - FACE_RADIUS) > 0.03 * FACE_RADIUS and \
            0.6 * FACE_RADIUS < fr < 1.12 * FACE_RADIUS:
        r_aff = FACE_RADIUS * FACE_RADIUS / fr
        norm, m_aff = rectify(base, ell, radius_out=r_aff)
    return norm, m_aff, r_aff


def _gray(img: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img


def _ms(t0: float) -> float:
    return round((time.perf_counter() - t0) * 1000.0, 3)


def _ellipse_in_input(ell: DialEllipse, to_base: np.ndarray):
    sx, sy = to_base[0, 0], to_base[1, 1]
    if abs(sx - sy) < 1e-9:
        return (ell.cx / sx, ell.cy / sy, ell.width / sx, ell.height / sy, ell.angle_deg)
    # anisotropic resize of a near-square crop: refit from sampled rim points
    t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    a, b = ell.width / 2, ell.height / 2
    ca, sa = math.cos(math.radians(ell.angle_deg)), math.sin(math.radians(ell.angle_deg))
    x = ell.cx + a * np.cos(t) * ca - b * np.sin(t) * sa
    y = ell.cy + a * np.cos(t) * sa + b * np.sin(t) * ca
    pts = np.column_stack([x / sx, y / sy]).astype(np.float32)
    (cx, cy), (w, h), ang = cv2.fitEllipse(pts)
    return (float(cx), float(cy), float(w), float(h), float(ang))


_ = Line  # re-exported type for annotations
