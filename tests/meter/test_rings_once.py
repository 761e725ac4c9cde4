"""Work made once per reading and handed to every step that needs it: each step gets what
it would compute itself, and another image gets its own."""

import cv2
import numpy as np
import pytest

from app.core.meter import arc_fit, load_profile, pivot_checks, read_gauge
from app.core.meter import scale as scale_mod
from app.core.meter.angles import DARK_FACE_GREY, median_face_grey
from app.core.meter.arc_fit import STEP, bands, ring_rows
from app.core.meter.pointer import CENTRE, read_normalised
from app.core.meter.tick_band import long_columns, short_runs, tick_ring_rows
from sim_robot.gauge_scene import render_sample


def _dark(seed: int) -> np.ndarray:
    """A read-only float image of dark marks (as :func:`.ring_centre.pass_images` makes)."""
    rng = np.random.default_rng(seed)
    img, _ = render_sample("plant", "clean", rng)
    grey = cv2.resize(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), (300, 300))
    out = (255.0 - grey).astype(np.float32)
    out.flags.writeable = False
    return out


def _fresh(pol: np.ndarray, thr: float):
    b = pol > thr
    short = short_runs(b, long_columns(STEP))
    return b, bands(b), short, tick_ring_rows(b, STEP, short=short)


def _same(got, want) -> None:
    b, rings, short, ticks = want
    assert np.array_equal(got.b, b) and np.array_equal(got.short(), short)
    assert got.rings() == rings and got.tick_rows() == ticks


def test_an_unwrap_and_its_rings_are_found_once_about_one_point():
    dark = _dark(1)
    c = (CENTRE + 0.3, CENTRE - 0.7)
    pol, _ = scale_mod.polar(dark, c, 60.0, 131.0)
    # a centre equal to it in the float32 the unwrap samples about is the same unwrap
    again, _ = scale_mod.polar(dark, (c[0] + 1e-9, c[1]), 60.0, 131.0)
    assert again is pol
    fresh, _ = scale_mod.polar(dark.copy(), c, 60.0, 131.0)  # (a writeable copy: unwrapped)
    assert np.array_equal(fresh, pol)
    rows = ring_rows(pol, 40.0)
    assert ring_rows(again, 40.0) is rows
    _same(rows, _fresh(pol, 40.0))
    # handed out read-only: no step can change what the next one is given
    with pytest.raises(ValueError):
        rows.b[0, 0] = True
    with pytest.raises(ValueError):
        rows.short()[0, 0] = True
    rows.rings().clear()  # (the lists are copies)
    _same(rows, _fresh(pol, 40.0))


def test_another_image_threshold_or_point_gets_its_own_rings():
    a, b = _dark(1), _dark(2)
    c = (CENTRE, CENTRE)
    pa, _ = scale_mod.polar(a, c, 60.0, 131.0)
    pb, _ = scale_mod.polar(b, c, 60.0, 131.0)
    pc, _ = scale_mod.polar(a, (CENTRE + 2.0, CENTRE), 60.0, 131.0)
    ra = ring_rows(pa, 40.0)
    for pol, thr in ((pb, 40.0), (pa, 90.0), (pc, 40.0)):
        got = ring_rows(pol, thr)
        assert got is not ra
        _same(got, _fresh(pol, thr))
    assert not np.array_equal(ring_rows(pb, 40.0).b, ra.b)
    # a writeable unwrap may change: it is never kept
    w = pa.copy()
    assert ring_rows(w, 40.0) is not ring_rows(w, 40.0)


def _reading(r):
    return (r.value, r.confidence, r.error, r.method, r.error_bound_fs)


def test_two_images_read_in_turn_each_get_their_own_reading():
    """The kept unwraps and rings of one reading are never another image's: read in turn,
    again in the other order, and each afresh (everything kept dropped first), every image
    gives the same reading."""
    cases = []  # (read by the profile's angles, which unwrap about the crop's centre)
    for family, seed, level in (("nordic", 2, "clean"), ("plant", 3, "clean"),
                                ("marine", 3, "clean"), ("process", 4, "clean")):
        img, truth = render_sample(family, level, np.random.default_rng(seed))
        cases.append((img, load_profile(truth["profile"])))
    first = [_reading(read_gauge(img, prof)) for img, prof in cases]
    backwards = [_reading(read_gauge(img, prof)) for img, prof in cases[::-1]][::-1]
    alone = []
    for img, prof in cases:
        scale_mod._MEMO.clear()
        arc_fit._ROWS_MEMO.clear()
        alone.append(_reading(read_gauge(img, prof)))
    assert first == backwards == alone
    assert all(r[3] == "profile-angles" and r[0] is not None for r in first)


def _dark_face():
    for seed in range(40):
        img, truth = render_sample("dark", "clean", np.random.default_rng(seed))
        grey = cv2.resize(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), (300, 300))
        if median_face_grey(grey) < DARK_FACE_GREY:
            return grey, load_profile(truth["profile"])
    raise AssertionError("no dark face drawn")


def test_a_dark_face_negative_is_read_once(monkeypatch):
    crop, prof = _dark_face()
    calls = []

    def counted(img, p):
        calls.append(img)
        return read_normalised(img, p)

    monkeypatch.setattr(pivot_checks, "read_normalised", counted)
    neg = pivot_checks.negative_pass(crop, prof)
    assert not calls  # made on first use ...
    got = neg()
    assert neg() is got and len(calls) == 1  # ... and once
    assert np.array_equal(calls[0], cv2.bitwise_not(crop))
    res = read_normalised(crop, prof)
    c = (CENTRE + 4.0, CENTRE - 3.0)
    # the second look's check with the negative already read reads no other, and answers
    # as it does reading the negative itself
    with_neg = pivot_checks.second_look_allowed(res, crop, prof, c, 135.0, neg)
    assert len(calls) == 1
    alone = pivot_checks.second_look_allowed(res, crop, prof, c, 135.0)
    assert len(calls) == 2 and with_neg == alone
