"""A two-ended needle whose tip ends in an arrow head and whose tail ends in a ring: the
tip is the longer end, but also the wider near the hub (it tapers from a wide root) and as
wide over its outer half (the arrow head) as the tail (its ring), so the widths said "no
sure tip" and the calibrated reader refused a plain, upright dial.  Where the shorter end
points clearly into the scale's gap while the longer lies on the scale, the shorter is the
tail: a tip never points into the gap farther than the stop pin beside an end mark
(app.core.meter.needle_ends.tail_in_gap).  When it is the long, wide end that points into
the gap (glare cut a thin tip short beside a long spade tail), the finder still does not
vouch for its choice."""

import math

import cv2
import numpy as np
import pytest

import app.core.meter as meter
from app.core.meter.needle import find_needle
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import random_style


@pytest.mark.parametrize("seed, frac", [(2, 0.35), (23, 0.35), (23, 0.65), (29, 0.35)])
def test_an_arrow_headed_tip_beside_a_ring_tail_in_the_gap_is_read(seed, frac):
    style = random_style("heritage", np.random.default_rng(seed))
    fs = style.max_value - style.min_value
    value = style.min_value + frac * fs
    img, t = draw_dial(style, value, 300)
    prof = style.profile()
    assert prof["needle"] == "two-ended"
    base = {k: v for k, v in prof.items() if k not in ("min_angle_deg", "max_angle_deg")}
    d = meter.make_calibrated_profile(base, t["pivot_xy"], t["min_mark_xy"], t["max_mark_xy"],
                                      clockwise=prof["max_angle_deg"] > prof["min_angle_deg"])
    r = meter.read_gauge(img, meter.load_profile(d))
    assert r.value == pytest.approx(value, abs=0.01 * fs), r.error


def _needle(tip_px: float, tail_px: float, tip_w: int, tail_w: int, ang_deg: float):
    img = np.full((300, 300), 235, np.uint8)
    c, ang = np.array([150.0, 150.0]), math.radians(ang_deg)
    u = np.array([math.sin(ang), -math.cos(ang)])
    for length, width, sign in ((tip_px, tip_w, 1.0), (tail_px, tail_w, -1.0)):
        end = c + sign * length * u
        cv2.line(img, (int(c[0] * 16), int(c[1] * 16)), (int(end[0] * 16), int(end[1] * 16)),
                 20, width, cv2.LINE_AA, 4)
    cv2.circle(img, (150, 150), 9, 20, -1, cv2.LINE_AA)
    return img


def _gap(lo: float, hi: float):
    """on_scale for a scale whose gap runs clockwise from ``lo`` to ``hi`` (degrees)."""
    return lambda a: not (lo <= a % 360.0 <= hi)


def test_a_long_wide_end_on_the_scale_with_the_short_end_in_the_gap_is_the_tip():
    img = _needle(95.0, 50.0, 9, 3, 60.0)  # long and wide at 60 deg, short and thin at 240
    blind = find_needle(img, (150.0, 150.0), 108.0, needle="two-ended")
    assert blind.ok and blind.scores.get("tip_vs_tail", 1.0) == 0.0
    seen = find_needle(img, (150.0, 150.0), 108.0, needle="two-ended",
                       on_scale=_gap(195.0, 285.0))
    assert seen.ok and seen.scores.get("tip_vs_tail", 1.0) == 1.0
    assert abs((seen.angle_deg - 60.0 + 180.0) % 360.0 - 180.0) < 1.0


@pytest.mark.parametrize("gap", [(195.0, 285.0), (120.0, 200.0)])
def test_a_long_wide_end_in_the_gap_or_both_ends_on_the_scale_is_still_no_sure_tip(gap):
    # the long wide end (at 240 deg) is a spade tail beside a tip cut short (at 60 deg):
    # with the gap where that long end points, or where neither end points, the scale does
    # not vouch for the long end (a tip never points into the gap, so a gap where the short
    # end points would mean that the short end is no tip)
    img = _needle(50.0, 82.0, 3, 9, 60.0)
    f = find_needle(img, (150.0, 150.0), 108.0, needle="two-ended", on_scale=_gap(*gap))
    assert f.ok and f.scores.get("tip_vs_tail", 1.0) == 0.0
