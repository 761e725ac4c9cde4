"""The held-out ``foundry`` gauge family: its own renderer, deterministic, and its truth
matches what it draws."""

import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.meter import load_profile
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_foundry import FOUNDRY, FOUNDRY_RED
from sim_robot.gauge_foundry_type import Ink, text_width, typeset
from sim_robot.gauge_scene import LEVELS, Look, Pose, compose, render_sample
from sim_robot.gauge_styles import random_style, random_value

from .gauge_marks import assert_end_marks_on_ink


def _styles(n, seed=0):
    rng = np.random.default_rng(seed)
    return [random_style(FOUNDRY, rng) for _ in range(n)]


def _wrap(a):
    return (a + 180.0) % 360.0 - 180.0


@pytest.mark.parametrize("level", LEVELS)
def test_the_same_seed_gives_the_same_bytes(level):
    for seed in (1, 2, 3):
        a, ta = render_sample(FOUNDRY, level, np.random.default_rng(seed))
        b, tb = render_sample(FOUNDRY, level, np.random.default_rng(seed))
        assert a.tobytes() == b.tobytes() and ta == tb
    c, _ = render_sample(FOUNDRY, level, np.random.default_rng(4))
    assert c.tobytes() != a.tobytes()


def test_a_dial_does_not_depend_on_what_was_drawn_before_it():
    st1, st2 = _styles(2, seed=9)
    first, _ = draw_dial(st1, st1.min_value, 240)
    draw_dial(st2, st2.max_value, 240)
    again, _ = draw_dial(st1, st1.min_value, 240)
    assert first.tobytes() == again.tobytes()


def test_styles_have_what_real_plant_gauges_have():
    styles = _styles(300)
    spans = np.array([abs(s.max_angle_deg - s.min_angle_deg) for s in styles])
    assert 0.3 < np.mean(spans == 270) < 0.6
    assert np.mean((spans >= 240) & (spans <= 300)) > 0.7
    assert 0.05 < np.mean(spans < 100) < 0.25  # quarter-turn scales
    vacuum = [s for s in styles if s.max_value <= 0]
    assert vacuum and all(s.direction < 0 and s.rest_at_max for s in vacuum)
    assert any(s.direction < 0 for s in styles if s.max_value > 0)  # some ccw pressure dials
    assert {s.needle_shape for s in styles} == {"lancet", "lozenge", "spear"}
    assert {s.fill for s in styles} == {"dry", "glycerine"}
    assert any(s.second_scale for s in styles) and any(s.unit == "kgf/cm2" for s in styles)
    for s in styles:
        p = s.profile()
        load_profile(p)
        assert (p.get("needle") == "two-ended") == (s.needle_shape in ("lancet", "lozenge"))
        assert (p.get("ignore_colour") == "red") == (s.setpoint is not None)
        assert 0 < s.label_every and round((s.max_value - s.min_value) / s.major_step) % (
            s.label_every) == 0  # both ends of the scale carry numerals


GREEN = (0, 255, 0)  # a needle colour no foundry dial prints: its pixels are the needle's


def _needle_angle_seen(img, st, truth):
    """The needle's direction from its own pixels between its hub and 0.8 of its length,
    on a dial drawn with a green needle (the glass may lighten them: green by hue)."""
    c = np.array(truth["pivot_xy"])
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    r = np.hypot(xx - c[0], yy - c[1])
    b, g, rd = (img[..., k].astype(int) for k in range(3))
    green = g - np.maximum(b, rd) > 80
    beyond_hub = 1.6 * st.hub_radius * img.shape[0]
    ys, xs = np.nonzero(green & (r > beyond_hub) & (r < 0.8 * truth["needle_len_px"]))
    assert len(xs) > 20
    vx, vy = (xs - c[0]).sum(), (ys - c[1]).sum()
    return math.degrees(math.atan2(vx, -vy))


