"""Lidar scans for the archive: decimated in time and beams, ranges packed (no Qt).

A scan arrives 5 times a second with 360 beams (float32, 1.4 kB). The archive keeps
at most one per ``every_s`` (default 1 s) and at most ``max_beams`` beams (every k-th
beam when there are more), each range as an unsigned 16-bit count of millimetres
(0..65.534 m; 65535 for no return, inf or NaN): 720 bytes for a 360-beam scan, about
62 MB a day at one scan a second — bounded, and enough to see in Foxglove what the
robot saw around an alarm. Retention prunes the table like every timed table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["NO_RETURN", "ScanDecimator", "pack_ranges", "unpack_ranges"]

NO_RETURN = 0xFFFF
MAX_MM = NO_RETURN - 1


def pack_ranges(ranges_m: Any) -> bytes:
    """Metres (float) to little-endian u16 millimetres; inf/NaN/<0 → NO_RETURN."""
    r = np.asarray(ranges_m, np.float64)
    mm = np.full(r.shape, NO_RETURN, np.uint16)
    ok = np.isfinite(r) & (r >= 0)
    mm[ok] = np.minimum(np.rint(r[ok] * 1000.0), MAX_MM).astype(np.uint16)
    return mm.astype("<u2").tobytes()


def unpack_ranges(blob: bytes) -> np.ndarray:
    """The stored ranges in metres (float64), inf where there was no return."""
    mm = np.frombuffer(blob, "<u2")
    out = mm.astype(np.float64) / 1000.0
    out[mm == NO_RETURN] = math.inf
    return out


@dataclass
class ScanDecimator:
    """Which scans to keep: one per ``every_s`` of desk time, ``max_beams`` beams."""

    every_s: float = 1.0
    max_beams: int = 720
    _last_t: float = -math.inf
    kept: int = 0
    skipped: int = 0

    def take(self, t: float, angle_min: float, angle_increment: float,
             ranges_m: Any) -> tuple[float, float, bytes] | None:
        """(angle_min, angle_increment, packed ranges) to store, or None to skip."""
        if t - self._last_t < self.every_s - 1e-6:  # (a float step of 0.2 s × 5)
            self.skipped += 1
            return None
        r = np.asarray(ranges_m)
        step = max(1, math.ceil(r.size / self.max_beams)) if self.max_beams > 0 else 1
        self._last_t = t
        self.kept += 1
        return float(angle_min), float(angle_increment) * step, pack_ranges(r[::step])
