"""A two-ended needle whose long end has gaps along it (a thin tip's reach bridged on to
the ticks) is read by that end when, weighing the ends, the short end is much the wider
near the hub: a counterweight, not a thin tip that faded or was cut short."""

import json

from stored_frames import HERE, fs_off, read_cal_ref, stored_cal_ref

from app.core.meter import load_profile
from app.core.meter.needle import find_needle

# `heritage` PG-302: a blue diamond-headed needle with a ring counterweight (two-ended), a
# red set-point pointer; its reference frame's needle has the same gappy long end
FRAME = "cal-ref-tuning-26-1-PG-302"


def test_a_gappy_long_end_beside_a_wide_counterweight_is_the_tip():
    r, truth = read_cal_ref(FRAME)
    assert r.method == "calibrated-reference"
    assert r.value is not None and fs_off(r, truth) < 0.5


def test_the_rule_weighs_the_ends_only():
    img, truth, prof = stored_cal_ref(FRAME)
    profile = load_profile(prof, base_dir=HERE)
    pivot = tuple(json.loads((HERE / f"{FRAME}.json").read_text())["pivot_xy"])
    R = profile.calibration.radius_px
    on_scale = lambda a: True  # noqa: E731 - both ends lie on this scale
    kw = dict(needle="two-ended", ignore_colour="red")
    weighed = find_needle(img, pivot, R, on_scale=on_scale, weigh_ends=True, **kw)
    assert weighed.ok and weighed.scores.get("tip_vs_tail", 1.0) == 1.0
    assert abs((weighed.angle_deg - truth["needle_angle_deg"] + 180) % 360 - 180) < 2.0
    # the uncalibrated reader (ends not weighed) keeps the profile's doubt
    plain = find_needle(img, pivot, R, on_scale=on_scale, **kw)
    assert plain.scores.get("tip_vs_tail", 1.0) == 0.0