def test_the_needle_is_drawn_at_the_value_and_ccw_scales_rise_anticlockwise():
    seen = {1: 0, -1: 0}
    for st in _styles(40, seed=3):
        st = replace(st, setpoint=None, stop_pin=False, needle_bgr=GREEN)
        fs = st.max_value - st.min_value
        angles = []
        for f in (0.25, 0.75):
            img, t = draw_dial(st, st.min_value + f * fs, 300)
            want = st.angle_of(st.min_value + f * fs)
            assert t["needle_angle_deg"] == pytest.approx(want)
            got = _needle_angle_seen(img, st, t)
            assert _wrap(got - want) == pytest.approx(0, abs=2.5), (st.name, st.needle_shape)
            angles.append(got)
        assert np.sign(_wrap(angles[1] - angles[0])) == st.direction
        seen[st.direction] += 1
    assert seen[1] and seen[-1]


def test_a_needle_at_rest_touches_the_stop_pin_beside_the_zero_mark():
    styles = [s for s in _styles(80, seed=4) if s.stop_pin]
    for rest_at_max in (False, True):
        st = replace(next(s for s in styles if s.rest_at_max == rest_at_max), setpoint=None,
                     needle_bgr=GREEN)
        v = st.rest_value
        img, t = draw_dial(st, v, 300)
        assert t["value"] == v == (st.max_value if rest_at_max else st.min_value)
        end = st.max_angle_deg if rest_at_max else st.min_angle_deg
        # beyond the scale's end, between the end mark and the pin
        beyond = _wrap(t["needle_angle_deg"] - end) * (st.direction if rest_at_max
                                                      else -st.direction)
        assert 0 < beyond < st.pin_offset_deg
        pin = _wrap(st.pin_angle_deg - t["needle_angle_deg"])
        # the pin's radius plus the needle's half-width seen from the pivot: a few degrees
        assert 1.0 < abs(pin) < 5.0
        assert abs(_wrap(_needle_angle_seen(img, st, t) - t["needle_angle_deg"])) < 1.5


def test_end_marks_lie_on_printed_ticks_at_the_ends_of_the_span():
    checked = 0
    for st in _styles(30, seed=6):
        st = replace(st, setpoint=None)
        v = 0.5 * (st.min_value + st.max_value)
        img, t = draw_dial(st, v, 300)
        c = np.array(t["pivot_xy"])
        for key, ang in (("min_mark_xy", st.min_angle_deg), ("max_mark_xy", st.max_angle_deg)):
            xy = np.array(t[key])
            got = math.degrees(math.atan2(xy[0] - c[0], -(xy[1] - c[1])))
            assert _wrap(got - ang) == pytest.approx(0, abs=1e-6)
            r_in, r_out = st.tick_span()
            assert r_in * 300 < np.hypot(*(xy - c)) < r_out * 300
            if abs(_wrap(t["needle_angle_deg"] - ang)) < 8:
                continue  # hidden under the needle
            # printed ink there: darker than the face round it (which glare may lighten)
            x, y = (int(round(q)) for q in xy)
            grey = img.astype(float).mean(axis=2)
            mark = grey[y - 1:y + 2, x - 1:x + 2].min()
            assert mark < np.median(grey[y - 6:y + 7, x - 6:x + 7]) - 40, (st.name, key)
            checked += 1
    assert checked > 40


def test_end_marks_in_a_tilted_distorted_frame_land_on_the_ink():
    checked = 0
    for i, st in enumerate(_styles(8, seed=7)):
        rng = np.random.default_rng(i)
        st = replace(st, setpoint=None, zones=())
        v = st.min_value + 0.5 * (st.max_value - st.min_value)
        img, t = compose(st, v, rng, frame_size=(640, 480),
                         pose=Pose(fill=0.75, tilt_deg=30, tilt_axis_deg=30, roll_deg=8),
                         look=Look(lens_k=0.08), backdrop="skid")
        checked += assert_end_marks_on_ink(img, t, st.ink_bgr, i)
    assert checked == 16


