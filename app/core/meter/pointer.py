"""Steps 2-8 of seed 000 section 3 on the normalised dial crop: the pointer and the scale.

:func:`read_normalised` takes the 300 x 300 crop in which the dial's face is a circle of
:data:`.dial.FACE_RADIUS` about the centre, and finds the darkness image (with glare
compensation), Otsu's threshold (eqs. 1-18), the pointer's region, its hub, its skeleton
(Zhang-Suen), its axis (eq. 19), the hub's centre (section 3.2), the tip, and the scale's
tick marks and end marks (:mod:`.scale`).  Results are a dict in crop coordinates.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .dial import FACE_RADIUS, NORM_SIZE, _median
from .geometry import (
    Line,
    choose_intersection,
    fit_circle,
    fit_line,
    line_circle_intersections,
    principal_axis,
)
from .hub_edges import find_hub_edges
from .otsu import binarize, otsu_threshold
from .profile import GaugeProfile
from .scale import find_scale, ring_angle
from .thinning import zhang_suen

__all__ = ["CENTRE", "FACE_MASK", "dark_features", "read_normalised", "robust_pointer_line",
           "segment_pointer"]

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

CENTRE = _C
FACE_MASK = _FACE_MASK


def _median_hist(h: np.ndarray) -> float:
    """Exact median of the values counted in a 256-bin histogram (as ``np.median``)."""
    c = np.cumsum(h)
    n = int(round(float(c[-1])))
    lo = int(np.searchsorted(c, (n - 1) // 2 + 1))
    hi = int(np.searchsorted(c, n // 2 + 1))
    return 0.5 * (lo + hi)



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
    # (circular neighbours: np.roll(hist, 1) and np.roll(hist, -1))
    hist = hist + np.concatenate((hist[-1:], hist[:-1])) + np.concatenate((hist[1:], hist[:1]))
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
    hub_from = "region" if hub_rms < 1.5 else "base"
    if hub_rms >= 1.5:
        # no circle fits the region about its thickest point: a cap the threshold left out
        # may still be seen in the grey image's edges (.hub_edges)
        cap = find_hub_edges(gray, line, (hx, hy), half_w, 0.2 * FACE_RADIUS,
                             (_C, _C, 0.2 * FACE_RADIUS), skel_pts)
        if cap is not None:
            (m, n), hub_r, hub_rms, hub_from = cap["centre"], cap["r"], cap["rms"], "edges"
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
    # the pointer's reach behind the hub, for telling a two-ended needle's tip from its tail
    ext_bw = float(max(0.0, np.max(np.where(on_axis, -proj * side, 0.0))))
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
        "tip_angle": tip_angle, "r_s": r_s, "otsu_t": t, "hub_from": hub_from,
        "dark": dark, "pmask": pmask, "ext_fw": tip_len, "ext_bw": ext_bw,
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

