"""Oblique views of a calibrated gauge: angles about the pivot measured on the dial's plane.

A dial seen at a tilt is foreshortened: equal angles on the dial are unequal in the image,
by up to a few percent of full scale at 30 degrees.  The face's rim is a circle on the
dial, so its image (an ellipse) gives the affine map that undoes the foreshortening: the
stretch along the ellipse's minor axis by a / b.  The rim is found ray by ray from the pivot
(where the bright face falls to the bezel, placed to a fraction of a pixel) and fitted
robustly (:func:`find_rectifier`).  The map is used only when the fit is clean, roughly
concentric with the pivot, and about as far out as a rim should be; otherwise angles are
read in the image (the identity).  A dark face in a lighter bezel has its rim as a
dark-to-bright step: that is tried on the inverted grey when the bright-to-dark one is not
clear all round.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .dial import _median

__all__ = ["Rectifier", "find_rectifier"]

N_RAYS = 96
MIN_RAY_SHARE = 0.5  # of the rays must find the rim and stay in the fit
MAX_RMS = 0.02  # fit residual, in units of the scale radius
MIN_AXIS_RATIO = 0.45  # flatter than this (about 63 deg of tilt) is not trusted
ROUND = 0.99  # rounder than this: read in the image as it is
FIRST_STEP = 0.5  # the face's first strong fall: at least this share of the ray's strongest
LIGHT_RIM_TRY = 0.9  # a rim on fewer of the rays than this: a dark-to-bright rim is tried too
RIM_OUT = 1.75  # the rim is searched out to this many scale radii from the pivot ...
# ... and, where no rim is found there, out to this many: the scale's radius comes from the
# clicked end marks, which a tilted dial foreshortens when they lie along its minor axis (a
# 180 deg scale seen from the side); a tilt of up to 45 deg (axis ratio 0.7) is covered
RIM_FAR = RIM_OUT / 0.7
# a rim found in one colour channel where grey shows none: on at least this share of the
# rays (one edge all round, not a coloured band that some rays cross)
COLOUR_RIM_RAYS = 0.85


class Rectifier:
    """A linear map of image vectors (about the pivot) onto the dial's plane."""

    def __init__(self, a: np.ndarray | None = None, ellipse=None, axis_ratio: float = 1.0,
                 support: float = 1.0):
        self.a = np.eye(2) if a is None else np.asarray(a, float)
        self.ellipse = ellipse  # cv2 form ((cx, cy), (w, h), angle) or None
        self.axis_ratio = axis_ratio
        self.support = support  # share of the rays with a step on the ellipse
        # whether a rim was found at all (round or an ellipse): without it, the identity
        # stands for a view whose tilt nothing has measured
        self.rim_seen = ellipse is not None
        self.base = np.eye(2)  # the map without the rim's part (a registration's, carried)
        # the end marks' evidence on the rim's correction (:mod:`.calibrated`): the 1-sigma
        # share of it in doubt they leave, infinite when they say nothing or disagree
        self.marks_sigma = math.inf
        self.marks_wrong = 0.0  # ... and the share of it they say is wrong

    @property
    def identity(self) -> bool:
        return self.ellipse is None

    def angle(self, dx: float, dy: float) -> float:
        """Angle clockwise from up, in [0, 360), of an image vector seen on the dial."""
        x, y = self.a @ np.array([dx, dy])
        return math.degrees(math.atan2(x, -y)) % 360.0

    def base_angle(self, dx: float, dy: float) -> float:
        """Angle as :meth:`angle`, without the rim's correction: in the image itself, or
        for a carried map in the reference image's geometry."""
        x, y = self.base @ np.array([dx, dy])
        return math.degrees(math.atan2(x, -y)) % 360.0

    def carried(self, j: np.ndarray) -> Rectifier:
        """The same rectification for another image whose vectors are ``j @ v`` of these
        (``j``: the registration's local linear part at the pivot).  Without a rim, angles
        are then measured as in the reference image: the change of view between the two
        frames is undone by the registration, whatever the rim shows."""
        inv = np.linalg.inv(j)
        out = Rectifier(inv if self.identity else self.a @ inv, self.ellipse, self.axis_ratio,
                        self.support)
        out.base = inv
        out.rim_seen = self.rim_seen
        out.marks_sigma = self.marks_sigma
        out.marks_wrong = self.marks_wrong
        return out


