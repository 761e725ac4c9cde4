"""Otsu binarisation, seed 000 section 3.1, eqs. 1-18."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["binarize", "otsu_threshold"]


def otsu_threshold(gray: np.ndarray, levels: int = 256, mask: np.ndarray | None = None) -> int:
    """Threshold t maximising eta(t) = sigma_b^2 / sigma_T^2 (eqs. 1-17).

    Histogram n_i and N (eq. 1), normalised q_i (eq. 2), class probabilities w(t) (eqs. 5-6),
    cumulative means u(t), u_T (eqs. 9-10), class means (eqs. 7-8) and the between-class
    variance sigma_b^2 = w1 w2 (u1 - u2)^2 (eq. 14).  The total variance sigma_T^2 (eq. 15)
    does not depend on t, so argmax eta (eqs. 16-17) is argmax sigma_b^2.  Vectorised over all
    t at once.  ``mask`` restricts the histogram to the pixels of interest (the dial).
    """
    if gray.dtype == np.uint8 and levels == 256 and (mask is None or mask.dtype == np.uint8):
        n = cv2.calcHist([gray], [0], mask, [256], [0, 256]).ravel().astype(np.float64)  # eq. 1
    else:
        vals = gray[mask > 0] if mask is not None else gray.ravel()
        vals = np.clip(vals, 0, levels - 1).astype(np.intp, copy=False)
        n = np.bincount(vals, minlength=levels).astype(np.float64)  # n_i, eq. 1
    total = n.sum()
    if total == 0:
        return 0
    q = n / total  # eq. 2
    i = np.arange(levels, dtype=np.float64)
    w = np.cumsum(q)  # w(t), eq. 5; w2 = 1 - w(t), eq. 6
    u = np.cumsum(i * q)  # u(t), eq. 9
    u_t = u[-1]  # u_T, eq. 10
    with np.errstate(divide="ignore", invalid="ignore"):
        u1 = u / w  # eq. 7
        u2 = (u_t - u) / (1.0 - w)  # eq. 8
        sb = w * (1.0 - w) * (u1 - u2) ** 2  # eq. 14
    sb = np.nan_to_num(sb, nan=-1.0, posinf=-1.0, neginf=-1.0)
    # eq. 17; for a flat plateau of maxima take its middle
    best = np.flatnonzero(sb >= sb.max() - 1e-12 * max(sb.max(), 1.0))
    return int(best[len(best) // 2])


def binarize(gray: np.ndarray, t: int) -> np.ndarray:
    """Eq. 18: 255 where I(x, y) > t, else 0 (uint8)."""
    if gray.dtype == np.uint8:
        return cv2.threshold(gray, int(t), 255, cv2.THRESH_BINARY)[1]
    return np.where(gray > t, 255, 0).astype(np.uint8)
