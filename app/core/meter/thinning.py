"""Zhang-Suen thinning (seed 000 section 3.1, ref. [11]): deletion tables for the 256
neighbourhoods, applied by a compiled kernel (numba) that visits only the object's pixels.

The kernel keeps the algorithm's parallel rule: in each sub-iteration every pixel is judged
on the image as it was before that sub-iteration, and the pixels marked are deleted
together afterwards.  It gives the same skeleton as applying the tables to the whole image
by a 3 x 3 correlation per sub-iteration, which spent most of its time on background."""

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
_LUTS_U8 = np.stack([t.astype(np.uint8) for t in _LUTS])  # (2, 256): first, second pass


@njit(cache=True)
def _thin(img: np.ndarray, luts: np.ndarray, max_iter: int) -> None:
    """Zhang-Suen in place on a 0/1 uint8 image with a background border of 1 px.

    The object's pixels are kept in a list that shrinks as they are deleted; each
    sub-iteration computes every listed pixel's neighbour code (bit k for P(k+2): P2
    north = 1, P3 north-east = 2, ... P9 north-west = 128) on the unchanged image, marks
    those its table deletes, then deletes them all at once."""
    ys, xs = np.nonzero(img)
    n = len(ys)
    kill = np.zeros(n, np.bool_)
    for _ in range(max_iter):
        changed = False
        for t in range(2):
            lut = luts[t]
            any_kill = False
            for k in range(n):
                y, x = ys[k], xs[k]
                code = (np.int64(img[y - 1, x]) + 2 * np.int64(img[y - 1, x + 1])
                        + 4 * np.int64(img[y, x + 1]) + 8 * np.int64(img[y + 1, x + 1])
                        + 16 * np.int64(img[y + 1, x]) + 32 * np.int64(img[y + 1, x - 1])
                        + 64 * np.int64(img[y, x - 1]) + 128 * np.int64(img[y - 1, x - 1]))
                if lut[code]:
                    kill[k] = True
                    any_kill = True
            if any_kill:
                changed = True
                m = 0
                for k in range(n):
                    if kill[k]:
                        img[ys[k], xs[k]] = 0
                        kill[k] = False
                    else:
                        ys[m] = ys[k]
                        xs[m] = xs[k]
                        m += 1
                n = m
        if not changed:
            break


def zhang_suen(mask: np.ndarray, max_iter: int = 200) -> np.ndarray:
    """One-pixel-wide skeleton of a binary mask (nonzero = object); returns uint8 0/255.

    Each sub-iteration deletes, all at once, the object pixels P1 with 2 <= B(P1) <= 6
    neighbours, exactly one 0->1 transition A(P1) around P2..P9, and P2*P4*P6 = P4*P6*P8 = 0
    (first pass) or P2*P4*P8 = P2*P6*P8 = 0 (second pass).  The conditions are precomputed
    for all 256 neighbourhoods (:func:`_build_luts`); the compiled kernel :func:`_thin`
    looks each remaining object pixel's neighbourhood up in them.  Works on the object's
    bounding box only.
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
    _thin(img, _LUTS_U8, max_iter)
    out[y0:y1, x0:x1] = img[1:-1, 1:-1] * 255
    return out
