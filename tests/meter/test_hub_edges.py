"""The hub cap found from the grey image's edges, whatever its contrast.

Where the threshold leaves a hub cap out of the pointer's region (a grey cap on a white
face, a faint light cap on a dark face's negative), the region's thickest point near the
centre is the tapered needle's base, up to a cap's radius from the pivot
(docs/meter-bench.md, "A pivot no second estimate confirms").  :mod:`.hub_edges` finds
the cap as a circle about the needle's line whose circumference crosses an edge all round.
"""

import math

import cv2
import numpy as np
import pytest

from app.core.meter import load_profile, read_gauge
from app.core.meter.geometry import Line
from app.core.meter.hub_edges import find_hub_edges
from app.core.meter.pointer import read_normalised
from sim_robot.gauge_scene import LEVELS, render_sample
from sim_robot.gauge_styles import TUNING_FAMILIES

PIVOT = (151.3, 148.6)
CAP_R = 15.0
ZONE = (150.0, 150.0, 27.0)


def _needle(img, colour, pivot=PIVOT, angle_deg=-50.0, length=110.0, base_w=9.0):
    """A tapered needle from the pivot (its base ``base_w`` wide) to a 2 px tip."""
    a = math.radians(angle_deg)
    u = np.array([math.sin(a), -math.cos(a)])
    n = np.array([-u[1], u[0]])
    p = np.array(pivot)
    tip = p + length * u
    poly = np.array([p + 0.5 * base_w * n, tip + 1.0 * n, tip - 1.0 * n, p - 0.5 * base_w * n])
    cv2.fillConvexPoly(img, np.round(poly * 16).astype(np.int32), colour, cv2.LINE_AA, 4)
    return Line((float(p[0]), float(p[1])), (float(u[0]), float(u[1])))


def _disc(img, centre, r, colour):
    cv2.circle(img, (int(round(centre[0] * 16)), int(round(centre[1] * 16))), int(round(r * 16)),
               colour, -1, cv2.LINE_AA, 4)


def _face(grey):
    img = np.full((300, 300), grey, np.uint8)
    return img


def _root(line: Line, cap_r=CAP_R):
    """The needle's base where it leaves the cap: the pointer region's thickest point."""
    return (line.point[0] + (cap_r + 3.0) * line.direction[0],
            line.point[1] + (cap_r + 3.0) * line.direction[1])


