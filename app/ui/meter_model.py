"""MeterModel: reads the meter the camera is on, off the GUI thread, and records the result.

It listens to the link: robot events ``inspection_started`` / ``inspection_done``
(``{point, gauge}``) open and close a reading session, and while a session is open each
decoded frame is read by :func:`app.core.meter_service.read_frame` on a one-thread pool.
A frame that arrives while the worker is busy is dropped (counted in ``frames_dropped``),
so nothing queues.  The operator can also ask for a reading (:meth:`request_read`): the
model sends ``look_at`` {gauge}, reads, and sends ``look_at`` {null} when done.

Fused records go to ``record_added``; a record outside the profile's normal band raises an
alarm on channel ``meter.<gauge id>`` through the telemetry model's alarm monitor (so the
window's alarm list and banner show it).  The found dial, pointer and value are offered as
image overlays (``overlays_changed``) for the video view.
"""

from __future__ import annotations

import functools
import logging
import math
import time
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, QThreadPool, QTimer, Signal

from app.core.alarms import AlarmMonitor
from app.core.meter import Reading
from app.core.meter_service import (
    NO_READING,
    OUT_OF_BAND,
    MeterRecord,
    MeterService,
    meter_channel,
    read_frame,
)
from app.ui.models import _GuardedModel, guarded
from app.widgets import OverlayLine, OverlayText

__all__ = ["MeterModel", "reading_overlays"]

log = logging.getLogger(__name__)

OK_COLOR = "#3ddc84"
BAD_COLOR = "#ffb000"
PIVOT_COLOR = "#00e5ff"
ENDS_COLOR = "#ff52d9"
MARK_PX = 6.0


def reading_overlays(reading: Reading, label: str = "") -> list:
    """Overlays for one reading, in the frame's pixel coordinates: the dial's ellipse (as
    36 segments) when one was found, the pivot (a cross), the scale's two end marks (carried
    over from the reference frame for a calibrated point: min and max), the needle from the
    pivot to its tip, and a caption with the value and how it was read."""
    out: list = []
    color = OK_COLOR if reading.value is not None else BAD_COLOR
    e = reading.dial_ellipse
    if e is not None:
        cx, cy, w, h, ang = (float(v) for v in e)
        ca, sa = math.cos(math.radians(ang)), math.sin(math.radians(ang))
        pts = []
        for k in range(37):
            t = 2 * math.pi * k / 36
            x, y = w / 2 * math.cos(t), h / 2 * math.sin(t)
            pts.append((cx + x * ca - y * sa, cy + x * sa + y * ca))
        out += [OverlayLine(*p, *q, color=color) for p, q in zip(pts, pts[1:], strict=False)]
    pivot = reading.dial_centre_xy
    if pivot is not None:
        px, py = (float(v) for v in pivot)
        out += [OverlayLine(px - MARK_PX, py, px + MARK_PX, py, color=PIVOT_COLOR),
                OverlayLine(px, py - MARK_PX, px, py + MARK_PX, color=PIVOT_COLOR)]
    if reading.scale_ends_xy is not None:
        for (x, y), name in zip(reading.scale_ends_xy, ("min", "max"), strict=False):
            x, y = float(x), float(y)
            out += [OverlayLine(x - MARK_PX, y - MARK_PX, x + MARK_PX, y + MARK_PX,
                                color=ENDS_COLOR),
                    OverlayLine(x - MARK_PX, y + MARK_PX, x + MARK_PX, y - MARK_PX,
                                color=ENDS_COLOR),
                    OverlayText(x + MARK_PX, y + 2 * MARK_PX, name, color=ENDS_COLOR)]
            if pivot is not None:  # the scale's ends as spokes from the pivot
                out.append(OverlayLine(px, py, x, y, color=ENDS_COLOR))
    if reading.pointer_line_xy is not None:
        (x0, y0), (x1, y1) = reading.pointer_line_xy
        out.append(OverlayLine(x0, y0, x1, y1, color=color))
    if reading.value is not None:
        txt = f"{label} {reading.value:.3g} {reading.unit}  ({reading.confidence:.2f})"
    else:
        txt = f"{label} no reading: {reading.error}"
    method = getattr(reading, "method", None)
    if method and method != "scale":
        txt += f"  [{method}]"
    if e is not None:
        out.append(OverlayText(e[0] - e[2] / 2, max(14.0, e[1] - e[3] / 2 - 8), txt.strip(),
                               color=color))
    elif pivot is not None:
        out.append(OverlayText(max(4.0, px - 60.0), max(14.0, py - 80.0), txt.strip(),
                               color=color))
    return out


