"""With a reference frame, the end marks' check leaves out the needles' pixels: out along
the needle's line past where its fit ends, a spade or hairline tip over an end mark is the
needle's, not the scale's print (``register_dense.NEEDLE_REACH``)."""

import math

from stored_frames import HERE, stored_cal_ref

import app.core.meter.register_dense as rd
from app.core.meter import load_profile, read_gauge
from app.core.meter.needle import NeedleFit

# a heritage dial whose reference frame has the spade needle on the maximum mark, its
# hairline past the spade; the needle's fit on the reference ends at the spade
FRAME = "cal-ref-tuning-15-0-PG-302"


def test_a_needle_past_its_fit_is_left_out_of_the_end_marks_check(monkeypatch):
    img, truth, prof = stored_cal_ref(FRAME)
    profile = load_profile(prof, base_dir=HERE)
    monkeypatch.setattr(rd, "_TEMPLATES", {})
    r = read_gauge(img, profile)
    assert r.value is not None, r.error
    assert abs(r.value - truth["value"]) / truth["full_scale"] * 100 < 1.0
    # the reference needle's mask ending with its fit: its tip spoils the mark's print
    monkeypatch.setattr(rd, "NEEDLE_REACH", 0.0)
    monkeypatch.setattr(rd, "_TEMPLATES", {})
    r = read_gauge(img, profile)
    assert r.value is None and "maximum mark does not line up" in r.error


def test_the_needle_mask_runs_out_past_a_short_fit():
    R = 100.0
    fit = NeedleFit(True, angle_deg=90.0, pivot_xy=(200.0, 150.0), length_px=0.8 * R,
                    tail_px=20.0, width_px=5.0)
    mask = rd.needle_mask((300, 400), fit, R)
    reach = rd.NEEDLE_REACH * R
    assert reach > R + rd.PATCH * R  # past an end mark's patch
    assert mask[150, int(200 + reach) - 2] and mask[150, int(200 + 0.9 * R)]
    hw = rd.NEEDLE_HW * R + 3.0  # (its round ends reach this far past them)
    assert not mask[150, int(math.ceil(200 + reach + hw)) + 2]
    assert not mask[150 + int(math.ceil(hw)) + 2, int(200 + R)]  # a strip along the line
    assert mask[150, 200 - 20]  # and its tail
