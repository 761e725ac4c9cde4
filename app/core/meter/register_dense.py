"""Registration of a plain dial by its pixels, where keypoints are too few.

A dial with a bare face (ticks, a logo, no numerals) gives ORB a few dozen corners at
most, and :func:`.register.register` refuses it.  Its pixels still fix the warp: the
bezel, the hub, the ticks and the print are all in place.  This module registers the dial
region of the reference frame to the new frame by intensity:

1. **A coarse start.**  The reference's dial region (a square around the pivot out to
   ``REGION`` times the scale ring's radius, with the reference's needle and the other
   needle-like lines (:func:`.rivals.candidate_angles`) painted over with the face around
   them, ``cv2.inpaint``), shrunk so the ring is ``COARSE_R`` px, is
   found in the shrunk frame near where the dial was (``cv2.matchTemplate``, normalised
   correlation, over zooms of +-``ZOOM``): a scale and a shift.
2. **ECC.**  From that start, the enhanced correlation coefficient (Evangelidis and
   Psarakis, "Parametric image alignment using enhanced correlation coefficient
   maximization", PAMI 2008, eq. 3: the correlation of the zero-mean, unit-norm template
   and warped image vectors, invariant to the lighting's gain and offset) is maximised over
   an affine warp on the coarse level, then over a homography on the full-size dial region
   (``cv2.findTransformECC``).
3. **Acceptance.**  A periodic face (equal ticks all round) has false optima one tick
   apart, and a needle that moved is a region the warp cannot explain, so the coefficient
   alone is not trusted.  The warp is kept only when (a) the coefficient over the dial is at
   least ``MIN_ECC``, (b) it is a plausible re-visit (:func:`.register.implausible`), and
   (c) each calibrated end mark and the hub, as small patches of the reference, sit in
   the warped frame where the warp puts them: their own best shift (normalised correlation
   over +-``LOCAL_PX``) is below ``MAX_LOCAL_PX`` with a correlation of at least
   ``MIN_LOCAL_NCC``, and the patch has print on it to correlate (a blank patch proves
   nothing).  An end-mark patch reaches past the scale's end, where no tick follows, so a
   warp one tick off does not pass.  A patch that fails is looked at once more with a
   glare streak across it, in either image, left out of both (:mod:`.glare_streak`).
   Anything else is a refusal with its reason.

The same ECC also polishes a keypoint warp (:func:`polish`): started there, on one level,
and kept only where the dial's picture agrees as well as (a) asks.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import cv2
import numpy as np

from .glare_streak import drop_along_arc, streak_mask
from .needle import find_needle
from .register import Registration, carry_points, implausible, reference_image
from .rivals import candidate_angles

__all__ = ["MIN_ECC", "check_landmarks", "dense_register", "landmark_offsets", "needle_mask",
           "polish"]

log = logging.getLogger(__name__)

REGION = 1.3  # the dial region: out to this times the scale ring's radius
SEARCH = 1.8  # the coarse search: this far around the reference position (region's size)
COARSE_R = 36.0  # the scale ring's radius on the coarse level, px
FINE_R = 70.0  # ... and on the fine level (at most the full size)
POLISH_R = 50.0  # a keypoint warp is polished with the ring this large (px) ...
POLISH_ITERS = 10  # ... in this many ECC steps from the keypoints' start
ZOOM = (0.92, 1.0, 1.08)  # zooms tried by the coarse search
MIN_COARSE = 0.25  # normalised correlation of the coarse match
MIN_ECC = 0.8  # the enhanced correlation coefficient over the dial region it explains
MIN_EXPLAINED = 0.7  # ... which is at least this share of it
OUTLIER = 3.0  # robust standard deviations of a pixel the warp does not explain
PATCH = 0.28  # half-size of a landmark patch, in units of the ring's radius (at least 9 px)
LOCAL_PX = 4  # a landmark's own best shift is looked for this far
MAX_LOCAL_PX = 1.0  # ... and must be this small
MIN_LOCAL_NCC = 0.7  # ... with this correlation
# A mark found a little farther off, clearly (correlation FIX_NCC), is where the warp is a
# little off: the mark is taken where it was found. Under half a scale division of fine
# ticks (about 0.05 R apart), so a warp one division off is never mended into a reading.
FIX_PX = 2.5
FIX_R = 0.02  # ... and at most this share of the ring's radius
FIX_NCC = 0.8
# a patch with a glare streak left out must still pin the mark along the scale: its
# correlation this far either way along the arc (px) this much below the peak
ALONG_PX = 3
ALONG_DROP = 0.2
MIN_PATCH_STD = 4.0  # grey levels of fine print: a patch with less proves nothing
DETAIL_PX = 3.0  # the fine print: finer than this blur
INWARD_STEPS = 2  # a hidden end mark's patch is moved inward along the scale this often
MIN_VALID = 0.5  # share of a patch that must be clear of the frame's needle
HIGH_PASS = 0.5  # the lighting: blur over this share of the ring's radius
NEEDLE_HW = 0.05  # half-width of the reference needle painted over (units of R, + 3 px)
# A needle's line is hidden out to this (units of R) however short its fit: a hairline or a
# spade tip past where the fit ends still covers an end mark's patch (1 + PATCH out,
# diagonally a little more) when the needle points at the mark
NEEDLE_REACH = 1.0 + 1.5 * PATCH

_TEMPLATES: dict[tuple, list] = {}


def _template(cal, dense: bool = False) -> list | None:
    """[the reference's fine print (:func:`_detail`, float32), the dial region's top-left
    corner, the region's print (:func:`_print`) with the needle-like lines painted over
    (made only when ``dense`` asks for it, else possibly None), the reference's pixels
    clear of those lines (bool), the region's mask of them and the region's grey]; cached
    per file, mtime and clicks.  None when the region leaves the reference."""
    path = Path(cal.image_path)
    st = path.stat()
    key = (path, st.st_mtime_ns, st.st_size, cal.center, cal.min_point, cal.max_point)
    hit = _TEMPLATES.get(key)
    R = cal.radius_px
    if hit is None:
        ref = reference_image(path)
        cx, cy = cal.center
        half = int(math.ceil(REGION * R))
        x0, y0 = int(round(cx)) - half, int(round(cy)) - half
        hgt, wid = ref.shape[:2]
        if x0 < 0 or y0 < 0 or x0 + 2 * half + 1 > wid or y0 + 2 * half + 1 > hgt:
            return None
        # the needle moves between frames: it is not part of the dial's picture, nor are
        # the other needle-like lines (which of them is the needle is not decided here)
        mask = needle_mask(ref.shape, find_needle(ref, cal.center, R), R)
        for a in candidate_angles(ref, cal.center, R):
            t = math.radians(a)
            ux, uy = math.sin(t), -math.cos(t)
            ends = [(int(round(cx + ux * r)), int(round(cy + uy * r)))
                    for r in (-0.5 * R, 1.08 * R)]
            cv2.line(mask, ends[0], ends[1], 255, max(3, int(round(2 * (NEEDLE_HW * R + 3.0)))))
        region = (slice(y0, y0 + 2 * half + 1), slice(x0, x0 + 2 * half + 1))
        if len(_TEMPLATES) > 32:
            _TEMPLATES.clear()
        hit = _TEMPLATES[key] = [_detail(ref), (x0, y0), None, mask == 0, mask[region],
                                 ref[region]]
    if dense and hit[2] is None:
        crop, mask = hit[5], hit[4]
        hit[2] = _print(cv2.inpaint(crop, mask, 3, cv2.INPAINT_TELEA) if mask.any() else crop,
                        R)
    return hit


def _detail(gray: np.ndarray) -> np.ndarray:
    """The fine print alone (ticks, numerals' strokes): the grey less its blur over
    ``DETAIL_PX``; a broad glare streak over an end mark is gone from it."""
    g = gray.astype(np.float32)
    return g - cv2.GaussianBlur(g, (0, 0), DETAIL_PX)


def _print(gray: np.ndarray, radius: float) -> np.ndarray:
    """The print without the lighting: the grey less its blur over a tenth of the dial
    (float32), so that a light falling from elsewhere does not move the alignment."""
    g = gray.astype(np.float32)
    sigma = max(2.0, HIGH_PASS * radius)
    k = min(1.0, 4.0 / sigma)  # a wide blur is as good on a shrunk image, and cheaper
    small = cv2.resize(g, None, fx=k, fy=k, interpolation=cv2.INTER_AREA)
    blur = cv2.resize(cv2.GaussianBlur(small, (0, 0), sigma * k), (g.shape[1], g.shape[0]),
                      interpolation=cv2.INTER_LINEAR)
    return g - blur


def _shift(tx: float, ty: float) -> np.ndarray:
    return np.array([[1.0, 0.0, tx], [0.0, 1.0, ty], [0.0, 0.0, 1.0]])


def _coarse(tmpl: np.ndarray, frame: np.ndarray, k: float):
    """(score, 3 x 3 warp of template pixels to frame pixels) of the best match of the
    template in the frame, both shrunk by ``k``, over the zooms ``ZOOM``."""
    win = cv2.resize(frame, None, fx=k, fy=k, interpolation=cv2.INTER_AREA)
    n = tmpl.shape[0]
    best = (-1.0, None)
    for z in ZOOM:
        kz = k * z
        m = max(8, int(round(n * kz)))
        t = cv2.resize(tmpl, (m, m), interpolation=cv2.INTER_AREA)
        if win.shape[0] <= m or win.shape[1] <= m:
            continue
        res = cv2.matchTemplate(win, t, cv2.TM_CCOEFF_NORMED)
        _, v, _, loc = cv2.minMaxLoc(res)
        if v > best[0]:
            s = m / n / k  # template px -> frame px
            best = (float(v), np.array([[s, 0.0, loc[0] / k], [0.0, s, loc[1] / k],
                                        [0.0, 0.0, 1.0]]))
    return best


def _level(tmpl: np.ndarray, frame: np.ndarray, k: float):
    """Template and frame shrunk by about ``k`` (the template to a whole size), and the
    scaling matrix from full-size to this level's pixels (the same for both)."""
    if k >= 1.0:
        return tmpl, frame, np.eye(3)
    m = max(8, int(round(tmpl.shape[0] * k)))
    kt = m / tmpl.shape[0]
    t = cv2.resize(tmpl, (m, m), interpolation=cv2.INTER_AREA)
    f = cv2.resize(frame, None, fx=kt, fy=kt, interpolation=cv2.INTER_AREA)
    return t, f, np.diag([kt, kt, 1.0])


def _ecc(tmpl, frame, warp, motion, iters: int, mask=None) -> tuple[float, np.ndarray] | None:
    """ECC from ``warp`` (template -> frame, 3 x 3); ``mask``: the frame's valid pixels."""
    w = warp.astype(np.float32) if motion == cv2.MOTION_HOMOGRAPHY \
        else warp[:2].astype(np.float32)
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, iters, 1e-4)
    try:
        cc, w = cv2.findTransformECC(tmpl, frame, w, motion, crit, mask, 3)
    except cv2.error as e:  # no convergence
        log.debug("ECC did not converge: %s", str(e).splitlines()[-1][:80])
        return None
    out = np.eye(3)
    out[: w.shape[0]] = w
    return float(cc), out


