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

from .draws import ransac_samples

__all__ = ["DialEllipse", "NORM_SIZE", "FACE_RADIUS", "find_dial", "normalise_size",
           "rectify", "face_radius", "rectify_projective", "projective_homography", "same_warp"]

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
    # (np.clip(np.round(.).astype(int), 0, side - 1) without the wrappers' overhead)
    xi = np.minimum(np.maximum(x.round().astype(int), 0), w - 1)
    yi = np.minimum(np.maximum(y.round().astype(int), 0), h - 1)
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


def median_u8(img: np.ndarray, mask: np.ndarray) -> float:
    """``np.median(img[mask > 0])`` of a uint8 image (exact: the mean of the two middle
    values) from its histogram under the uint8 ``mask``, without gathering the pixels;
    NaN when the mask is empty."""
    c = np.cumsum(cv2.calcHist([img], [0], mask, [256], [0, 256]).ravel())
    n = int(round(float(c[-1])))
    if n == 0:
        return math.nan
    return 0.5 * (int(np.searchsorted(c, (n - 1) // 2 + 1))
                  + int(np.searchsorted(c, n // 2 + 1)))


def find_dial(image: np.ndarray, min_fill: float = 0.3) -> DialEllipse | None:
    """Face-rim ellipse of the best-supported dial in the image, or None."""
    c = find_dial_candidates(image, min_fill)
    return c[0] if c else None


RIM_SURE = 0.85  # a rim with this share of its perimeter on edges needs no second look


def find_dial_candidates(image: np.ndarray, min_fill: float = 0.3,
                         search_px: float | None = None,
                         votes_only: bool = False) -> list[DialEllipse]:
    """Dial-rim ellipse candidates, best first.

    Canny edges on a reduced copy; every long edge contour gets an ellipse fit; a candidate
    is scored by the share of its perimeter lying on edges and by the contrast of a bright
    face inside against a darker rim outside.  Tilt up to ~45 deg (axis ratio >= 0.65).
    ``search_px``: the reduced copy's longer side (default :data:`CROP_FIND_PX` for a crop,
    320 for a frame).  ``votes_only``: only the rims of the gradients' circle vote
    (:func:`_hough_rims`), scored alike, also on a crop: for a second look where the
    contours' rims held no dial.
    """
    gray = _to_gray(image)
    h0, w0 = gray.shape
    crop = abs(h0 - w0) <= 0.12 * max(h0, w0)
    if search_px is None:
        search_px = CROP_FIND_PX if crop else 320.0
    s = min(1.0, search_px / max(h0, w0))
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

    def candidates():
        for c in contours:
            # a long closed contour is dense: every k-th point gives the same fit, cheaper
            yield cv2.fitEllipse(np.ascontiguousarray(c[:: max(1, len(c) // 200)]))
        if best is None or best[6] < RIM_SURE:
            # a rim arc merged with clutter edges: RANSAC ellipses on each long contour
            # (seeded alike on every image, made only where it is needed)
            rng = np.random.default_rng(0)
            for c in contours:
                e = _ransac_ellipse(c.reshape(-1, 2).astype(np.float32), rng, min_d)
                if e is not None:
                    yield e

    seen: list[tuple[float, float, float, float]] = []
    found: list[tuple] = []

    def scored(ells) -> None:
        nonlocal best
        for (ex, ey), (ea, eb), ang in ells:
            # the two sides of one edge give near-identical ellipses: score each once
            tol = 0.004 * (ea + eb)
            if any(abs(ex - a) < tol and abs(ey - b) < tol and abs(ea - c) < tol
                   and abs(eb - d) < tol for a, b, c, d in seen):
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
            score = support + 0.5 * float(np.clip(contrast / 80.0, -1, 1)) + \
                0.1 * minor / min(h, w)
            found.append((score, ex, ey, ea, eb, ang, support))
            if best is None or score > best[0]:
                best = found[-1]

    if not votes_only:
        scored(candidates())
    if votes_only or (not found and not crop):
        # no long contour held a rim (a knurled or glinting bezel, glare across it, and a
        # backdrop of bricks or pipes whose edges are the longest): circles voted for by
        # the edges' gradients, each refitted as an ellipse to the edge points near it
        scored(_hough_rims(small, edges, min_d, med))
    found.sort(key=lambda f: -f[0])
    return aimed_first([DialEllipse(ex / s, ey / s, ea / s, eb / s, ang, sup)
                        for _, ex, ey, ea, eb, ang, sup in found], (h0, w0))


AIMED_NEARER = 0.3  # a rim this much nearer the frame's centre (share of its half-side)...
AIMED_AMONG = 3  # ... among the best few is the dial the camera is aimed at


def off_centre(cx: float, cy: float, shape) -> float:
    """How far a point lies from the frame's centre, in shares of the frame's half-side."""
    h, w = shape[:2]
    return math.hypot(cx - w / 2.0, cy - h / 2.0) / (min(h, w) / 2.0)


def aimed_first(cands: list[DialEllipse], shape: tuple[int, int]) -> list[DialEllipse]:
    """The rim candidates with the one the camera is aimed at first.

    A frame may hold other gauges beside the one it was taken of, and the best-supported
    rim is then not always that one's (a bezel broken by screws and glare has less support
    than a plain one beside it).  The camera is aimed at the gauge it reads: of the best
    :data:`AIMED_AMONG`, a rim whose centre lies nearer the frame's centre than the first's
    by more than :data:`AIMED_NEARER` of the frame's half-side goes first (the nearest such);
    the others keep their order."""
    if len(cands) < 2:
        return cands
    off = [off_centre(e.cx, e.cy, shape) for e in cands[:AIMED_AMONG]]
    k = min(range(len(off)), key=lambda j: (off[j], j))
    if off[k] >= off[0] - AIMED_NEARER:
        return cands
    return [cands[k], *cands[:k], *cands[k + 1:]]


HOUGH_CIRCLES = 4  # circles of the gradient vote to refit as rims
HOUGH_REFITS = 4  # refits of each to the edge points near it
HOUGH_NEAR = 0.06  # ... those within this share of its radius (and 2 px)


def _hough_rims(small: np.ndarray, edges: np.ndarray, min_d: float, med: float):
    """Rim ellipses from circles found by the gradient vote (OpenCV's HOUGH_GRADIENT_ALT,
    whose circles need not be closed contours).  Each of the best few is refitted as an
    ellipse to the edge points near it, a few times over (a tilted rim is an ellipse that
    the circle only approximates; each refit moves onto the edge nearest it).  Yields cv2
    ellipses, the circle itself too; the caller scores them as any other rim."""
    h, w = small.shape
    circles = cv2.HoughCircles(small, cv2.HOUGH_GRADIENT_ALT, 1.5, min_d / 2.0,
                               param1=max(30.0, 0.9 * med), param2=0.6,
                               minRadius=int(min_d / 2.0), maxRadius=int(0.58 * max(h, w)))
    if circles is None:
        return
    ys, xs = np.nonzero(edges)
    pts = np.column_stack([xs, ys]).astype(np.float32)
    for cx, cy, r in circles[0][:HOUGH_CIRCLES]:
        e = ((float(cx), float(cy)), (2.0 * float(r), 2.0 * float(r)), 0.0)
        yield e
        for _ in range(HOUGH_REFITS):
            near = pts[_ellipse_residual(pts, e) < max(2.0, HOUGH_NEAR * float(r))]
            if len(near) < 40:
                break
            e = cv2.fitEllipse(near)
        else:
            yield e


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
    """Ellipse through the largest consistent subset of a contour (RANSAC, 5-point fits).

    The samples are drawn and fitted first, then every plausible ellipse's inliers are
    counted in one pass over the points (:func:`_inlier_counts`); the first with the most
    wins, as when they were counted one by one."""
    n = len(pts)
    if n < 40:
        return None
    tried = []
    # five points spread along the contour, so one arc is not sampled five times: a start,
    # a stretch of n/8 to n/2 after it and five distinct points of it (:mod:`.draws`)
    for idx in ransac_samples(rng, n, iters):
        try:
            e = cv2.fitEllipse(pts[idx])
        except cv2.error:
            continue
        if min(e[1]) >= min_d and min(e[1]) >= 0.6 * max(e[1]):
            tried.append(e)
    if not tried:
        return None
    counts = _inlier_counts(pts, tried)
    k = int(np.argmax(counts))
    best, best_in = tried[k], int(counts[k])
    if best_in < 30:
        return None
    inl = pts[_ellipse_residual(pts, best) < 1.5]
    return cv2.fitEllipse(inl) if len(inl) >= 5 else best


def _inlier_counts(pts: np.ndarray, ells: list) -> np.ndarray:
    """Points of ``pts`` within 1.5 px of each ellipse (:func:`_ellipse_residual` for all
    of them at once).  Each ellipse's numbers enter as the scalars the one-by-one form uses
    (cast to the points' dtype), so every residual has the same value."""
    par = []
    for (cx, cy), (w, h), ang in ells:
        a, b = max(w / 2, 1e-3), max(h / 2, 1e-3)
        t = math.radians(ang)
        par.append((cx, cy, math.cos(t), math.sin(t), a, b, a + b))
    cx, cy, ct, st, a, b, ab = (np.array(col, pts.dtype)[:, None] for col in zip(*par, strict=True))
    dx, dy = pts[None, :, 0] - cx, pts[None, :, 1] - cy
    xr = dx * ct + dy * st
    yr = -dx * st + dy * ct
    return np.count_nonzero(np.abs(np.hypot(xr / a, yr / b) - 1.0) * ab / 2 < 1.5, axis=1)


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
    """``np.median(v.astype(float32), axis=1)`` by one sort of the rows (same values).
    The rows are sorted as float32, which numpy does several times faster than uint8 rows:
    the conversion keeps the values' order, so the middle values are the same."""
    n = v.shape[1]
    srt = np.sort(v if v.dtype == np.float32 else v.astype(np.float32), axis=1)
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
    h = projective_homography(ell, centre_xy, radius_out, size)
    if h is None:
        return None
    crop = cv2.warpPerspective(image, h, (size, size), flags=cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_REPLICATE)
    return crop, h


def projective_homography(ell: DialEllipse, centre_xy, radius_out: float = FACE_RADIUS,
                          size: int = NORM_SIZE) -> np.ndarray | None:
    """:func:`rectify_projective`'s 3x3 image->crop homography alone (no warp), or None if
    the geometry is degenerate."""
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
    return out_t @ hs @ h1 @ t


SAME_WARP_PX = 0.01  # two warps whose crops sample the input this near alike are one


def same_warp(h_a: np.ndarray, h_b: np.ndarray) -> bool:
    """Two input -> normalised crop homographies sample the input within
    :data:`SAME_WARP_PX` of each other at the crop's corners and centre (where a
    projective map's difference over the square is largest, and its middle)."""
    q = np.array([[0, 0, 1.0], [NORM_SIZE, 0, 1.0], [0, NORM_SIZE, 1.0],
                  [NORM_SIZE, NORM_SIZE, 1.0], [NORM_SIZE / 2.0, NORM_SIZE / 2.0, 1.0]]).T
    a = np.linalg.solve(h_a, q)
    b = np.linalg.solve(h_b, q)
    a, b = a[:2] / a[2], b[:2] / b[2]
    return bool(np.abs(a - b).max() <= SAME_WARP_PX)
