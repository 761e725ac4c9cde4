"""Zhang-Suen thinning (seed 000 section 3.1, ref. [11]), vectorised with numpy."""

from __future__ import annotations

import numpy as np

__all__ = ["zhang_suen"]


def zhang_suen(mask: np.ndarray, max_iter: int = 200) -> np.ndarray:
    """One-pixel-wide skeleton of a binary mask (nonzero = object); returns uint8 0/255.

    Each sub-iteration marks, for all pixels at once, the object pixels P1 with
    2 <= B(P1) <= 6 neighbours, exactly one 0->1 transition A(P1) in the ring P2..P9, and
    P2*P4*P6 = P4*P6*P8 = 0 (first pass) or P2*P4*P8 = P2*P6*P8 = 0 (second pass); the
    marked pixels are removed together.  Repeats until nothing changes.  Works on the
    bounding box of the object only, so cost scales with the pointer, not the image.
    """
    m = np.asarray(mask) > 0
    out = np.zeros(m.shape, np.uint8)
    ys, xs = np.nonzero(m)
    if len(ys) == 0:
        return out
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    img = np.zeros((y1 - y0 + 2, x1 - x0 + 2), np.uint8)
    img[1:-1, 1:-1] = m[y0:y1, x0:x1]
    for _ in range(max_iter):
        changed = False
        for step in (0, 1):
            p2 = img[:-2, 1:-1]
            p3 = img[:-2, 2:]
            p4 = img[1:-1, 2:]
            p5 = img[2:, 2:]
            p6 = img[2:, 1:-1]
            p7 = img[2:, :-2]
            p8 = img[1:-1, :-2]
            p9 = img[:-2, :-2]
            ring = (p2, p3, p4, p5, p6, p7, p8, p9, p2)
            b = p2 + p3 + p4 + p5 + p6 + p7 + p8 + p9
            a = np.zeros_like(b)
            for k in range(8):
                a += (ring[k] == 0) & (ring[k + 1] == 1)
            if step == 0:
                c1 = (p2 * p4 * p6) == 0
                c2 = (p4 * p6 * p8) == 0
            else:
                c1 = (p2 * p4 * p8) == 0
                c2 = (p2 * p6 * p8) == 0
            kill = (img[1:-1, 1:-1] == 1) & (b >= 2) & (b <= 6) & (a == 1) & c1 & c2
            if kill.any():
                img[1:-1, 1:-1][kill] = 0
                changed = True
        if not changed:
            break
    out[y0:y1, x0:x1] = img[1:-1, 1:-1] * 255
    return out
