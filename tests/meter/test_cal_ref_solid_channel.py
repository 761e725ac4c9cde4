"""A red needle near the opposite of a dark column of print (a numeral above the end tick):
the dark channel takes the print for the needle and the needle for its tail, its line has
gaps, and the colour channel alone shows the needle whole where that tail was looked for."""

import math

import pytest
from stored_frames import fs_off, read_cal_ref, stored

import app.core.meter.calibrated as calibrated
from app.core.meter.needle import find_needle

# `process` CG-301, a red needle on a white face: at 0.70 MPa (lap 1) the "-0.1" numeral
# and the minimum tick lie 10 deg off the needle's opposite; at 0.14 MPa (lap 2) the "0.9"
# numeral and the maximum tick lie on it
FRAMES = ["cal-ref-tuning-99-1-CG-301", "cal-ref-tuning-99-2-CG-301"]


@pytest.mark.parametrize("name", FRAMES)
def test_the_needle_seen_whole_in_another_channel_is_read(name):
    r, truth = read_cal_ref(name)
    assert r.value is not None and fs_off(r, truth) < 0.3
    assert r.scores["needle_solid"] == 1.0


@pytest.mark.parametrize("name", FRAMES)
def test_without_the_other_channel_the_gappy_print_line_is_refused(name, monkeypatch):
    monkeypatch.setattr(calibrated, "find_solid_needle", find_needle)
    r, _ = read_cal_ref(name)
    assert r.value is None and "gaps along it" in r.error


def test_a_channel_asked_alone():
    img, truth = stored(FRAMES[0])
    piv = truth["pivot_xy"]
    radius = math.dist(piv, truth["min_mark_xy"])
    turn = truth["needle_angle_deg"] % 360.0
    dark = find_needle(img, piv, radius, channel="dark")
    colour = find_needle(img, piv, radius, channel="colour")
    # the dark channel's line is the print, its tip 180 deg from the needle's, with gaps
    assert abs((dark.angle_deg - turn) % 360.0 - 180.0) < 16.0
    assert dark.scores["needle_solid"] < 1.0
    assert abs((colour.angle_deg - turn + 180.0) % 360.0 - 180.0) < 1.5
    assert min(colour.scores.values()) == 1.0