def find_rectifier(gray: np.ndarray, pivot, radius: float,
                   colour: np.ndarray | None = None, *, round_ratio: float = ROUND) -> Rectifier:
    """Rim ellipse around ``pivot`` (the scale ring's radius ``radius``) -> :class:`Rectifier`
    (the identity when the rim is not clear).

    Each ray from the pivot gives up to three bright-to-dark steps (to a fraction of a
    pixel); the rim is each ray's strongest, first strong, first or last step, whichever
    ellipse (nearly) every ray has a step on (:func:`_hypotheses`).  For each, a conic
    centred on the pivot, A x^2 + B x y + C y^2 = 1, fitted by iteratively reweighted least
    squares, then a free conic reweighted the same way, keep the steps that lie on one
    closed rim (a coloured band or a bezel's second edge on some rays is not symmetric about
    the pivot and drops out); the ellipse through them (``cv2.fitEllipse``) gives the map.
    It must be centred on the pivot within the clicks' error; when it is not (the steps
    mixed two edges) the identity is returned: angles are then read in the image.  Where no
    rim is found out to ``RIM_OUT`` scale radii, it is looked for out to ``RIM_FAR``: the
    radius comes from the clicks, which a tilt can foreshorten.  Where grey shows no rim
    and the ``colour`` (BGR) frame is given, a face and a background of like grey but
    another colour (a blue face on green) part in one colour channel: the channels are
    searched the same way, and a rim on at least ``COLOUR_RIM_RAYS`` of the rays is
    taken.  A rim rounder than ``round_ratio`` is taken as seen head-on (the identity);
    a reference frame's rim, fitted once, is kept however round (1.0)."""
    px, py = float(pivot[0]), float(pivot[1])
    best = _any_rim(gray, px, py, radius)
    if best is None and colour is not None and colour.ndim == 3:
        for c in range(3):
            got = _any_rim(np.ascontiguousarray(colour[:, :, c]), px, py, radius)
            if got is not None and got[0] >= COLOUR_RIM_RAYS * N_RAYS and \
                    (best is None or got[0] > best[0]):
                best = got
    if best is None:
        return Rectifier()
    n_on, ell, n_rays = best
    (_, _), (w_, h_), _ = ell
    ratio = min(w_, h_) / max(w_, h_)
    if ratio > round_ratio:
        out = Rectifier(None, None, ratio)
        out.rim_seen = True  # round: seen head-on
        return out
    return Rectifier(_stretch(ell), ell, ratio, n_on / max(n_rays, 1))


def _any_rim(gray, px: float, py: float, radius: float):
    """:func:`_either_rim` out to ``RIM_OUT`` scale radii, else out to ``RIM_FAR``."""
    best = _either_rim(gray, px, py, radius, RIM_OUT)
    return best if best is not None else _either_rim(gray, px, py, radius, RIM_FAR)


def _either_rim(gray, px: float, py: float, radius: float, out: float):
    """The rim as a bright-to-dark step, or as a dark-to-bright one (a dark face in a
    lighter bezel) where that is on more rays: :func:`_best_rim`'s answer, or None."""
    best = _best_rim(gray, px, py, radius, out)
    if best is None or best[0] < LIGHT_RIM_TRY * best[2]:
        dark = _best_rim(cv2.bitwise_not(gray), px, py, radius, out)
        if dark is not None and (best is None or dark[0] > best[0]):
            best = dark
    return best


def _best_rim(gray, px: float, py: float, radius: float, out: float):
    """The rim hypothesis most rays have a bright-to-dark step on, searched out to ``out``
    scale radii: (rays on it, the ellipse, rays with a step at all), or None."""
    cand, strength = _rim_candidates(gray, px, py, radius, out)
    best = None
    n_rays = int((strength > 0).any(axis=1).sum())  # the rays with a step at all
    for pts in _hypotheses(cand, strength):
        ell = _fit_rim(pts, px, py, radius, out)
        if ell is None:
            continue
        # the rays that have a step on this ellipse: one edge all round has nearly all
        # (only real steps count: a ray's empty slots hold no point of the image)
        n_on = int(((_residual(cand.reshape(-1, 2), ell).reshape(cand.shape[:2])
                     <= 0.015 * radius + 1.0) & (strength > 0)).any(axis=1).sum())
        if best is None or n_on > best[0]:
            best = (n_on, ell, n_rays)
        if n_on >= n_rays:  # every ray has its step on it: no other can do better
            break
    return best


