"""Calibrated inspection points: the calibration schema and reading through the three
clicks (two-ended needles, arrow tails, the stop pin, anticlockwise scales, a set-point
pointer, glare, text), without a reference frame (the points are in image coordinates)."""

import json
import math

import cv2
import numpy as np
import pytest
from gauge_draw import (
    C,
    add_glare,
    base_profile,
    calibration,
    draw_face,
    draw_needle,
    end_mark,
)

from app.core.meter import (
    Calibration,
    load_profile,
    make_calibrated_profile,
    read_gauge,
    save_profile,
)
from sim_robot.gauge_render import STOCK_SPECS, render_dial, render_view

A_MIN, SPAN = -135.0, 270.0  # the drawn dial: 0..80 kPa clockwise over 270 deg


def _angle(v, a_min=A_MIN, span=SPAN, cw=True, vmax=80.0):
    return a_min + (1 if cw else -1) * span * v / vmax


def _profile(a_min=A_MIN, span=SPAN, cw=True, **kw):
    a_max = a_min + (span if cw else -span)
    return load_profile(base_profile(calibration=calibration(a_min, a_max, cw), **kw))


# ------------------------------------------------------------------ schema and validation

def test_calibrated_profile_loads_without_angles_and_round_trips(tmp_path):
    (tmp_path / "ref").mkdir()
    cv2.imwrite(str(tmp_path / "ref" / "pg.png"), draw_face(A_MIN, SPAN))
    d = base_profile(normal_max=60.0, needle="two-ended", ignore_colour="red",
                     calibration=calibration(A_MIN, 135.0, image="ref/pg.png"))
    p = load_profile(d, base_dir=tmp_path)
    cal = p.calibration
    assert isinstance(cal, Calibration) and cal.clockwise
    assert cal.image_path == (tmp_path / "ref" / "pg.png").resolve()
    assert cal.center == (C, C) and cal.radius_px == pytest.approx(120.0)
    assert p.needle == "two-ended" and p.ignore_colour == "red"
    assert p.span_deg == pytest.approx(270.0)
    out = p.to_dict()
    assert out["calibration"]["image"] == "ref/pg.png"  # written as given
    assert "min_angle_deg" not in out
    assert load_profile(out, base_dir=tmp_path) == p
    # a profile file resolves the image relative to itself, wherever the process runs
    path = save_profile(p, tmp_path / "pg.json")
    assert load_profile(path).calibration.image_path == cal.image_path
    # existing profiles keep their form
    stock = load_profile(STOCK_SPECS[1].profile())
    assert stock.calibration is None and stock.needle == "single"
    assert "calibration" not in stock.to_dict() and "needle" not in stock.to_dict()


def test_make_calibrated_profile_drops_the_base_angles():
    base = dict(STOCK_SPECS[1].profile())  # with -135/135 angles
    d = make_calibrated_profile(base, (100, 100), (40, 160), (160, 160), clockwise=False,
                                image="ref/a.png")
    assert "min_angle_deg" not in d and d["calibration"]["clockwise"] is False
    assert d["calibration"]["image"] == "ref/a.png" and d["normal_max"] == 1.2
    p = load_profile(d, check_image=False)
    assert p.max_angle_deg < p.min_angle_deg  # anticlockwise: 90 deg from 7:30 to 4:30
    assert p.span_deg == pytest.approx(90.0)
    with pytest.raises(ValueError, match="center"):
        make_calibrated_profile(base, ("a", 1), (40, 160), (160, 160))


_CAL = {"center": [100, 100], "min_point": [40, 160], "max_point": [160, 160]}


@pytest.mark.parametrize("change, msg", [
    ({"center": [100]}, "'center' must be \\[x, y\\]"),
    ({"min_point": [100, 103]}, "at least 8 px"),
    ({"max_point": [40, 161]}, "coincide"),
    ({"max_point": [400, 400]}, "very different distances"),
    ({"clockwise": "yes"}, "'clockwise' must be true or false"),
    ({"colour": 1}, "unknown calibration field"),
    ({"image": ""}, "'image' must be"),
    ({"image": "nowhere/ref.png"}, "nowhere/ref.png: no such file"),
])
def test_bad_calibrations_raise_clear_errors(change, msg, tmp_path):
    d = base_profile(calibration={**_CAL, **change})
    with pytest.raises(ValueError, match=msg):
        load_profile(d, base_dir=tmp_path)


