"""Per-row and per-column counts of a boolean image, by one OpenCV reduction.

The polar steps count lit pixels along every ring (row) or every ray (column) of a
thresholded polar image many times per reading; numpy's ``count_nonzero(..., axis=)`` and
``mean(axis=)`` on booleans go through a conversion of every element first.  The counts are
exact integers, so ``counts / n`` is the same number as numpy's mean of the booleans.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["col_counts", "row_counts"]


def row_counts(m: np.ndarray) -> np.ndarray:
    """``np.count_nonzero(m, axis=1)`` of a 2-D bool array (as int32)."""
    return _reduce(m, 1)


def col_counts(m: np.ndarray) -> np.ndarray:
    """``np.count_nonzero(m, axis=0)`` of a 2-D bool array (as int32)."""
    return _reduce(m, 0)


def _reduce(m: np.ndarray, dim: int) -> np.ndarray:
    if m.size == 0:
        return np.count_nonzero(m, axis=dim).astype(np.int32)
    if not m.flags.c_contiguous:
        m = np.ascontiguousarray(m)
    return cv2.reduce(m.view(np.uint8), dim, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel()
