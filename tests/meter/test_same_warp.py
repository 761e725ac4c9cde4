"""The perspective pass the angles path retries about the scale ring's pivot is skipped
only where it would warp the input exactly as the crop just read (the same crop, the same
refusal), and runs wherever the pivot is elsewhere."""

import numpy as np
import pytest

import app.core.meter.learned as learned
import app.core.meter.reader as reader
from app.core.meter import load_profile, read_gauge
from app.core.meter.dial import DialEllipse, projective_homography, same_warp
from sim_robot.gauge_scene import render_sample

_ELL = DialEllipse(160.0, 150.0, 260.0, 220.0, 20.0, 0.9)


def test_same_warp_is_one_warp_only():
    h = projective_homography(_ELL, (163.0, 151.0))
    assert same_warp(h, h)
    assert same_warp(h, projective_homography(_ELL, (163.0005, 151.0)))
    for d in ((0.5, 0.0), (0.0, 0.2), (-1.0, 1.0)):
        other = projective_homography(_ELL, (163.0 + d[0], 151.0 + d[1]))
        assert not same_warp(h, other)
    assert not same_warp(h, projective_homography(_ELL, (163.0, 151.0), radius_out=130.0))


def _retries_first(monkeypatch):
    # the second look as it is made where the learned keypoints do not read the crop
    # first (test_learned_before_retries.py): these views are read by them
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", False)


def _read_counting(monkeypatch, img, prof, skip: bool):
    calls = []
    orig = reader.rectify_projective

    def counting(*a, **k):
        calls.append(tuple(float(v) for v in a[2]))
        return orig(*a, **k)

    monkeypatch.setattr(reader, "rectify_projective", counting)
    _retries_first(monkeypatch)
    if not skip:  # the second look always made, as before it could be skipped
        monkeypatch.setattr(reader, "same_warp", lambda a, b: False)
    r = read_gauge(img, prof)
    monkeypatch.undo()
    return r, calls


def _same_warp_answers(monkeypatch, family, seed):
    """A field view of ``family`` and its profile, read once, with what
    ``same_warp`` answered on the way."""
    img, truth = render_sample(family, "field", np.random.default_rng(seed))
    prof = load_profile(truth["profile"])
    seen = []
    orig_same = reader.same_warp

    def spy(a, b):
        seen.append(orig_same(a, b))
        return seen[-1]

    monkeypatch.setattr(reader, "same_warp", spy)
    _retries_first(monkeypatch)
    read_gauge(img, prof)
    monkeypatch.undo()
    return img, prof, seen


@pytest.mark.parametrize("family, seed", [("heritage", 25), ("heritage", 4)])
def test_second_look_skipped_where_it_repeats_the_crop(monkeypatch, family, seed):
    # field views whose angles path refuses on a crop already rectified about the very
    # pivot the scale ring then gives: the second look would read that crop again.
    # (``colour`` seed 20 was one; its second look is now made about the pivot on the
    # needle's line, where it reads: test_span_pivot.py)
    img, prof, seen = _same_warp_answers(monkeypatch, family, seed)
    assert True in seen  # the skip's condition holds here
    new, new_calls = _read_counting(monkeypatch, img, prof, skip=True)
    old, old_calls = _read_counting(monkeypatch, img, prof, skip=False)
    assert len(old_calls) == len(new_calls) + seen.count(True)
    assert (new.value, new.confidence, new.error) == (old.value, old.confidence, old.error)


@pytest.mark.parametrize("family, seed", [("plant", 2), ("colour", 10)])
def test_second_look_made_where_the_pivot_differs(monkeypatch, family, seed):
    # field views whose angles path refuses and retries about a pivot other than the one
    # their crop was made about: the second look runs as before.  (``colour`` seed 1 made
    # its second look only when the full search's rim read the fast path's view again,
    # which is no longer done: test_same_view.py)
    img, prof, seen = _same_warp_answers(monkeypatch, family, seed)
    assert seen and True not in seen
    new, new_calls = _read_counting(monkeypatch, img, prof, skip=True)
    old, old_calls = _read_counting(monkeypatch, img, prof, skip=False)
    assert new_calls == old_calls and len(new_calls) >= len(seen)
    assert (new.value, new.confidence, new.error) == (old.value, old.confidence, old.error)