def test_profile_level_calibration_errors(tmp_path):
    with pytest.raises(ValueError, match="contradicts"):
        load_profile(base_profile(min_angle_deg=-135, max_angle_deg=135,
                                  calibration={**_CAL, "clockwise": False}))
    with pytest.raises(ValueError, match="'needle' must be one of"):
        load_profile(base_profile(calibration=_CAL, needle="double"))
    with pytest.raises(ValueError, match="'ignore_colour' must be one of"):
        load_profile(base_profile(calibration=_CAL, ignore_colour="purple"))
    with pytest.raises(ValueError, match="'calibration' must be an object"):
        load_profile(base_profile(calibration=[1, 2]))
    bad = tmp_path / "ref.png"
    bad.write_text("not a png")
    with pytest.raises(ValueError, match="ref.png: not a readable image"):
        load_profile(base_profile(calibration={**_CAL, "image": "ref.png"}), base_dir=tmp_path)
    # angles given: their order gives the direction
    p = load_profile(base_profile(min_angle_deg=135, max_angle_deg=-135, calibration=_CAL))
    assert p.calibration.clockwise is False


# ------------------------------------------------------------------ reading

def _read(img, prof):
    r = read_gauge(img, prof)
    assert r.method == "calibrated" and r.homography is None
    return r


@pytest.mark.parametrize("v", [3.0, 21.0, 40.0, 57.5, 77.0])
def test_plain_needle_reads_and_carries_geometry(v):
    img = draw_needle(draw_face(A_MIN, SPAN), _angle(v))
    r = _read(img, _profile())
    assert r.value == pytest.approx(v, abs=0.004 * 80), r.error
    # the pivot and end marks, refined on the image, stay where they were clicked exactly
    assert r.confidence >= 0.5 and r.dial_centre_xy == pytest.approx((C, C), abs=0.5)
    assert r.scale_ends_xy[0] == pytest.approx(end_mark(A_MIN), abs=0.5)
    # the tip: along the needle, at its end (or on a tick mark the needle points at)
    tx, ty = r.pointer_tip_xy
    assert 106 <= math.dist((tx, ty), (C, C)) <= 128
    assert math.degrees(math.atan2(tx - C, C - ty)) == pytest.approx(_angle(v), abs=1.0)
    assert r.angle_deg == pytest.approx(_angle(v), abs=1.0)


def test_click_noise_of_three_pixels_stays_within_one_percent():
    rng = np.random.default_rng(11)
    errs = []
    for _ in range(24):
        v = float(rng.uniform(0, 80))
        img = draw_needle(draw_face(A_MIN, SPAN), _angle(v))
        pts = [np.array(p) + rng.uniform(-3, 3, 2)
               for p in ((C, C), end_mark(A_MIN), end_mark(A_MIN + SPAN))]
        d = make_calibrated_profile(base_profile(), *pts)
        r = read_gauge(img, d)
        assert r.value is not None, r.error
        errs.append(abs(r.value - v) / 80)
    assert max(errs) < 0.012 and np.mean(errs) < 0.005


@pytest.mark.parametrize("v", [12.0, 50.0, 66.0])
def test_two_ended_needle_reads_its_long_thin_end(v):
    # the tail is 80 % of the tip's length and wider: it lies on the scale too
    img = draw_needle(draw_face(A_MIN, SPAN), _angle(v), style="two-ended", tail=90,
                      tail_width=9)
    r = _read(img, _profile(needle="two-ended"))
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error


