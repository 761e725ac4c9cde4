"""A needle with gaps along it whose line misses the carried pivot (issue 11, a calibration
with a reference frame).

With a reference frame the pivot is carried from the reference by the registration, and a
needle's line may miss it by a few px (the reference's pivot and the warp are not exact):
:func:`.needle.find_needle` tolerates a miss of up to 0.04 R (4 px at least) in full and
refuses from 0.08 R (8 px).  That tolerance is for a needle seen solid from its hub out.
A needle with gaps along it (``needle_solid`` below 1: cover under 0.85) is a line fitted
partly on what the gaps leave: a glare streak along the needle washes a stretch of it out
(``out = (1 - a) needle + 255 a``), and what is left beside the line (a numeral, the
maker's name one above the other) pulls the fit, turning it about its middle, which moves
its foot off the pivot.  Such a line is held to half the tolerance: a miss of 0.02 R (2 px
at least) in full, none from 0.04 R (4 px): :func:`gappy_line_score`.

Tuning seeds 11-40 of the ``cal-ref`` row (docs/meter-bench.md, "a glare streak along the
needle"): right readings with gaps along the needle missed the carried pivot by at most
2.4 px (0.034 R); seed 30's washed-out ``plant`` needle read 4.4 % FS off, its line 4.2 px
(0.047 R) from the pivot.
"""

from __future__ import annotations

import math

__all__ = ["GAPPY_BAD", "GAPPY_GOOD", "gappy_line_score"]

GAPPY_BAD = 0.04  # a gappy needle's line missing the pivot this far (units of R) is refused
GAPPY_GOOD = 0.02  # ... and this near is trusted in full
MIN_BAD_PX = 4.0  # ... but never tighter than these (px)
MIN_GOOD_PX = 2.0


def gappy_line_score(scores: dict, line_pivot, carried_pivot, radius: float) -> float:
    """1 for a needle seen solid (``scores`` without a ``needle_solid`` below 1); for one
    with gaps, how near its line's foot ``line_pivot`` lies to ``carried_pivot`` (0 to 1)."""
    if scores.get("needle_solid", 1.0) >= 1.0:
        return 1.0
    miss = math.hypot(line_pivot[0] - carried_pivot[0], line_pivot[1] - carried_pivot[1])
    bad = max(MIN_BAD_PX, GAPPY_BAD * radius)
    good = max(MIN_GOOD_PX, GAPPY_GOOD * radius)
    return float(min(1.0, max(0.0, (bad - miss) / (bad - good))))
