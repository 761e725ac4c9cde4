"""A second ring of the dial's marks whose end marks miss the profile's span contradicts
the scale only when it is not centred on it (:func:`app.core.meter.arc_fit.fit_profile_arc`):
a printed arc whose caps pass both end ticks by as much (or numerals centred on them) is a
ring of other extent about the same arc; one that passes a single end is a scale shifted or
cut at one end, and the fit is refused."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from app.core.meter.arc_fit import fit_profile_arc

SIZE, C, R_TICKS, R_ARC = 300, (150.0, 150.0), 100.0, 112.0
TURN = 7.0  # the dial's turn in the picture (deg, clockwise)
OVER = 3.5  # deg: how far the printed arc's caps pass an end tick


def _ticks() -> list[float]:
    """Tick angles strewn unevenly over the inside of the arc, at least 3 deg apart (no
    comb of even ticks: only the end marks place the scale), and its two end ticks."""
    rng = np.random.default_rng(1)
    out: list[float] = []
    while len(out) < 34:
        a = float(rng.uniform(-129.0, 129.0))
        if all(abs(a - b) >= 3.0 for b in out):
            out.append(a)
    return sorted([-135.0, *out, 135.0])


def _p(a: float, r: float) -> tuple[int, int]:
    t = math.radians(a + TURN)
    return (int(round((C[0] + r * math.sin(t)) * 16)), int(round((C[1] - r * math.cos(t)) * 16)))


def _dial(arc_from: float, arc_to: float) -> np.ndarray:
    """Darkness image: radial ticks from -135 to +135 deg (upright) on one ring and, outside
    it, a printed arc (3 px thick) from ``arc_from`` to ``arc_to``; all turned by TURN."""
    img = np.zeros((SIZE, SIZE), np.uint8)
    for a in _ticks():
        cv2.line(img, _p(a, R_TICKS - 16.0), _p(a, R_TICKS), 255, 2, cv2.LINE_AA, 4)
    cv2.ellipse(img, (int(C[0] * 16), int(C[1] * 16)), (int(R_ARC * 16), int(R_ARC * 16)),
                0.0, arc_from - 90.0 + TURN, arc_to - 90.0 + TURN, 255, 3, cv2.LINE_AA, 4)
    return img


def _fit(img: np.ndarray):
    return fit_profile_arc([(img, 50)], C, 135.0, None, -135.0 % 360.0, 270.0)


def test_an_arc_passing_both_end_ticks_alike_does_not_contradict_them():
    """The arc's caps lie OVER deg beyond both end ticks: its own end marks miss the span
    by about twice that, but their mean turn is the ticks' one.  The old rule refused the
    dial ("scale marks at two radii disagree")."""
    fit = _fit(_dial(-135.0 - OVER, 135.0 + OVER))
    assert fit.rho_deg is not None, fit
    assert fit.rho_deg == pytest.approx(TURN, abs=0.5)
    assert fit.ends == 2


@pytest.mark.parametrize("arc", [(-135.0, 135.0 + 2 * OVER), (-135.0 - 2 * OVER, 135.0)])
def test_an_arc_passing_one_end_tick_only_still_refuses(arc):
    """The same excess at one end only: the arc's end marks miss the span by as much, but
    their mean turn lies half of it off the ticks' turn; the dial's marks disagree."""
    fit = _fit(_dial(*arc))
    assert fit.rho_deg is None, fit
    assert "two radii disagree" in (fit.error or ""), fit