@pytest.mark.parametrize("v", [10.0, 20.0, 70.0])
def test_a_faded_tip_opposite_a_weight_and_print_is_no_confident_tail(v):
    # a thin tip that fades out at 0.45 R (a low-contrast zone of the face) opposite a short
    # wide weight with a column of numerals beyond it: the weight and the print make the
    # longer end, but it is the wider one and has gaps along it.  Never the tail's reading
    a = _angle(v)
    face = draw_face(A_MIN, SPAN, text=False)
    img = draw_needle(face.copy(), a, style="two-ended", tail=34, tail_width=16, width=4.0)
    dx, dy = math.sin(math.radians(a)), -math.cos(math.radians(a))
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    far = (xx - C) * dx + (yy - C) * dy > 0.45 * 120
    img[far] = (0.03 * img[far] + 0.97 * face[far]).astype(np.uint8)
    for r in (52, 67, 82, 97):
        cv2.putText(img, "8", (int(C - dx * r - 6), int(C - dy * r + 7)),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.8, (30, 30, 30), 3, cv2.LINE_AA)
    r = _read(img, _profile(needle="two-ended"))
    assert r.value is None or r.value == pytest.approx(v, abs=0.01 * 80), (r.value, r.scores)


@pytest.mark.parametrize("v", [8.0, 44.0, 70.0])
def test_arrow_tail_is_not_the_tip(v):
    img = draw_needle(draw_face(A_MIN, SPAN), _angle(v), style="arrow-tail", tail=45,
                      tail_width=26)
    r = _read(img, _profile())
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error


def test_needle_on_the_stop_pin_reads_the_minimum():
    face = draw_face(A_MIN, SPAN)
    below = draw_needle(face.copy(), A_MIN - 3.0)  # resting on the pin below the zero mark
    pin = end_mark(A_MIN - 6, 100)
    cv2.circle(below, (int(pin[0]), int(pin[1])), 4, (80, 80, 80), -1)  # the stop pin
    r = _read(below, _profile())
    assert r.value == 0.0 and r.angle_deg == pytest.approx(A_MIN)
    far = draw_needle(face.copy(), A_MIN - 40.0)  # in the gap below the scale: not a reading
    r = _read(far, _profile())
    assert r.value is None and "outside the scale" in r.error


@pytest.mark.parametrize("angles_form", [False, True])
def test_anticlockwise_scale(angles_form):
    a_min = 135.0  # zero at 4:30, values rise anticlockwise
    face = draw_face(a_min, SPAN, clockwise=False)
    v = 20.0
    img = draw_needle(face, _angle(v, a_min, cw=False))
    if angles_form:  # min_angle_deg > max_angle_deg says anticlockwise, no "clockwise" key
        cal = calibration(a_min, a_min - SPAN)
        del cal["clockwise"]
        prof = load_profile(base_profile(min_angle_deg=135, max_angle_deg=-135, calibration=cal))
    else:
        prof = _profile(a_min, cw=False)
    r = _read(img, prof)
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error


def test_red_set_point_pointer_is_ignored_when_the_profile_says_so():
    v, setpoint = 30.0, 62.0
    img = draw_face(A_MIN, SPAN)
    draw_needle(img, _angle(setpoint), colour=(30, 30, 200), width=5, tail=0, hub=6)
    draw_needle(img, _angle(v))
    r = _read(img, _profile(ignore_colour="red"))
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error
    # without the hint two pointers compete: a refusal, not a guess
    r = _read(img, _profile())
    assert r.value is None and "second pointer" in r.error


def test_glare_across_the_needle():
    v = 52.0
    img = draw_needle(draw_face(A_MIN, SPAN), _angle(v))
    img = add_glare(img, end_mark(_angle(v), 60), 30, 22, 0.7)
    r = _read(img, _profile())
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error


def test_light_needle_on_a_dark_face():
    v = 33.0
    face = draw_face(A_MIN, SPAN, face=(35, 35, 40), ink=(235, 235, 235))
    img = draw_needle(face, _angle(v), colour=(240, 240, 240))
    r = _read(img, _profile())
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error


def test_no_needle_is_a_refusal():
    r = _read(draw_face(A_MIN, SPAN), _profile())
    assert r.value is None and r.error


