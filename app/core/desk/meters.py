"""Meter sessions of the desk (no Qt): which gauge the camera is on, which frames to read.

The robot's events ``inspection_started`` / ``inspection_done`` (``{point, gauge}``) open
and close a reading session of :class:`~app.core.meter_service.MeterService`; the operator
can ask for one too (:meth:`DeskMeters.request_read`: ``look_at`` {gauge}, read, ``look_at``
{null}). While a session is open each frame is handed to ``submit`` (the Qt adapter runs
:func:`~app.core.meter_service.read_frame` on a worker thread and calls :meth:`on_result`
back on the desk's thread); a frame that arrives while the worker is busy is dropped and
counted, so nothing queues. A fused record out of the profile's normal band raises an alarm
on ``meter.<gauge id>`` in the desk's one alarm monitor.
"""

from __future__ import annotations

import functools
import logging
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from app.core.i18n import translate
from app.core.meter_service import (
    NO_READING,
    MeterRecord,
    MeterService,
    meter_channel,
    read_frame,
)

__all__ = ["DeskMeters", "run_inline"]

log = logging.getLogger(__name__)


def run_inline(job: Callable[[], Any], done: Callable[[Any], None]) -> None:
    """A ``submit`` that reads on the caller's thread (tests, tools without a pool)."""
    done(job())


def is_rgb(image: Any) -> bool:
    return (isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.ndim == 3
            and image.shape[2] == 3 and image.size > 0)