def _hypotheses(cand: np.ndarray, strength: np.ndarray):
    """Per ray one step, four ways: the strongest; the innermost of at least ``FIRST_STEP``
    of the strongest (the face ends at the first strong fall); the innermost and the
    outermost at all.  A band of colour just inside the rim makes the inner ones mix two
    circles, a bezel of two tones (lit unevenly) the strongest; the rim is the one that
    (nearly) every ray has a step on."""
    ok = strength > 0
    rows = np.arange(len(cand))
    strong = ok & (strength >= FIRST_STEP * strength.max(axis=1, keepdims=True))
    picks = (np.argmax(strength, axis=1),
             np.argmax(strong, axis=1),  # candidates are ordered from the inside out
             np.argmax(ok, axis=1),
             ok.shape[1] - 1 - np.argmax(ok[:, ::-1], axis=1))
    seen = []
    for k in picks:
        has = ok[rows, k]
        key = np.where(has, k, -1)
        if any((key == s).all() for s in seen):  # the same steps as one tried already
            continue
        seen.append(key)
        yield cand[rows, k][has]


def _fit_rim(pts: np.ndarray, px: float, py: float, radius: float, out: float):
    """The rim ellipse (cv2 form) through the steps ``pts``, or None when they are too few,
    scattered, flat, off the pivot or not about as far out as a rim should be."""
    need = MIN_RAY_SHARE * N_RAYS
    if len(pts) < need:
        return None
    dx, dy = pts[:, 0] - px, pts[:, 1] - py
    q = np.column_stack([dx * dx, dx * dy, dy * dy])
    rho = np.hypot(dx, dy)
    w = np.ones(len(pts))
    for _ in range(5):
        abc = _wls(q, w)
        res = np.abs(rho - 1.0 / np.sqrt(np.maximum((q @ abc) / rho**2, 1e-12)))
        sigma = max(1.5, 1.5 * _median(res))
        w = 1.0 / (1.0 + (res / sigma) ** 2)
    # then a free conic (A x^2 + B x y + C y^2 + D x + E y = 1), reweighted the same way:
    # the pivot's click error and the perspective shift of the centre are absorbed
    g = np.column_stack([q, dx, dy])
    for _ in range(4):
        coef = _wls(g, w)
        res = _conic_distance(coef, dx, dy)
        sigma = max(0.75, 1.5 * _median(res))
        w = 1.0 / (1.0 + (res / sigma) ** 2)
    pts = pts[res < 0.015 * radius + 1.0]
    if len(pts) < need:
        return None
    ell = cv2.fitEllipse(pts)
    (cx, cy), (w_, h_), _ = ell
    rms = float(np.sqrt(np.mean(_residual(pts, ell) ** 2)))
    ratio = min(w_, h_) / max(w_, h_)
    if (rms > MAX_RMS * radius or ratio < MIN_AXIS_RATIO
            or math.hypot(cx - px, cy - py) > 0.1 * radius + 3.0
            or not 1.0 * radius < 0.25 * (w_ + h_) < out * radius):
        return None
    return ell


