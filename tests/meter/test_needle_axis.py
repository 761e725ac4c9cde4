"""The shaft's weighted line fit (:mod:`app.core.meter.needle_axis`) on drawn needles."""

import math

import cv2
import numpy as np
import pytest

from app.core.meter.needle_axis import fit_shaft

SIZE, PIVOT, LENGTH = 300, (150.3, 149.6), 115.0


def _needle(angle_deg: float, width_px: float = 3.0, blur: float = 0.8) -> np.ndarray:
    """A bright tapered needle on black, supersampled and blurred: the
    darkness image of a dark needle on a light face."""
    a = math.radians(angle_deg)
    u = np.array([math.sin(a), -math.cos(a)])
    nrm = np.array([-u[1], u[0]])
    p = np.asarray(PIVOT)
    tip = p + LENGTH * u
    poly = np.array([p + width_px * nrm, tip + 0.3 * width_px * nrm,
                     tip - 0.3 * width_px * nrm, p - width_px * nrm])
    k = 8  # drawn 8 x larger and averaged down: exact to 1/8 px (pixel centres at integers)
    big = np.zeros((SIZE * k, SIZE * k), np.uint8)
    cv2.fillPoly(big, [np.round((poly + 0.5) * k - 0.5).astype(np.int32)], 255)
    img = cv2.resize(big, (SIZE, SIZE), interpolation=cv2.INTER_AREA)
    return cv2.GaussianBlur(img, (0, 0), blur)


def _fit(img: np.ndarray, guess_deg: float):
    mask = (img > 100).astype(np.uint8)
    return fit_shaft(mask, img, PIVOT, guess_deg, LENGTH)


@pytest.mark.parametrize("angle", [-131.7, -62.25, 3.4, 47.9, 118.6, 171.05])
def test_fit_recovers_the_needles_angle_within_a_tenth_of_a_degree(angle):
    img = _needle(angle)
    fit = _fit(img, angle + 2.5)  # a guess 2.5 deg off, as a coarse finder gives
    assert fit is not None
    err = (fit.angle_deg - angle + 180.0) % 360.0 - 180.0
    assert abs(err) < 0.1


def test_a_numeral_touching_the_shaft_does_not_tilt_it():
    angle = 61.3
    img = _needle(angle)
    a = math.radians(angle)
    # a bold "8" sitting against one side of the shaft, 70 % out along it
    c = np.asarray(PIVOT) + 0.7 * LENGTH * np.array([math.sin(a), -math.cos(a)])
    c = c + 7.0 * np.array([math.cos(a), math.sin(a)])
    cv2.putText(img, "8", (int(c[0]) - 4, int(c[1]) + 6), cv2.FONT_HERSHEY_SIMPLEX, 0.5, 255, 2)
    fit = _fit(img, angle - 2.0)
    assert fit is not None
    err = (fit.angle_deg - angle + 180.0) % 360.0 - 180.0
    assert abs(err) < 0.3


def test_angle_at_the_ring_is_the_crossing_about_the_centre():
    img = _needle(90.0)  # pointing right, the pivot 0.4 px above the crop's centre
    fit = _fit(img, 90.0)
    assert fit is not None
    # about a centre 5 px below the pivot the needle is seen a little above horizontal
    r = 100.0
    expect = math.degrees(math.atan2(r * math.cos(math.asin(5.4 / r)), 5.4)) % 360.0
    got = fit.angle_at((150.3, 155.0), r)
    assert got is not None and abs(got - expect) < 0.1


def test_no_needle_no_fit():
    img = np.zeros((SIZE, SIZE), np.uint8)
    assert _fit(img, 30.0) is None
