"""A second needle-like line about a calibrated pivot (app.core.meter.rivals): a set-point
flag or pointer, a glare streak.  Dials of the tuning families rendered upright, with what
they lack drawn on them with OpenCV; the reader takes the line the calibration tells is the
needle, and refuses when nothing tells."""

import math
from dataclasses import replace

import cv2
import numpy as np
import pytest

from app.core.meter import make_calibrated_profile, read_gauge
from app.core.meter.rivals import candidate_angles
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import random_style

RED = (40, 40, 210)
BLACK = (25, 25, 25)


def _style(family="process", seed=2, **kw):
    st = random_style(family, np.random.default_rng(seed))
    return replace(st, setpoint=None, stop_pin=False, **kw)


def _frac_angle(st, frac):
    return st.min_angle_deg + frac * (st.max_angle_deg - st.min_angle_deg)


def _line(img, c, angle, r0, r1, width, colour):
    t = math.radians(angle)
    p = [(int(round((c[0] + r * math.sin(t)) * 16)), int(round((c[1] - r * math.cos(t)) * 16)))
         for r in (r0, r1)]
    cv2.line(img, p[0], p[1], colour, max(1, int(round(width))), cv2.LINE_AA, 4)


def _flag(img, c, angle, length, colour):
    """A set-point flag: a thin stem from the hub and a triangular flag near its end."""
    _line(img, c, angle, 0.0, length, 2, colour)
    t = math.radians(angle)
    u, n = np.array([math.sin(t), -math.cos(t)]), np.array([math.cos(t), math.sin(t)])
    base = np.array(c, float)
    tri = [base + 0.72 * length * u, base + 0.95 * length * u, base + 0.8 * length * u + 9 * n]
    cv2.fillPoly(img, [np.round(np.array(tri) * 16).astype(np.int32)], colour, cv2.LINE_AA, 4)


def _profile(st, truth, **kw):
    base = {k: v for k, v in st.profile().items() if k not in ("min_angle_deg",
                                                               "max_angle_deg")}
    base.update(kw)
    return make_calibrated_profile(base, truth["pivot_xy"], truth["min_mark_xy"],
                                   truth["max_mark_xy"], clockwise=st.direction > 0)


def _fs(st):
    return st.max_value - st.min_value


@pytest.mark.parametrize("frac, flag_frac", [(0.62, 0.3), (0.2, 0.3), (0.85, 0.55)])
def test_a_red_set_point_flag_is_not_the_needle(frac, flag_frac):
    st = _style(needle_shape="two-ended", needle_bgr=BLACK)
    v = st.min_value + frac * _fs(st)
    img, t = draw_dial(st, v, size=300)
    R = math.dist(t["pivot_xy"], t["min_mark_xy"])
    _flag(img, t["pivot_xy"], _frac_angle(st, flag_frac), 0.95 * R, RED)
    r = read_gauge(img, _profile(st, t, ignore_colour="red"))
    assert r.value == pytest.approx(v, abs=0.005 * _fs(st)), r.error


@pytest.mark.parametrize("frac, other", [(0.7, 0.35), (0.15, 0.5)])
def test_a_two_ended_needle_is_told_from_a_pointer_without_a_counterweight(frac, other):
    st = _style(needle_shape="two-ended", needle_bgr=BLACK)
    v = st.min_value + frac * _fs(st)
    img, t = draw_dial(st, v, size=300)
    R = math.dist(t["pivot_xy"], t["min_mark_xy"])
    # a second black pointer of the needle's length and width, no counterweight
    _line(img, t["pivot_xy"], _frac_angle(st, other), 0.0, 0.95 * R, 4, BLACK)
    assert len(candidate_angles(img, t["pivot_xy"], R)) >= 2
    r = read_gauge(img, _profile(st, t))
    assert r.value == pytest.approx(v, abs=0.005 * _fs(st)), r.error
    # a single-ended needle beside it: nothing tells them apart, a refusal
    st1 = replace(st, needle_shape="thin")
    img1, t1 = draw_dial(st1, v, size=300)
    _line(img1, t1["pivot_xy"], _frac_angle(st1, other), 0.0, 0.95 * R, 4, BLACK)
    r = read_gauge(img1, _profile(st1, t1))
    assert r.value is None or abs(r.value - v) <= 0.005 * _fs(st1)


