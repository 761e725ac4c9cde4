"""A real downward seam camera for the climber on a real board
(``sim-robot --robot climber --serial DEVICE --seam-camera-device CAM``):
frames from OpenCV's ``VideoCapture`` (a device index such as ``0``, a
``/dev/video*`` path, a video file or a stream URL), grabbed on a thread of
their own so that the relay's navigation never waits for the camera, each
stamped on the board's clock as the relay hears it (:func:`board_clock`).

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
from collections import deque
from collections.abc import Callable

import cv2
import numpy as np

log = logging.getLogger(__name__)

CLOCK_WINDOW_S = 5.0  # reports whose least delay sets the board clock
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


def board_clock(relay, window_s: float = CLOCK_WINDOW_S,
                host_clock: Callable[[], float] = time.monotonic) -> Callable[[], float | None]:
    """The board's time now as ``relay`` hears it, or None before the first report.

    Each report gives the board's clock minus the host's (scaled by the relay's
    time scale, 1 with a real board) at the moment the relay took it in: the
    true offset less that report's delay. A report the relay took in late (a
    busy host, a backed-up serial buffer) would stamp every frame after it
    late by as much, and the estimate, on reports that come on time, would pass
    those frames by and drop them. So the clock keeps the largest offset of the
    reports of the last ``window_s`` (the one with the least delay, as NTP keeps
    its shortest round trip); the window lets it follow a board clock that
    drifts from the host's. ``host_clock`` is the clock of ``relay.report_stamp``."""
    scale = float(relay.cfg.time_scale)
    best: deque[tuple[float, float]] = deque()  # (host time, offset), offsets falling
    last = None

    def now() -> float | None:
        nonlocal last
        stamp = relay.report_stamp  # (one pair, set at once)
        if stamp is None:
            return None
        t_host = host_clock()
        if stamp is not last:
            last = stamp
            t_board, mono = stamp
            off = t_board - scale * mono
            while best and best[-1][1] <= off:
                best.pop()
            best.append((mono, off))
        while len(best) > 1 and best[0][0] < t_host - window_s:
            best.popleft()
        return scale * t_host + best[0][1]

    return now
