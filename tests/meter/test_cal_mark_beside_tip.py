"""A needle a few pixels short of an end mark, with print beside its tip (a numeral, a
diamond mark's neighbours): the top-hat that looks for the end mark's tick beyond the
needle closes the tip, the print and the mark into one wide patch and sees no tick there,
so the mark was taken to be under the needle and the reading became the end's value,
2.5 % FS off.  The mark is looked for against the face itself too
(app.core.meter.hidden_mark): the clicked end mark is kept, and the reading is right, or
refused where the click alone is too uncertain for the scale (a small dial's end)."""

import math

import numpy as np
import pytest

import app.core.meter as meter
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import random_style


@pytest.mark.parametrize("family, seed, frac, end", [
    ("marine", 21, 0.975, "max"),   # diamond marks with dots between them
    ("marine", 21, 0.025, "min"),
    ("dark", 37, 0.025, "min"),     # a light needle on a dark face, "0" beside its tip
])
def test_a_mark_just_beyond_the_tip_is_not_taken_to_be_under_it(family, seed, frac, end):
    style = random_style(family, np.random.default_rng(seed))
    fs = style.max_value - style.min_value
    value = style.min_value + frac * fs
    img, t = draw_dial(style, value, 300)
    px, py = t["pivot_xy"]
    mx, my = t[f"{end}_mark_xy"]
    # (what the case is: the needle passes the end mark within a few pixels)
    rm = math.hypot(mx - px, my - py)
    a_mark = math.degrees(math.atan2(mx - px, -(my - py)))
    off = (t["needle_angle_deg"] - a_mark + 180.0) % 360.0 - 180.0
    assert 2.0 < abs(math.radians(off)) * rm < 7.0
    prof = style.profile()
    base = {k: v for k, v in prof.items() if k not in ("min_angle_deg", "max_angle_deg")}
    d = meter.make_calibrated_profile(base, t["pivot_xy"], t["min_mark_xy"], t["max_mark_xy"],
                                      clockwise=prof["max_angle_deg"] > prof["min_angle_deg"])
    r = meter.read_gauge(img, meter.load_profile(d))
    if r.value is not None:
        assert r.value == pytest.approx(value, abs=0.01 * fs)
    else:  # not the end's value: the click's own uncertainty, said so
        assert "too uncertain" in r.error
        assert abs(r.raw_value - value) < abs(r.raw_value - getattr(style, f"{end}_value"))
