"""MeterModel: the meter panel's Qt view of the desk pipeline's meter sessions.

The sessions themselves (which gauge the camera is on, which frames to read, fusion,
records, the out-of-band alarm) are :class:`app.core.desk.meters.DeskMeters`, run by the
desk pipeline; the frames are read on the desk session's one-thread pool. This model
turns the pipeline's meter listeners into signals (``record_added``, ``reading_ready``,
``status_changed``, ``session_changed``, ``log_line``), offers the found dial, pointer
and value as image overlays (``overlays_changed``) for the video view, and passes the
operator's requests (read a meter, the route with calibrated points) to the pipeline.
"""

from __future__ import annotations

import functools
import logging
import math
import time
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, Signal

from app.core.i18n import translate
from app.core.meter import Reading
from app.core.meter_service import MeterRecord, meter_channel, prepare_references
from app.ui.models import _GuardedModel
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
        txt = translate("MeterModel", "{label} no reading: {why}").format(label=label,
                                                                          why=reading.error)
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


class MeterModel(_GuardedModel):
    """State between the desk pipeline's meters and the meter panel. ``desk``: the
    DeskSession (app/session.py) whose pipeline and worker pool it shows."""

    record_added = Signal(object)  # MeterRecord
    reading_ready = Signal(str, object)  # gauge id, Reading (one frame)
    overlays_changed = Signal(list)  # overlays for the video view ([] clears)
    status_changed = Signal(str)
    session_changed = Signal(object)  # gauge id being read, or None
    alarm_raised = Signal(object)  # core.alarms.Alarm (a meter's channel)
    alarm_cleared = Signal(object)
    log_line = Signal(str, str)  # level, text (for the event log)

    def __init__(self, desk: Any, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.desk = desk
        self.pool = desk.pool
        p = desk.pipeline
        self.meters = p.meters
        self.service = p.meters.service
        p.listen("meter_reading", self._on_reading)
        p.listen("meter_record", self.record_added.emit)
        p.listen("meter_status", self.status_changed.emit)
        p.listen("meter_session", self._on_session)
        p.listen("log", self._on_log)
        p.listen("alarm", self._on_alarm)

    # ------------------------------------------------------------ queries
    @property
    def busy(self) -> bool:
        return self.meters.busy

    @property
    def frames_read(self) -> int:
        return self.meters.frames_read

    @property
    def frames_dropped(self) -> int:
        return self.meters.frames_dropped

    @property
    def frames_seen(self) -> int:
        return self.meters.frames_seen

    @property
    def last_image(self) -> np.ndarray | None:
        return self.meters.last_image

    @property
    def last_point(self) -> tuple[str, str] | None:
        return self.meters.last_point

    @property
    def last_read_frame(self) -> tuple | None:
        return self.meters.last_read_frame

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
        f = self.meters.last_read_frame
        if f is not None and time.monotonic() - f[3] <= recent_s:
            return f[0], f[2]
        return self.meters.last_image, None

    # ------------------------------------------------------------ the operator's requests
    def request_read(self, gauge_id: str, point: str | None = None) -> None:
        """The operator's "Read meter": aim the head at the gauge and read it."""
        self.meters.request_read(gauge_id, point)

    def set_route(self, route_path) -> None:
        """Make a route file the active one for calibrated point profiles (None: none)."""
        why = self.service.set_route(route_path)
        if why is not None:
            text = self.tr("route not used for meter profiles: {why}").format(why=why)
            self.status_changed.emit(text)
            self.log_line.emit("warning", text)
            return
        # the calibrated points' reference frames measured now on the worker, not on
        # each point's first frame of the patrol
        profs = self.service.route_profiles()
        if profs:
            self.desk.jobs.start(functools.partial(prepare_references, profs),
                                 self._references_prepared)

    def _references_prepared(self, whys: list) -> None:
        failed = [w for w in whys if w is not None]
        self.service.references_failed(failed)
        for w in failed:
            self.log_line.emit("warning", self.tr("reference not prepared: {why}").format(why=w))

    def reload_route(self) -> None:
        """Re-read the active route (after a point was calibrated)."""
        self.set_route(self.service.route_path)

    def cancel(self) -> None:
        self.meters.cancel()

    def wait_idle(self, timeout_ms: int = 5000) -> bool:
        """Wait for the worker to finish its frame (tests, shutdown)."""
        return self.desk.wait_idle(timeout_ms)

    # ------------------------------------------------------------ pipeline -> signals
    def _on_reading(self, gauge_id: str, reading: Reading) -> None:
        self.reading_ready.emit(gauge_id, reading)
        self.overlays_changed.emit(reading_overlays(reading, gauge_id))

    def _on_session(self, gauge: str | None) -> None:
        if gauge is None:
            self.overlays_changed.emit([])
        self.session_changed.emit(gauge)

    def _on_log(self, level: str, source: str, text: str) -> None:
        if source == "meter":
            self.log_line.emit(level, text)

    def _on_alarm(self, tr: Any) -> None:
        if not str(tr.alarm.key).startswith(meter_channel("")):
            return
        if tr.raised:
            self.alarm_raised.emit(tr.alarm)
        elif tr.cleared:
            self.alarm_cleared.emit(tr.alarm)
