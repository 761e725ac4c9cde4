"""A dial small in its frame or crop (small_dial): found by the finer search, cut out of the input
and read as a crop, its geometry carried back to the frame."""

import cv2
import numpy as np
import pytest

from app.core.meter import load_profile, read_gauge, small_dial
from app.core.meter.dial import DialEllipse
from app.core.meter.reading import Reading
from bench.meter_rows import ROW_IDS
from sim_robot.gauge_scene import LEVELS, render_sample
from sim_robot.gauge_styles import TUNING_FAMILIES
from tests.meter.stored_frames import FRAMES, stored


def _hard(idx: int, seed: int = 6):
    name = f"tuning-hard-{seed}-{idx}"
    return stored(name) if name in FRAMES else _tuning("hard", idx, seed)


def _tuning(level: str, idx: int, seed: int = 6):
    rng = np.random.default_rng([seed, ROW_IDS["tuning"], LEVELS.index(level)])
    for i in range(idx + 1):
        img, truth = render_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], level, rng)
    return img, truth


def _far(img: np.ndarray, n: int = 3) -> np.ndarray:
    """The frame in the middle of one n times as wide and high, in its median colour."""
    h, w = img.shape[:2]
    fill = [int(v) for v in np.median(img.reshape(-1, 3), axis=0)]
    return cv2.copyMakeBorder(img, (n - 1) * h // 2, (n - 1) * h // 2, (n - 1) * w // 2,
                              (n - 1) * w // 2, cv2.BORDER_CONSTANT, value=fill)


def test_a_crop_is_cut_with_the_inputs_edge_repeated_where_it_reaches_past_it():
    img = np.arange(100, dtype=np.uint8).reshape(10, 10)
    crop = small_dial._cut(img, -2, 5, 6)
    assert crop.shape == (6, 6)
    assert (crop[:, :2] == crop[:, 2:3]).all()  # the left edge repeated
    assert (crop[:5, 2:] == img[5:10, 0:4]).all() and (crop[5] == crop[4]).all()


def test_nothing_small_is_tried_where_the_whole_frame_search_found_a_rim():
    # a station frame's big dial refused (glare) with another, small gauge beside it: that
    # one was read 32 % FS off before the small pass waited for a frame with no rim
    img, truth = _hard(22, seed=3)
    r = read_gauge(img, load_profile(truth["profile"]))
    assert r.value is None or abs(r.value - truth["value"]) / truth["full_scale"] < 0.02
    tried = []
    got = small_dial.read_small_dial(img, img[:, :, 0], 1.0,
                                     (DialEllipse(10.0, 10.0, 5.0, 5.0, 0.0, 1.0),),
                                     lambda c: tried.append(c) or Reading(1.0, "bar", 1.0))
    assert got is None and not tried


def test_the_crops_geometry_is_shifted_into_the_frame():
    r = Reading(value=1.0, unit="bar", confidence=1.0, dial_ellipse=(10.0, 20.0, 8.0, 6.0, 5.0),
                dial_centre_xy=(10.0, 20.0), pointer_line_xy=((10.0, 20.0), (1.0, 2.0)))
    out = small_dial.shifted(r, 100, 50)
    assert out.dial_centre_xy == (110.0, 70.0) and out.pointer_line_xy[1] == (101.0, 52.0)
    assert out.dial_ellipse == (110.0, 70.0, 8.0, 6.0, 5.0) and out.pointer_tip_xy is None


@pytest.mark.parametrize("level,idx", [("hard", 0), ("hard", 3), ("hard", 10), ("clean", 3),
                                       ("field", 0)])
def test_a_dial_three_times_farther_off_is_found_and_read(level, idx, monkeypatch):
    # a frame (hard), and a crop placed so that it is still square, taken for a crop
    img, truth = _hard(idx) if level == "hard" else _tuning(level, idx)
    prof = load_profile(truth["profile"])
    near, far = read_gauge(img, prof), read_gauge(_far(img), prof)
    assert near.value is not None and far.value is not None, far.error
    assert abs(far.value - truth["value"]) / truth["full_scale"] < 0.01
    # its pivot in the wide frame's pixels: the near frame's, moved by the border
    h, w = img.shape[:2]
    a, b = near.dial_centre_xy, far.dial_centre_xy
    assert np.hypot(a[0] + w - b[0], a[1] + h - b[1]) < 3.0
    # the search alone does not consider a dial so small in its input
    monkeypatch.setattr(small_dial, "TRIES", 0)
    assert read_gauge(_far(img), prof).value is None