def _wls(a: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted least squares a x = 1 (weights ``w``) by its normal equations: a 3 x 3 or
    5 x 5 solve, far cheaper than a general least-squares solver on so few unknowns."""
    aw = a * w[:, None]
    try:
        return np.linalg.solve(aw.T @ aw, aw.T @ w)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(aw, w, rcond=None)[0]


def _conic_distance(coef, dx, dy) -> np.ndarray:
    """Approximate distance (px) of points from the conic: |f| / |grad f|."""
    a, b, c, d, e = coef
    f = a * dx * dx + b * dx * dy + c * dy * dy + d * dx + e * dy - 1.0
    gx = 2 * a * dx + b * dy + d
    gy = b * dx + 2 * c * dy + e
    return np.abs(f) / np.maximum(np.hypot(gx, gy), 1e-12)


def _rim_candidates(gray, px, py, radius, out: float) -> tuple[np.ndarray, np.ndarray]:
    """Up to three bright-to-dark steps on each ray between 0.98 and ``out`` x ``radius`` that
    are not thin dark lines, from the inside out: their image points (rays x 3 x 2, to a
    fraction of a pixel) and strengths (rays x 3; 0 where there is none)."""
    r_lo, r_hi = 0.98 * radius, out * radius
    rs = np.arange(r_lo, r_hi, 1.0, dtype=np.float32)
    th = np.linspace(0, 2 * np.pi, N_RAYS, endpoint=False).astype(np.float32)
    sx, sy = np.sin(th)[:, None], -np.cos(th)[:, None]
    mx = (px + sx * rs[None, :]).astype(np.float32)
    my = (py + sy * rs[None, :]).astype(np.float32)
    hgt, wid = gray.shape[:2]
    inside = (mx >= 0) & (my >= 0) & (mx <= wid - 1) & (my <= hgt - 1)
    v = cv2.remap(gray, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    v = cv2.GaussianBlur(v.astype(np.float32), (5, 1), 0)
    d = v[:, 2:] - v[:, :-2]  # bright face -> darker bezel: a strong negative step
    d[~(inside[:, 2:] & inside[:, :-2])] = 0.0
    mid = d[:, 1:-1]
    is_min = (mid < d[:, :-2]) & (mid <= d[:, 2:]) & (mid < -16.0)
    cand = np.argsort(np.where(is_min, mid, 0.0), axis=1)[:, :3] + 1  # 3 strongest steps
    cand = np.sort(cand, axis=1)  # from the inside out
    # a thin dark line on the face (a colour band, a ring) is not the rim: the grey comes
    # back to the face's level within a few pixels after it
    n = v.shape[1]
    thin_px = int(round(0.03 * radius)) + 1
    rows = np.arange(N_RAYS)
    strength = np.zeros((N_RAYS, 3), np.float32)
    xy = np.zeros((N_RAYS, 3, 2), np.float32)
    for c in range(3):
        kk = cand[:, c]
        valid = is_min[rows, kk - 1]
        before = v[rows, np.maximum(kk - 2, 0)]
        lo = np.minimum(kk + 1, n - 1)
        win = v[rows[:, None], np.minimum(lo[:, None] + np.arange(thin_px + 1)[None, :], n - 1)]
        drop = before - win.min(axis=1)
        back = win[:, -1] > before - 0.3 * drop
        kc = np.clip(kk, 1, d.shape[1] - 2)
        dmin = d[rows, kc]
        strength[:, c] = np.where(valid & ~back, -dmin, 0.0)
        y0, y2 = d[rows, kc - 1], d[rows, kc + 1]
        den = y0 - 2.0 * dmin + y2
        off = np.clip(np.where(np.abs(den) > 1e-6, 0.5 * (y0 - y2) / np.where(den == 0, 1, den),
                               0.0), -0.5, 0.5)
        r = r_lo + kc + 1 + off
        xy[:, c, 0] = px + r * sx[:, 0]
        xy[:, c, 1] = py + r * sy[:, 0]
    return xy, strength


def _stretch(ell) -> np.ndarray:
    """The linear map that turns the ellipse's shape into a circle of its major radius."""
    (_, _), (w, h), ang = ell
    t = math.radians(ang)
    rot = np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])
    s = np.diag([max(w, h) / w, max(w, h) / h])
    return rot @ s @ rot.T


def _residual(pts: np.ndarray, ell) -> np.ndarray:
    """Approximate distance (px) of points from an ellipse in cv2 form."""
    (cx, cy), (w, h), ang = ell
    t = math.radians(ang)
    dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
    xr = dx * math.cos(t) + dy * math.sin(t)
    yr = -dx * math.sin(t) + dy * math.cos(t)
    return np.abs(np.hypot(xr / (w / 2), yr / (h / 2)) - 1.0) * (w + h) / 4