class _Emitter(QObject):
    """Carries a worker's result back to the GUI thread (queued)."""

    done = Signal(object)


class MeterModel(_GuardedModel):
    """State between the link, the meter reader and the meter panel."""

    record_added = Signal(object)  # MeterRecord
    reading_ready = Signal(str, object)  # gauge id, Reading (one frame)
    overlays_changed = Signal(list)  # overlays for the video view ([] clears)
    status_changed = Signal(str)
    session_changed = Signal(object)  # gauge id being read, or None
    alarm_raised = Signal(object)  # core.alarms.Alarm
    alarm_cleared = Signal(object)
    log_line = Signal(str, str)  # level, text (for the event log)

    def __init__(self, link: Any = None, telemetry_model: Any = None, *,
                 service: MeterService | None = None, timeout_s: float = 12.0,
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.link = link
        self.telemetry_model = telemetry_model
        self.service = service if service is not None else MeterService()
        self.monitor = (telemetry_model.monitor if telemetry_model is not None
                        else AlarmMonitor(()))
        self.pool = QThreadPool(self)
        self.pool.setMaxThreadCount(1)
        self._emitter = _Emitter()
        self._emitter.done.connect(self._on_result)
        self.busy = False
        self.frames_seen = 0
        self.frames_read = 0
        self.frames_dropped = 0
        self.last_image = None  # the newest frame's RGB image (for calibration)
        self.last_point: tuple[str, str] | None = None  # (point, gauge) last inspected
        # the frame behind the latest reading: (RGB image, gauge id, point, monotonic time)
        self.last_read_frame: tuple[np.ndarray, str, str, float] | None = None
        self._token = 0
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(int(timeout_s * 1000))
        self._timer.timeout.connect(self._on_timeout)
        if link is not None:
            link.frame_decoded.connect(self.on_frame)
            link.event_received.connect(self.on_event)

    # ------------------------------------------------------------ queries
    def gauge_ids(self) -> list[str]:
        return sorted(self.service.gauges)

    def current_gauge(self) -> str | None:
        s = self.service.session
        return None if s is None else s.gauge_id

    def records(self) -> list[MeterRecord]:
        return list(self.service.records)

    def calibration_frame(self, recent_s: float = 60.0) -> tuple[np.ndarray | None, str | None]:
        """The frame to calibrate on, and the point it shows: the frame of the latest good
        reading when it is recent (the camera was on a gauge), else the live frame."""
        f = self.last_read_frame
        if f is not None and time.monotonic() - f[3] <= recent_s:
            return f[0], f[2]
        return self.last_image, None

    # ------------------------------------------------------------ inputs
    @guarded
    def on_event(self, ev: Any) -> None:
        """Slot for ``RobotLink.event_received``."""
        code = str(getattr(ev, "code", ""))
        if code not in ("inspection_started", "inspection_done"):
            return
        data = getattr(ev, "data", None) or {}
        gauge = data.get("gauge")
        if gauge is None:
            return  # an inspection without a meter (a tank wall, a valve): nothing to read
        gauge = str(gauge)
        if gauge not in self.service.gauges:
            self.log_line.emit("warning", f"{code}: gauge {gauge} is not in the station "
                               "configuration; not read")
            return
        if code == "inspection_started":
            if data.get("point") is not None:
                self.last_point = (str(data["point"]), gauge)
            self._start(gauge, data.get("point"), "patrol")
        else:
            self._finish(gauge)

    def request_read(self, gauge_id: str, point: str | None = None) -> None:
        """The operator's "Read meter": aim the head at the gauge and read it (with the
        calibrated profile of the route's ``point`` when it has one)."""
        try:
            self.service.profile_for(gauge_id, point)
        except ValueError as e:
            self.status_changed.emit(str(e))
            self.log_line.emit("warning", str(e))
            return
        self._send_look_at(gauge_id)
        self._start(gauge_id, point, "operator")

    def set_route(self, route_path) -> None:
        """Make a route file the active one for calibrated point profiles (None: none)."""
        why = self.service.set_route(route_path)
        if why is not None:
            self.status_changed.emit(f"route not used for meter profiles: {why}")
            self.log_line.emit("warning", f"route not used for meter profiles: {why}")

    def reload_route(self) -> None:
        """Re-read the active route (after a point was calibrated)."""
        self.set_route(self.service.route_path)

    def cancel(self) -> None:
        s = self.service.session
        if s is not None:
            self._finish(s.gauge_id)

    def on_frame(self, frame: Any) -> None:
        """Slot for ``RobotLink.frame_decoded``: hand the frame to the worker, or drop it.
        A malformed frame is skipped here without counting: the video model counts it."""
        image = getattr(frame, "image", None)
        if not (isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.ndim == 3
                and image.shape[2] == 3 and image.size):
            return
        self.frames_seen += 1
        self.last_image = image
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
        job = functools.partial(_work, self._emitter, self._token, s.gauge_id, image,
                                s.profile)
        self.pool.start(job)

    # ------------------------------------------------------------ worker results
    def _on_result(self, res: tuple) -> None:
        token, gauge_id, reading, image = res
        if token == self._token:
            self.busy = False
        self.frames_read += 1
        s = self.service.session
        if s is None or s.gauge_id != gauge_id:
            return  # the session ended while this frame was read
        if reading.value is not None:
            self.last_read_frame = (image, gauge_id, s.point, time.monotonic())
        self.reading_ready.emit(gauge_id, reading)
        self.overlays_changed.emit(reading_overlays(reading, gauge_id))
        rec = self.service.add(gauge_id, reading)
        if rec is not None:
            self._recorded(rec)
        else:
            self.status_changed.emit(f"reading {gauge_id}: {s.attempts}/{s.frames_wanted} "
                                     f"frames")

    # ------------------------------------------------------------ sessions
    def _start(self, gauge: str, point: Any, source: str) -> None:
        try:
            self.service.start(gauge, None if point is None else str(point), source)
        except ValueError as e:
            self.log_line.emit("warning", f"meter {gauge}: {e}")
            self.status_changed.emit(str(e))
            return
        self._timer.start()
        self.session_changed.emit(gauge)
        self.status_changed.emit(f"reading {gauge} …")

    def _finish(self, gauge: str) -> None:
        rec = self.service.finish(gauge)
        if rec is not None:
            self._recorded(rec)

    def _on_timeout(self) -> None:
        s = self.service.session
        if s is not None:
            self._finish(s.gauge_id)

    def _recorded(self, rec: MeterRecord) -> None:
        self._timer.stop()
        if rec.source == "operator":
            self._send_look_at(None)
        self.overlays_changed.emit([])
        self.session_changed.emit(None)
        if rec.state == NO_READING:
            self.status_changed.emit(f"{rec.gauge_id}: no reading ({rec.reason})")
            self.log_line.emit("warning", f"meter {rec.gauge_id}: no reading ({rec.reason})")
        else:
            self.status_changed.emit(f"{rec.gauge_id}: {rec.value:.4g} {rec.unit} "
                                     f"(confidence {rec.confidence:.2f})")
            self.log_line.emit("info", f"meter {rec.gauge_id} at {rec.point}: "
                               f"{rec.value:.4g} {rec.unit}, {rec.state} "
                               f"(confidence {rec.confidence:.2f})")
        self.record_added.emit(rec)
        if rec.value is not None:
            self._check_alarm(rec)

    def _check_alarm(self, rec: MeterRecord) -> None:
        channel = meter_channel(rec.gauge_id)
        if self.monitor.rule(channel) is None:
            rule = self.service.alarm_rule(rec.gauge_id)
            if rule is None:
                return
            self.monitor.set_rule(rule)
        # the telemetry model hears every transition through its monitor listener
        for c in self.monitor.update(channel, rec.value, rec.t):
            if c.raised:
                self.alarm_raised.emit(c.alarm)
            elif c.cleared:
                self.alarm_cleared.emit(c.alarm)
        if rec.state == OUT_OF_BAND:
            log.info("meter %s out of band: %s %s", rec.gauge_id, rec.value, rec.unit)

    def _send_look_at(self, gauge: str | None) -> None:
        if self.link is None:
            return
        try:
            self.link.send_command("look_at", {"gauge": gauge})
        except Exception:  # a failing link must not take the desk down
            log.exception("look_at could not be sent")
            self.status_changed.emit("could not send look_at")

    # ------------------------------------------------------------ lifecycle
    def wait_idle(self, timeout_ms: int = 5000) -> bool:
        """Wait for the worker to finish its frame (tests, shutdown)."""
        return self.pool.waitForDone(timeout_ms)


def _work(emitter: _Emitter, token: int, gauge_id: str, image, profile) -> None:
    """Runs on the pool's thread: read one frame, send the result back."""
    reading = read_frame(image, profile)
    emitter.done.emit((token, gauge_id, reading, image))