def _blur_noise(img, seed=3):
    img = cv2.GaussianBlur(img, (0, 0), 1.0).astype(np.float32)
    img += np.random.default_rng(seed).normal(0.0, 3.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def test_a_grey_cap_on_a_white_face_is_found_behind_the_needles_base():
    img = _face(240)
    line = _needle(img, 20)
    _disc(img, PIVOT, CAP_R, 150)
    cap = find_hub_edges(_blur_noise(img), line, _root(line), 4.5, 27.0, ZONE)
    assert cap is not None
    assert math.dist(cap["centre"], PIVOT) < 0.6
    assert abs(cap["r"] - CAP_R) < 0.8


def test_a_faint_light_cap_on_a_dark_face_is_found():
    """Light on dark, 25 grey levels of contrast, a light needle (a dark dial's face)."""
    img = _face(30)
    line = _needle(img, 230)
    _disc(img, PIVOT, CAP_R, 55)
    cap = find_hub_edges(_blur_noise(img), line, _root(line), 4.5, 27.0, ZONE)
    assert cap is not None
    assert math.dist(cap["centre"], PIVOT) < 0.6


def test_a_domed_cap_lighter_than_the_face_on_one_side_and_darker_on_the_other():
    """The edge's sign changes round the circle: shaded from 60 to 200 over a face of 130."""
    img = _face(130).astype(np.float32)
    line = _needle(img, 15.0)
    yy, xx = np.mgrid[0:300, 0:300].astype(np.float32)
    inside = np.hypot(xx - PIVOT[0], yy - PIVOT[1]) < CAP_R
    shade = 130.0 + 70.0 * np.clip((xx - PIVOT[0] + yy - PIVOT[1]) / (CAP_R * math.sqrt(2)),
                                   -1.0, 1.0)
    img[inside] = shade[inside]
    cap = find_hub_edges(_blur_noise(img.astype(np.uint8)), line, _root(line), 4.5, 27.0, ZONE)
    assert cap is not None
    assert math.dist(cap["centre"], PIVOT) < 0.8


def test_a_set_point_pointers_ring_about_the_cap_does_not_move_it():
    img = _face(235)
    line = _needle(img, 20)
    cv2.circle(img, (int(round(PIVOT[0] * 16)), int(round(PIVOT[1] * 16))), 22 * 16, 60, 3,
               cv2.LINE_AA, 4)
    _disc(img, PIVOT, CAP_R, 160)
    cap = find_hub_edges(_blur_noise(img), line, _root(line), 4.5, 27.0, ZONE)
    assert cap is not None
    assert math.dist(cap["centre"], PIVOT) < 0.8


def test_no_cap_no_circle():
    """A needle alone on a plain face (its base is the pivot): nothing is found."""
    img = _face(235)
    line = _needle(img, 20)
    assert find_hub_edges(_blur_noise(img), line, _root(line, 0.0), 4.5, 27.0, ZONE) is None


def test_a_disc_off_the_needles_line_is_not_a_hub():
    """A logo's disc 9 px beside the needle's line, near its root: not the pivot."""
    img = _face(235)
    line = _needle(img, 20)
    u = line.direction
    off = (PIVOT[0] - 9.0 * u[1] - 6.0 * u[0], PIVOT[1] + 9.0 * u[0] - 6.0 * u[1])
    _disc(img, off, 10.0, 150)
    assert find_hub_edges(_blur_noise(img), line, _root(line, 0.0), 4.5, 27.0, ZONE) is None


def test_the_pointer_steps_take_the_cap_the_threshold_left_out():
    """In :func:`.pointer.read_normalised`: a grey cap lighter than Otsu's threshold on a
    white face with a black tapered needle.  The region's thickest point is the needle's
    base; the hub is now the cap's centre, and the needle's line is refitted through it."""
    img = _face(240)
    _needle(img, 15, base_w=10.0)
    _disc(img, PIVOT, CAP_R, 185)
    img = _blur_noise(img)
    cv2.circle(img, (150, 150), 140, 0, 4)  # the rim
    res = read_normalised(cv2.cvtColor(img, cv2.COLOR_GRAY2BGR),
                          load_profile({"name": "t", "unit": "bar", "min_value": 0,
                                        "max_value": 10, "min_angle_deg": -135,
                                        "max_angle_deg": 135}))
    assert res["hub_from"] == "edges"
    assert math.dist(res["centre"], PIVOT) < 0.8
    assert float(res["line"].distance(PIVOT)[0]) < 0.8


def _tuning_image(seed: int, level: str, index: int):
    rng = np.random.default_rng([seed, 11, LEVELS.index(level)])
    for i in range(index + 1):
        img, truth = render_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], level, rng)
    return img, truth


@pytest.mark.parametrize("level,index,style", [("clean", 7, "plant_0_1.6MPa"),
                                               ("hard", 8, "dark_50_250psi")])
def test_the_bench_dials_whose_cap_was_missed_are_read_about_it(level, index, style):
    """Seed 10 clean #7 (a grey cap on a white face) and hard #8 (a faint light cap on a
    tilted dark dial) were read about the needle's base, 9 and 24 px off the pivot; the
    classical reader now reads both about the cap, within their bounds."""
    img, truth = _tuning_image(10, level, index)
    assert truth["style"] == style
    r = read_gauge(img, load_profile(truth["profile"]), learned_fallback=False)
    assert r.value is not None, r.error
    err = abs(r.value - truth["value"]) / truth["full_scale"] * 100.0
    assert err <= min(0.5, r.error_bound_fs if r.error_bound_fs is not None else 0.5)
    assert math.dist(r.dial_centre_xy, truth["pivot_xy"]) < 2.0
    if level == "clean":  # the hub is a fitted circle now: no doubt, the scale path reads
        assert r.method == "scale"