def test_a_dual_scale_dial_prints_its_second_scale_in_red_inside_the_main_one():
    st = replace(next(s for s in _styles(60, seed=8) if s.second_scale), setpoint=None,
                 zones=(), needle_bgr=(16, 15, 14))
    img, t = draw_dial(st, st.min_value, 300)
    plain, _ = draw_dial(replace(st, second_scale=None, second_unit=""), st.min_value, 300)
    red = np.linalg.norm(img.astype(float) - np.array(FOUNDRY_RED, float), axis=2) < 80
    assert not (np.linalg.norm(plain.astype(float) - np.array(FOUNDRY_RED, float), axis=2)
                < 80).any()
    ys, xs = np.nonzero(red)
    r = np.hypot(xs - 150, ys - 150)
    assert len(r) > 200 and np.percentile(r, 95) < st.tick_span()[0] * 300  # inside the ticks
    # the truth is the main scale's: the same with or without the second scale
    assert t == draw_dial(replace(st, second_scale=None), st.min_value, 300)[1]


def test_the_drag_pointer_is_red_at_its_value():
    st = next(s for s in _styles(60, seed=5) if s.setpoint is not None)
    img, t = draw_dial(st, st.min_value + 0.5 * (st.max_value - st.min_value), 300)
    a = math.radians(st.angle_of(st.setpoint))
    dist = []
    for r in np.linspace(0.5, 0.85, 8) * t["needle_len_px"]:
        x, y = 150 + r * math.sin(a), 150 - r * math.cos(a)
        patch = img[int(round(y)) - 1:int(round(y)) + 2, int(round(x)) - 1:int(round(x)) + 2]
        dist.append(np.linalg.norm(patch.reshape(-1, 3) - FOUNDRY_RED, axis=1).min())
    assert np.median(dist) < 70


def test_glycerine_fill_shows_a_meniscus_near_the_top_only():
    st = replace(_styles(1, seed=10)[0], fill="dry", setpoint=None)
    dry, _ = draw_dial(st, st.min_value, 300)
    wet, _ = draw_dial(replace(st, fill="glycerine"), st.min_value, 300)
    diff = np.abs(wet.astype(int) - dry.astype(int)).max(axis=2)
    rows = diff[:, 120:180].mean(axis=1)  # a band down the middle of the face
    top = int(np.argmax(rows[:150]))
    assert 150 - st.face_radius * 300 < top < 150 - 0.7 * st.face_radius * 300
    assert rows[top] > 3 * np.median(rows[top + 20:250])


def test_the_typeface_prints_as_wide_as_it_says():
    ink = Ink(400, (0, 0, 0))
    typeset(ink, "160", 200, 200, 40.0, 0.13)
    ys, xs = np.nonzero(ink.mask > 128)
    pen = 0.13 * 40
    assert np.ptp(xs) == pytest.approx(text_width("160", 40.0) - 0.2 * 40 + pen, abs=6)
    assert np.ptp(ys) == pytest.approx(40 + 0.7 * pen, abs=4)
    turned = Ink(400, (0, 0, 0))
    typeset(turned, "160", 200, 200, 40.0, 0.13, angle_deg=90)
    ys, xs = np.nonzero(turned.mask > 128)
    assert np.ptp(ys) == pytest.approx(text_width("160", 40.0) - 0.2 * 40 + pen, abs=6)


def test_random_value_rests_on_the_pin_at_the_zero_end():
    rng = np.random.default_rng(12)
    pinned = [s for s in _styles(120, seed=11) if s.stop_pin]
    vals = [(s, random_value(s, rng)) for s in pinned for _ in range(4)]
    rest = np.mean([v == s.rest_value for s, v in vals])
    assert 0.25 < rest < 0.5
    assert any(s.rest_at_max and v == 0.0 for s, v in vals)
