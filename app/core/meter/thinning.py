"""Zhang-Suen thinning (seed 000 section 3.1, ref. [11]), vectorised (numpy tables, OpenCV)."""

from __future__ import annotations

import cv2
import numpy as np

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
# correlation weights giving bit k for P(k+2): P2 north = 1, P3 = 2, ... P9 north-west = 128
_CODE_KERNEL = np.array([[128, 1, 2], [64, 0, 4], [32, 16, 8]], np.float32)


def zhang_suen(mask: np.ndarray, max_iter: int = 200) -> np.ndarray:
    """One-pixel-wide skeleton of a binary mask (nonzero = object); returns uint8 0/255.

    Each sub-iteration deletes, all at once, the object pixels P1 with 2 <= B(P1) <= 6
    neighbours, exactly one 0->1 transition A(P1) around P2..P9, and P2*P4*P6 = P4*P6*P8 = 0
    (first pass) or P2*P4*P8 = P2*P6*P8 = 0 (second pass).  The conditions are precomputed
    for all 256 neighbourhoods, so a pass is one 3 x 3 correlation (the neighbour code) and
    one table look-up over the whole array -- no per-pixel Python loop.  Works on the
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
    img = np.zeros((bh + 2, bw + 2), np.uint8)
    np.greater(m[y0:y1, x0:x1], 0, out=img[1:-1, 1:-1], casting="unsafe")
    for _ in range(max_iter):
        changed = False
        for lut in _LUTS_U8:
            # the 8-neighbour code of every pixel in one correlation (weights 1 .. 128)
            code = cv2.filter2D(img, cv2.CV_8U, _CODE_KERNEL, borderType=cv2.BORDER_CONSTANT)
            kill = cv2.bitwise_and(cv2.LUT(code, lut), img)
            if cv2.countNonZero(kill):
                cv2.subtract(img, kill, dst=img)
                changed = True
        if not changed:
            break
    out[y0:y1, x0:x1] = img[1:-1, 1:-1] * 255
    return out
