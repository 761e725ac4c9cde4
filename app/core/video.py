"""Camera frames: JPEG decoding off the GUI thread, and the newest-frame mailbox (no Qt)."""

from __future__ import annotations

import threading
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["DecodedFrame", "LatestFrame", "decode_jpeg_rgb"]


@dataclass
class DecodedFrame:
    frame_id: int
    capture_ts_us: int
    image: np.ndarray  # H x W x 3, uint8, RGB
    latency_ms: float  # robot capture -> decoded here (same clock on loopback)
    width: int
    height: int
    camera_pan_rad: float = 0.0
    # the robot's own JPEG bytes: recorded and snapshotted as they came, never re-encoded
    jpeg: bytes | None = None


def decode_jpeg_rgb(jpeg: bytes) -> np.ndarray | None:
    """Decode a JPEG into an RGB array, or None when the bytes are not an image."""
    buf = np.frombuffer(jpeg, dtype=np.uint8)
    if buf.size == 0:
        return None
    bgr = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    if bgr is None:
        return None
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


class LatestFrame:
    """A one-place mailbox between the thread that decodes frames and the one that shows
    them. :meth:`put` returns True when the box was empty (the reader must be woken);
    a frame put while the previous one is still unread replaces it and is counted in
    ``dropped``, so a GUI that falls behind always gets the newest frame and nothing
    queues up."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._frame: DecodedFrame | None = None
        self.dropped = 0

    def put(self, frame: DecodedFrame) -> bool:
        with self._lock:
            empty = self._frame is None
            if not empty:
                self.dropped += 1
            self._frame = frame
        return empty

    def take(self) -> DecodedFrame | None:
        with self._lock:
            frame, self._frame = self._frame, None
        return frame
