"""Telling a needle's tip from its tail, or from another line through the hub, when both
of its ends reach nearly as far (:func:`.needle.find_needle`, step 3): the widths of the
two ends near the hub and over their outer halves, the scale's arc, and whether a line runs
on past the scale ring, where no needle reaches."""

from __future__ import annotations

import logging

import cv2
import numpy as np

from .dial import _median
from .needle_line import N_TH, R_IN

__all__ = ["side_width", "outer_width", "weigh_end_cues", "runs_on", "tail_in_gap"]

log = logging.getLogger(__name__)

WIDER_TIP = 1.4  # a longer end this much wider than the other is no sure tip
# ends whose reach differs by less than this (units of R) are weighed by their widths and the
# scale (a thin tip fades before its end, while print beyond a tail's weight prolongs it)
WEIGH_REACH = 0.2
BOTH_LONG = 0.8  # a single needle with two ends this long (units of R): one is something else
BEYOND = (1.08, 1.15)  # radii past the scale ring (units of R) where no needle reaches


def side_width(p: np.ndarray, th0: int, rs: np.ndarray, r_lo: float, r_hi: float) -> float:
    """Mean angular width x radius (px) of the response near ray ``th0`` over r_lo..r_hi."""
    sel = ((rs >= r_lo) & (rs <= r_hi)).nonzero()[0]
    if len(sel) == 0:
        return 0.0
    idx = (th0 + np.arange(-30, 31)) % N_TH
    v = p[idx][:, sel]  # rays near th0 x the radii chosen: all radii at once
    pk = v.max(axis=0)
    on = pk > 0
    if not on.any():
        return 0.0
    ws = (v[:, on] > 0.5 * pk[on]).sum(axis=0) * (2 * np.pi / N_TH) * rs[sel][on]
    return _median(ws)


def outer_width(p: np.ndarray, th0: int, rs: np.ndarray, ext: float, R: float) -> float:
    """Width (px) of one end of the needle over the outer half of its reach ``ext``."""
    return side_width(p, th0, rs, max(R_IN * R, 0.5 * ext), 0.9 * ext)


def _clearly_on(on_scale, angle: float, slack_deg: float) -> bool | None:
    """Whether the angle ``angle`` +- ``slack_deg`` is on the scale all along (True), off it
    all along (False), or either (None)."""
    ons = {on_scale(angle - slack_deg), on_scale(angle), on_scale(angle + slack_deg)}
    return ons.pop() if len(ons) == 1 else None


def tail_in_gap(on_scale, tip: int, tail: int, slack_deg: float) -> bool:
    """Whether the end taken for the tail (ray ``tail``) points clearly into the scale's gap
    while the tip (ray ``tip``) lies clearly on the scale.  A tip never points into the
    gap farther than the stop pin beside an end mark (``on_scale`` allows that much), so the
    end that does is the tail, whatever the widths say: an arrow-headed tip is as wide at
    its end as a tail's ring or weight, and a tapered tip the wider near the hub."""
    return _clearly_on(on_scale, tip * 360.0 / N_TH, slack_deg) is True \
        and _clearly_on(on_scale, tail * 360.0 / N_TH, slack_deg) is False


def weigh_end_cues(pol: np.ndarray, rs: np.ndarray, R: float, a, b, on_scale,
                   scores: dict, slack_deg: float = 0.0,
                   past_ring: tuple[bool, bool] | None = None) -> tuple[int, int]:
    """(tip, tail) rays of a needle whose two ends ``a`` and ``b`` ((ray, reach, width near
    the hub) each) reach nearly as far (within ``WEIGH_REACH``).  Three cues, each one only
    where it is clear: the thinner end near the hub, the end whose outer half is the thinner
    (a tip tapers to its end, a tail ends in feathers, a disc or a spade), the end on the
    scale's arc (the other pointing into the gap).  When the cues that speak disagree, or
    none speaks, the score ``tip_vs_tail`` is 0: text or a numeral beside one end can make
    it look wider.  ``past_ring`` (a single needle whose two ends both reach out to the
    scale, so that one of them is no part of it: a streak of glare or a printed line
    through the hub): whether each end's line runs on past the scale ring (:func:`runs_on`).
    When one of them does, it is the other thing (no needle reaches there), and the widths,
    which then compare the needle with no tail of its own, say nothing (a needle's root is
    the wider beside a thin streak); when neither or both do, the widths speak as above."""
    (i, ext_a, wid_a), (j, ext_b, wid_b) = a, b
    out_a, out_b = outer_width(pol, i, rs, ext_a, R), outer_width(pol, j, rs, ext_b, R)
    votes = set()
    if past_ring is not None and past_ring[0] != past_ring[1]:
        votes.add(j if past_ring[0] else i)  # the widths compared the needle with no tail
    else:
        if min(wid_a, wid_b) < 0.8 * max(wid_a, wid_b):
            votes.add(i if wid_a < wid_b else j)
        if max(out_a, out_b) > WIDER_TIP * max(min(out_a, out_b), 1e-6):
            votes.add(i if out_a < out_b else j)
    # the scale speaks only where it is clear: each end's ray is the middle of its lobe
    # about the clicked pivot, a few degrees off the needle's line, so an end within that
    # of an end mark's tolerance may lie either side of it (a needle resting on the pin just
    # below the minimum, its tail well on the scale)
    a_on, b_on = (_clearly_on(on_scale, k * 360.0 / N_TH, slack_deg) for k in (i, j))
    if a_on is not None and b_on is not None and a_on != b_on:
        votes.add(i if a_on else j)
    log.debug("needle ends weighed: outer halves %.1f / %.1f px, on the scale %s / %s", out_a,
              out_b, a_on, b_on)
    if len(votes) != 1:
        scores["tip_vs_tail"] = 0.0
        return (i, j) if len(votes) == 0 or wid_a <= wid_b else (j, i)
    tip = votes.pop()
    return (i, j) if tip == i else (j, i)


def runs_on(img: np.ndarray, centre, R: float, ends, thr: float, half: int) -> tuple[bool, ...]:
    """Whether the line along each of the rays ``ends`` runs on past the scale ring, over
    BEYOND (units of R) where no needle reaches: over 3/4 of those radii above ``thr`` on
    the ray or its ``half`` neighbours either side (``img``: the needle's channel in the
    crop, ``centre`` the pivot there)."""
    cx, cy = centre
    rs = np.linspace(BEYOND[0] * R, BEYOND[1] * R, 8, dtype=np.float32)
    out = []
    for k in ends:
        ks = (k + np.arange(-half, half + 1)) % N_TH
        th = ks * (2.0 * np.pi / N_TH)
        map_x = (cx + np.sin(th)[:, None] * rs[None, :]).astype(np.float32)
        map_y = (cy - np.cos(th)[:, None] * rs[None, :]).astype(np.float32)
        v = cv2.remap(img, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                      borderValue=0)
        out.append(bool(np.mean(v.max(axis=0) > thr) > 0.75))
    log.debug("needle ends run on past the scale ring: %s", out)
    return tuple(out)
