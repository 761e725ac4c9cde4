"""A real downward seam camera for the climber on a real board
(``sim-robot --robot climber --serial DEVICE --seam-camera-device CAM``):
frames from OpenCV's ``VideoCapture`` (a device index such as ``0``, a
``/dev/video*`` path, a video file or a stream URL), grabbed on a thread of
their own so that the relay's navigation never waits for the camera, each
stamped on the board's clock as the relay last heard it (the latest report's
MCU time plus the wall time since it came).

The camera must look at the wall with the body's forward axis up in the image
and its left to the image's left (the simulated camera's convention,
:mod:`.camera_view`); its scale (metres a pixel on the wall) is the user's
calibration. The relay finds the seams in the frames
(app/core/localisation/seam_camera.py).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

import cv2
import numpy as np

log = logging.getLogger(__name__)

FILE_FPS = 10.0  # a video file is played at its own rate, or this when it states none


class SeamCamera:
    """The newest frame of ``source``, once: calling it returns ``(t_s, frame)``
    for a frame not handed out before, or None (no new frame, or no board time
    yet). ``failures`` counts the frames the capture could not read; a file
    that ends stops the thread (``ended``)."""

    def __init__(self, source: str, board_time: Callable[[], float | None] | None = None) -> None:
        self.source = source
        self.board_time = board_time
        self.cap = cv2.VideoCapture(int(source) if source.isdigit() else source)
        if not self.cap.isOpened():
            raise ValueError(f"cannot open the seam camera {source!r}")
        self.is_file = not source.isdigit() and not source.startswith("/dev/")
        fps = self.cap.get(cv2.CAP_PROP_FPS) if self.is_file else 0.0
        self._period = 1.0 / (fps if fps and fps > 0 else FILE_FPS) if self.is_file else 0.0
        self._lock = threading.Lock()
        self._latest: tuple[float, np.ndarray] | None = None
        self._stop = threading.Event()
        self.failures = 0
        self.frames = 0
        self.ended = False
        self._thread = threading.Thread(target=self._run, name="seam-camera", daemon=True)

    def start(self) -> SeamCamera:
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.is_set():
            ok, frame = self.cap.read()
            if not ok:
                if self.is_file:
                    self.ended = True
                    log.info("seam camera %s: the file ended after %d frames",
                             self.source, self.frames)
                    return
                self.failures += 1
                self._stop.wait(0.05)
                continue
            t = self.board_time() if self.board_time is not None else None
            if t is not None:
                with self._lock:
                    self._latest = (t, frame)
                self.frames += 1
            if self._period:
                self._stop.wait(self._period)

    def __call__(self) -> tuple[float, np.ndarray] | None:
        with self._lock:
            out, self._latest = self._latest, None
        return out

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2)
        self.cap.release()


def board_clock(relay) -> Callable[[], float | None]:
    """The board's time now as ``relay`` last heard it: the latest report's MCU
    time plus the wall time since it came (None before the first report)."""

    def now() -> float | None:
        rep = relay.report
        if rep is None:
            return None
        return rep.mcu_time_ms / 1000.0 + (time.monotonic() - relay.report_mono)

    return now