@pytest.mark.parametrize("frac", [0.3, 0.75])
def test_a_glare_streak_beside_the_pivot_is_not_the_needle(frac):
    st = _style("dark", seed=3)
    v = st.min_value + frac * _fs(st)
    img, t = draw_dial(st, v, size=300)
    R = math.dist(t["pivot_xy"], t["min_mark_xy"])
    # a bright streak across the face that passes 0.12 R from the pivot
    a = _frac_angle(st, 1.0 - frac) + 10.0
    tt = math.radians(a)
    off = 0.12 * R * np.array([math.cos(tt), math.sin(tt)])
    c = np.array(t["pivot_xy"]) + off
    u = np.array([math.sin(tt), -math.cos(tt)])
    p0, p1 = c - 1.2 * R * u, c + 1.2 * R * u
    streak = img.copy()
    cv2.line(streak, tuple(np.round(p0).astype(int)), tuple(np.round(p1).astype(int)),
             (245, 245, 245), 5, cv2.LINE_AA)
    img = cv2.addWeighted(img, 0.3, streak, 0.7, 0)
    r = read_gauge(img, _profile(st, t))
    assert r.value is None or abs(r.value - v) <= 0.005 * _fs(st)
    assert r.value is not None, r.error


def _warp(img, angle_deg, scale, tx, ty):
    h, w = img.shape[:2]
    m = cv2.getRotationMatrix2D((w / 2, h / 2), angle_deg, scale)
    m[:, 2] += (tx, ty)
    return cv2.warpAffine(img, m, (w, h), borderMode=cv2.BORDER_REPLICATE), m


def _scene(st, v, setpoint_frac, R=None):
    """The dial on a textured wall, 420 x 420, with a black set-point pointer (no tail)."""
    dial, t = draw_dial(st, v, size=300)
    R = R or math.dist(t["pivot_xy"], t["min_mark_xy"])
    _line(dial, t["pivot_xy"], _frac_angle(st, setpoint_frac), 0.0, 0.9 * R, 3, BLACK)
    wall = np.random.default_rng(0).integers(60, 200, (420, 420, 3)).astype(np.uint8)
    wall = cv2.GaussianBlur(wall, (7, 7), 0)
    wall[60:360, 60:360] = dial
    shift = {k: (t[k][0] + 60, t[k][1] + 60) for k in ("pivot_xy", "min_mark_xy", "max_mark_xy")}
    return wall, shift


@pytest.mark.parametrize("frac_ref, frac, setpoint", [(0.3, 0.7, 0.5), (0.8, 0.25, 0.6)])
def test_a_pointer_that_has_not_moved_since_the_reference_is_the_set_point(tmp_path, frac_ref,
                                                                           frac, setpoint):
    st = _style(needle_shape="thin", needle_bgr=BLACK)
    fs = _fs(st)
    ref, t = _scene(st, st.min_value + frac_ref * fs, setpoint)
    (tmp_path / "ref").mkdir()
    cv2.imwrite(str(tmp_path / "ref" / "p.png"), ref)
    base = {k: w for k, w in st.profile().items() if k not in ("min_angle_deg",
                                                               "max_angle_deg")}
    prof = make_calibrated_profile(base, t["pivot_xy"], t["min_mark_xy"], t["max_mark_xy"],
                                   image="ref/p.png", clockwise=st.direction > 0)
    path = tmp_path / "p.json"
    import json
    path.write_text(json.dumps(prof))
    v = st.min_value + frac * fs
    live, _ = _scene(st, v, setpoint)
    live, _ = _warp(live, 3.0, 1.04, 6, -5)
    r = read_gauge(live, str(path))
    assert r.value == pytest.approx(v, abs=0.005 * fs), r.error
    # the needle where it was in the reference: both lines are where they were, and
    # nothing tells which is the needle; never a wrong reading
    same, _ = _scene(st, st.min_value + frac_ref * fs, setpoint)
    r = read_gauge(_warp(same, -2.0, 0.97, -4, 3)[0], str(path))
    assert r.value is None or abs(r.value - (st.min_value + frac_ref * fs)) <= 0.005 * fs


