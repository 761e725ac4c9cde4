"""Zhang-Suen thinning (seed 000 section 3.1, ref. [11]): a compiled (numba) pass over the
object's pixels, driven by the two sub-iterations' deletion tables."""

from __future__ import annotations

import cv2
import numpy as np
from numba import njit

__all__ = ["zhang_suen"]


def _build_luts() -> tuple[np.ndarray, np.ndarray]:
    """Deletion tables for the two sub-iterations, indexed by the 8-neighbour code.

    Bit k of the code is P(k+2) of Zhang-Suen's ring P2 (north), P3, ..., P9 (north-west).
    """
    codes = np.arange(256)
    p = [(codes >> k) & 1 for k in range(8)]  # p[0] = P2 ... p[7] = P9
    b = sum(p)
    a = sum(((p[k] == 0) & (p[(k + 1) % 8] == 1)).astype(int) for k in range(8))
    p2, p4, p6, p8 = p[0], p[2], p[4], p[6]
    base = (b >= 2) & (b <= 6) & (a == 1)
    first = base & (p2 * p4 * p6 == 0) & (p4 * p6 * p8 == 0)
    second = base & (p2 * p4 * p8 == 0) & (p2 * p6 * p8 == 0)
    return first.astype(bool), second.astype(bool)


_LUTS = _build_luts()
_LUTS_U8 = tuple(t.astype(np.uint8) for t in _LUTS)


def zhang_suen(mask: np.ndarray, max_iter: int = 200) -> np.ndarray:
    """One-pixel-wide skeleton of a binary mask (nonzero = object); returns uint8 0/255.

    Each sub-iteration deletes, all at once, the object pixels P1 with 2 <= B(P1) <= 6
    neighbours, exactly one 0->1 transition A(P1) around P2..P9, and P2*P4*P6 = P4*P6*P8 = 0
    (first pass) or P2*P4*P8 = P2*P6*P8 = 0 (second pass).  The conditions are precomputed
    for all 256 neighbourhoods, so a pixel's test is its neighbour code and one table
    look-up; only the pixels still on the object are visited (:func:`_thin`).  Works on the
    object's bounding box only.
    """
    m = np.asarray(mask)
    if m.dtype != np.uint8:
        m = (m > 0).view(np.uint8)
    out = np.zeros(m.shape, np.uint8)
    x0, y0, bw, bh = cv2.boundingRect(m)  # bounding box of the nonzero pixels
    if bw == 0 or bh == 0:
        return out
    y1, x1 = y0 + bh, x0 + bw
    img = np.zeros((bh + 2, bw + 2), np.uint8)  # the box with a border of 0s
    np.greater(m[y0:y1, x0:x1], 0, out=img[1:-1, 1:-1], casting="unsafe")
    _thin(img, max_iter, _LUTS_U8[0], _LUTS_U8[1])
    out[y0:y1, x0:x1] = img[1:-1, 1:-1] * 255
    return out


@njit(cache=True)
def _thin(img, max_iter, lut1, lut2):
    """Zhang-Suen on ``img`` (0/1, a border of 0s), in place: each sub-iteration finds the
    pixels its table deletes from the codes of the image as it stands, then deletes them
    all; stops after a whole iteration deletes nothing, or after ``max_iter``."""
    ys, xs = np.nonzero(img)
    n = len(ys)
    kill = np.empty(n, np.bool_)
    for _ in range(max_iter):
        changed = False
        for sub in range(2):
            lut = lut1 if sub == 0 else lut2
            nk = 0
            for i in range(n):
                y, x = ys[i], xs[i]
                # bit k for P(k+2): north 1, north-east 2, ..., north-west 128
                code = (img[y - 1, x] + 2 * img[y - 1, x + 1] + 4 * img[y, x + 1]
                        + 8 * img[y + 1, x + 1] + 16 * img[y + 1, x]
                        + 32 * img[y + 1, x - 1] + 64 * img[y, x - 1]
                        + 128 * img[y - 1, x - 1])
                k = lut[code] != 0
                kill[i] = k
                nk += k
            if nk:
                changed = True
                j = 0
                for i in range(n):  # delete them, and keep the list of the pixels left
                    if kill[i]:
                        img[ys[i], xs[i]] = 0
                    else:
                        ys[j], xs[j] = ys[i], xs[i]
                        j += 1
                n = j
        if not changed:
            break
