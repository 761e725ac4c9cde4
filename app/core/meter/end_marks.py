"""The scale's end marks on one ring of polar evidence, for :mod:`.arc_fit`.

:func:`end_mark` walks in from the scale's gap to the first mark: a tick by its centre
line, a printed arc by its outer edge, a numeral beside the end passed over as gap (its
shape in the thresholded polar image, :func:`mark_shape`), and the needle's columns as
unknown: a tick just inside the needle is ``"behind"`` it (the end mark, or the first tick
inside one under the needle, which only the other end can tell).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from .arc_line import mark_cols
from .scale import N_ANG

log = logging.getLogger(__name__)

__all__ = ["end_mark", "mark_shape", "radial_lengths"]

STEP = 360.0 / N_ANG  # polar columns, deg
END_SEARCH_DEG = 18.0  # deg either side of where the coarse turn puts an end mark
SHORT_MARK_DEG = 4.0  # a run of evidence up to this long is a tick: its centre counts
GAP_CLEAN_DEG = 8.0  # an end mark has at least this much of empty gap outside it
HIDE_COLS = 6  # a mark this close (columns) after the needle may be cut by it
MARK_MARGIN_ROWS = 12  # radii either side of the ring looked at for an end mark's shape
TICK_LEN_SHARE = 0.6  # a tick is this long radially as the ring's major ticks, or longer
SPINE_SHARE = 0.8  # columns this nearly as long radially as the longest: the stroke
PRINT_MAX_DEG = 8.0  # print passed over is at most this long (a numeral; not an arc)
PRINT_HOLES = 0.2  # share of a mark's radii crossing it twice that makes it print
DRIFT_PX = 2.0  # a stroke's column may wander this far (px) across its radii ...
DRIFT_SHARE = 0.3  # ... or this share of its radial length
STROKE_ASPECT = 1.5  # a stroke is this many times as long radially as it is wide
FRINGE_COLS = 1  # columns of blur either side of a stroke that are still the stroke


def end_mark(e: np.ndarray, known: np.ndarray, at: float, inward: int, level: float,
              marks=None):
    """(kind, column) of the end mark nearest ``at``: the first run of evidence met coming
    in from the gap side, its centre for a short mark or a radial stroke (``"tick"``: a thin
    tick, or a thick end tick by its centre line) or its outer edge for a long one
    (``"edge"``, a printed arc).  With ``marks`` (see :func:`_fit`), a run whose shape is
    print beside the scale (a numeral: holes, strokes that are not radial) is passed over as
    gap.  The kind and column come with how far the mark's place may be off (deg,
    :func:`merged_doubt`).  ``"hidden"`` when unknown columns (the needle) lie just outside
    it; ``"missing"`` when no mark is within the search window."""
    n = len(e)
    reach = int(round(END_SEARCH_DEG / STEP))
    gap_cols = int(round(GAP_CLEAN_DEG / STEP))
    start = int(round(at)) - inward * (reach + gap_cols)
    steps = [(start + inward * k) % n for k in range(2 * reach + gap_cols + 1)]
    seen_gap, last_unknown, skip_to = 0, None, -1
    for k, c in enumerate(steps):
        if k <= skip_to:  # inside print passed over: gap
            continue
        if not known[c]:  # the needle: neither gap nor mark
            last_unknown = k
            continue
        if e[c] < level:
            seen_gap += 1
            continue
        behind = last_unknown is not None and k - last_unknown <= HIDE_COLS
        if not behind and seen_gap < gap_cols:
            seen_gap = 0  # no clean gap before this evidence: not the scale's end
            continue
        run = [c]
        for c2 in steps[k + 1:]:
            if not known[c2] or e[c2] < level:
                break
            run.append(c2)
        shape, spine = mark_shape(marks, run) if marks is not None else ("other", None)
        if behind:
            # it touches the needle: the end mark may be under it.  A tick here is the end
            # mark or the first tick inside it, which only the other end mark can tell
            # (:func:`_ends_fit`); its side towards the needle may be cut off
            if shape == "stroke":
                return "behind", float(spine[0]), 0.5 * _mark_width(marks, run, *spine) * STEP
            if shape != "print" and len(run) * STEP <= SHORT_MARK_DEG:
                return "behind", weighted_col(e, run, c, inward), 0.5 * len(run) * STEP
            return "hidden"
        if shape == "print":  # a numeral beside the end mark: part of the gap
            seen_gap += len(run)
            skip_to = k + len(run) - 1
            continue
        if shape == "stroke":  # a tick, by its centre line
            return "tick", float(spine[0]), merged_doubt(_mark_width(marks, run, *spine),
                                                          spine[1])
        if len(run) * STEP <= SHORT_MARK_DEG:
            return "tick", weighted_col(e, run, c, inward), 0.0
        # a long run: its outer edge, interpolated to where the evidence crosses the level
        prev = steps[k - 1]
        f = (level - e[prev]) / max(e[c] - e[prev], 1e-6)
        return "edge", float(c - inward * (1.0 - f)) % n, 0.0
    return "hidden" if last_unknown is not None else "missing"


def _mark_width(marks, run: list[int], centre: float, width: int) -> int:
    """The run's columns that are the mark, not a printed arc line running on from it
    (:func:`.arc_line.mark_cols`; ``marks[6]``, where given, is the line's rows)."""
    if len(marks) <= 6:
        return len(run)
    b, lo, hi = marks[:3]
    r0, r1 = max(0, lo - MARK_MARGIN_ROWS), min(b.shape[0], hi + 1 + MARK_MARGIN_ROWS)
    return mark_cols(b, r0, r1, marks[6], run, centre, width)


def weighted_col(e: np.ndarray, run: list[int], c: int, inward: int) -> float:
    """The evidence-weighted middle column of a short run of evidence starting at ``c``."""
    wts = e[run]
    pos = np.array([c + inward * j for j in range(len(run))], float)
    return float((pos * wts).sum() / wts.sum()) % len(e)


def merged_doubt(run_cols: int, spine_cols: int) -> float:
    """How far (deg) an end mark placed by its stroke may be off, where the run of evidence
    it was found in is wider than the stroke: the mark may be the whole run (an end dot or
    ring, a cap of a printed arc with a tick in it), whose middle lies up to half of it from
    the stroke.  A stroke with at most :data:`FRINGE_COLS` of blur either side is the mark."""
    if run_cols - spine_cols <= 2 * FRINGE_COLS:
        return 0.0
    return 0.5 * run_cols * STEP


def radial_lengths(b: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Each polar column's radial length: the stretch of lit radii through the ring's middle
    row, within :data:`MARK_MARGIN_ROWS` of the ring's rows (px, 0 where the middle row is
    not lit)."""
    m = MARK_MARGIN_ROWS
    r0, r1 = max(0, lo - m), min(b.shape[0], hi + 1 + m)
    sub = b[r0:r1]
    mid = (lo + hi) // 2 - r0
    up = lit_run(sub[mid::-1])  # lit rows from the middle inward
    down = lit_run(sub[mid:])  # ... and outward
    return np.where(sub[mid], up + down - 1, 0).astype(float)


def lit_run(rows: np.ndarray) -> np.ndarray:
    """Per column, how many of ``rows`` (bool) are lit from the first one on without a
    break: the index of the first unlit row, or all of them."""
    off = ~rows
    return np.where(off.any(axis=0), off.argmax(axis=0), rows.shape[0])


def mark_shape(marks, run: list[int]):
    """What the run of evidence ``run`` (polar columns, from the gap side inward) is, by
    its shape in the thresholded polar image, and where its stroke's centre line lies:
    (kind, column).

    A tick is a stroke along the radius (:func:`radial_lengths`): as long radially as
    the ring's major ticks nearly (:data:`TICK_LEN_SHARE` of their length) and as
    :data:`STROKE_ASPECT` times its width or longer.  The stroke is the first group of
    the run's columns, from the gap side, nearly as long as the longest
    (:data:`SPINE_SHARE`); its centre line is that group's middle: a numeral or the corner
    of a printed arc merged into the run beside it crosses fewer radii and does not pull
    it.  ``"stroke"`` then, with that column; ``"print"`` (a numeral, a word: no such
    stroke, and on many radii crossing the run twice or drifting across the columns, i.e.
    not pointing at the pivot); else ``"other"`` (a printed arc's end, a dot), column None.
    For a stroke the column comes with the stroke's width in columns."""
    b, lo, hi, r_px, lengths, ref = marks[:6]
    n = b.shape[1]
    length = lengths[run]
    top = float(length.max())
    if top <= 0:
        return "other", None
    col_px = math.radians(STEP) * r_px
    spine = length >= SPINE_SHARE * top
    a = int(spine.argmax())  # the first stroke met coming in from the gap
    z = a
    while z < len(spine) - 1 and spine[z + 1]:
        z += 1
    s_top = float(length[a:z + 1].max())
    inward = 1 if (run[-1] - run[0]) % n == len(run) - 1 else -1
    if s_top >= TICK_LEN_SHARE * ref and s_top >= STROKE_ASPECT * (z - a + 1) * col_px:
        return "stroke", ((run[0] + inward * (a + z) / 2.0) % n, z - a + 1)
    if len(run) * STEP > PRINT_MAX_DEG:
        return "other", None
    m = MARK_MARGIN_ROWS
    r0, r1 = max(0, lo - m), min(b.shape[0], hi + 1 + m)
    rows = b[r0:r1][:, sorted(run)]
    rows = rows[rows.any(axis=1)]
    if len(rows) == 0:
        return "other", None
    edges = np.count_nonzero(np.diff(rows.astype(np.int8), axis=1) == 1, axis=1) \
        + rows[:, 0]
    holes = float(np.mean(edges >= 2))
    jj = np.arange(rows.shape[1], dtype=float)
    cent = (rows * jj).sum(axis=1) / np.maximum(rows.sum(axis=1), 1)
    drift_px = float(cent.max() - cent.min()) * col_px
    log.debug("mark %s holes %.2f drift %.1f top %.0f", run[0], holes, drift_px, top)
    if holes >= PRINT_HOLES or drift_px > max(DRIFT_PX, DRIFT_SHARE * top):
        return "print", None
    return "other", None
