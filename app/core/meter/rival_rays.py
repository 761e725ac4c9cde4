"""A second pointer among the rays of :mod:`.needle`: only a straight line about the pivot.

:func:`.needle.find_needle` refuses a needle (its ``needle_unique`` score) when another
direction about the pivot holds nearly as much line evidence: a second pointer.  That
evidence is a low percentile of a ray's response over its radii, widened over a few
pixels either side, so it is also high where print and glare happen to lie along a ray
between them: a maker's plate by the hub with a word beyond it, a glare streak crossing
the ray at a shallow angle, a column of numerals.  None of these is a pointer.  A pointer
turns about the pivot: its centres across the ray, radius by radius, lie on one straight
line through the pivot, over most of the ray's radii (the needle's own test, the centres'
consensus of :mod:`.needle_line`).  :func:`strongest_pointer` passes over a direction whose
evidence is not such a line and takes the next, a few times; where the directions tried
are all something else, the next one counts as it is (no more are looked at).
"""

from __future__ import annotations

import numpy as np

from .needle_line import N_TH, _centroids, _fit_needle, _needle_points

POINTER_COVER = 0.5  # a pointer's centres are found over this share of the ray's radii ...
POINTER_SHARE = 0.5  # ... this share of them lie on one line ...
POINTER_REACH = 0.35  # ... which runs over this much of the scale's radius (units of R) ...
POINTER_PIVOT = 0.08  # ... and passes the pivot within this (units of R, 8 px at least)
TRIES = 4  # directions passed over before the next one counts as it is
MARGIN_DEG = 8.0  # a direction passed over takes its lobe and this much either side with it


def pointer_like(pol: np.ndarray, k: int, rs: np.ndarray, r_max: float, R: float,
                 pivot) -> bool:
    """Whether the response ``pol`` (polar, N_TH rays x radii ``rs``) along ray ``k`` out
    to ``r_max`` is a straight line through ``pivot`` (x, y, the polar frame's centre in
    the pixels its maps sample), as a pointer is."""
    n_r = int(np.count_nonzero(rs <= r_max))
    piece = _centroids(pol, k, rs, r_max, 0.07 * R + 5.0, pivot)
    if n_r == 0 or len(piece[0]) < max(6, POINTER_COVER * n_r):
        return False
    pts, wts, cover = _needle_points([piece])
    if len(pts) < 6:
        return False
    c, u, _, share = _fit_needle(pts, wts, cover)
    if share < POINTER_SHARE:
        return False
    nrm = np.array([-u[1], u[0]])
    on = np.abs((pts - c) @ nrm) <= 1.5
    along = (pts[on] - c) @ u
    if len(along) < 2 or float(along.max() - along.min()) < POINTER_REACH * R:
        return False
    return abs(float((np.asarray(pivot, float) - c) @ nrm)) <= max(8.0, POINTER_PIVOT * R)


def strongest_pointer(s: np.ndarray, away: np.ndarray, floor: float, is_pointer) -> float:
    """The largest evidence ``s`` over the rays ``away`` that belongs to a pointer
    (``is_pointer(k)``, asked only of rays whose evidence exceeds ``floor``, where it
    matters); 0 where no ray is left."""
    left = away.copy()
    m = int(round(MARGIN_DEG * N_TH / 360.0))
    for _ in range(TRIES):
        if not left.any():
            return 0.0
        k = int(np.flatnonzero(left)[np.argmax(s[left])])
        v = float(s[k])
        if v <= floor:
            return v
        # a wide line makes a plateau: its middle is the line's axis (as the needle's)
        lo, hi = _lobe(s, k, 0.7 * v)
        if is_pointer(((lo + hi) // 2) % N_TH):
            return v
        # its lobe above half its evidence, and a margin, passed over
        lo, hi = _lobe(s, k, 0.5 * v)
        left[np.arange(lo - m, hi + m + 1) % N_TH] = False
    return float(s[left].max()) if left.any() else 0.0


def _lobe(s: np.ndarray, i: int, thr: float) -> tuple[int, int]:
    """The run of rays around ``i`` (circular, unwrapped indices) where ``s > thr``, as far
    as a quarter turn either side."""
    steps = np.arange(1, len(s) // 4 + 1)
    return i - _leading(s.take(i - steps, mode="wrap") > thr), \
        i + _leading(s.take(i + steps, mode="wrap") > thr)


def _leading(on: np.ndarray) -> int:
    return len(on) if on.all() else int(on.argmin())


__all__ = ["pointer_like", "strongest_pointer"]
