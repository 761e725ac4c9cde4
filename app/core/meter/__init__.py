"""Pointer-gauge reading (seed 000 section 3), Qt-free: numpy + OpenCV + stdlib.

Public API: :func:`load_profile`, :func:`read_gauge` -> :class:`Reading`,
:class:`MeterFusion`, :func:`calibrate_profile`, :func:`save_profile`.
"""

from .fusion import FusedReading, MeterFusion
from .profile import GaugeProfile, calibrate_profile, load_profile, save_profile
from .reader import MIN_CONFIDENCE, Reading, read_gauge

__all__ = [
    "MIN_CONFIDENCE",
    "FusedReading",
    "GaugeProfile",
    "MeterFusion",
    "Reading",
    "calibrate_profile",
    "load_profile",
    "read_gauge",
    "save_profile",
]
