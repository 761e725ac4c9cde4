"""Finding the dial in a frame and mapping it to the normalised 300 x 300 upright-ish crop.

Section 3.1 step 1 (size normalisation) for ready crops; beyond the paper: the dial's face
rim is found as an ellipse among clutter and an oblique view is rectified by the affine map
that turns that ellipse into a circle.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["DialEllipse", "NORM_SIZE", "FACE_RADIUS", "find_dial", "normalise_size",
           "rectify", "face_radius"]

log = logging.getLogger(__name__)

NORM_SIZE = 300  # the paper's working size (section 3.1)
FACE_RADIUS = 135.0  # face radius in the normalised crop
CROP_FIND_PX = 320.0  # a crop is searched for its rim at up to this size


@dataclass(frozen=True)
class DialEllipse:
    """The face rim in image coordinates: centre, full axes (cv2 convention), angle, score."""

    cx: float
    cy: float
    width: float
    height: float
    angle_deg: float
    support: float

    @property
    def radius(self) -> float:
        return (self.width + self.height) / 4.0


def normalise_size(img: np.ndarray, size: int = NORM_SIZE) -> np.ndarray:
    """Step 1 (section 3.1): resize the dial image to size x size."""
    interp = cv2.INTER_AREA if max(img.shape[:2]) > size else cv2.INTER_LINEAR
    return cv2.resize(img, (size, size), interpolation=interp)


def _to_gray(img: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img


_UNIT: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _ellipse_points(cx, cy, w, h, ang, n=96, scale=1.0):
    cs = _UNIT.get(n)
    if cs is None:
        t = np.linspace(0, 2 * np.pi, n, endpoint=False)
        cs = _UNIT[n] = (np.cos(t), np.sin(t))
    ct, st = cs
    a, b = w / 2 * scale, h / 2 * scale
    c, s = math.cos(math.radians(ang)), math.sin(math.radians(ang))
    x = cx + a * ct * c - b * st * s
    y = cy + a * ct * s + b * st * c
    return x, y


def _sample(img, x, y):
    h, w = img.shape[:2]
    xi = np.clip(np.round(x).astype(int), 0, w - 1)
    yi = np.clip(np.round(y).astype(int), 0, h - 1)
    inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    return img[yi, xi], inside


def _median(a: np.ndarray) -> float:
    """``np.median`` of a 1-D array without its per-call overhead (by one sort; uint8 by
    its histogram).  Same value."""
    n = len(a)
    if a.dtype == np.uint8 and n > 512:
        c = np.cumsum(np.bincount(a, minlength=256))
        return 0.5 * (int(np.searchsorted(c, (n - 1) // 2 + 1))
                      + int(np.searchsorted(c, n // 2 + 1)))
    srt = np.sort(a)
    if n % 2:
        return float(srt[n // 2])
    return 0.5 * (float(srt[n // 2 - 1]) + float(srt[n // 2]))


def find_dial(image: np.ndarray, min_fill: float = 0.3) -> DialEllipse | None:
    """Face-rim ellipse of the best-supported dial in the image, or None."""
    c = find_dial_candidates(image, min_fill)
    return c[0] if c else None


def find_dial_candidates(image: np.ndarray, min_fill: float = 0.3) -> list[DialEllipse]:
    """Dial-rim ellipse candidates, best first.

    Canny edges on a reduced copy; every long edge contour gets an ellipse fit; a candidate
    is scored by the share of its perimeter lying on edges and by the contrast of a bright
    face inside against a darker rim outside.  Tilt up to ~45 deg (axis ratio >= 0.65).
    """
    gray = _to_gray(image)
    h0, w0 = gray.shape
    crop = abs(h0 - w0) <= 0.12 * max(h0, w0)
    s = min(1.0, (CROP_FIND_PX if crop else 320.0) / max(h0, w0))
    small = cv2.resize(gray, None, fx=s, fy=s, interpolation=cv2.INTER_AREA) if s < 1 else gray
    small = cv2.GaussianBlur(small, (5, 5), 1.2)
    h, w = small.shape
    med = _median(small.ravel())
    edges = cv2.Canny(small, max(10.0, 0.33 * med), max(30.0, 0.9 * med))
    dil = cv2.dilate(edges, np.ones((3, 3), np.uint8))
    contours, _ = cv2.findContours(edges, cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    min_d = min_fill * min(h, w)
    best = None
    contours = sorted((c for c in contours if len(c) >= max(30, 1.5 * min_d)), key=len,
                      reverse=True)[:8]
    contours = [c for c in contours if max(cv2.boundingRect(c)[2:]) >= min_d]
    rng = np.random.default_rng(0)

    def candidates():
        for c in contours:
            # a long closed contour is dense: every k-th point gives the same fit, cheaper
            yield cv2.fitEllipse(np.ascontiguousarray(c[:: max(1, len(c) // 200)]))
        if best is None or best[6] < 0.85:
            # a rim arc merged with clutter edges: RANSAC ellipses on each long contour
            for c in contours:
                e = _ransac_ellipse(c.reshape(-1, 2).astype(np.float32), rng, min_d)
                if e is not None:
                    yield e

    seen: list[tuple[float, float, float, float]] = []
    found: list[tuple] = []
    for (ex, ey), (ea, eb), ang in candidates():
        # the two sides of one edge give near-identical ellipses: score each once
        tol = 0.004 * (ea + eb)
        if any(abs(ex - a) < tol and abs(ey - b) < tol and abs(ea - c) < tol and abs(eb - d) < tol
               for a, b, c, d in seen):
            continue
        seen.append((ex, ey, ea, eb))
        major, minor = max(ea, eb), min(ea, eb)
        if minor < 0.65 * major or minor < min_d or major > 1.15 * max(h, w):
            continue
        px, py = _ellipse_points(ex, ey, ea, eb, ang)
        on, inside = _sample(dil, px, py)
        if inside.mean() < 0.85:
            continue
        support = float((on[inside] > 0).mean())
        if support < 0.5:
            continue
        gi, ii = _sample(small, *_ellipse_points(ex, ey, ea, eb, ang, 64, 0.9))
        go, io = _sample(small, *_ellipse_points(ex, ey, ea, eb, ang, 64, 1.08))
        contrast = _median(gi[ii]) - _median(go[io]) if io.any() else 0.0
        score = support + 0.5 * float(np.clip(contrast / 80.0, -1, 1)) + 0.1 * minor / min(h, w)
        found.append((score, ex, ey, ea, eb, ang, support))
        if best is None or score > best[0]:
            best = found[-1]
    found.sort(key=lambda f: -f[0])
    return [DialEllipse(ex / s, ey / s, ea / s, eb / s, ang, sup)
            for _, ex, ey, ea, eb, ang, sup in found]


def _ellipse_residual(pts: np.ndarray, e) -> np.ndarray:
    """Approximate distance (px) of points from an ellipse given in cv2 form."""
    (cx, cy), (w, h), ang = e
    a, b = max(w / 2, 1e-3), max(h / 2, 1e-3)
    t = math.radians(ang)
    dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
    xr = dx * math.cos(t) + dy * math.sin(t)
    yr = -dx * math.sin(t) + dy * math.cos(t)
    return np.abs(np.hypot(xr / a, yr / b) - 1.0) * (a + b) / 2


def _ransac_ellipse(pts: np.ndarray, rng: np.random.Generator, min_d: float, iters: int = 24):
    """Ellipse through the largest consistent subset of a contour (RANSAC, 5-point fits)."""
    n = len(pts)
    if n < 40:
        return None
    best, best_in = None, 0
    for _ in range(iters):
        # five points spread along the contour, so one arc is not sampled five times
        base = int(rng.integers(0, n))
        span = int(rng.integers(n // 8, n // 2 + 1))
        idx = (base + np.sort(rng.choice(span, 5, replace=False))) % n
        try:
            e = cv2.fitEllipse(pts[idx])
        except cv2.error:
            continue
        if not (min(e[1]) >= min_d and min(e[1]) >= 0.6 * max(e[1])):
            continue
        inl = int((_ellipse_residual(pts, e) < 1.5).sum())
        if inl > best_in:
            best, best_in = e, inl
    if best is None or best_in < 30:
        return None
    inl = pts[_ellipse_residual(pts, best) < 1.5]
    return cv2.fitEllipse(inl) if len(inl) >= 5 else best


def rectify(
    image: np.ndarray, ell: DialEllipse, radius_out: float = FACE_RADIUS, size: int = NORM_SIZE,
) -> tuple[np.ndarray, np.ndarray]:
    """Warp so the ellipse becomes a circle of ``radius_out`` centred in a size x size crop.

    The affine map scales along the ellipse's own axes and turns back, so the image's up
    direction is kept as well as an affine map can.  Returns (crop, 2x3 frame->crop matrix).
    """
    a, b = ell.width / 2.0, ell.height / 2.0
    t = math.radians(ell.angle_deg)
    r = np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])
    s = np.diag([radius_out / a, radius_out / b])
    lin = r @ s @ r.T
    c = np.array([ell.cx, ell.cy])
    off = np.array([size / 2.0, size / 2.0]) - lin @ c
    m = np.hstack([lin, off[:, None]])
    out = cv2.warpAffine(image, m, (size, size), flags=cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)
    return out, m


_RING_IDX: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def face_radius(gray: np.ndarray, centre=(NORM_SIZE / 2, NORM_SIZE / 2),
                r_lo: float = 60.0, r_hi: float = 149.0) -> float | None:
    """Radius where the bright face ends, from the median grey on rings around ``centre``.

    Scans inward from ``r_hi``: first into the darker bezel, then to the first ring bright
    again, so dark tick rings and numerals inside the face do not count.
    """
    rs = np.arange(r_lo, r_hi, 1.0)
    key = (gray.shape[:2], float(centre[0]), float(centre[1]), float(r_lo), float(r_hi))
    idx = _RING_IDX.get(key)
    if idx is None:  # the ring sample positions depend only on the geometry: cached
        th = np.linspace(0, 2 * np.pi, 120, endpoint=False)
        x = centre[0] + rs[:, None] * np.sin(th)[None, :]
        y = centre[1] - rs[:, None] * np.cos(th)[None, :]
        h, w = gray.shape[:2]
        idx = (np.clip(np.round(y).astype(int), 0, h - 1), np.clip(np.round(x).astype(int), 0,
                                                                      w - 1))
        if len(_RING_IDX) > 16:
            _RING_IDX.clear()
        _RING_IDX[key] = idx
    v = gray[idx]
    prof = _row_medians(v)
    face = _percentile75(prof)
    thr = face - max(25.0, 0.22 * face)
    dark = prof < thr
    k = len(rs) - 1
    while True:
        while k > 0 and not dark[k]:
            k -= 1
        while k > 0 and dark[k]:
            k -= 1
        if k < 4:
            return None
        if not dark[k - 4:k + 1].any():  # a wide bright ring: the face, not a bezel highlight
            break
    p0, p1 = prof[k], prof[k + 1]  # p0 bright, p1 dark
    f = (p0 - thr) / max(p0 - p1, 1e-6)
    return float(rs[k] + f)


def _row_medians(v: np.ndarray) -> np.ndarray:
    """``np.median(v.astype(float32), axis=1)`` by one sort of the rows (same values)."""
    n = v.shape[1]
    srt = np.sort(v, axis=1)
    if n % 2:
        return srt[:, n // 2].astype(np.float32)
    return (srt[:, n // 2 - 1].astype(np.float32) + srt[:, n // 2].astype(np.float32)) * \
        np.float32(0.5)


def _percentile75(a: np.ndarray) -> float:
    """``np.percentile(a, 75)`` (linear interpolation) of a 1-D array, by one sort."""
    srt = np.sort(a)
    pos = 0.75 * (len(srt) - 1)
    i = int(pos)
    f = pos - i
    if f == 0 or i + 1 >= len(srt):
        return float(srt[i])
    lo, hi = float(srt[i]), float(srt[i + 1])
    return lo + (hi - lo) * f


def ellipse_conic(ell: DialEllipse) -> np.ndarray:
    """3x3 symmetric conic matrix C with x^T C x = 0 on the ellipse (homogeneous x)."""
    a, b = ell.width / 2.0, ell.height / 2.0
    t = math.radians(ell.angle_deg)
    r = np.array([[math.cos(t), math.sin(t)], [-math.sin(t), math.cos(t)]])
    m = r.T @ np.diag([1.0 / a**2, 1.0 / b**2]) @ r
    c = np.array([ell.cx, ell.cy])
    out = np.empty((3, 3))
    out[:2, :2] = m
    out[:2, 2] = out[2, :2] = -m @ c
    out[2, 2] = c @ m @ c - 1.0
    return out


def rectify_projective(
    image: np.ndarray, ell: DialEllipse, centre_xy, radius_out: float = FACE_RADIUS,
    size: int = NORM_SIZE,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Undo the perspective of an oblique view from the rim ellipse and the dial centre.

    The image of the circle's centre is the pole of the plane's vanishing line with respect
    to the rim conic, so l = C c.  Sending l to infinity makes the rim an ellipse centred on
    the hub; a symmetric linear map then makes it a circle of ``radius_out``.  Unlike the
    affine map of :func:`rectify` this also removes the angular distortion of perspective.
    Returns (crop, 3x3 image->crop homography) or None if the geometry is degenerate.
    """
    cx, cy = centre_xy
    t = np.array([[1, 0, -cx], [0, 1, -cy], [0, 0, 1.0]])
    ti = np.linalg.inv(t)
    c1 = ti.T @ ellipse_conic(ell) @ ti
    if c1[2, 2] >= 0:  # the centre must lie inside the rim
        return None
    l_vec = c1[:, 2]
    h1 = np.array([[1, 0, 0], [0, 1, 0], [l_vec[0] / l_vec[2], l_vec[1] / l_vec[2], 1.0]])
    h1i = np.linalg.inv(h1)
    c2 = h1i.T @ c1 @ h1i
    a = c2[:2, :2] / -c2[2, 2]
    w, v = np.linalg.eigh(a)
    if w.min() <= 0:
        return None
    s = v @ np.diag(np.sqrt(w)) @ v.T * radius_out
    hs = np.eye(3)
    hs[:2, :2] = s
    out_t = np.array([[1, 0, size / 2.0], [0, 1, size / 2.0], [0, 0, 1.0]])
    h = out_t @ hs @ h1 @ t
    crop = cv2.warpPerspective(image, h, (size, size), flags=cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_REPLICATE)
    return crop, h


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
    face = float(np.median(v[:, : len(rs) // 4]))
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
    fraction of a pixel; otherwise None.
    """
    h, w = gray.shape[:2]
    pts = ok = None
    for i, band in enumerate(bands):
        pts, ok = rim_edge_points(gray, ell, band)
        if ok.mean() < min_share:
            return None
        p = pts[ok]
        prev = ell
        ell = cv2.fitEllipse(p)
        keep = _ellipse_residual(p, ell) < 1.5
        if keep.sum() < min_share * len(pts):
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
    if share < min_share or rms > max_rms or minor < 0.65 * major or minor < 0.5 * min(h, w) \
            or major > 1.15 * max(h, w):
        return None
    return DialEllipse(float(ex), float(ey), float(ea), float(eb), float(ang), share)


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
    (:func:`find_dial_candidates`).
    """
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
