"""A second edge's word on a reference frame's rim (issue 11, section 1, a calibration with
a reference frame).

The rim's tilt correction (:func:`.oblique.find_rectifier`) is the ellipse that most rays
have a step on.  Where no ellipse has a step on every ray, the winner may mix two edges: the
printed scale arc over the top of the dial and the face's edge below it, say, whose ellipse
is flatter than either (the tuning seeds' references show it at axis ratios 0.93-0.96 on
dials seen nearly head-on).  Its support (the share of its rays) leaves its correction in
doubt, and a reading whose correction is large is refused for the tilt.

On the dial, its face's edge, the bezel's edges and the printed arcs are all circles about
the pivot, so their images are ellipses of one shape (one axis ratio and one axis); a
mixture of two edges is no such circle, and another edge does not share its shape.  Two
hypotheses of the rim (:func:`rim_hypotheses`: each step picked per ray by
:mod:`.oblique`, on the grey and on its inverse, searched out to both reaches) that lie on
different edges (:func:`apart`: another polarity, or sizes further apart than the steps'
tolerance allows for one edge) and agree in shape (:func:`shape_gap` below ``AGREE``)
confirm each other.  Where the chosen rim is confirmed, nothing changes; where another pair
confirms each other and the chosen rim is not one of them, the rim becomes the pair's member
on the larger share of its own rays (:func:`second_edge`).  Where no two edges agree, a
chosen rim on less than ``CLEAN`` of its rays (the share below which :mod:`.oblique` looks
for a rim of the other polarity too) gives way to another edge on at least that share of
the rays that have a step of its polarity: one edge wherever it is seen (the outer edge of
a printed arc, a dark-to-bright step, seen only over the scale's span), not two edges
mixed.

This is done once per reference file (the reference's geometry is cached), so it costs the
frames nothing.  The uncalibrated reader's rims are not touched.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import cv2
import numpy as np

from .oblique import (
    LIGHT_RIM_TRY,
    RIM_FAR,
    RIM_OUT,
    ROUND,
    Rectifier,
    _fit_rim,
    _hypotheses,
    _residual,
    _rim_candidates,
    _stretch,
)

__all__ = ["AGREE", "Hypothesis", "apart", "rim_hypotheses", "second_edge", "shape_gap"]

log = logging.getLogger(__name__)

AGREE = 0.01  # two ellipses of one shape: 1 - the ratio of the singular values between them
APART = 3.0  # ... on two edges: sizes further apart than this many step tolerances
CLEAN = LIGHT_RIM_TRY  # an edge on this share of the rays with a step of its polarity


@dataclass(frozen=True)
class Hypothesis:
    """One fitted rim hypothesis: on the inverted grey or not, its ellipse (cv2 form), the
    rays with a step on it and the rays with a step at all."""

    inverted: bool
    ellipse: tuple
    n_on: int
    n_rays: int

    @property
    def share(self) -> float:
        return self.n_on / max(self.n_rays, 1)

    @property
    def size(self) -> float:
        (_, _), (w, h), _ = self.ellipse
        return 0.25 * (w + h)


def _tolerance(radius: float) -> float:
    """A step this far from an ellipse is on it (as :mod:`.oblique` counts support)."""
    return 0.015 * radius + 1.0


def rim_hypotheses(gray: np.ndarray, pivot, radius: float) -> list[Hypothesis]:
    """Every rim hypothesis :mod:`.oblique` fits about ``pivot``, bright-to-dark and
    dark-to-bright, out to both reaches (duplicates left in)."""
    px, py = float(pivot[0]), float(pivot[1])
    out = []
    for inverted in (False, True):
        g = cv2.bitwise_not(gray) if inverted else gray
        for reach in (RIM_OUT, RIM_FAR):
            cand, strength = _rim_candidates(g, px, py, radius, reach)
            n_rays = int((strength > 0).any(axis=1).sum())
            for pts in _hypotheses(cand, strength):
                ell = _fit_rim(pts, px, py, radius, reach)
                if ell is None:
                    continue
                on = (_residual(cand.reshape(-1, 2), ell).reshape(cand.shape[:2])
                      <= _tolerance(radius)) & (strength > 0)
                out.append(Hypothesis(inverted, ell, int(on.any(axis=1).sum()), n_rays))
    return out


def _unit_map(ell) -> np.ndarray:
    s = _stretch(ell)
    return s / math.sqrt(abs(np.linalg.det(s)))


def shape_gap(e1, e2) -> float:
    """How far two ellipses (cv2 form) are from one shape: 1 - the ratio of the singular
    values of one's rectifying map undone by the other's (0: the same axis ratio and axis,
    wherever centred and however large)."""
    sv = np.linalg.svd(_unit_map(e1) @ np.linalg.inv(_unit_map(e2)), compute_uv=False)
    return float(1.0 - sv[1] / sv[0])


def apart(a: Hypothesis, b: Hypothesis, radius: float) -> bool:
    """Whether two hypotheses lie on two edges: another polarity, or sizes further apart
    than ``APART`` step tolerances (hypotheses of one edge, or of one mixture of two,
    differ by less)."""
    return a.inverted != b.inverted or abs(a.size - b.size) > APART * _tolerance(radius)


def _same(e1, e2) -> bool:
    return all(np.allclose(np.ravel(u), np.ravel(v), atol=1e-6)
               for u, v in zip(e1, e2, strict=True))


def second_edge(gray: np.ndarray, pivot, radius: float, rect: Rectifier, *,
                round_ratio: float = ROUND) -> Rectifier:
    """``rect`` (found on ``gray`` about ``pivot``), or another edge's rim when the chosen
    one is not supported on every ray and no other edge shares its shape, and either two
    other edges share theirs or, the chosen one on less than ``CLEAN`` of its rays, another
    edge is on at least that share of its own (see the module's docstring)."""
    if rect.identity or rect.support >= 1.0:
        return rect
    hyps = rim_hypotheses(gray, pivot, radius)
    chosen = [h for h in hyps if _same(h.ellipse, rect.ellipse)]
    if not chosen:
        return rect
    mine = chosen[0]
    if any(apart(h, mine, radius) and shape_gap(h.ellipse, mine.ellipse) < AGREE
           for h in hyps):
        log.debug("the rim is confirmed by another edge")
        return rect
    pairs = [(a, b) for i, a in enumerate(hyps) for b in hyps[i + 1:]
             if apart(a, b, radius) and shape_gap(a.ellipse, b.ellipse) < AGREE]
    if pairs:
        a, b = max(pairs, key=lambda p: p[0].n_on + p[1].n_on)
        h = max((a, b), key=lambda q: q.share)
    else:  # no two edges agree: an edge on nearly all the rays it is seen on, if any
        clean = [q for q in hyps if apart(q, mine, radius) and q.share >= CLEAN
                 and q.share > mine.share > 0.0 and mine.share < CLEAN]
        if not clean:
            return rect
        h = max(clean, key=lambda q: (q.share, q.n_on))
    (_, _), (w, hh), _ = h.ellipse
    ratio = min(w, hh) / max(w, hh)
    log.debug("the rim (axis ratio %.3f, %.2f of its rays) is no other edge's shape; another "
              "edge's (%.3f, %.2f) taken", rect.axis_ratio, rect.support, ratio, h.share)
    if ratio > round_ratio:
        out = Rectifier(None, None, ratio)
        out.rim_seen = True
        return out
    return Rectifier(_stretch(h.ellipse), h.ellipse, ratio, h.share)
