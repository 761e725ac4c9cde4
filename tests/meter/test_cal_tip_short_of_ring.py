"""A two-ended needle (a ring counterweight) whose long thin tip ends short of the tick
ring: its reach is bridged on to the ticks, and the stretch between its end and the ring
was counted as gaps along the needle, as if the long end were print beyond a tail's
weight, so the tip could not be told from the tail and the reading was refused.  Where the
reach runs on to the tick ring, which every ray meets, the needle's cover is now measured
out to where it is last seen before it (app.core.meter.needle); print bridged on to inside
the ring still leaves a gap (test_cal_stress.py, a two-ended needle not read by its tail;
test_calibrated.py, a faded tip opposite a weight with print beyond it)."""

import numpy as np
import pytest

import app.core.meter as meter
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import random_style


@pytest.mark.parametrize("seed, frac", [(1, 0.3), (4, 0.85), (11, 0.3), (11, 0.6), (29, 0.3)])
def test_a_tip_short_of_the_tick_ring_is_read(seed, frac):
    style = random_style("heritage", np.random.default_rng(seed))
    prof = style.profile()
    assert prof.get("needle") == "two-ended"
    fs = style.max_value - style.min_value
    value = style.min_value + frac * fs
    img, t = draw_dial(style, value, 300)
    base = {k: v for k, v in prof.items() if k not in ("min_angle_deg", "max_angle_deg")}
    d = meter.make_calibrated_profile(base, t["pivot_xy"], t["min_mark_xy"], t["max_mark_xy"],
                                      clockwise=prof["max_angle_deg"] > prof["min_angle_deg"])
    r = meter.read_gauge(img, meter.load_profile(d))
    assert r.value == pytest.approx(value, abs=0.005 * fs), r.error