@pytest.mark.parametrize("frac", [0.2, 0.8])
def test_a_line_pointing_into_the_gap_below_the_scale_is_not_the_needle(frac):
    # a bolder line than the needle (a bracket, a crack in the glass) from the hub into the
    # gap between the scale's ends; the needle points at the scale
    st = _style(needle_shape="thin", needle_bgr=BLACK)
    v = st.min_value + frac * _fs(st)
    img, t = draw_dial(st, v, size=300)
    R = math.dist(t["pivot_xy"], t["min_mark_xy"])
    gap = 0.5 * (st.min_angle_deg + st.max_angle_deg) + 180.0
    _line(img, t["pivot_xy"], gap, 0.0, 0.9 * R, 7, BLACK)
    r = read_gauge(img, _profile(st, t))
    assert r.value == pytest.approx(v, abs=0.005 * _fs(st)), r.error


@pytest.mark.parametrize("family, frac, setpoint", [("plant", 0.3, 0.6), ("plant", 0.0, 0.5),
                                                    ("plant", 0.3, 0.4), ("nordic", 0.3, 0.6)])
def test_a_red_needle_is_told_from_a_red_set_point_on_its_disc_by_its_counterweight(
        family, frac, setpoint):
    """A vermilion two-ended needle over a red set-point pointer (turning on a red disc
    under the hub) with "ignore red": both lines are red; only the needle's counterweight
    reaches beyond the hub, the set-point's disc reaches as far every way."""
    st = _style(family, seed=2, needle_shape="two-ended", needle_bgr=(12, 64, 244),
                hub_bgr=(128, 132, 140))
    st = replace(st, setpoint=st.min_value + setpoint * _fs(st), tail_len=0.12)
    v = st.min_value + frac * _fs(st)
    img, t = draw_dial(st, v, size=300)
    r = read_gauge(img, _profile(st, t, ignore_colour="red", needle="two-ended"))
    assert r.value == pytest.approx(v, abs=0.005 * _fs(st)), r.error


def _stored_read(name):
    from tests.meter.stored_frames import stored_stress

    img, truth, prof = stored_stress(name)
    return read_gauge(img, prof), truth, prof


def test_the_fringe_of_a_pointer_of_the_colour_to_ignore_is_not_the_needle():
    """bench/meter_cal_stress.py --families atlas, case setpoint, seed 3, #148: the profile
    says red is not the needle; with the red pointer masked, the line left along its dark
    fringe agreed with the red pointer's line and was read as the needle (0.38 for 0.44 MPa,
    9 % FS off).  A line of the colour to ignore is no agreement: the needle is chosen among
    the lines, or the reading refused."""
    r, truth, prof = _stored_read("stress-setpoint-atlas-3-148")
    assert prof["ignore_colour"] == "red"
    assert r.value is None or abs(r.value - truth["value"]) <= 0.02 * truth["full_scale"], \
        (r.value, truth["value"], r.scores)


def test_a_needle_resting_on_its_pin_is_not_read_by_its_tail_after_the_other_lines_are_painted():
    """bench/meter_cal_stress.py --families atlas, case rest, seed 4, #233: a two-ended needle
    resting on its pin; the first finding had its tip right but saw a rival, and the needle's
    fit with the other line painted over (the print beside the needle inpainted) found its
    ends the other way round: read 585 kPa for 0 at confidence 0.90.  The first finding's
    line with its ends swapped leaves the tip unsettled: a refusal or the needle's value."""
    r, truth, prof = _stored_read("stress-rest-atlas-4-233")
    assert truth["value"] == prof["min_value"]
    assert r.value is None or abs(r.value - truth["value"]) <= 0.02 * truth["full_scale"], \
        (r.value, truth["value"], r.scores)
