"""The printed arc line under an end mark: which of a run's columns are the mark.

An end mark found by :func:`.end_marks.end_mark` is placed by its stroke (a tick's centre
line); where the run of evidence it was found in is wider than the stroke, the mark may be
the whole run (an end dot or ring, a cap with a tick in it), whose middle lies up to half
of it from the stroke, and that doubt enters the reading's bound
(:func:`.end_marks.merged_doubt`).  On a ring crossed by a printed arc line, the run goes
on along the line, often to the next break of the line, many degrees into the scale, and
its "middle" is no mark's: the doubt then said that the end mark could be 5-10 deg off
where the tick was plain.

The line is the same thin band of radii all along the scale: its rows are lit over most of
the scale's columns, which no ring of ticks, dots or numerals lights (:func:`line_rows`).
With the line's rows taken out, the mark is the print still joined to the stroke (a ring's
walls either side of its hole, a dot's halves, a cap); the line going on from it is gone
(:func:`mark_cols`).
"""

from __future__ import annotations

import cv2
import numpy as np

from .counts import row_counts

__all__ = ["line_rows", "mark_cols"]

LINE_ROW_SHARE = 0.6  # a row lit over this share of the scale's known columns: the line
LINE_BLUR_ROWS = 1  # rows either side of the line's that its blur still lights
LINE_RUN_COLS = 16  # polar columns (8 deg): a row lit longer than this is a line, no mark


def line_rows(b: np.ndarray, r0: int, r1: int, on_scale: np.ndarray) -> np.ndarray:
    """The rows of the thresholded polar image ``b`` (bool, one per row of ``b``) that hold
    a printed arc line: between rows ``r0`` and ``r1`` (the window an end mark's shape is
    judged in), lit over :data:`LINE_ROW_SHARE` of the columns ``on_scale`` (bool, the
    scale's known columns), and :data:`LINE_BLUR_ROWS` either side of those."""
    out = np.zeros(b.shape[0], bool)
    if not on_scale.any():
        return out
    share = row_counts(b[r0:r1][:, on_scale]) / float(on_scale.sum())
    hit = np.flatnonzero(share >= LINE_ROW_SHARE) + r0
    for d in range(-LINE_BLUR_ROWS, LINE_BLUR_ROWS + 1):
        out[np.clip(hit + d, 0, b.shape[0] - 1)] = True
    return out


def _long_rows(sub: np.ndarray) -> np.ndarray:
    """Rows of ``sub`` (uint8, 0/1: the window's rows over a run's columns) lit without a
    break over more than a mark's width (:data:`LINE_RUN_COLS`, as print passed over at
    an end, :data:`.end_marks.PRINT_MAX_DEG`), and :data:`LINE_BLUR_ROWS` either side: the
    line where it wanders over the rows of the whole scale (a view not quite rectified)."""
    out = np.zeros(sub.shape[0], bool)
    if sub.shape[1] <= LINE_RUN_COLS:
        return out
    k = np.ones((1, LINE_RUN_COLS + 1), np.uint8)
    hit = np.flatnonzero(cv2.erode(sub, k, borderType=cv2.BORDER_CONSTANT,
                                   borderValue=0).any(axis=1))
    for d in range(-LINE_BLUR_ROWS, LINE_BLUR_ROWS + 1):
        out[np.clip(hit + d, 0, sub.shape[0] - 1)] = True
    return out


def mark_cols(b: np.ndarray, r0: int, r1: int, line: np.ndarray, run: list[int],
              centre: float, width: int) -> int:
    """How many of ``run``'s columns (polar columns of ``b``, from the gap side inward) are
    the end mark whose stroke (``width`` columns) has its centre line at column ``centre``:
    all of them where the ring has no printed line (``line``, from :func:`line_rows`, all
    False); else the columns of the print, off the line, joined to the stroke between rows
    ``r0`` and ``r1`` (the window its shape is judged in): a line's rows taken out, a ring's
    walls, a dot's halves and a cap stay joined to the stroke, the line going on from it
    is gone."""
    if not run:
        return 0
    n = b.shape[1]
    sub = b[r0:r1][:, run].astype(np.uint8)
    local = _long_rows(sub)
    if not line.any() and not local.any():
        return len(run)
    sub[line[r0:r1] | local] = 0
    near = [j for j, c in enumerate(run)
            if abs((c - centre + n / 2.0) % n - n / 2.0) <= max(width - 1, 0) / 2.0 + 0.5]
    if not near:
        return len(run)
    _, lab = cv2.connectedComponents(sub, connectivity=8)
    ids = np.unique(lab[:, near[0]:near[-1] + 1])
    ids = ids[ids > 0]
    if len(ids) == 0:
        return len(run)  # the stroke is no more than the line: no telling
    cols = np.flatnonzero(np.isin(lab, ids).any(axis=0))
    return int(cols[-1] - cols[0] + 1)
