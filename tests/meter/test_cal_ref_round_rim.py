"""A reference frame's rim is fitted once and kept however round it is: a dial 8 deg off
head-on is round to 0.99, and taking it as head-on left that view in every reading of the
point.  Where grey shows no rim on the reference (a face of the background's grey in
another colour), the rim is looked for in its colour channels."""

import math

from stored_frames import HERE, fs_off, read_cal_ref, stored_cal_ref

import app.core.meter.calibrated as calibrated
from app.core.meter import load_profile
from app.core.meter.oblique import ROUND

# `plant` PG-101: the reference's rim on every ray, axis ratio 0.993 (a view of 0.20 deg)
ROUND_RIM = "cal-ref-tuning-19-2-PG-101"
# `colour` PG-201: grey shows no rim on the reference; one colour channel does (0.978)
COLOUR_RIM = "cal-ref-tuning-13-1-PG-201"


def test_a_nearly_round_reference_rim_is_kept(monkeypatch):
    r, truth = read_cal_ref(ROUND_RIM)
    assert r.method == "calibrated-reference"
    assert r.value is not None and fs_off(r, truth) < 0.06
    # snapped to head-on as an uncalibrated frame's rim is: the view is left in the reading
    monkeypatch.setattr(calibrated, "REF_ROUND", ROUND)
    r, truth = read_cal_ref(ROUND_RIM)
    assert r.value is not None and fs_off(r, truth) > 0.15


def test_a_reference_rim_seen_in_colour_only_undoes_its_view():
    r, truth = read_cal_ref(COLOUR_RIM)
    assert r.value is not None and fs_off(r, truth) < 0.06
    img, _, prof = stored_cal_ref(COLOUR_RIM)
    profile = load_profile(prof, base_dir=HERE)
    calibrated._REFERENCES.clear()
    rect = calibrated._reference_geometry(profile.calibration, profile)[0]
    calibrated._REFERENCES.clear()
    assert not rect.identity and math.isclose(rect.axis_ratio, 0.978, abs_tol=0.01)
