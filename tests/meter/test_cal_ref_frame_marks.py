"""With a reference frame, an end mark the reference could not place on its tick (kept as
clicked there) is placed on each frame instead, where the needle and the light have moved;
not where the tick found there is much wider than the other end's (one print)."""

import math

from stored_frames import fs_off, read_cal_ref

import app.core.meter.calibrated as calibrated
import app.core.meter.mark_points as mark_points

# `dark` PG-102: a glare band across the reference's minimum mark keeps its click (1.5 px
# off the tick, 0.85 % FS); the frame shows the tick clearly
FRAME = "cal-ref-tuning-24-3-PG-102"
# `colour` PG-201: the reference's needle lies on the maximum mark (a dot at a red band's
# end); in the frame the needle is 4 deg from it, and the tick found there is the dot run
# together with the band's end, twice the minimum dot's width
WIDE = "cal-ref-tuning-26-4-PG-201"


def test_an_end_mark_the_reference_kept_as_clicked_is_placed_on_the_frame(monkeypatch):
    r, truth = read_cal_ref(FRAME)
    assert r.method == "calibrated-reference"
    assert r.value is not None and fs_off(r, truth) < 0.15
    # without it, the reference's click (off the tick by a glare band) stays in the reading
    monkeypatch.setattr(calibrated, "frame_marks", lambda *a: None)
    r, truth = read_cal_ref(FRAME)
    assert r.value is not None and fs_off(r, truth) > 0.5


def test_a_tick_much_wider_than_the_other_ends_is_not_taken_for_the_mark(monkeypatch):
    r, truth = read_cal_ref(WIDE)
    assert r.value is None or fs_off(r, truth) < 0.5
    # taken, the dot run together with the band's end reads more than 1 % FS off
    monkeypatch.setattr(mark_points, "WIDTH_MATCH", math.inf)
    r, truth = read_cal_ref(WIDE)
    assert r.value is not None and fs_off(r, truth) > 1.0
