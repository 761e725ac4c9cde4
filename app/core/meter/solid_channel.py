"""A needle whose chosen line has gaps, seen whole in another channel where that line's
tail would be (the calibrated reader).

:func:`.needle.find_needle` looks for the needle in each of its responses (dark, light and
colour print against the face) and takes the channel that sets its strongest line apart
best from the second-best direction.  That second-best direction is sought away from the
line's axis *and from its opposite*, where the needle's own tail lies.  So a column of dark
print (a numeral and an end tick one above the other) that lies near the opposite of a red
needle is not weighed against the needle in the dark channel: both lines are "one axis",
the print's is the darker, and the channel takes the print for the needle and the red needle
for its tail.  The line fitted there has gaps along it (``needle_solid``), and the reading
is refused.

Here, where the chosen line has gaps, each other channel is asked alone.  A line that
every check sees as a clean needle there (each of its scores 1: solid, straight, through the
pivot, alone, long, clear), pointing into the zone where the chosen line's tail was looked
for (within ``OPPOSITE_DEG`` of its opposite, where the chosen channel could not weigh it),
is the needle.  A line elsewhere is not taken: it may be another pointer (a set-point's),
which the chosen channel did weigh.
"""

from __future__ import annotations

import logging

import numpy as np

from .needle import NeedleFit, find_needle

__all__ = ["OPPOSITE_DEG", "find_solid_needle"]

log = logging.getLogger(__name__)

CHANNELS = ("dark", "light", "colour")
OPPOSITE_DEG = 16.0  # the tail's zone about the axis' opposite (needle._away's margin)


def _off_opposite(a_deg: float, b_deg: float) -> float:
    """How far direction ``b_deg`` lies from the opposite of ``a_deg`` (deg, 0–180)."""
    return abs((b_deg - a_deg) % 360.0 - 180.0)


def find_solid_needle(image: np.ndarray, pivot, radius: float, **kw) -> NeedleFit:
    """:func:`.needle.find_needle` (``kw`` its options); where the needle found has gaps
    along it, the clean needle another channel alone shows at its opposite, if any."""
    nf = find_needle(image, pivot, radius, **kw)
    if not nf.ok or nf.scores.get("needle_solid", 1.0) >= 1.0 or kw.get("channel"):
        return nf
    for ch in CHANNELS:
        if ch == nf.polarity:
            continue
        alt = find_needle(image, pivot, radius, channel=ch, **kw)
        if not alt.ok or not alt.scores or min(alt.scores.values()) < 1.0:
            continue
        if _off_opposite(nf.angle_deg, alt.angle_deg) > OPPOSITE_DEG:
            continue
        log.debug("the %s line at %.1f deg has gaps; the %s channel alone sees a clean "
                  "needle at %.1f deg, where its tail was looked for", nf.polarity,
                  nf.angle_deg, ch, alt.angle_deg)
        return alt
    return nf
