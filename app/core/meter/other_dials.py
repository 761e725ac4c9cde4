"""Other gauges in the frame: which dial the profile describes, and when that is not known.

A camera frame may hold other gauges beside the one the inspection point aims the camera
head at, even gauges of the very same model on one manifold.  The reader knows the one it
reads only by where the camera is aimed:

1. **The aimed-at dial first** (:func:`.dial.aimed_first`): of the best few rims, one much
   nearer the frame's centre than the best-supported goes first.
2. **A rival dial**: a rim about another centre (:func:`distinct`) among the best few,
   not more than :data:`RIVAL_FARTHER` (half the frame's half-side) farther from the
   frame's centre than the dial read (:func:`rival_of`).  The aim is a prior, not a
   proof: a camera head's aim is off by the inspection point's drift, and a frame taken by
   hand centres what caught the eye; but a gauge at the frame's edge, with the one read
   near its centre, is not the one the camera was aimed at.
3. **Read both**: where the rival reads against the profile too and the two readings
   disagree (by more than :data:`AGREE_FS`, or their stated error bounds), the reading is
   refused (:func:`check_rival`): the frame then holds two gauges this profile fits, and
   which one it describes is not known.  Where the rival is no readable dial (a valve's
   hand wheel, a gauge of another scale whose checks fail) or reads alike, the reading
   stands.

So two like gauges side by side are refused rather than read at random, and the one
aimed at is read beside others near the frame's edge (docs/meter-bench.md, "Other gauges
in the frame", for the limit's choice).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace

from .dial import AIMED_AMONG, DialEllipse, off_centre
from .reading import Reading

__all__ = ["AGREE_FS", "NEARER_UNREAD", "RIVAL_FARTHER", "box_rival", "check_rival", "distinct",
           "nearer_unread", "readings_agree", "rival_of"]

AGREE_FS = 2.0  # two readings of one scale within this (% FS) are alike
RIVAL_FARTHER = 0.5  # share of the frame's half-side (see rival_of)
SAME_CENTRE = 0.25  # rims whose centres are closer than this share of the smaller are one dial

NEARER_UNREAD = ("keypoints: a dial nearer the frame's centre did not read ({why}); another "
                 "one did (which of the two the profile describes is not known)")
RIVAL_READS = ("another dial in the frame reads {v:.4g} against this profile (which of the "
               "two it describes is not known)")


def distinct(a: DialEllipse, b: DialEllipse) -> bool:
    """Two rims about different centres (not a dial's bezel and its face)."""
    side = min(a.width, a.height, b.width, b.height)
    return math.hypot(a.cx - b.cx, a.cy - b.cy) >= SAME_CENTRE * side


def rival_of(read: DialEllipse, cands: Sequence[DialEllipse],
             shape: Sequence[int]) -> DialEllipse | None:
    """The first of the best :data:`.dial.AIMED_AMONG` rims that is another dial than
    ``read`` and lies not more than :data:`RIVAL_FARTHER` farther from the frame's centre
    (:func:`.dial.off_centre`); None if there is none."""
    own = off_centre(read.cx, read.cy, shape)
    return next((e for e in cands[:AIMED_AMONG] if distinct(read, e)
                 and off_centre(e.cx, e.cy, shape) <= own + RIVAL_FARTHER), None)


def box_rival(read, other, crop_side: float, shape: Sequence[int]) -> bool:
    """:func:`rival_of` for two boxes ``((cx, cy), side)`` of the learned keypoints, each
    the square of side ``crop_side`` times a rim's diameter about its centre."""
    return rival_of(_box_rim(read, crop_side), [_box_rim(other, crop_side)], shape) is not None


def nearer_unread(box, unread, crop_side: float, shape: Sequence[int]) -> bool:
    """Among the boxes ``unread`` (of the learned keypoints, none of which read), one about
    another dial than ``box`` and nearer the frame's centre: the dial the camera was more
    likely aimed at did not read, and ``box`` is not known to be the one described."""
    own, off = _box_rim(box, crop_side), off_centre(box[0][0], box[0][1], shape)
    return any(distinct(own, _box_rim(u, crop_side)) and off_centre(u[0][0], u[0][1], shape) < off
               for u in unread)


def _box_rim(box, crop_side: float) -> DialEllipse:
    """The rim a keypoint box ``((cx, cy), side)`` was made about (its side is ``crop_side``
    times the rim's diameter)."""
    (cx, cy), side = box
    return DialEllipse(cx, cy, side / crop_side, side / crop_side, 0.0, 0.0)


def readings_agree(a: Reading | dict, b: Reading | dict, full_scale: float) -> bool:
    """Two readings of one scale within :data:`AGREE_FS` or the sum of their stated error
    bounds (% FS), whichever is larger."""
    def get(r, k):
        return r[k] if isinstance(r, dict) else getattr(r, k)

    gap = 100.0 * abs(get(a, "value") - get(b, "value")) / max(abs(full_scale), 1e-12)
    bounds = (get(a, "error_bound_fs") or 0.0) + (get(b, "error_bound_fs") or 0.0)
    return gap <= max(AGREE_FS, bounds)


def check_rival(r: Reading, read: DialEllipse, cands: Sequence[DialEllipse],
                shape: Sequence[int], read_at: Callable[[DialEllipse], Reading],
                full_scale: float) -> Reading:
    """``r`` (a reading made on the rim ``read``), or its refusal where a rival dial
    (:func:`rival_of`) read by ``read_at`` gives another value."""
    if r.value is None:
        return r
    other = rival_of(read, cands, shape)
    if other is None:
        return r
    o = read_at(other)
    if o.value is None or readings_agree(r, o, full_scale):
        return r
    scores = dict(r.scores, rival_dial_value=round(float(o.value), 6))
    return replace(r, value=None, confidence=0.0, error=RIVAL_READS.format(v=o.value),
                   raw_value=r.value, scores=scores, in_normal_band=None)