class DeskMeters:
    """``emit(kind, *args)``: the pipeline's listeners (meter_reading, meter_record,
    meter_session, meter_status, log); ``send(name, args)``: the command gateway;
    ``monitor``: the desk's alarm monitor."""

    def __init__(self, service: MeterService, monitor: Any, *, emit: Callable[..., None],
                 send: Callable[[str, dict], Any],
                 submit: Callable[[Callable, Callable], None] = run_inline,
                 timeout_s: float = 12.0, mono: Callable[[], float] = time.monotonic) -> None:
        self.service = service
        self.monitor = monitor
        self._emit, self._send, self.submit = emit, send, submit
        self.timeout_s = float(timeout_s)
        self._mono = mono
        self.busy = False
        self.frames_seen = self.frames_read = self.frames_dropped = 0
        self.last_image: np.ndarray | None = None  # the newest frame (for calibration)
        self.last_jpeg: bytes | None = None
        self.last_point: tuple[str, str] | None = None  # (point, gauge) last inspected
        # the frame behind the latest good reading: (RGB image, gauge id, point, mono time)
        self.last_read_frame: tuple[np.ndarray, str, str, float] | None = None
        self.warmed: int | None = None  # gauge profiles the warm-up read (None: not run)
        self._read_jpeg: bytes | None = None
        self._token = 0
        self._deadline: float | None = None

    # ------------------------------------------------------------ inputs
    def on_event(self, ev: Any) -> None:
        code = str(getattr(ev, "code", ""))
        if code not in ("inspection_started", "inspection_done"):
            return
        data = getattr(ev, "data", None) or {}
        gauge = data.get("gauge")
        if gauge is None:
            return  # an inspection without a meter (a tank wall, a valve): nothing to read
        gauge = str(gauge)
        if gauge not in self.service.gauges:
            self._emit("log", "warning", "meter", f"{code}: gauge {gauge} is not in the "
                       "station configuration; not read")
            return
        if code == "inspection_started":
            if data.get("point") is not None:
                self.last_point = (str(data["point"]), gauge)
            self._start(gauge, data.get("point"), "patrol")
        else:
            self._finish(gauge)

    def on_frame(self, frame: Any) -> None:
        """Hand the frame to the worker, or drop it (busy, or no session wants it)."""
        image = getattr(frame, "image", None)
        if not is_rgb(image):
            return
        self.frames_seen += 1
        self.last_image = image
        self.last_jpeg = getattr(frame, "jpeg", None)
        # "taken after the session began" is judged on the robot's capture stamp only when
        # the clocks agree (a plausible latency); otherwise the settle time alone decides
        ts = getattr(frame, "capture_ts_us", None)
        try:
            lat = float(getattr(frame, "latency_ms", math.nan))
            ts = int(ts) if ts is not None and 0.0 <= lat < 5000.0 else None
        except (TypeError, ValueError):
            ts = None
        if not self.service.wants_frame(ts):
            return
        if self.busy:
            self.frames_dropped += 1
            return
        s = self.service.session
        self.busy = True
        self._token += 1
        token, jpeg = self._token, self.last_jpeg
        job = functools.partial(read_frame, image, s.profile)
        self.submit(job, lambda reading: self.on_result(token, s.gauge_id, reading, image,
                                                        jpeg))

    def warm_up(self) -> None:
        """Warm the reader up on the reading thread (see app/core/meter_warmup.py);
        a desk that reads meters calls it once at start."""
        from app.core.meter_warmup import warm_up_reader

        self.warmed = -1  # running
        self.submit(functools.partial(warm_up_reader, self.service),
                    lambda n: setattr(self, "warmed", n))

    def request_read(self, gauge_id: str, point: str | None = None) -> bool:
        """The operator's "Read meter": aim the head at the gauge and read it (with the
        calibrated profile of the route's ``point`` when it has one)."""
        try:
            self.service.profile_for(gauge_id, point)
        except ValueError as e:
            self._emit("meter_status", str(e))
            self._emit("log", "warning", "meter", str(e))
            return False
        self._send("look_at", {"gauge": gauge_id})
        self._start(gauge_id, point, "operator")
        return True

    def cancel(self) -> None:
        s = self.service.session
        if s is not None:
            self._finish(s.gauge_id)

    def tick(self) -> None:
        """A session that saw no end within ``timeout_s`` is closed with what it has."""
        if self._deadline is not None and self._mono() >= self._deadline:
            self._deadline = None
            self.cancel()

    # ------------------------------------------------------------ worker results
    def on_result(self, token: int, gauge_id: str, reading: Any, image: np.ndarray,
                  jpeg: bytes | None = None) -> None:
        if token == self._token:
            self.busy = False
        self.frames_read += 1
        s = self.service.session
        if s is None or s.gauge_id != gauge_id:
            return  # the session ended while this frame was read
        if reading.value is not None:
            self.last_read_frame = (image, gauge_id, s.point, self._mono())
            self._read_jpeg = jpeg
        self._emit("meter_reading", gauge_id, reading)
        rec = self.service.add(gauge_id, reading)
        if rec is not None:
            self._recorded(rec)
        else:
            self._emit("meter_status", translate("Meters", "reading {gauge}: {n}/{wanted} frames")
                       .format(gauge=gauge_id, n=s.attempts, wanted=s.frames_wanted))

    def snapshot_of(self, rec: MeterRecord) -> Any:
        """The frame a record was read from: the robot's JPEG when it was kept, else the
        RGB frame (the archive's writer encodes it)."""
        f = self.last_read_frame
        if f is not None and f[1] == rec.gauge_id:
            return self._read_jpeg if self._read_jpeg else f[0]
        return self.last_jpeg if self.last_jpeg else self.last_image

    # ------------------------------------------------------------ sessions
    def _start(self, gauge: str, point: Any, source: str) -> None:
        try:
            self.service.start(gauge, None if point is None else str(point), source)
        except ValueError as e:
            self._emit("log", "warning", "meter", f"meter {gauge}: {e}")
            self._emit("meter_status", str(e))
            return
        self._deadline = self._mono() + self.timeout_s
        self._emit("meter_session", gauge)
        self._emit("meter_status", translate("Meters", "reading {gauge} …").format(gauge=gauge))

    def _finish(self, gauge: str) -> None:
        rec = self.service.finish(gauge)
        if rec is not None:
            self._recorded(rec)

    def _recorded(self, rec: MeterRecord) -> None:
        self._deadline = None
        if rec.source == "operator":
            self._send("look_at", {"gauge": None})
        self._emit("meter_session", None)
        if rec.state == NO_READING:
            self._emit("meter_status", translate("Meters", "{gauge}: no reading ({why})").format(
                gauge=rec.gauge_id, why=rec.reason))
            self._emit("log", "warning", "meter", translate(
                "Meters", "meter {gauge}: no reading ({why})").format(gauge=rec.gauge_id,
                                                                      why=rec.reason))
        else:
            value, conf = f"{rec.value:.4g}", f"{rec.confidence:.2f}"
            self._emit("meter_status", translate(
                "Meters", "{gauge}: {value} {unit} (confidence {conf})").format(
                gauge=rec.gauge_id, value=value, unit=rec.unit, conf=conf))
            self._emit("log", "info", "meter", translate(
                "Meters", "meter {gauge} at {point}: {value} {unit}, {state} (confidence {conf})"
            ).format(gauge=rec.gauge_id, point=rec.point, value=value, unit=rec.unit,
                     state=translate("MeterState", rec.state), conf=conf))
        self._emit("meter_record", rec)
        if rec.value is not None:
            self._check_alarm(rec)

    def _check_alarm(self, rec: MeterRecord) -> None:
        channel = meter_channel(rec.gauge_id)
        if self.monitor.rule(channel) is None:
            rule = self.service.alarm_rule(rec.gauge_id)
            if rule is None:
                return
            self.monitor.set_rule(rule)
        self.monitor.update(channel, rec.value, rec.t)  # transitions reach the listeners
