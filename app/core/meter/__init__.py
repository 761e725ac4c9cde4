"""Pointer-gauge reading (seed 000 section 3), Qt-free: numpy + OpenCV + stdlib.

Public API: :func:`load_profile`, :func:`read_gauge` -> :class:`Reading`,
:class:`MeterFusion`, :func:`calibrate_profile`, :func:`make_calibrated_profile`,
:func:`save_profile`.  A calibrated profile is read by :mod:`.calibrated` (registration to a
reference frame in :mod:`.register`, the needle around a known pivot in :mod:`.needle`).
Where the uncalibrated reader's own scale finder refuses, a small learned keypoint network
(:mod:`.keypoints`, ONNX through OpenCV's dnn module) is tried under its own checks.
"""

from .fusion import FusedReading, MeterFusion
from .profile import (
    Calibration,
    GaugeProfile,
    calibrate_profile,
    load_profile,
    make_calibrated_profile,
    save_profile,
)
from .reader import MIN_CONFIDENCE, Reading, read_gauge

__all__ = [
    "MIN_CONFIDENCE",
    "Calibration",
    "FusedReading",
    "GaugeProfile",
    "MeterFusion",
    "Reading",
    "calibrate_profile",
    "load_profile",
    "make_calibrated_profile",
    "read_gauge",
    "save_profile",
]
