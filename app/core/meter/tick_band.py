"""The ring of tick marks found by the ticks' own shape, for the comb of :mod:`.tick_comb`.

:func:`.arc_fit.bands` picks rings of the polar image by how many dark runs cross them or
how much of them is covered.  On many real dials that is not where the ticks are: a row
of numerals crosses more runs than a ring of short ticks; ticks hang from a printed arc or
cross it (the arc, dark all along, hides them in the band's mean); minor ticks are stubs
two or three pixels long beside a rail.  Here the ticks are found by what makes them
ticks: short along the ring and radial (the same columns over several radii).

1. **Short runs**: in each row of the polar image (one radius), the dark runs longer than
   a wide tick (:data:`LONG_DEG`: rails, printed arcs, colour zones, a bezel) are removed
   (a row-wise white top-hat, :func:`short_runs`).  A tick crossing an arc keeps its parts
   above and below it; a stub beside a rail keeps its own rows.
2. **Radial strokes**: a column dark in two neighbouring rows of what is left is a
   stroke: one per tick, and some per numeral.  The rows where most strokes begin,
   widened to the neighbouring rows with nearly as many, are a candidate ring; the next
   candidates lie apart from it.  Which of them holds ticks the comb tells: numerals do
   not lie in phase on a comb.
3. **Evidence**: the share of that ring's rows dark (after step 1) in each column, zero
   where the needle hides the ring: what :func:`.tick_comb.comb_turn` reads.  Columns
   where long runs cover most of the ring's rows (a colour zone over the ticks, print)
   are unknown like the needle's: a tick there cannot be seen, nor the ring's being bare.
"""

from __future__ import annotations

import cv2
import numpy as np

from .counts import col_counts, row_counts

__all__ = ["long_columns", "ring_evidence", "short_runs", "tick_ring_rows", "tick_rings"]

LONG_DEG = 7.0  # a dark run longer than this along a ring is no tick (a rail, an arc)
STROKE_ROWS = 2  # a tick is dark over at least this many neighbouring radii (1 px each)
MIN_STROKES = 6  # strokes a ring of ticks has at least
NEAR_BEST = 0.6  # rows with this share of the best row's strokes belong to the ring
MAX_RINGS = 3  # candidate rings tried


def long_columns(step_deg: float) -> int:
    """Polar columns of ``step_deg`` that make a run too long for a tick (:data:`LONG_DEG`)."""
    return int(round(LONG_DEG / step_deg)) + 1


def short_runs(b: np.ndarray, long_cols: int) -> np.ndarray:
    """``b`` (rows x circular columns, bool) without its runs of ``long_cols`` columns or
    more in each row: a row-wise opening by a line that long, taken off (columns wrap)."""
    pad = long_cols
    u = b.astype(np.uint8)
    wrapped = np.concatenate([u[:, -pad:], u, u[:, :pad]], axis=1)
    line = np.ones((1, long_cols), np.uint8)
    opened = cv2.morphologyEx(wrapped, cv2.MORPH_OPEN, line, borderType=cv2.BORDER_CONSTANT,
                              borderValue=0)[:, pad:-pad]
    return b & (opened == 0)


def tick_rings(b: np.ndarray, hidden: np.ndarray, step_deg: float, most: int = MAX_RINGS,
               short: np.ndarray | None = None, rows: list[tuple[int, int]] | None = None):
    """Candidate rings of ticks in the thresholded polar image ``b`` (``hidden``: the
    needle's columns per row), most strokes first: a list of (evidence, known, (lo, hi)).
    Numerals make strokes too; the comb (:mod:`.tick_comb`) tells which ring is ticks.
    ``short``: ``short_runs(b, ...)`` for this ``step_deg`` if the caller has it already;
    ``rows``: :func:`tick_ring_rows` of them (for ``most``) likewise.
    See the module's docstring."""
    s = short if short is not None else short_runs(b, long_columns(step_deg))
    out = []
    for lo, hi in rows if rows is not None else _ring_rows(s, most):
        e, seen = ring_evidence(b, s, lo, hi)
        known = ~hidden[lo:hi + 1].any(axis=0) & seen
        out.append((np.where(known, e, 0.0), known, (lo, hi)))
    return out


def ring_evidence(b: np.ndarray, s: np.ndarray, lo: int, hi: int) -> tuple[np.ndarray,
                                                                          np.ndarray]:
    """The evidence of the ring of ticks in rows ``lo..hi`` of ``b`` (``s``: its short
    runs) before the needle's columns are hidden: the share of the ring's rows dark in short
    runs, per column, and the columns where ticks can be seen at all (where long runs cover
    most of the ring's rows, a colour zone or a blob of print, they cannot)."""
    rows = slice(lo, hi + 1)
    n_rows = hi + 1 - lo  # (counts / n_rows: the rows' mean)
    covered = col_counts(b[rows] & ~s[rows]) / n_rows > 0.5
    return col_counts(s[rows]) / n_rows, ~covered


def tick_ring_rows(b: np.ndarray, step_deg: float, most: int = MAX_RINGS,
                   short: np.ndarray | None = None) -> list[tuple[int, int]]:
    """The rows (lo, hi) of :func:`tick_rings`' candidate rings alone, without their
    evidence: where the rings lie does not depend on it (nor on the needle's columns)."""
    s = short if short is not None else short_runs(b, long_columns(step_deg))
    return _ring_rows(s, most)


def _ring_rows(s: np.ndarray, most: int) -> list[tuple[int, int]]:
    """Steps 1-2 on the short runs ``s``: the rows (lo, hi) of up to ``most`` rings of
    radial strokes, most strokes first."""
    n_rows = s.shape[0]
    k = STROKE_ROWS
    if n_rows < k + 2:
        return []
    stroke = s[: n_rows - k + 1].copy()
    for j in range(1, k):
        stroke &= s[j: n_rows - k + 1 + j]
    # strokes per starting row: runs of stroke columns round the ring
    prev = np.empty_like(stroke)  # each column's left neighbour (columns wrap)
    prev[:, 1:], prev[:, 0] = stroke[:, :-1], stroke[:, -1]
    count = row_counts(stroke & ~prev).astype(float)
    out = []
    while len(out) < most:
        top = int(count.argmax())
        if count[top] < MIN_STROKES:
            break
        lo = hi = top
        near = count >= NEAR_BEST * count[top]
        while lo > 0 and near[lo - 1]:
            lo -= 1
        while hi < len(near) - 1 and near[hi + 1]:
            hi += 1
        count[max(0, lo - k + 1): hi + k] = 0  # the next ring lies apart from this one
        hi += k - 1  # the last starting row's stroke reaches this far
        out.append((lo, hi))
    return out
