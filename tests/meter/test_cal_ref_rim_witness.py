"""A reference frame's rim that mixes two edges (the printed scale arc over the top, the
face's edge below) is no other edge's shape; where two other edges share theirs, the rim
is taken from them and the dial's tilt is no longer in doubt."""

from stored_frames import HERE, fs_off, stored_cal_ref

import app.core.meter.calibrated as calibrated
from app.core.meter import load_profile, read_gauge
from app.core.meter.rim_witness import Hypothesis, apart, shape_gap

# a `plant` dial seen nearly head-on (axis ratio 0.997): its rim's winner (63 of 96 rays)
# mixes the scale arc and the face's edge at an axis ratio of 0.932; the bezel's outer
# edge (60 rays) and the arc's outer edge (dark to bright, 58 of 58) agree on 0.998
FRAME = "cal-ref-tuning-59-0-PG-101"


def test_a_rim_two_other_edges_contradict_is_replaced_by_theirs(monkeypatch):
    img, truth, prof = stored_cal_ref(FRAME)
    profile = load_profile(prof, base_dir=HERE)
    calibrated._REFERENCES.clear()
    r = read_gauge(img, profile)
    assert r.value is not None and fs_off(r, truth) < 0.3
    assert r.scores.get("tilt", 1.0) == 1.0
    # with the mixed rim, its correction is in doubt and the reading is refused
    calibrated._REFERENCES.clear()
    monkeypatch.setattr(calibrated, "second_edge", lambda gray, pivot, radius, rect, **kw: rect)
    # (and without the dial's circles' word on it, :mod:`app.core.meter.rim_focus`)
    monkeypatch.setattr(calibrated, "sharpest_rim", lambda gray, piv, clicked, radius, rect: rect)
    r = read_gauge(img, profile)
    calibrated._REFERENCES.clear()
    assert r.value is None and "tilt" in r.error


def test_shapes_agree_whatever_their_size_and_centre():
    a = ((100.0, 100.0), (180.0, 200.0), 30.0)
    b = ((103.0, 98.0), (90.0, 100.0), 30.0)  # smaller, off centre, the same shape
    c = ((100.0, 100.0), (180.0, 200.0), 80.0)  # the same ratio about another axis
    assert shape_gap(a, b) < 1e-6
    assert shape_gap(a, c) > 0.05


def test_edges_apart_by_polarity_or_size():
    e = ((0.0, 0.0), (200.0, 200.0), 0.0)
    f = ((0.0, 0.0), (204.0, 204.0), 0.0)
    g = ((0.0, 0.0), (240.0, 240.0), 0.0)
    h = Hypothesis(False, e, 60, 96)
    assert not apart(h, Hypothesis(False, f, 60, 96), 90.0)  # one edge (1 px)
    assert apart(h, Hypothesis(False, g, 60, 96), 90.0)  # 10 px
    assert apart(h, Hypothesis(True, f, 58, 58), 90.0)