def needle_mask(shape, fit, radius: float) -> np.ndarray:
    """A mask (uint8, 255 = hidden) of a found needle's pixels with room beside them: its
    line from the tail's end to the tip, and on out to ``NEEDLE_REACH`` of the radius (the
    fit may end short of a thin or spade tip), ``NEEDLE_HW`` of the radius (+3 px) either
    side."""
    mask = np.zeros(shape[:2], np.uint8)
    if fit is None or not fit.ok:
        return mask
    hw = max(NEEDLE_HW * radius + 3.0, 0.5 * fit.width_px + 3.0)
    t = math.radians(fit.angle_deg)
    ux, uy = math.sin(t), -math.cos(t)
    px, py = fit.pivot_xy
    a = (px - ux * (fit.tail_px + 3.0), py - uy * (fit.tail_px + 3.0))
    reach = max(fit.length_px + 3.0, NEEDLE_REACH * radius)
    b = (px + ux * reach, py + uy * reach)
    cv2.line(mask, (int(round(a[0])), int(round(a[1]))), (int(round(b[0])), int(round(b[1]))),
             255, max(3, int(round(2 * hw))))
    return mask


def _masked_ncc(back: np.ndarray, valid: np.ndarray, patch: np.ndarray,
                patch_valid: np.ndarray) -> np.ndarray:
    """Normalised correlation of ``patch`` with every same-sized window of ``back``, over
    the pixels valid in both (a shifts x shifts array; -1 where too few).  The sums over
    each window's common pixels are correlations of masked images (six ``TM_CCORR``)."""
    v = valid.astype(np.float32)
    pv = patch_valid.astype(np.float32)
    a = back.astype(np.float32) * v
    b = patch.astype(np.float32) * pv

    def corr(x, k):
        return cv2.matchTemplate(x, k, cv2.TM_CCORR).astype(np.float64)

    n = corr(v, pv)
    s_a, s_aa, s_ab = corr(a, pv), corr(a * a, pv), corr(a, b)
    s_b, s_bb = corr(v, b), corr(v, b * b)
    nn = np.maximum(n, 1.0)
    cov = s_ab - s_a * s_b / nn
    den = np.sqrt(np.maximum(s_aa - s_a * s_a / nn, 0.0) * np.maximum(s_bb - s_b * s_b / nn, 0.0))
    out = np.where(den > 1e-9, cov / np.maximum(den, 1e-9), -1.0)
    return np.where(n >= MIN_VALID * patch.size, out, -1.0)


