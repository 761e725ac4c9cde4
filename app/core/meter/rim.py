"""The dial's face rim found and refined from rays: around a hub, around a ready crop's
face edge, and a rim guess tightened by the edge points along its rays.

Split from :mod:`.dial` (which finds rim candidates among clutter and rectifies them):
these are the rim steps that start from a known centre or a near-normalised crop.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .dial import FACE_RADIUS, NORM_SIZE, DialEllipse, _ellipse_residual, _sample, face_radius
from .order_stats import median

__all__ = ["find_crop_rim", "is_head_on_crop", "refine_rim", "rim_edge_points",
           "rim_points_around"]


def rim_points_around(gray: np.ndarray, centre, r_lo: float = 70.0, r_hi: float = 149.0,
                      n_ang: int = 120) -> np.ndarray:
    """Face-edge points found ray by ray from ``centre`` (the hub): where the bright face
    ends.  Used to re-fit a rim that is concentric with the hub when the first ellipse was
    something else.  Returns an (N, 2) float32 array in ``gray``'s pixel coordinates."""
    rs = np.arange(r_lo, r_hi, 1.0)
    th = np.linspace(0, 2 * np.pi, n_ang, endpoint=False)
    x = centre[0] + rs[None, :] * np.sin(th)[:, None]
    y = centre[1] - rs[None, :] * np.cos(th)[:, None]
    v, inside = _sample(gray, x, y)
    v = cv2.GaussianBlur(v.astype(np.float32), (1, 5), 0)
    face = float(median(v[:, : len(rs) // 4]))  # (np.median's value)
    thr = face - max(25.0, 0.22 * face)
    below = (v < thr) & inside
    below[:, :3] = False
    has = below.any(axis=1)
    first = np.argmax(below, axis=1)
    # the edge must stay dark for a few pixels (a bezel, not a tick or a numeral)
    run_ok = np.zeros(n_ang, bool)
    for k in np.flatnonzero(has):
        j = first[k]
        run_ok[k] = below[k, j:j + 4].all() and inside[k, min(j + 4, len(rs) - 1)]
    idx = np.flatnonzero(has & run_ok)
    r = rs[first[idx]]
    return np.column_stack([centre[0] + r * np.sin(th[idx]),
                            centre[1] - r * np.cos(th[idx])]).astype(np.float32)


_RAY_CACHE: dict[tuple[int, int], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _ray_grid(n_rays: int, n_steps: int):
    key = (n_rays, n_steps)
    g = _RAY_CACHE.get(key)
    if g is None:
        th = np.linspace(0, 2 * np.pi, n_rays, endpoint=False)
        g = _RAY_CACHE[key] = (np.cos(th), np.sin(th), np.linspace(-1.0, 1.0, n_steps))
    return g


def rim_edge_points(gray: np.ndarray, ell, band: float, n_rays: int = 180,
                    min_step: float = 8.0) -> tuple[np.ndarray, np.ndarray]:
    """Sub-pixel face-edge points along rays through a guessed rim ellipse (cv2 form).

    Each ray crosses the guess radially within +-``band`` px.  The edge is where the grey
    falls fastest going outward (the bright face against the darker bezel); a parabola
    through the derivative's extreme places it to a fraction of a pixel.  Returns the
    (N, 2) float32 points and, per ray, whether it had a clear edge (a drop of at least
    ``min_step`` grey levels per px).
    """
    (cx, cy), (w, h), ang = ell
    ct, st, s = _ray_grid(n_rays, int(2 * band) + 1)
    a, b = w / 2.0, h / 2.0
    c, sn = math.cos(math.radians(ang)), math.sin(math.radians(ang))
    ux = a * ct * c - b * st * sn  # guess ellipse point relative to its centre
    uy = a * ct * sn + b * st * c
    rad = np.hypot(ux, uy)
    ux, uy = ux / rad, uy / rad
    r = rad[:, None] + band * s[None, :]
    mx = (cx + r * ux[:, None]).astype(np.float32)
    my = (cy + r * uy[:, None]).astype(np.float32)
    v = cv2.remap(gray, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    v = v.astype(np.float32)
    d = v[:, 2:] - v[:, :-2]  # central difference, 2 px apart
    k = np.argmin(d, axis=1)
    dmin = d[np.arange(n_rays), k]
    ok = (dmin <= -2.0 * min_step) & (k > 0) & (k < d.shape[1] - 1)
    kc = np.clip(k, 1, d.shape[1] - 2)
    y0 = d[np.arange(n_rays), kc - 1]
    y2 = d[np.arange(n_rays), kc + 1]
    den = y0 - 2.0 * dmin + y2
    off = np.where(np.abs(den) > 1e-6, 0.5 * (y0 - y2) / np.where(den == 0, 1, den), 0.0)
    off = np.clip(off, -0.5, 0.5)
    rr = rad - band + (kc + 1 + off) * (2.0 * band / (len(s) - 1))
    pts = np.column_stack([cx + rr * ux, cy + rr * uy]).astype(np.float32)
    return pts, ok


def refine_rim(gray: np.ndarray, ell, bands=(6.0, 4.0), min_share: float = 0.85,
               max_rms: float = 0.6) -> DialEllipse | None:
    """Refine a rough rim ellipse (cv2 form) on the face edge found ray by ray.

    For each band, the edge points along rays through the current ellipse
    (:func:`rim_edge_points`) get an ellipse fit; points more than 1.5 px off it are
    dropped and it is refitted.  The next band is skipped when it would find the same edge
    points (:func:`_settled`): a clean head-on crop is refined by one band.  Accepted only
    when almost every ray finds a clear edge and the edge points lie on the ellipse to a
    fraction of a pixel, or when fewer rays (:data:`TIGHT_SHARE`, all round the rim) lie on
    it to a quarter of a pixel; otherwise None.
    """
    h, w = gray.shape[:2]
    pts = ok = None
    floor = min(min_share, TIGHT_SHARE)
    for i, band in enumerate(bands):
        pts, ok = rim_edge_points(gray, ell, band)
        if ok.mean() < floor:
            return None
        p = pts[ok]
        prev = ell
        ell = cv2.fitEllipse(p)
        keep = _ellipse_residual(p, ell) < 1.5
        if keep.sum() < floor * len(pts):
            return None
        ell = cv2.fitEllipse(p[keep])
        if i + 1 < len(bands) and _settled(prev, ell, ok, int(keep.sum()), band, bands[i + 1]):
            break
    res = _ellipse_residual(pts, ell)
    good = ok & (res < 1.0)
    share = float(good.mean())
    rms = float(np.sqrt(np.mean(res[good] ** 2))) if good.any() else 99.0
    (ex, ey), (ea, eb), ang = ell
    major, minor = max(ea, eb), min(ea, eb)
    # most rays on the ellipse, or fewer (lugs, screws, a bezel's print cut the edge) on
    # an ellipse they fit very tightly, spread all round
    tight = share >= TIGHT_SHARE and rms <= TIGHT_RMS and _all_round(good)
    if not (share >= min_share and rms <= max_rms) and not tight:
        return None
    if minor < 0.65 * major or minor < 0.5 * min(h, w) or major > 1.15 * max(h, w):
        return None
    return DialEllipse(float(ex), float(ey), float(ea), float(eb), float(ang), share)


TIGHT_SHARE = 0.6  # share of rays that suffices when they fit the rim very tightly ...
TIGHT_RMS = 0.25  # ... within this rms (px)
MAX_GAP_RAYS = 0.15  # ... and leave no gap longer than this share of the rays


def _all_round(good: np.ndarray) -> bool:
    """Whether the rays on the rim leave no long gap round it (a rim seen on one side only
    is no rim)."""
    if not good.any():
        return False
    idx = np.flatnonzero(good)
    gaps = np.diff(np.concatenate([idx, [idx[0] + len(good)]]))
    return int(gaps.max()) - 1 <= MAX_GAP_RAYS * len(good)


def _settled(guess, ell, ok: np.ndarray, n_kept: int, band: float, next_band: float) -> bool:
    """True when the next, narrower band around ``ell`` would find the same edge points.

    Nearly every ray found a clear edge and nearly all of them were kept by the fit, and the
    fit moved less than a pixel from the ``guess`` the rays were cast through (centre shift,
    axis change, and the turn of its axes).  The next band's window around the fit then lies
    inside this band's window around the guess, so it holds no edge this band did not see,
    and the points it would drop (over 1.5 px off the fit) are already dropped."""
    if ok.mean() < 0.97 or n_kept < 0.95 * len(ok):
        return False
    (gx, gy), (gw, gh), ga = guess
    (cx, cy), (ew, eh), ea = ell
    turn = abs(math.sin(math.radians(ea - ga))) * 0.5 * abs(ew - eh)
    moved = math.hypot(cx - gx, cy - gy) + 0.5 * max(abs(ew - gw), abs(eh - gh)) + turn
    return moved < min(1.0, band - next_band)


def is_head_on_crop(ell: DialEllipse, shape, tol_px: float = 0.5) -> bool:
    """True when a ``NORM_SIZE`` crop's rim is already the normalised circle: centred within
    ``tol_px`` of the crop's centre, round within ``tol_px`` and of radius within 1 % of
    ``FACE_RADIUS``.  Rectifying it would move no face pixel by more than about one pixel,
    so the reader uses the crop as it is (no warp)."""
    if tuple(shape[:2]) != (NORM_SIZE, NORM_SIZE):
        return False
    a, b = ell.width / 2.0, ell.height / 2.0
    return (math.hypot(ell.cx - NORM_SIZE / 2.0, ell.cy - NORM_SIZE / 2.0) <= tol_px
            and abs(a - b) <= tol_px
            and abs(0.5 * (a + b) - FACE_RADIUS) <= 0.01 * FACE_RADIUS)


def find_crop_rim(gray: np.ndarray, min_share: float = 0.85,
                  max_rms: float = 0.6) -> DialEllipse | None:
    """Fast path for an input that is already a dial crop (about 300 x 300).

    A crop of the normalised size is first refined from the normalised circle (centred,
    radius ``FACE_RADIUS``).  Otherwise, or if that fails, it guesses the face rim as the
    circle around the crop's centre at :func:`face_radius`,
    finds the face edge on rays through that guess (:func:`rim_edge_points`), fits an
    ellipse to it, and refines once on rays through that ellipse (:func:`refine_rim`).
    Accepted only when almost every ray finds a clear edge and the edge points lie on the
    ellipse to a fraction of a pixel; otherwise None, and the caller runs the full search
    (:func:`find_dial_candidates`).  A dark face (light marks) is looked at in the negative
    when the crop's own grey finds no rim.
    """
    ell = _crop_rim(gray, min_share, max_rms)
    if ell is None and _dark_face(gray):
        # a dark face inside a lighter bezel: its edge rises going outward; the negative's
        # falls, as the rays look for
        ell = _crop_rim(cv2.bitwise_not(gray), min_share, max_rms)
    return ell


DARK_FACE_GREY = 100  # a crop whose middle's median grey is below this has a dark face


def _dark_face(gray: np.ndarray) -> bool:
    h, w = gray.shape[:2]
    mid = gray[h // 4: 3 * h // 4, w // 4: 3 * w // 4]
    return float(np.median(mid[::2, ::2])) < DARK_FACE_GREY


def _crop_rim(gray: np.ndarray, min_share: float, max_rms: float) -> DialEllipse | None:
    """:func:`find_crop_rim` on one polarity: a bright face inside a darker bezel."""
    h, w = gray.shape[:2]
    if (h, w) == (NORM_SIZE, NORM_SIZE):
        # a crop at the normalised size is first tried as the normalised circle itself: a
        # head-on crop is refined from it at once, without measuring the face radius
        ell = refine_rim(gray, ((w / 2.0, h / 2.0), (2 * FACE_RADIUS, 2 * FACE_RADIUS), 0.0),
                         (6.0, 4.0), min_share, max_rms)
        if ell is not None:
            return ell
    fr = face_radius(gray, centre=(w / 2.0, h / 2.0))
    if fr is None or fr < 0.3 * min(h, w):
        return None
    guess = ((w / 2.0, h / 2.0), (2 * fr, 2 * fr), 0.0)
    ell = refine_rim(gray, guess, (6.0, 4.0), min_share, max_rms)
    if ell is None:  # the dial is off the crop's centre or tilted: a wider first search
        wide = _wide_rim_guess(gray, guess)
        if wide is not None:
            ell = refine_rim(gray, wide, (6.0, 4.0), min_share, max_rms)
    return ell


def _wide_rim_guess(gray: np.ndarray, guess, band: float = 16.0):
    """Rough rim ellipse from the strongest face edge within +-``band`` px of ``guess`` on
    each ray; edges of ticks near the rim are dropped by refitting to the points within
    6, 3 and 1.5 px of the ellipse in turn.  None if under 60 % of the rays agree."""
    pts, ok = rim_edge_points(gray, guess, band)
    p = pts[ok]
    if len(p) < 0.6 * len(pts):
        return None
    ell = cv2.fitEllipse(p)
    for tol in (6.0, 3.0, 1.5):
        keep = _ellipse_residual(p, ell) < tol
        if keep.sum() < 0.6 * len(pts):
            return None
        p = p[keep]
        ell = cv2.fitEllipse(p)
    return ell
