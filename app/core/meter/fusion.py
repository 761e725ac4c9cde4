"""Fusing several readings of the same meter into one robust reading."""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from .reader import Reading

__all__ = ["FusedReading", "MeterFusion"]


@dataclass(frozen=True)
class FusedReading:
    value: float | None
    unit: str
    confidence: float
    error: str | None
    n_used: int
    n_total: int
    spread: float | None  # robust spread (1.4826 MAD) of the values used


class MeterFusion:
    """Robust median of the last ``window`` readings of one meter.

    Refused and low-confidence readings are skipped; values farther than
    ``max(3 sigma_MAD, outlier_fs * full_scale)`` from the median are dropped as outliers.
    The fused confidence is the median confidence of the kept readings, scaled down when
    few frames agree or when they spread by more than ``agree_fs`` of full scale.
    """

    def __init__(self, full_scale: float, unit: str = "", *, window: int = 7,
                 min_readings: int = 2, min_confidence: float = 0.5,
                 outlier_fs: float = 0.01, agree_fs: float = 0.01) -> None:
        if full_scale <= 0:
            raise ValueError("full_scale must be positive")
        self.full_scale = float(full_scale)
        self.unit = unit
        self.min_readings = int(min_readings)
        self.min_confidence = float(min_confidence)
        self.outlier_fs = outlier_fs
        self.agree_fs = agree_fs
        self._buf: deque[Reading] = deque(maxlen=int(window))

    def add(self, reading: Reading) -> None:
        self._buf.append(reading)
        if not self.unit:
            self.unit = reading.unit

    def clear(self) -> None:
        self._buf.clear()

    def __len__(self) -> int:
        return len(self._buf)

    def fused(self) -> FusedReading:
        total = len(self._buf)
        good = [r for r in self._buf if r.value is not None and r.confidence >= self.min_confidence]
        if len(good) < self.min_readings:
            return FusedReading(None, self.unit, 0.0,
                                f"only {len(good)} of {total} frames readable", len(good), total,
                                None)
        v = np.array([r.value for r in good])
        c = np.array([r.confidence for r in good])
        med = float(np.median(v))
        sig = 1.4826 * float(np.median(np.abs(v - med)))
        keep = np.abs(v - med) <= max(3 * sig, self.outlier_fs * self.full_scale)
        if keep.sum() < self.min_readings:
            return FusedReading(None, self.unit, 0.0, "frames disagree", int(keep.sum()), total,
                                sig)
        vk = v[keep]
        value = float(np.median(vk))
        spread = 1.4826 * float(np.median(np.abs(vk - value)))
        conf = float(np.median(c[keep]))
        conf *= math.sqrt(keep.sum() / max(total, 1))
        conf *= max(0.0, 1.0 - spread / (self.agree_fs * self.full_scale) * 0.5)
        conf = round(min(1.0, max(0.0, conf)), 4)
        if conf < self.min_confidence:
            return FusedReading(None, self.unit, conf, "fused confidence too low",
                                int(keep.sum()), total, spread)
        return FusedReading(value, self.unit, conf, None, int(keep.sum()), total, spread)
