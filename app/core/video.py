"""Camera frames: JPEG decoding off the GUI thread (no Qt)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass
class DecodedFrame:
    frame_id: int
    capture_ts_us: int
    image: np.ndarray  # H x W x 3, uint8, RGB
    latency_ms: float  # robot capture -> decoded here (same clock on loopback)
    width: int
    height: int
    camera_pan_rad: float = 0.0


def decode_jpeg_rgb(jpeg: bytes) -> np.ndarray | None:
    """Decode a JPEG into an RGB array, or None when the bytes are not an image."""
    buf = np.frombuffer(jpeg, dtype=np.uint8)
    if buf.size == 0:
        return None
    bgr = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    if bgr is None:
        return None
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
