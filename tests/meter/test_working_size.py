"""Large inputs read at the reader's working sizes (working_size.shrink), with the geometry
carried back to the input's pixels (working_size.to_input)."""

import cv2
import numpy as np
import pytest

from app.core.meter import load_profile, read_gauge, working_size
from app.core.meter.reading import Reading
from bench.meter_rows import ROW_IDS
from sim_robot.gauge_scene import LEVELS, render_sample
from sim_robot.gauge_styles import TUNING_FAMILIES
from tests.meter.stored_frames import FRAMES, stored


def test_small_inputs_pass_as_they_are_and_large_ones_shrink_to_the_working_size():
    for shape in ((300, 300, 3), (320, 320), (480, 640, 3), (375, 360)):
        img = np.zeros(shape, np.uint8)
        out, k = working_size.shrink(img)
        assert out is img and k == 1.0
    out, k = working_size.shrink(np.zeros((900, 930, 3), np.uint8))  # a crop
    assert max(out.shape[:2]) == working_size.CROP_SIDE and k < 1.0
    out, k = working_size.shrink(np.zeros((2880, 3840, 3), np.uint8))  # a frame
    assert out.shape[:2] == (960, 1280) and k == pytest.approx(1 / 3)


def test_the_geometry_is_carried_back_pixel_centre_onto_pixel_centre():
    r = Reading(value=1.0, unit="bar", confidence=1.0, dial_ellipse=(99.5, 49.5, 80.0, 60.0, 30.0),
                dial_centre_xy=(99.5, 49.5), dial_radius_px=40.0, pointer_tip_xy=(0.0, 0.0),
                pointer_line_xy=((99.5, 49.5), (0.0, 0.0)), scale_ends_xy=None)
    out = working_size.to_input(r, 0.5, (200, 400))  # shrunk from 200 x 400 to 100 x 200
    assert out.dial_centre_xy == (199.5, 99.5)  # the centre of pixels 199-200, 99-100
    assert out.pointer_tip_xy == (0.5, 0.5)  # pixel 0 of the half-size image covers 0-1
    assert out.dial_ellipse == (199.5, 99.5, 160.0, 120.0, 30.0)
    assert out.dial_radius_px == 80.0 and out.scale_ends_xy is None and out.value == 1.0
    assert working_size.to_input(r, 1.0, (100, 200)) is r


@pytest.mark.parametrize("level,idx", [("clean", 4), ("clean", 6), ("hard", 11), ("hard", 13)])
def test_a_dial_photographed_six_times_larger_reads_as_the_original(level, idx, monkeypatch):
    name = f"tuning-{level}-1-{idx}"
    if name in FRAMES:  # deep in the stream: stored (tests/meter/stored_frames.py)
        img, truth = stored(name)
    else:
        rng = np.random.default_rng([1, ROW_IDS["tuning"], LEVELS.index(level)])
        for i in range(idx + 1):
            img, truth = render_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], level, rng)
    prof = load_profile(truth["profile"])
    big = cv2.resize(img, None, fx=6, fy=6, interpolation=cv2.INTER_CUBIC)
    small, large = read_gauge(img, prof), read_gauge(big, prof)
    assert small.value is not None and large.value is not None, large.error
    assert abs(large.value - truth["value"]) / truth["full_scale"] < 0.01
    # the overlay's pivot on the large image: where the original's lies, six times over
    # (within 3 px of the original's; the two may be read by different paths)
    a, b = small.dial_centre_xy, large.dial_centre_xy
    assert np.hypot((a[0] + 0.5) * 6 - 0.5 - b[0], (a[1] + 0.5) * 6 - 0.5 - b[1]) < 18.0
    # read at full size instead, the thin marks alias in every resampling and it is refused
    monkeypatch.setattr(working_size, "CROP_SIDE", 10 ** 9)
    monkeypatch.setattr(working_size, "FRAME_SIDE", 10 ** 9)
    assert read_gauge(big, prof).value is None


@pytest.mark.parametrize("shape,size", [((3600, 3600), (375, 375)), ((3024, 4031), (1280, 960)),
                                        ((1301, 1297), (375, 374))])
def test_area_resize_by_whole_blocks_puts_each_point_where_one_area_resize_does(shape, size):
    """Bright discs on a dark ground, shrunk in two stages (whole f × f blocks, then the rest)
    and by one area resize: the same size, each disc's centroid within 0.3 px of the other's
    (the second stage's size is rounded: up to half a pixel over the whole side), and the
    grey levels within a few steps (the far edges padded up to a multiple of f)."""
    rng = np.random.default_rng(1)
    img = np.zeros(shape, np.uint8)
    h, w = shape
    for _ in range(12):
        cv2.circle(img, (int(rng.integers(0, w)), int(rng.integers(0, h))), int(0.02 * w), 255, -1)
    cv2.circle(img, (w - 5, h - 5), int(0.02 * w), 255, -1)  # at the padded corner
    one = cv2.resize(img, size, interpolation=cv2.INTER_AREA)
    two = working_size.area_resize(img, size)
    assert two.shape == one.shape
    assert np.abs(two.astype(int) - one.astype(int)).mean() < 1.0
    n, lab = cv2.connectedComponents((one > 127).astype(np.uint8))
    for i in range(1, n):
        ys, xs = np.nonzero(lab == i)
        a = (xs @ one[ys, xs] / one[ys, xs].sum(), ys @ one[ys, xs] / one[ys, xs].sum())
        b = (xs @ two[ys, xs] / two[ys, xs].sum(), ys @ two[ys, xs] / two[ys, xs].sum())
        assert abs(a[0] - b[0]) < 0.3 and abs(a[1] - b[1]) < 0.3, (i, a, b)
