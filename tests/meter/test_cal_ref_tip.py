"""With a reference frame whose needle's tip is sure, the frame's needle's tip is the end
where the reference needle's strip, carried over by the registration, fits: a two-ended
needle whose own widths and gaps leave its tip in doubt is read, not refused."""

import math

from stored_frames import HERE, fs_off, stored_cal_ref

import app.core.meter.calibrated as calibrated
import app.core.meter.needle as needle
from app.core.meter import load_profile, read_gauge
from app.core.meter.ref_tip import strip_points

# a `heritage` two-ended needle (a diamond head, a ring counterweight) near the scale's
# maximum, its ring pointing at the stop pin below the minimum (not into the scale's gap);
# the tip's reach bridged on to the ticks leaves gaps along the long end
FRAME = "cal-ref-tuning-28-0-PG-302"


def test_the_reference_needle_tells_the_tip_of_a_two_ended_needle(monkeypatch):
    img, truth, prof = stored_cal_ref(FRAME)
    profile = load_profile(prof, base_dir=HERE)
    r = read_gauge(img, profile)
    assert r.value is not None and fs_off(r, truth) < 0.5
    assert r.method == "calibrated-reference"
    # without the reference needle's word, the tip could not be told from the tail (the
    # ring counterweight, twice the tip's width near the hub, also tells it now: that cue
    # is set aside here, in the frame and in the reference alike)
    monkeypatch.setattr(needle, "COUNTERWEIGHT", math.inf)
    calibrated._REFERENCES.clear()
    r = read_gauge(img, profile)
    assert r.value is not None and fs_off(r, truth) < 0.5
    calibrated._REFERENCES.clear()
    monkeypatch.setattr(calibrated, "_reference_tip", lambda *a: None)
    r = read_gauge(img, profile)
    calibrated._REFERENCES.clear()  # (measured without the counterweight's cue)
    assert r.value is None and "tip from its tail" in r.error


def test_a_strip_runs_from_the_tail_through_the_hub_to_the_tip():
    pts = strip_points((100.0, 100.0), 90.0, 50.0)  # along +x
    mid = pts.shape[1] // 2
    assert pts[0, mid, 0] < 60 and pts[-1, mid, 0] > 140
    assert abs(pts[-1, mid, 1] - 100.0) < 1e-9
