"""Where the classical paths refuse a crop's first view, the learned keypoints read it before
any classical retry (the dial search's other rims, a second look about the scale ring's
centre): a retry is made only where they refuse too.  On a crop the keypoints look at the
whole image, so their reading is the one they gave after the retries.  An oblique crop whose
ticks span another arc than the profile's is read by them before the profile's angles."""

import numpy as np
import pytest

import app.core.meter.learned as learned
import app.core.meter.reader as reader
from app.core.meter import load_profile, read_gauge
from sim_robot.gauge_scene import render_sample


def _sample(family: str, level: str, seed: int):
    img, truth = render_sample(family, level, np.random.default_rng(seed))
    return img, load_profile(truth["profile"]), truth


def _same(a, b) -> bool:
    return (a.value, a.confidence, a.method, a.error, a.error_bound_fs) == \
        (b.value, b.confidence, b.method, b.error, b.error_bound_fs)


def _counting(monkeypatch, name: str, module=reader) -> list:
    calls: list = []
    orig = getattr(module, name)

    def counted(*a, **k):
        calls.append(1)
        return orig(*a, **k)

    monkeypatch.setattr(module, name, counted)
    return calls


def _no_search(*a, **k):
    raise AssertionError("the dial search ran after the keypoints had read the crop")


def test_keypoints_read_the_crop_before_the_dial_search(monkeypatch):
    # the crop fast path refuses this `nordic` field crop on its own rim
    img, prof, truth = _sample("nordic", "field", 0)
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", False)
    searches = _counting(monkeypatch, "_full_search")
    r_all = read_gauge(img, prof)  # every classical path first, as before
    assert len(searches) == 1 and r_all.method == "keypoints"
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", True)
    monkeypatch.setattr(reader, "_full_search", _no_search)
    r = read_gauge(img, prof)
    assert _same(r, r_all)
    assert abs(r.value - truth["value"]) / truth["full_scale"] < 0.02


def test_keypoints_read_the_crop_before_a_second_look(monkeypatch):
    # a `heritage` field crop with no rim of its own: the search's view, refused by the
    # profile's angles, would be looked at again about the scale ring's centre
    img, prof, truth = _sample("heritage", "field", 7)
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", False)
    looks = _counting(monkeypatch, "rectify_projective")
    r_all = read_gauge(img, prof)
    assert len(looks) == 1 and r_all.method == "keypoints"
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", True)
    looks.clear()
    r = read_gauge(img, prof)
    assert looks == [] and _same(r, r_all)
    assert abs(r.value - truth["value"]) / truth["full_scale"] < 0.02


@pytest.mark.parametrize("case", [("marine", "clean", 2), ("heritage", "clean", 10)])
def test_a_refusal_is_the_same_and_the_keypoints_run_once(monkeypatch, case):
    # the keypoints refuse these crops too: the classical retries are made as before, and
    # the refusal (its reasons, the classical ones and the keypoints') is unchanged
    img, prof, _ = _sample(*case)
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", False)
    r_all = read_gauge(img, prof)
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", True)
    kp_reads = _counting(monkeypatch, "keypoint_reading", learned)
    searches = _counting(monkeypatch, "_full_search")
    r = read_gauge(img, prof)
    assert r.value is None and _same(r, r_all)
    assert len(kp_reads) == 1 and len(searches) == 1


def test_keypoints_read_an_oblique_crop_whose_ticks_span_another_arc(monkeypatch):
    # a `nordic` field crop seen obliquely, its scale finder's ticks over another arc than
    # the profile's: the profile's angles would refuse it, and the keypoints read it
    img, prof, truth = _sample("nordic", "field", 1)
    monkeypatch.setattr(learned, "FORESEE_ARC_REFUSAL", False)
    angles = _counting(monkeypatch, "_angles_reading")
    r_all = read_gauge(img, prof)
    assert len(angles) == 1 and r_all.method == "keypoints"

    def no_angles(*a, **k):
        raise AssertionError("the profile's angles ran before the keypoints")

    monkeypatch.setattr(learned, "FORESEE_ARC_REFUSAL", True)
    monkeypatch.setattr(reader, "_angles_reading", no_angles)
    r = read_gauge(img, prof)
    assert _same(r, r_all)
    assert abs(r.value - truth["value"]) / truth["full_scale"] < 0.02
