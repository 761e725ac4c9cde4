"""A needle resting on its stop pin, below the scale's minimum mark.

A gauge at rest (no pressure, or less than the scale's minimum) shows its needle on the
stop pin, a few degrees below the minimum mark; real gauges' pins sit up to 10-15 deg
below it, and 13 of 29 real photographs of issue 11 showed gauges at rest.  Such a needle
reads the minimum.  How far below the minimum that is believed: ``PIN_TOL_DEG`` always,
and up to ``PIN_MAX_DEG`` where the gap between the scale's ends is wide (``PIN_GAP`` of
it, so that the needle stays far nearer the minimum than the maximum).  Beyond a sure
distance the score ``stop_pin`` falls from 1 to ``PIN_SURE`` at that limit: the further
below, the likelier another line was taken for the needle.

Where the scale's place is itself an estimate (read against the profile's angles, no
clicks), a needle found below the minimum says either that it rests on the pin or that the
scale was placed wrongly, turned towards the maximum, with the needle among its ticks.
:func:`gap_is_bare` tells the two apart on the ring of scale marks the scale was placed
by: resting on the pin, the needle lies in the scale's gap, where that ring is bare from
the minimum mark to the needle and on past it; on a misplaced scale the ticks (or the
printed arc) the turn left out go on below the minimum found, round the needle.
"""

from __future__ import annotations

import math

import numpy as np

PIN_TOL_DEG = 9.0  # a needle this far below the minimum rests on the stop pin
PIN_MAX_DEG = 20.0  # ... or as far as this, where the gap between the scale's ends allows
PIN_GAP = 0.35  # ... up to this share of that gap
PIN_SURE = 0.8  # the stop_pin score of a needle at the farthest pin tolerance

END_RUN_DEG = 1.5  # the minimum mark's own stroke reaches this far either side of its place
MARK_RUN_MAX_DEG = 4.0  # ... and its run of evidence (a numeral merged) no farther below it
BARE_MARGIN_DEG = 1.0  # the gap seen bare past the needle is wider than any space between
# the ring's marks on the scale by this much
LINE_DEG = 1.0  # the columns this near the needle's line are its own, lit or not
FOOT_FS = 0.01  # the needle's print on the ring reaches past its line by this share of the
FOOT_MAX_DEG = 3.0  # span at most, and no more than this: what it may hide is that near


def pin_tolerance(span_deg: float) -> float:
    """How far below the minimum (deg) a needle reads the minimum, resting on the stop pin,
    on a scale of ``span_deg``: ``PIN_TOL_DEG``, or up to ``PIN_MAX_DEG`` where the gap
    between the scale's ends is wide (``PIN_GAP`` of it: the needle stays nearer the minimum
    than the maximum by far)."""
    return max(PIN_TOL_DEG, min(PIN_MAX_DEG, PIN_GAP * (360.0 - span_deg)))


def pin_score(below_deg: float, span_deg: float, sure_deg: float = PIN_TOL_DEG) -> float:
    """The ``stop_pin`` score of a needle ``below_deg`` below the minimum: 1 up to
    ``sure_deg``, falling linearly to ``PIN_SURE`` at :func:`pin_tolerance`."""
    tol = pin_tolerance(span_deg)
    if below_deg <= sure_deg:
        return 1.0
    return round(1.0 - (1.0 - PIN_SURE) * (below_deg - sure_deg) / max(tol - sure_deg, 1e-6), 4)


def widest_space(e: np.ndarray, known: np.ndarray, level: float, step_deg: float,
                 start_deg: float, span_deg: float) -> float:
    """The widest space (deg) between the ring's marks on the scale (clockwise from
    ``start_deg``, ``span_deg`` long): the longest run of visible columns below ``level``
    (columns the needle hides break a run)."""
    n = len(e)
    ks = np.arange(int(math.floor(span_deg / step_deg)) + 1)
    cols = np.rint(start_deg / step_deg + ks).astype(int) % n
    bare = known[cols] & (e[cols] < level)
    best = run = 0
    for b in bare:
        run = run + 1 if b else 0
        best = max(best, run)
    return best * step_deg


