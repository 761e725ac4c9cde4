"""Registration of a camera frame to a calibrated inspection point's reference frame.

The robot stops at the same inspection point on every patrol, so the gauge is seen from
nearly the same place as in the reference frame the operator clicked.  The dial's plane is
mapped from the reference to the new frame by a homography: ORB keypoints (FAST corners
with rotated BRIEF descriptors) on the reference, restricted to the dial region and cached
per reference file, matched to the frame's keypoints with Lowe's ratio test, and a robust
fit (``cv2.findHomography`` with MAGSAC++).  The pivot and the end marks are then carried
over with ``cv2.perspectiveTransform``.

A registration that cannot be trusted is refused with a reason, never used: too few
inliers, too small a share of the matches agreeing, inliers bunched in one part of the dial,
or an implausible warp (scale, shear, strong perspective, reflection, the dial leaving the
frame).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

__all__ = [
    "MIN_INLIERS",
    "Registration",
    "carry_points",
    "jacobian",
    "reference_features",
    "reference_image",
    "register",
]

log = logging.getLogger(__name__)

MIN_INLIERS = 25
MIN_INLIER_SHARE = 0.25  # of the matches that passed the ratio test
RATIO = 0.8  # Lowe's ratio test
REGION_FACTOR = 1.4  # the dial region: out to 1.4 x the pivot-to-end-mark distance
SEARCH_FACTOR = 1.8  # the frame is searched first this far around the reference position
RANSAC_PX = 3.0
MIN_SPREAD = 0.2  # the inliers' spread over the dial, in units of its radius
REF_FEATURES = 700  # ORB keypoints on the reference dial region (matching costs N x M)
FRAME_FEATURES = 900
MAX_SCALE = 2.0  # frame scale relative to the reference: 1/2 .. 2
MAX_ANISOTROPY = 1.6  # ratio of the local scales along two axes (a change of tilt)
MAX_PERSPECTIVE = 0.25  # relative change of the local scale across the dial


@dataclass
class Registration:
    """Result of :func:`register`: ``homography`` maps reference pixels to frame pixels."""

    ok: bool
    homography: np.ndarray | None
    n_inliers: int = 0
    n_matches: int = 0
    score: float = 0.0
    error: str | None = None


_IMAGES: dict[Path, tuple[tuple[int, int], np.ndarray]] = {}
_FEATURES: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def _stamp(path: Path) -> tuple[int, int]:
    st = path.stat()
    return st.st_mtime_ns, st.st_size


def reference_image(path) -> np.ndarray:
    """The reference frame as grey, decoded once and cached while its file is unchanged.

    Raises ValueError naming the file when it is missing or not an image."""
    path = Path(path)
    try:
        stamp = _stamp(path)
    except OSError:
        raise ValueError(f"reference image {path}: no such file") from None
    hit = _IMAGES.get(path)
    if hit is not None and hit[0] == stamp:
        return hit[1]
    data = np.fromfile(str(path), dtype=np.uint8) if path.is_file() else np.empty(0, np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE) if data.size else None
    if img is None:
        raise ValueError(f"reference image {path}: not a readable image")
    if len(_IMAGES) > 64:
        _IMAGES.clear()
    _IMAGES[path] = (stamp, img)
    return img


def _orb(n: int) -> cv2.ORB:
    # few pyramid levels: a re-visited point is seen at nearly the same scale
    return cv2.ORB_create(nfeatures=n, scaleFactor=1.2, nlevels=6, edgeThreshold=15,
                          patchSize=15, fastThreshold=12)


def _disc_mask(shape, centre, radius: float) -> np.ndarray:
    m = np.zeros(shape[:2], np.uint8)
    cv2.circle(m, (int(round(centre[0])), int(round(centre[1]))), max(1, int(radius)), 255, -1)
    return m


def reference_features(path, centre, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """ORB keypoints (N x 2 float32) and descriptors of the reference's dial region (a disc
    of ``REGION_FACTOR * radius`` around the pivot), cached per file, mtime and region."""
    path = Path(path)
    img = reference_image(path)
    key = (path, _stamp(path), round(centre[0], 1), round(centre[1], 1), round(radius, 1))
    hit = _FEATURES.get(key)
    if hit is not None:
        return hit
    kps, desc = _orb(REF_FEATURES).detectAndCompute(img, _disc_mask(img.shape, centre,
                                                            REGION_FACTOR * radius))
    pts = np.array([k.pt for k in kps], np.float32).reshape(-1, 2)
    if desc is None:
        desc = np.zeros((0, 32), np.uint8)
    if len(_FEATURES) > 64:
        _FEATURES.clear()
    hit = _FEATURES[key] = (pts, desc)
    return hit


def carry_points(h: np.ndarray, pts) -> np.ndarray:
    """Points (N x 2) carried through the homography ``h``."""
    p = np.asarray(pts, np.float64).reshape(-1, 1, 2)
    return cv2.perspectiveTransform(p, np.asarray(h, np.float64)).reshape(-1, 2)


def _ramp(x: float, bad: float, good: float) -> float:
    return float(min(1.0, max(0.0, (x - bad) / (good - bad))))


def jacobian(h: np.ndarray, x: float, y: float) -> np.ndarray:
    """Local linear part of the homography at (x, y)."""
    u, v, w = h @ np.array([x, y, 1.0])
    return np.array([[h[0, 0] * w - u * h[2, 0], h[0, 1] * w - u * h[2, 1]],
                     [h[1, 0] * w - v * h[2, 0], h[1, 1] * w - v * h[2, 1]]]) / (w * w)


def implausible(h: np.ndarray, centre, radius: float, frame_shape, carried) -> str | None:
    """Why the warp cannot be a re-visit of the same dial (None when it is plausible)."""
    cx, cy = centre
    j = jacobian(h, cx, cy)
    if not np.all(np.isfinite(j)) or np.linalg.det(j) <= 0:
        return "implausible warp (mirrored or degenerate)"
    s = np.linalg.svd(j, compute_uv=False)
    scale = math.sqrt(s[0] * s[1])
    if not 1.0 / MAX_SCALE <= scale <= MAX_SCALE:
        return f"implausible warp (scale {scale:.2f})"
    if s[0] / s[1] > MAX_ANISOTROPY:
        return f"implausible warp (shear or tilt change {s[0] / s[1]:.2f})"
    scales = []
    for dx, dy in ((radius, 0), (-radius, 0), (0, radius), (0, -radius)):
        jj = jacobian(h, cx + dx, cy + dy)
        scales.append(math.sqrt(abs(np.linalg.det(jj))))
    spread = (max(scales) - min(scales)) / scale
    if spread > MAX_PERSPECTIVE:
        return f"implausible warp (strong perspective: local scale varies {100 * spread:.0f} %)"
    hgt, wid = frame_shape[:2]
    p = np.asarray(carried)
    if (p[:, 0] < 1).any() or (p[:, 1] < 1).any() or (p[:, 0] > wid - 2).any() \
            or (p[:, 1] > hgt - 2).any():
        return "the carried points leave the image"
    return None


def register(frame_gray: np.ndarray, cal) -> Registration:
    """Register a grey frame to ``cal``'s reference image (a :class:`Calibration` with
    ``image_path``); returns a :class:`Registration`, refused with a reason if unsure."""
    radius = cal.radius_px
    try:
        ref_pts, ref_desc = reference_features(cal.image_path, cal.center, radius)
    except ValueError as e:
        return Registration(False, None, error=f"registration failed: {e}")
    if len(ref_pts) < MIN_INLIERS:
        return Registration(False, None, error=f"registration failed: the reference has only "
                                               f"{len(ref_pts)} features on the dial")
    orb = _orb(FRAME_FEATURES)
    # first around where the dial was in the reference, then the whole frame
    masks = [_disc_mask(frame_gray.shape, cal.center, SEARCH_FACTOR * REGION_FACTOR * radius),
             None]
    best = None
    for mask in masks:
        reg = _match(orb, frame_gray, mask, ref_pts, ref_desc, cal, radius)
        if reg.ok:
            return reg
        if best is None or reg.n_inliers > best.n_inliers:
            best = reg
    return best


def _match(orb, frame_gray, mask, ref_pts, ref_desc, cal, radius) -> Registration:
    kps, desc = orb.detectAndCompute(frame_gray, mask)
    if desc is None or len(kps) < MIN_INLIERS:
        n = 0 if desc is None else len(kps)
        return Registration(False, None, error=f"registration failed: {n} features in the frame")
    pts = np.array([k.pt for k in kps], np.float32)
    pairs = cv2.BFMatcher(cv2.NORM_HAMMING).knnMatch(ref_desc, desc, k=2)
    good = [m[0] for m in pairs if len(m) == 2 and m[0].distance < RATIO * m[1].distance]
    n = len(good)
    if n < MIN_INLIERS:
        return Registration(False, None, n_inliers=n, n_matches=n,
                            error=f"registration failed: {n} matches (need {MIN_INLIERS})")
    src = ref_pts[[m.queryIdx for m in good]]
    dst = pts[[m.trainIdx for m in good]]
    h, inl = cv2.findHomography(src, dst, cv2.USAC_MAGSAC, RANSAC_PX, maxIters=2000,
                                confidence=0.999)
    if h is None or inl is None:
        return Registration(False, None, 0, n, error="registration failed: no homography")
    inl = inl.ravel().astype(bool)
    k = int(inl.sum())
    share = k / n
    if k < MIN_INLIERS:
        return Registration(False, None, k, n,
                            error=f"registration failed: {k} inliers (need {MIN_INLIERS})")
    if share < MIN_INLIER_SHARE:
        return Registration(False, None, k, n,
                            error=f"registration failed: {100 * share:.0f} % of {n} matches "
                                  f"agree (need {100 * MIN_INLIER_SHARE:.0f} %)")
    # the inliers must spread over the dial, not sit in one corner of it: the smaller
    # standard deviation of their positions (the half-dial of a 180 deg scale gives
    # about 0.3 R) and the larger one, in units of the dial's radius
    d = src[inl].astype(np.float64)
    s_lo, s_hi = np.sqrt(np.maximum(np.linalg.eigvalsh(np.cov(d.T)), 0.0)) / max(radius, 1.0)
    log.debug("registration spread %.2f %.2f", s_lo, s_hi)
    if s_lo < MIN_SPREAD or s_hi < 2 * MIN_SPREAD:
        return Registration(False, None, k, n, error="registration failed: the matches cover "
                                                     "only part of the dial")
    carried = carry_points(h, [cal.center, cal.min_point, cal.max_point])
    why = implausible(h, cal.center, radius, frame_gray.shape, carried)
    if why is not None:
        return Registration(False, None, k, n, error=f"registration failed: {why}")
    score = min(_ramp(k, MIN_INLIERS, 2 * MIN_INLIERS + 10), _ramp(share, MIN_INLIER_SHARE, 0.5))
    return Registration(True, h, k, n, score=0.7 + 0.3 * score)
