"""A pivot's doubt reaches the reading through the needle's angle less the scale's turn,
both seen about the same pivot (:func:`app.core.meter.angles.pivot_lever`): a short arc's
end marks move with the needle and cancel most of it, a long arc's move against a needle
near its middle and add to it."""

import math

import numpy as np
import pytest

from app.core.meter.angles import pivot_lever
from app.core.meter.arc_fit import ArcFit
from tests.meter.stored_frames import fs_off, read_first_drawn

R = 100.0  # px, the scale ring's radius


def _seen(a_deg: float, d) -> float:
    """Angle (deg, clockwise from up) of the ring's point at ``a_deg`` seen from a pivot
    moved by ``d`` (px)."""
    x = R * math.sin(math.radians(a_deg)) - d[0]
    y = -R * math.cos(math.radians(a_deg)) - d[1]
    return math.degrees(math.atan2(x, -y))


def _worst_error_deg(marks, needle_deg: float, d_px: float) -> float:
    """The largest change of the needle's angle less the marks' mean turn, over the
    directions of a pivot moved by ``d_px``."""
    worst = 0.0
    for b in np.linspace(0.0, 2.0 * math.pi, 721):
        d = (d_px * math.cos(b), d_px * math.sin(b))
        turn = np.mean([(_seen(a, d) - a + 180.0) % 360.0 - 180.0 for a in marks])
        moved = (_seen(needle_deg, d) - needle_deg + 180.0) % 360.0 - 180.0
        worst = max(worst, abs(moved - turn))
    return worst


@pytest.mark.parametrize("span", [90.0, 150.0, 270.0, 320.0])
@pytest.mark.parametrize("phi", [0.0, 0.3, 0.5])  # the needle's place, in spans from the middle
def test_the_lever_is_the_geometry_of_a_moved_pivot(span, phi):
    d_px = 0.05  # small: the lever is the first-order effect
    unit = math.degrees(d_px / R)
    phi_deg = phi * span
    ends = [-span / 2.0, span / 2.0]
    got = pivot_lever(ArcFit(0.0, ends=2), span, phi_deg)
    assert got == pytest.approx(_worst_error_deg(ends, phi_deg, d_px) / unit, rel=0.01)
    ticks = list(np.linspace(-span / 2.0, span / 2.0, 201))  # a comb: evenly over the arc
    got = pivot_lever(ArcFit(0.0, ends=2, method="comb"), span, phi_deg)
    assert got == pytest.approx(_worst_error_deg(ticks, phi_deg, d_px) / unit, rel=0.01)
    # one end mark, or a comb that verified one end (it may be a tooth out): as before
    assert pivot_lever(ArcFit(0.0, ends=1), span, phi_deg) == 1.0
    assert pivot_lever(ArcFit(0.0, ends=1, method="comb"), span, phi_deg) == 1.0


def test_short_arc_cancels_long_arc_adds():
    two = ArcFit(0.0, ends=2)
    assert pivot_lever(two, 100.0, 0.0) < 0.4  # the ends move with a needle at the middle
    assert pivot_lever(two, 100.0, 50.0) == pytest.approx(math.sin(math.radians(50.0)))
    assert pivot_lever(two, 300.0, 0.0) > 1.8  # they move against it


def test_short_arc_read_by_the_classical_reader():
    # an `atlas` field crop on a 125 deg arc: its error bound was mostly the pivot's doubt,
    # taken whole (1.29 % FS in all), and the crop went to the learned fallback; the doubt
    # that reaches the reading leaves 0.62 % FS, and the profile's angles read it
    r, truth = read_first_drawn("atlas", "field", 2)
    assert r.value is not None and r.method == "profile-angles"
    assert fs_off(r, truth) <= r.error_bound_fs < 0.9