def gap_is_bare(e: np.ndarray, seen: np.ndarray, level: float, step_deg: float,
                min_deg: float, needle_deg: float, down: float, span_deg: float,
                space_deg: float) -> tuple[bool, str]:
    """Whether the ring of scale marks is bare where a needle resting on the stop pin lies:
    from the minimum mark at ``min_deg`` to the needle at ``needle_deg`` below it, and past
    the needle, away from the scale, over a run of columns wider than the widest space
    between the ring's marks on the scale (``space_deg``, :func:`widest_space`, plus
    :data:`BARE_MARGIN_DEG`), short of the maximum mark across the gap.  A run that wide
    without a mark lies in no scale of that ring: it is the gap.  On a scale placed turned
    towards its maximum, the marks the turn left out go on below the minimum found, round
    the needle, and one of them is met.

    The needle itself prints on the ring: the run of lit (or unseen) columns about its line
    (at least :data:`LINE_DEG` either side) is its own, and unknown.  A mark it hides lies
    within that run, so the run may reach past the line, away from the scale, by no more than
    :data:`FOOT_FS` of the span (:data:`FOOT_MAX_DEG` at most): a scale's minimum mark
    hidden there would leave the needle that near the minimum.

    ``e``: each polar column's evidence on the ring, ``step_deg`` apart, clockwise from up;
    ``seen``: the columns where marks can be seen on the ring (the needle not hidden);
    ``level``: the evidence that makes a mark (:func:`.arc_fit.mark_level`); ``down``: the
    sign of angles going below the minimum (-1 for a clockwise scale); ``span_deg``: the
    scale's.  The minimum mark's own run of evidence is passed over: it starts within
    :data:`END_RUN_DEG` of ``min_deg`` and ends within :data:`MARK_RUN_MAX_DEG` of it (a
    run going on farther, a printed arc's, is the scale going on).  Returns (bare, why
    not)."""
    n = len(e)
    sgn = 1 if down > 0 else -1
    below = abs(((needle_deg - min_deg) * down + 180.0) % 360.0 - 180.0)
    c0 = int(round(needle_deg / step_deg)) % n
    line = int(round(LINE_DEG / step_deg))

    def reach(way: int) -> int:  # columns of the needle's run from its line, ``way`` on
        k = 0
        while k < n // 4:
            c = (c0 + way * (k + 1)) % n
            if k + 1 > line and seen[c] and e[c] < level:
                break
            k += 1
        return k

    far, near = reach(sgn), reach(-sgn)
    if far * step_deg > min(FOOT_FS * span_deg, FOOT_MAX_DEG):
        return False, f"a mark touches the needle ({far * step_deg:.1f} deg past its line)"
    need = int(math.ceil((space_deg + BARE_MARGIN_DEG) / step_deg))
    ks = np.arange(int(math.floor((360.0 - span_deg - 2.0 * END_RUN_DEG) / step_deg)) + 1)
    cols = np.rint((min_deg + down * ks * step_deg) / step_deg).astype(int) % n
    # the minimum mark's own run: from within END_RUN_DEG of its place, while lit
    k0 = int(math.ceil(END_RUN_DEG / step_deg))
    while k0 < len(cols) and seen[cols[k0]] and e[cols[k0]] >= level:
        k0 += 1
    if k0 * step_deg > MARK_RUN_MAX_DEG:  # a printed arc, say, going on below the minimum
        return False, f"scale marks run on {k0 * step_deg:.1f} deg below the minimum"
    k_needle = below / step_deg
    run = 0  # the bare run past the needle
    for k in range(k0, len(cols)):
        c = cols[k]
        if k_needle - near - 0.5 <= k <= k_needle + far + 0.5:  # the needle's own
            continue
        if not seen[c]:
            if run:  # hidden past the needle: what it hides is unknown
                return False, f"the ring is hidden {k * step_deg:.1f} deg below the minimum"
            continue
        if e[c] >= level:
            return False, f"scale marks {k * step_deg:.1f} deg below the minimum"
        if k > k_needle:
            run += 1
            if run >= need:
                return True, ""
    return False, f"the gap seen past the needle is no wider than the spaces between marks " \
        f"({space_deg:.1f} deg)"