def test_tick_table_profile_through_a_calibration():
    spec = STOCK_SPECS[0]  # the paper's gauge, Table 1 (non-linear at its ends)
    size = 300
    prof = dict(spec.profile())
    m, n = size / 2, size / 2

    def end(a):
        return [m + 108 * math.sin(math.radians(a)), n - 108 * math.cos(math.radians(a))]

    d = make_calibrated_profile(prof, (m, n), end(spec.angle_of(0.0)), end(spec.angle_of(4.0)))
    p = load_profile(d)
    assert p.ticks and p.calibration
    for v in (0.3, 1.37, 2.56, 3.75):
        r = read_gauge(render_dial(spec, v, size), p)
        assert r.value == pytest.approx(v, abs=0.02), r.error


def test_calibrated_profile_file_through_read_gauge(tmp_path):
    v = 47.0
    img = draw_needle(draw_face(A_MIN, SPAN), _angle(v))
    path = tmp_path / "pg.json"
    path.write_text(json.dumps(base_profile(calibration=calibration(A_MIN, 135.0))))
    r = read_gauge(img, str(path))
    assert r.value == pytest.approx(v, abs=0.004 * 80)


@pytest.mark.parametrize("v, axis", [(2.8, 20.0), (6.3, 70.0)])
def test_oblique_view_is_read_on_the_dial_plane(v, axis):
    spec = STOCK_SPECS[2]  # 0-10 bar, 240 deg, dark bezel
    img, truth = render_view(spec, v, tilt_deg=35.0, tilt_axis_deg=axis, roll_deg=5.0,
                             noise_sigma=1.0, offset_frac=(0.0, 0.0),
                             rng=np.random.default_rng(4))
    h = np.array(truth["homography"])
    size = int(round(0.6 * 480 / 0.98))
    size += size % 2
    c, rad = size / 2, 0.37 * size

    def px(x, y):
        q = h @ np.array([x, y, 1.0])
        return [q[0] / q[2], q[1] / q[2]]

    def end(a):
        return px(c + rad * math.sin(math.radians(a)), c - rad * math.cos(math.radians(a)))

    pts = (px(c, c), end(spec.min_angle_deg), end(spec.max_angle_deg))
    r = read_gauge(img, make_calibrated_profile(spec.profile(), *pts))
    assert r.value == pytest.approx(v, abs=0.004 * 10), r.error
    # the rim's ellipse was found: its axes are foreshortened by about cos 35 deg
    assert r.dial_ellipse is not None
    w, hh = r.dial_ellipse[2:4]
    assert min(w, hh) / max(w, hh) == pytest.approx(math.cos(math.radians(35)), abs=0.03)
    # reading the angles in the image instead would be off by more than 2 % FS here
    (cx, cy), p0, p1 = pts
    tip = truth["tip_xy"]

    def img_angle(p):
        return math.degrees(math.atan2(p[0] - cx, cy - p[1])) % 360

    a0, a1, at = img_angle(p0), img_angle(p1), img_angle(tip)
    naive = ((at - a0) % 360) / ((a1 - a0) % 360) * 10.0
    assert abs(naive - v) > 0.2


def test_tick_table_with_an_anticlockwise_calibration_round_trips():
    spec = STOCK_SPECS[0]  # the table runs clockwise on its template
    d = make_calibrated_profile(spec.profile(), (150, 150), (230, 220), (70, 220),
                                clockwise=False)
    p = load_profile(d)
    assert p.calibration.clockwise is False and p.ticks
    assert load_profile(p.to_dict()) == p


# ------------------------------------------------------------------ what pulled the needle

@pytest.mark.parametrize("v", [18.0, 33.0, 61.0])
def test_a_stop_pin_and_a_numeral_beside_the_needle_do_not_pull_its_axis(v):
    # a grey pin against the needle's side and the stroke of a bold numeral along it near
    # the tip: both respond more than the thin tip, on one side; a line turned a little
    # passes within a pixel of the needle's inner run and of the stroke
    a = _angle(v)
    img = draw_needle(draw_face(A_MIN, SPAN, text=False), a, width=4.0)
    s = math.radians(a + 90.0)
    dx, dy = math.sin(s), -math.cos(s)
    x, y = end_mark(a, 75.0)
    cv2.circle(img, (int(round(x + 6.5 * dx)), int(round(y + 6.5 * dy))), 5, (95, 95, 100),
               -1, cv2.LINE_AA)
    (x0, y0), (x1, y1) = end_mark(a, 80.0), end_mark(a, 94.0)
    cv2.line(img, (int(x0 + 4.5 * dx), int(y0 + 4.5 * dy)), (int(x1 + 4.5 * dx),
             int(y1 + 4.5 * dy)), (20, 20, 20), 3, cv2.LINE_AA)
    r = _read(img, _profile())
    assert r.value == pytest.approx(v, abs=0.004 * 80), r.error
    assert r.angle_deg == pytest.approx(a, abs=0.5)


