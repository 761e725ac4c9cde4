"""The ``atlas`` family (held out until it was looked at): what it draws, and its truth."""

import math
from dataclasses import replace

import cv2
import numpy as np
import pytest

from app.core.meter import load_profile
from sim_robot.gauge_atlas import ATLAS, SETPOINT_RED, block_text, block_width
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_scene import Look, Pose, _glare, compose
from sim_robot.gauge_styles import (
    HELD_OUT_CHOICES,
    HELD_OUT_FAMILY,
    TUNING_FAMILIES,
    random_style,
    random_value,
)

from .gauge_marks import assert_end_marks_on_ink


def _styles(n, seed=0):
    rng = np.random.default_rng(seed)
    return [random_style(ATLAS, rng) for _ in range(n)]


def _wrap(a):
    return (a + 180.0) % 360.0 - 180.0


def test_atlas_is_a_former_held_out_family_kept_out_of_tuning():
    assert HELD_OUT_FAMILY != ATLAS and ATLAS in HELD_OUT_CHOICES
    assert ATLAS not in TUNING_FAMILIES


def test_atlas_styles_have_what_real_plant_gauges_have():
    styles = _styles(200)
    spans = np.array([abs(s.max_angle_deg - s.min_angle_deg) for s in styles])
    assert (spans >= 300).mean() > 0.2 and ((spans >= 90) & (spans <= 180)).mean() > 0.2
    assert 0.15 < np.mean([s.direction < 0 for s in styles]) < 0.5  # counter-clockwise
    for s in styles:
        p = s.profile()
        load_profile(p)
        assert p["needle"] == "two-ended"  # every atlas needle has a tail wider than its tip
        assert (p.get("ignore_colour") == "red") == (s.setpoint is not None)
        assert ("normal_min" in p) == bool(s.zones)
        if p["max_angle_deg"] < p["min_angle_deg"]:
            assert s.direction < 0
    assert {s.needle_shape for s in styles} == {"dart", "crescent", "paddle"}
    # the needle rests on its stop pin in about a third of the images of pinned gauges
    rng = np.random.default_rng(1)
    pinned = [s for s in styles if s.stop_pin]
    rest = np.mean([random_value(s, rng) == s.min_value for s in pinned for _ in range(5)])
    assert 0.25 < rest < 0.5


def _needle_angle_seen(img, st, truth, other):
    """The needle's direction from its own pixels beyond its tail, to 0.8 of its length:
    needle-coloured pixels that differ from ``other``, the same dial at another value (a
    needle may have the colour of the ink)."""
    c = np.array(truth["pivot_xy"])
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    r = np.hypot(xx - c[0], yy - c[1])
    near = np.linalg.norm(img.astype(float) - np.array(st.needle_bgr, float), axis=2) < 40
    near &= np.abs(img.astype(int) - other.astype(int)).max(axis=2) > 30
    beyond_tail = 1.1 * max(st.tail_len, 2.5 * st.hub_radius) * img.shape[0]
    sel = near & (r > beyond_tail) & (r < 0.8 * truth["needle_len_px"])
    ys, xs = np.nonzero(sel)
    vx, vy = (xs - c[0]).sum(), (ys - c[1]).sum()
    return math.degrees(math.atan2(vx, -vy))


def test_needle_is_drawn_at_the_value_and_ccw_scales_rise_anticlockwise():
    seen = {1: 0, -1: 0}
    for st in _styles(60, seed=3):
        st = replace(st, setpoint=None, stop_pin=False)
        fs = st.max_value - st.min_value
        angles = []
        drawn = [draw_dial(st, st.min_value + f * fs, 300) for f in (0.3, 0.7)]
        for f, (img, t), (other, _) in zip((0.3, 0.7), drawn, drawn[::-1], strict=True):
            got = _needle_angle_seen(img, st, t, other)
            assert _wrap(got - st.angle_of(st.min_value + f * fs)) == pytest.approx(0, abs=3)
            angles.append(got)
        # a higher value turns the needle clockwise on a clockwise scale, else anticlockwise
        assert np.sign(_wrap(angles[1] - angles[0])) == st.direction
        seen[st.direction] += 1
    assert seen[1] and seen[-1]


def test_a_needle_on_the_stop_pin_lies_between_the_pin_and_the_minimum_mark():
    st = replace(next(s for s in _styles(40, seed=4) if s.stop_pin), setpoint=None)
    img, t = draw_dial(st, st.min_value, 300)
    other, _ = draw_dial(st, st.min_value + 0.5 * (st.max_value - st.min_value), 300)
    assert t["value"] == st.min_value
    below = (st.min_angle_deg - t["needle_angle_deg"]) * st.direction
    assert 0 < below < st.pin_offset_deg
    assert abs(_wrap(_needle_angle_seen(img, st, t, other) - t["needle_angle_deg"])) < 3


