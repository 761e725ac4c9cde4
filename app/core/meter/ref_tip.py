"""Which end of the needle is its tip, told by the reference frame's needle (issue 11,
section 1, a calibration with a reference frame).

A needle is one rigid piece turning about its pivot: its tip and its tail look the same in
every frame of the inspection point, only turned.  Where the reference frame's needle has a
sure tip (``calibrated._reference_tip``: no doubt left by its own ends, and the tip on
the clicked scale), its picture along its axis, tip side and tail side, is a
template for the needle in any frame registered to it.  In the frame, the strip along the
needle's axis is taken through the registration (in the reference's coordinates, turned to
the frame needle's direction, carried into the frame), and correlated with the reference's
strip both ways round: the needle's tip lies where the reference's tip fits
(:func:`tip_teller`).  Both ways round compare the same frame pixels with the same
template, so the dial's print under the strip, the light and the glare count alike for both;
only the needle's own shape (a diamond head against a ring, a taper against a spade) tells
them apart.  Each radius's row is taken less its mean across the strip (the needle against
the face beside it), so that a slope of the light along the dial does not count.

The strip is asked only where the frame's needle leaves its tip in doubt
(:func:`find_needle_told`), and it tells only when one way round fits
clearly (``SURE_NCC``) and clearly better than the other (``SURE_GAP``): a low-contrast
needle under a hot spot of glare may fit the wrong way round a little better.
"""

from __future__ import annotations

import logging
import math

import cv2
import numpy as np

from .needle import NeedleFit, find_needle
from .register import carry_points

__all__ = ["find_needle_told", "reference_strip", "strip_scores", "strip_points", "tip_teller"]

log = logging.getLogger(__name__)

HUB = 0.12  # the strip leaves out the hub, alike both ways round (units of R)
REACH = 1.0  # ... and runs out to the scale ring on both sides
N_R = 48  # samples along each side
N_S = 17  # samples across
HALF = 0.1  # the strip's half-width: 0.1 R + 3 px (the face on both sides of the needle)


def strip_points(pivot, angle_deg: float, R: float) -> np.ndarray:
    """(2 N_R x N_S x 2) points of the strip along image angle ``angle_deg`` (clockwise
    from up) about ``pivot``: rows from the far tail through the hub to the far tip."""
    t = math.radians(angle_deg)
    u = np.array([math.sin(t), -math.cos(t)])
    n = np.array([math.cos(t), math.sin(t)])
    side = np.linspace(HUB * R, REACH * R, N_R)
    rs = np.concatenate([-side[::-1], side])
    half = HALF * R + 3.0
    ss = np.linspace(-half, half, N_S)
    return (np.asarray(pivot, float)[None, None, :] + rs[:, None, None] * u
            + ss[None, :, None] * n)


def _sample(gray: np.ndarray, pts: np.ndarray) -> np.ndarray:
    mx = pts[..., 0].astype(np.float32)
    my = pts[..., 1].astype(np.float32)
    return cv2.remap(gray, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
                     ).astype(np.float32)


def _ncc(a: np.ndarray, b: np.ndarray) -> float:
    """Correlation of two strips, each radius's row less its mean across the strip: the
    needle against the face beside it, not the light's slope along the dial."""
    a = a - a.mean(axis=1, keepdims=True)
    b = b - b.mean(axis=1, keepdims=True)
    d = math.sqrt(float((a * a).sum()) * float((b * b).sum()))
    return float((a * b).sum()) / d if d > 1e-6 else 0.0


SURE_NCC = 0.4  # the reference's strip fits the frame's this well one way round ...
SURE_GAP = 0.2  # ... and by this much better than the other way round: the tip is told


def reference_strip(ref_gray: np.ndarray, ref_pivot, ref_radius: float,
                    tip_deg: float) -> np.ndarray:
    """The reference frame's strip along its needle, whose tip lies along ``tip_deg``."""
    return _sample(ref_gray, strip_points(ref_pivot, tip_deg, ref_radius))


def _ref_angle(inv: np.ndarray, ref_pivot, frame_pivot, angle_deg: float,
               frame_r: float) -> float:
    """The image angle in the reference of the frame's direction ``angle_deg``."""
    t = math.radians(angle_deg)
    p = np.array([[frame_pivot[0] + 0.5 * frame_r * math.sin(t),
                   frame_pivot[1] - 0.5 * frame_r * math.cos(t)]])
    q = carry_points(inv, p)[0] - np.asarray(ref_pivot, float)
    return math.degrees(math.atan2(q[0], -q[1])) % 360.0


def strip_scores(strip: np.ndarray, ref_pivot, ref_radius: float, hom: np.ndarray,
                 gray: np.ndarray, frame_pivot, frame_r: float,
                 angle_deg: float) -> tuple[float, float]:
    """(correlation of the reference's strip with the frame's taking the end along
    ``angle_deg`` for the tip, the same taking the other end for it).  The frame's strip
    is laid out in the reference's coordinates, turned to the frame needle's direction
    there, and carried into the frame by ``hom`` (reference -> frame pixels)."""
    a = _ref_angle(np.linalg.inv(hom), ref_pivot, frame_pivot, angle_deg, frame_r)
    pts = strip_points(ref_pivot, a, ref_radius)
    s = _sample(gray, carry_points(hom, pts.reshape(-1, 2)).reshape(pts.shape))
    return _ncc(s, strip), _ncc(s[::-1, ::-1], strip)


def tip_teller(strip: np.ndarray, ref_pivot, ref_radius: float, hom: np.ndarray,
               gray: np.ndarray, frame_pivot, frame_r: float):
    """For :func:`find_needle_told`: +1 when the end along an image angle
    is surely the tip by the reference's strip, -1 when the other end surely is, else 0."""

    def tip_of(angle_deg: float) -> int:
        one, other = strip_scores(strip, ref_pivot, ref_radius, hom, gray, frame_pivot,
                                  frame_r, angle_deg)
        log.debug("reference needle's strip: %.2f this way round, %.2f the other", one, other)
        if max(one, other) >= SURE_NCC and abs(one - other) >= SURE_GAP:
            return 1 if one > other else -1
        return 0

    return tip_of


def find_needle_told(image: np.ndarray, pivot, radius: float, tip_of, *, find=find_needle,
                     **kw) -> NeedleFit:
    """``find`` (:func:`.needle.find_needle` or a wrapper of it; ``kw`` its options), and
    where the needle's own ends leave its tip in doubt (``tip_vs_tail`` 0), ``tip_of``
    (:func:`tip_teller`, or None) asked which end is the tip: where it tells, the needle is
    measured again with that end for its tip."""
    nf = find(image, pivot, radius, **kw)
    if tip_of is None or not nf.ok or nf.scores.get("tip_vs_tail", 1.0) > 0.0:
        return nf
    known = tip_of(nf.angle_deg)
    if not known:
        return nf
    log.debug("needle's tip told by the reference needle: %s",
              "this end" if known > 0 else "the other end")
    tip_deg = nf.angle_deg + (0.0 if known > 0 else 180.0)
    return find(image, pivot, radius, tip_deg=tip_deg, **kw)