# ------------------------------------------------------------------ the rim of a tilted dial

def _squashed(img, pts, ratio, axis_deg, centre):
    """The image and points foreshortened by ``ratio`` along the direction ``axis_deg``
    (clockwise from up) about ``centre``: a dial seen at a tilt, orthographically."""
    t = math.radians(axis_deg)
    u = np.array([math.sin(t), -math.cos(t)])
    m = np.eye(2) - (1.0 - ratio) * np.outer(u, u)
    c = np.array([centre, centre])
    a = np.hstack([m, (c - m @ c)[:, None]])
    out = cv2.warpAffine(img, a, (img.shape[1], img.shape[0]), flags=cv2.INTER_LINEAR,
                         borderValue=(160, 160, 160))
    return out, [tuple(m @ (np.array(p) - c) + c) for p in pts]


@pytest.mark.parametrize("v", [14.0, 61.0])
def test_a_two_tone_bezel_does_not_mix_two_rims(v):
    # the face ends in a ring lit unevenly, then a darker ring: the first step is the
    # stronger on some rays, the second on others (in a pattern that looks like a tilt);
    # a fit that took the strongest step on each ray would mix two circles
    rng = np.random.default_rng(3)
    img = draw_needle(draw_face(A_MIN, SPAN, face=(200, 200, 200)), _angle(v))
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    rr, th = np.hypot(xx - C, yy - C), np.arctan2(xx - C, C - yy)
    ring = (150 + 20 * np.cos(2 * th))[..., None]
    img = np.where((rr >= 145)[..., None], ring, img)
    img = np.where((rr >= 153)[..., None], 100.0, img)
    img = np.where((rr >= 161)[..., None], 160.0, img)
    img = np.clip(cv2.GaussianBlur(img.astype(np.float32), (3, 3), 0)
                  + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
    pad = 40  # room for the whole rim
    img = cv2.copyMakeBorder(img, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=(160,) * 3)
    ratio, axis = math.cos(math.radians(32)), 60.0
    pts = [(x + pad, y + pad) for x, y in ((C, C), end_mark(A_MIN), end_mark(A_MIN + SPAN))]
    tilted, pts = _squashed(img, pts, ratio, axis, C + pad)
    r = read_gauge(tilted, make_calibrated_profile(base_profile(), *pts))
    assert r.value == pytest.approx(v, abs=0.004 * 80), r.error
    w, hh = r.dial_ellipse[2:4]
    assert min(w, hh) / max(w, hh) == pytest.approx(ratio, abs=0.02)


# ------------------------------------------------------------------ colours

def test_a_set_point_hub_over_the_needles_root_is_not_a_gap():
    # the red set-point pointer turns on a wide red disc under the needle; masked out, the
    # disc takes the needle's root with it: unseen there, not a needle with gaps
    v, setpoint = 27.0, 66.0
    img = draw_face(A_MIN, SPAN)
    draw_needle(img, _angle(setpoint), colour=(30, 30, 200), width=5, tail=0, hub=44)
    draw_needle(img, _angle(v), hub=12)
    r = _read(img, _profile(ignore_colour="red"))
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error
    assert r.confidence >= 0.9 and r.scores["needle_solid"] == 1.0


@pytest.mark.parametrize("v", [12.0, 70.0])
def test_a_red_needle_on_a_blue_face(v):
    img = draw_needle(draw_face(A_MIN, SPAN, face=(200, 120, 40), ink=(20, 20, 20)), _angle(v),
                      colour=(40, 40, 190))
    r = _read(img, _profile())
    assert r.value == pytest.approx(v, abs=0.005 * 80), r.error

