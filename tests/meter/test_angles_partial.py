"""Reading against the profile's angles where the dial's scale is only partly verified: the
confidence follows the error bound the reading states, and that bound carries what was
left unverified."""

import numpy as np
import pytest

from app.core.meter import angles, arc_fit, pointer, read_gauge
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_scene import Look, Pose, compose
from sim_robot.gauge_styles import DialStyle

WRONG_FS = 2.0  # % FS: a returned reading further off than this is a confident wrong one


@pytest.fixture
def no_scale_finder(monkeypatch):
    """The dial's own scale is never found (as on gauges it was not tuned on)."""
    monkeypatch.setattr(pointer, "find_scale", lambda *a, **k: (None, "no tick marks found"))


def _err_fs(r, value, st) -> float:
    return abs(r.value - value) / (st.max_value - st.min_value) * 100


def test_a_narrow_scale_whose_bound_is_over_the_line_is_refused_with_why(no_scale_finder):
    """On a 144 deg scale a degree of the needle is 0.7 % FS: with the dial's own scale
    not found, the verified geometry leaves bounds over the ramp's 0.5 line (0.625 % FS),
    and the reading is refused with the reason, not returned. (A ramp with its 0.5 line at
    1 % FS read these within their bounds on our own styles, but returned confident wrong
    readings on a style family it was not tuned on.)"""
    st = DialStyle(name="plant_0_16bar", min_value=0.0, max_value=16.0,
                   min_angle_deg=-72.0, max_angle_deg=72.0, needle_shape="arrow")
    assert angles.BOUND_GOOD < 0.625 < angles.BOUND_BAD <= 1.0
    for k, value in enumerate((0.6, 3.3, 8.1, 12.7, 15.4)):
        img, _ = compose(st, value, np.random.default_rng(20 + k), frame_size=(320, 320),
                         pose=Pose(fill=0.9, roll_deg=3.0), look=Look(noise_sigma=1.5),
                         backdrop="plain")
        r = read_gauge(img, st.profile(), learned_fallback=False)
        if r.value is not None:  # returned: then it holds a bound under the line
            assert r.error_bound_fs is not None and r.error_bound_fs <= 0.625
            assert _err_fs(r, value, st) <= WRONG_FS
        else:
            assert "profile angles:" in r.error, r.error


def test_a_turn_resting_on_one_end_mark_carries_the_learned_marks_whole_tolerance(
        no_scale_finder, monkeypatch):
    """The needle on an end mark hides it: the turn rests on the other end mark and the
    profile's span, and only the learned end marks check it, within their tolerance.  Here
    they say 1 deg off the true turn (0): the reading's bound must carry their whole
    tolerance (a tuning frame read 2 % FS off where the two turns agreed within 2.2 deg),
    so it is refused on a 270 deg scale rather than read at a bound of 0.65 % FS."""
    monkeypatch.setattr(arc_fit, "comb_turn", lambda *a, **k: None)  # the end marks alone
    asked = []

    def learned_turn(kp, c, prof):
        asked.append(kp is not None)
        return 1.0

    monkeypatch.setattr(angles, "_keypoint_turn", learned_turn)
    st = DialStyle(name="plant_0_10bar", min_angle_deg=-135.0, max_angle_deg=135.0)
    floor = 100.0 * angles.KP_TURN_TOL_DEG / 270.0
    for value in (0.0, 10.0):
        asked.clear()
        img, _ = draw_dial(st, value, 300)
        r = read_gauge(img, st.profile(), learned_confirm=True, learned_fallback=False)
        assert asked and all(asked), "the one-end turn was not put to the learned marks"
        if r.value is None:
            assert "the scale's ends leave the reading uncertain" in r.error, r.error
        else:
            assert r.error_bound_fs >= floor


def test_a_refusal_for_the_bound_keeps_its_candidate_and_bound(no_scale_finder):
    """A reading refused for the bound it states still says what it would have read and
    that bound (``raw_value``, ``error_bound_fs``): what a bench needs to tell an
    over-cautious refusal from a sound one.  On this narrow scale the candidates lie
    within their bounds."""
    st = DialStyle(name="plant_0_16bar", min_value=0.0, max_value=16.0,
                   min_angle_deg=-72.0, max_angle_deg=72.0, needle_shape="arrow")
    refused = 0
    for k, value in enumerate((0.6, 3.3, 8.1, 12.7, 15.4)):
        img, _ = compose(st, value, np.random.default_rng(20 + k), frame_size=(320, 320),
                         pose=Pose(fill=0.9, roll_deg=3.0), look=Look(noise_sigma=1.5),
                         backdrop="plain")
        r = read_gauge(img, st.profile(), learned_fallback=False)
        if r.value is not None or "uncertain" not in r.error:
            continue
        refused += 1
        assert r.raw_value is not None and r.error_bound_fs is not None, r
        assert r.error_bound_fs > 0.625
        assert abs(r.raw_value - value) / 16.0 * 100 <= r.error_bound_fs
    assert refused >= 1