def _peak(res: np.ndarray, i: int, j: int) -> tuple[float, float]:
    """Sub-pixel offsets of a correlation peak: a parabola through it and its neighbours."""
    out = []
    for a, b, c in ((res[i, j - 1] if j > 0 else None, res[i, j],
                     res[i, j + 1] if j < res.shape[1] - 1 else None),
                    (res[i - 1, j] if i > 0 else None, res[i, j],
                     res[i + 1, j] if i < res.shape[0] - 1 else None)):
        den = 0.0 if a is None or c is None else a - 2 * b + c
        out.append(0.5 * (a - c) / den if den < -1e-9 else 0.0)
    return out[0], out[1]


def _explained(tmpl: np.ndarray, frame: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    """The frame's pixels (uint8 mask, 255 = valid) that the warp ``w`` (template -> frame)
    explains, and their share of the template.  Both pictures are normalised to zero mean
    and unit variance, as the ECC compares them; a pixel whose difference is over
    ``OUTLIER`` robust standard deviations (and its surroundings) is unexplained: glare that
    moved, the needle that moved."""
    n = tmpl.shape[0]
    back = cv2.warpPerspective(frame, w, (tmpl.shape[1], n),
                               flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
    a = (tmpl - tmpl.mean()) / max(float(tmpl.std()), 1e-6)
    b = (back - back.mean()) / max(float(back.std()), 1e-6)
    r = cv2.GaussianBlur(np.abs(a - b), (0, 0), 1.5)
    sigma = 1.4826 * float(np.median(r)) + 1e-6
    bad = (r > OUTLIER * sigma).astype(np.uint8) * 255
    bad = cv2.dilate(bad, np.ones((5, 5), np.uint8))
    share = 1.0 - float(np.count_nonzero(bad)) / bad.size
    mask = cv2.warpPerspective(255 - bad, w, (frame.shape[1], frame.shape[0]),
                               flags=cv2.INTER_NEAREST, borderValue=0)
    return mask, share


def landmark_offsets(tmpl: np.ndarray, clear: np.ndarray, corner, frame: np.ndarray,
                     h: np.ndarray, points, radius: float, hidden: np.ndarray | None = None
                     ) -> list[tuple[float, float, float, float, float, float]]:
    """For each reference point, (best shift in px, its correlation, the patch's std, the
    share of it seen in both images, the shift's x and y in reference pixels): the
    reference's fine print around it (from the dial region ``tmpl`` at ``corner``, whose
    pixels ``clear`` are clear of its needle) against the frame's, warped back onto the
    reference by ``h`` (reference -> frame), leaving out the frame's pixels marked in
    ``hidden`` (its needle).  A point carried right has its own best shift near 0."""
    out = []
    for point in points:
        got = _patch_match(tmpl, clear, corner, frame, h, point, radius, hidden)
        out.append((math.inf, 0.0, 0.0, 0.0, 0.0, 0.0) if got is None else got[0])
    return out


def _patch_match(tmpl, clear, corner, frame, h, point, radius: float, hidden,
                 streaks_of: np.ndarray | None = None):
    """(:func:`landmark_offsets`' tuple for ``point``, the correlation over the shifts
    (``LOCAL_PX`` either way; -1 where too little is seen)), or None when the patch leaves
    the dial region.  ``streaks_of``: the reference's grey; a glare streak across the place
    in one of the two images (:func:`.glare_streak.streak_mask`) is then left out of both."""
    half = max(9, int(round(PATCH * radius)))
    n = 2 * half + 1
    big = n + 2 * LOCAL_PX
    x, y = point
    x0, y0 = int(round(x)) - half - corner[0], int(round(y)) - half - corner[1]
    if x0 < 0 or y0 < 0 or x0 + n > tmpl.shape[1] or y0 + n > tmpl.shape[0]:
        return None
    patch = tmpl[y0:y0 + n, x0:x0 + n]
    patch_valid = clear[y0:y0 + n, x0:x0 + n]
    # the frame around the same place, in reference pixels, with room for the search
    to_win = _shift(-(x0 + corner[0] - LOCAL_PX), -(y0 + corner[1] - LOCAL_PX))
    to_ref = to_win @ np.linalg.inv(h)
    raw = cv2.warpPerspective(frame, to_ref, (big, big), flags=cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_REPLICATE)
    back = _detail(raw)
    valid = np.ones((big, big), bool)
    if hidden is not None:
        valid = cv2.warpPerspective(hidden, to_ref, (big, big), flags=cv2.INTER_NEAREST,
                                    borderMode=cv2.BORDER_CONSTANT, borderValue=255) == 0
    if streaks_of is not None:  # the grey of both about the place, in reference pixels
        ref = cv2.warpAffine(streaks_of, to_win[:2], (big, big), flags=cv2.INTER_NEAREST,
                             borderMode=cv2.BORDER_REPLICATE)
        streak = streak_mask(raw, ref)
        valid = valid & ~streak
        patch_valid = patch_valid & ~streak[LOCAL_PX:LOCAL_PX + n, LOCAL_PX:LOCAL_PX + n]
    res = cv2.matchTemplate(back, patch, cv2.TM_CCOEFF_NORMED) \
        if valid.all() and patch_valid.all() else _masked_ncc(back, valid, patch, patch_valid)
    i, j = np.unravel_index(int(np.argmax(res)), res.shape)
    ox, oy = _peak(res, i, j)
    dx, dy = j + ox - LOCAL_PX, i + oy - LOCAL_PX
    v0 = valid[LOCAL_PX:LOCAL_PX + n, LOCAL_PX:LOCAL_PX + n] & patch_valid
    std = float(patch[v0].std()) if v0.any() else 0.0
    return (math.hypot(dx, dy), float(res[i, j]), std, float(v0.mean()), float(dx),
            float(dy)), res


def check_landmarks(frame_gray: np.ndarray, cal, h: np.ndarray,
                    hidden: np.ndarray | None = None) -> tuple[str | None, list]:
    """(why the warp ``h`` (reference -> frame) does not carry the calibrated end marks onto
    the frame's end marks, or None when both line up; per end mark, minimum then maximum,
    the shift (x, y, reference pixels) by which the frame's mark lies off the warped one
    where that is small and clear enough to take the mark where it was found (``FIX_PX``),
    else (0, 0)); ``hidden``: the frame's needle.  Where a needle hides most of an end
    mark's patch (in either image), the patch is taken a step inward along the scale (up to
    ``INWARD_STEPS``): the scale's own print there."""
    try:
        hit = _template(cal)
    except (OSError, ValueError) as e:
        return f"registration failed: {e}", []
    if hit is None:
        return "registration failed: the dial region leaves the reference image", []
    detail, clear = hit[0], hit[3]
    cx, cy = cal.center
    R = cal.radius_px
    step = max(9, int(round(PATCH * R))) / max(R, 1.0)  # one patch's half-width, radians
    sign = 1.0 if cal.clockwise else -1.0
    fix_px = min(FIX_PX, FIX_R * R)
    shifts = []
    for name, (x, y), inward in (("minimum mark", cal.min_point, sign),
                                 ("maximum mark", cal.max_point, -sign)):
        a, r = math.atan2(x - cx, -(y - cy)), math.hypot(x - cx, y - cy)
        for k in range(INWARD_STEPS + 1):
            t = a + inward * k * step
            off, ncc, std, vis, dx, dy = landmark_offsets(
                detail, clear, (0, 0), frame_gray, h,
                [(cx + r * math.sin(t), cy - r * math.cos(t))], R, hidden)[0]
            if vis >= MIN_VALID and std >= MIN_PATCH_STD:
                break
        else:
            return f"registration failed: the needles hide the {name}'s print from the check", []
        log.debug("landmark %s: shift %.2f px, ncc %.2f, std %.1f, seen %.2f", name, off, ncc,
                  std, vis)
        if ncc >= MIN_LOCAL_NCC and off <= MAX_LOCAL_PX:
            shifts.append((0.0, 0.0))
        elif ncc >= FIX_NCC and off <= fix_px:
            shifts.append((dx, dy))
        elif _lines_up_past_streak(detail, clear, frame_gray, h, (cx + r * math.sin(t),
                                                                 cy - r * math.cos(t)),
                                   (cx, cy), R, hidden, cal.image_path):
            shifts.append((0.0, 0.0))
        else:
            return f"registration failed: the {name} does not line up ({off:.1f} px, {ncc:.2f})", []
    return None, shifts


def _lines_up_past_streak(detail, clear, frame_gray, h, point, pivot, R: float, hidden,
                          image_path) -> bool:
    """Whether the end mark's patch about ``point`` lines up (within ``MAX_LOCAL_PX`` at
    ``MIN_LOCAL_NCC``, as the check asks) once a glare streak across it in either image
    is left out of both (:mod:`.glare_streak`), with ``MIN_VALID`` of it still seen and
    the correlation ``ALONG_PX`` px either way along the arc ``ALONG_DROP`` below its peak."""
    try:
        got = _patch_match(detail, clear, (0, 0), frame_gray, h, point, R, hidden,
                           reference_image(image_path))
    except (OSError, ValueError):
        return False
    if got is None:
        return False
    (off, ncc, std, vis, dx, dy), res = got
    drop = drop_along_arc(res, (LOCAL_PX + dx, LOCAL_PX + dy), point, pivot, ALONG_PX)
    log.debug("landmark past a glare streak: shift %.2f px, ncc %.2f, std %.1f, seen %.2f, "
              "drop along the arc %.2f", off, ncc, std, vis, drop)
    return vis >= MIN_VALID and std >= MIN_PATCH_STD and ncc >= MIN_LOCAL_NCC \
        and off <= MAX_LOCAL_PX and drop >= ALONG_DROP


def _align(tmpl: np.ndarray, frame: np.ndarray, start: np.ndarray, k: float, radius: float):
    """((ECC, warp template -> frame), None) from ``start``, or (None, why not): an affine
    warp on the coarse level (shrunk by ``k``), then on the fine level a homography, and
    again without what it cannot explain."""
    coarse_t, coarse_f, to_c = _level(tmpl, frame, k)
    w = to_c @ start @ np.linalg.inv(to_c)
    got = _ecc(coarse_t, coarse_f, w, cv2.MOTION_AFFINE, 40, _explained(coarse_t, coarse_f, w)[0])
    fine_t, fine_f, to_f = _level(tmpl, frame, min(1.0, FINE_R / max(radius, 1.0)))
    share = 0.0
    for iters in (15, 10):
        if got is None:
            break
        w = to_f @ np.linalg.inv(to_c) @ got[1] @ to_c @ np.linalg.inv(to_f) \
            if iters == 15 else got[1]
        valid, share = _explained(fine_t, fine_f, w)
        got = _ecc(fine_t, fine_f, w, cv2.MOTION_HOMOGRAPHY, iters, valid)
    if got is None:
        return None, "the dial's picture did not align"
    log.debug("dense registration: %.2f of the dial explained, ECC %.3f", share, got[0])
    if share < MIN_EXPLAINED:
        return None, f"the warp explains only {100 * share:.0f} % of the dial's picture"
    if got[0] < MIN_ECC:
        return None, f"the dial's picture agrees only {got[0]:.2f} (need {MIN_ECC})"
    return (got[0], np.linalg.inv(to_f) @ got[1] @ to_f), None


def _window(frame_gray: np.ndarray, corner, n: int, radius: float):
    """The frame's print (:func:`_print`) in a window around where the dial region (``n``
    px square at ``corner``) was in the reference, and the window's top-left corner."""
    reach = int(SEARCH * n / 2.0)
    cx, cy = corner[0] + n // 2, corner[1] + n // 2
    hgt, wid = frame_gray.shape[:2]
    fx0, fy0 = max(0, cx - reach), max(0, cy - reach)
    fx1, fy1 = min(wid, cx + reach + 1), min(hgt, cy + reach + 1)
    return _print(frame_gray[fy0:fy1, fx0:fx1], radius), (fx0, fy0)


def polish(frame_gray: np.ndarray, cal, h: np.ndarray) -> np.ndarray | None:
    """The warp ``h`` (reference -> frame, from keypoints) polished by the dial's picture:
    ECC over a homography (step 2 above), started from ``h`` with the pixels it does not
    explain left out, on a level with the ring ``POLISH_R`` px large; None unless the
    coefficient over the dial reaches ``MIN_ECC`` on at least ``MIN_EXPLAINED`` of it.
    Keypoints are found to a pixel or so each, and a few dozen of them leave the warp's
    local linear part at the pivot (the change of view the reading undoes) off by up to
    half a degree in angle; the whole dial's print fixes it more closely where it agrees
    this well."""
    R = cal.radius_px
    try:
        hit = _template(cal, dense=True)
    except (OSError, ValueError):
        return None
    if hit is None:
        return None
    corner, tmpl = hit[1], hit[2]
    frame, (fx0, fy0) = _window(frame_gray, corner, tmpl.shape[0], R)
    fine_t, fine_f, to_f = _level(tmpl, frame, min(1.0, POLISH_R / max(R, 1.0)))
    w = to_f @ _shift(-fx0, -fy0) @ h @ _shift(corner[0], corner[1]) @ np.linalg.inv(to_f)
    valid, share = _explained(fine_t, fine_f, w)
    got = _ecc(fine_t, fine_f, w, cv2.MOTION_HOMOGRAPHY, POLISH_ITERS, valid)
    if got is None:
        return None
    w = got[1]
    log.debug("keypoint warp polished: %.2f of the dial explained, ECC %.3f", share, got[0])
    if share < MIN_EXPLAINED or got[0] < MIN_ECC:
        return None
    out = _shift(fx0, fy0) @ np.linalg.inv(to_f) @ w @ to_f @ _shift(-corner[0], -corner[1])
    return out / out[2, 2]


def dense_register(frame_gray: np.ndarray, cal) -> Registration:
    """Register a grey frame to ``cal``'s reference image by its dial region's pixels;
    refused with a reason unless every acceptance check holds."""
    R = cal.radius_px
    try:
        hit = _template(cal, dense=True)
    except (OSError, ValueError) as e:
        return Registration(False, None, error=f"registration failed: {e}")
    if hit is None:
        return Registration(False, None, error="registration failed: the dial region leaves "
                                               "the reference image")
    corner, tmpl = hit[1], hit[2]
    frame, (fx0, fy0) = _window(frame_gray, corner, tmpl.shape[0], R)
    k = min(1.0, COARSE_R / max(R, 1.0))
    score, warp = _coarse(tmpl, frame, k)
    # from the coarse match, else (glare may hide the dial from it) from where the dial was
    starts = [warp] if warp is not None and score >= MIN_COARSE else []
    starts.append(_shift(corner[0] - fx0, corner[1] - fy0))
    why = f"the dial was not found by its picture ({score:.2f})"
    for start in starts:
        got, why = _align(tmpl, frame, start, k, R)
        if got is not None:
            break
    if got is None:
        return Registration(False, None, error=f"registration failed: {why}")
    cc, w = got
    h = _shift(fx0, fy0) @ w @ _shift(-corner[0], -corner[1])  # reference -> frame pixels
    h = h / h[2, 2]
    carried = carry_points(h, [cal.center, cal.min_point, cal.max_point])
    why = implausible(h, cal.center, R, frame_gray.shape, carried)
    if why is not None:
        return Registration(False, None, error=f"registration failed: {why}")
    return Registration(True, h, score=0.7 + 0.3 * min(1.0, (cc - MIN_ECC) / (1.0 - MIN_ECC)))