def test_set_point_flag_is_red_and_lies_at_its_value():
    st = next(s for s in _styles(60, seed=5) if s.setpoint is not None)
    img, t = draw_dial(st, st.min_value + 0.5 * (st.max_value - st.min_value), 300)
    c = np.array(t["pivot_xy"])
    a = math.radians(st.angle_of(st.setpoint))
    reds = []
    for r in np.linspace(0.4, 0.75, 8) * t["needle_len_px"]:
        x, y = c + r * np.array([math.sin(a), -math.cos(a)])
        patch = img[int(round(y)) - 1:int(round(y)) + 2, int(round(x)) - 1:int(round(x)) + 2]
        reds.append(np.linalg.norm(patch.reshape(-1, 3) - SETPOINT_RED, axis=1).min())
    assert np.median(reds) < 60
    hsv = cv2.cvtColor(np.uint8([[SETPOINT_RED]]), cv2.COLOR_BGR2HSV)[0, 0]
    assert (hsv[0] < 8 or hsv[0] > 172) and hsv[1] > 200  # red by any reading of hue


def test_end_marks_in_a_tilted_distorted_frame_land_on_the_ink():
    checked = 0
    for i, st in enumerate(_styles(8, seed=6)):
        rng = np.random.default_rng(i)
        v = st.min_value + 0.5 * (st.max_value - st.min_value)
        img, t = compose(replace(st, setpoint=None), v, rng, frame_size=(640, 480),
                         pose=Pose(fill=0.75, tilt_deg=20, tilt_axis_deg=30, roll_deg=8),
                         look=Look(lens_k=0.08), backdrop="grating")
        checked += assert_end_marks_on_ink(img, t, st.ink_bgr, i)
    assert checked == 16


def test_a_glare_streak_is_laid_across_the_needle():
    st = replace(_styles(1, seed=7)[0], setpoint=None)
    dial, t = draw_dial(st, st.min_value + 0.6 * (st.max_value - st.min_value), 300)
    out = _glare(dial, Look(streak_on_needle=True), t["needle_angle_deg"],
                 np.random.default_rng(0), t["needle_len_px"])
    lift = out.mean(axis=2) - dial.astype(np.float32).mean(axis=2)
    a = math.radians(t["needle_angle_deg"])
    c = np.array(t["pivot_xy"])
    ray = [c + r * np.array([math.sin(a), -math.cos(a)])
           for r in np.linspace(0.3, 0.8, 40) * t["needle_len_px"]]
    assert max(lift[int(round(y)), int(round(x))] for x, y in ray) > 40  # on the needle
    # ... and the streak runs on across the face on both sides of the needle
    yy, xx = np.mgrid[0:300, 0:300]
    side = (xx - c[0]) * -math.cos(a) - (yy - c[1]) * math.sin(a)
    bright = lift > 40
    assert (bright & (side > 15)).any() and (bright & (side < -15)).any()
    # without it the glass stays clear
    clear = _glare(dial, Look(), t["needle_angle_deg"], np.random.default_rng(0),
                   t["needle_len_px"])
    assert np.array_equal(clear.astype(np.uint8), dial)


@pytest.mark.parametrize("angle", [0.0, 90.0])
def test_block_numerals_are_solid_cells_turned_with_the_text(angle):
    img = np.zeros((200, 200, 3), np.uint8)
    block_text(img, "18", 100, 100, 50.0, (255, 255, 255), angle)
    ink = (img[..., 0] > 128).astype(np.uint8)
    n, _, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=4)
    assert n - 1 == 2  # each glyph one solid blob of cells, no dots, no strokes
    cells = "010110010010111".count("1") + "111101111101111".count("1")
    assert 0.9 < ink.sum() / (cells * 10.0 ** 2) < 1.3  # the cells filled (anti-aliased edge)
    ys, xs = np.nonzero(ink)
    wide, tall = np.ptp(xs) + 1, np.ptp(ys) + 1
    text_w = block_width("18", 50.0)
    if angle == 0:
        assert wide == pytest.approx(text_w, abs=4) and tall == pytest.approx(50, abs=4)
    else:  # turned a quarter: the text's width now runs down the image
        assert tall == pytest.approx(text_w, abs=4) and wide == pytest.approx(50, abs=4)
