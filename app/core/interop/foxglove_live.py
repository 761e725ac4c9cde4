"""The live desk over the Foxglove WebSocket protocol (no Qt).

A thin adapter: it listens to the desk pipeline (the one the window and the headless
desk run) and logs each message on a ``foxglove-sdk`` channel of its own
``foxglove.Context``; the SDK's server (``foxglove.start_server``) speaks the
protocol, so nothing of it is written here. Topics and schemas are the MCAP export's
(:mod:`app.core.records.mcap_export`), plus what the archive does not keep:

==============  ============================  =====================================
/telemetry      station_patrol.Telemetry      every telemetry message (JSON)
/pose, /tf      foxglove.PoseInFrame,         the robot's pose; ``map`` -> ``base_link``
                foxglove.FrameTransform
/scan           foxglove.LaserScan            the lidar (frame ``base_link``)
/map            foxglove.Grid                 the occupancy map when it arrives
/path/global    foxglove.PosesInFrame         the global plan
/camera         foxglove.CompressedImage      the robot's JPEG frames as received
/events         foxglove.Log                  robot events and link states
/alarms         foxglove.Log                  alarm transitions
==============  ============================  =====================================

The server binds to loopback unless told otherwise (``host``); a late client gets
the newest map, because the server is started with no backlog of past messages
and the map is sent again to each new subscriber of ``/map``.
Messages are logged on the pipeline's thread; the SDK serialises and sends them on
its own threads, so a slow client never holds up the desk.
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from app.core.records import mcap_export as fx

log = logging.getLogger(__name__)

DEFAULT_PORT = 8765


class FoxgloveLive:
    """Serve ``pipeline``'s live data on ``host:port`` (port 0: any free port; see
    :attr:`port`). ``clock``: UTC epoch seconds for messages without a time of their own."""

    def __init__(self, pipeline: Any, port: int = DEFAULT_PORT, host: str = "127.0.0.1", *,
                 name: str = "station-patrol desk",
                 clock: Callable[[], float] = time.time) -> None:
        import foxglove
        from foxglove import channels as fc
        from foxglove.websocket import ServerListener

        self.pipeline = pipeline
        self._clock = clock
        self.sent = 0
        self._map: Any = None
        self._ctx = ctx = foxglove.Context()  # the server and channels live while it does
        self._ch = {
            "/telemetry": fx.json_channel("/telemetry", fx.TELEMETRY_SCHEMA,
                                          fx.telemetry_schema(self._channel_names()), ctx),
            "/pose": fc.PoseInFrameChannel("/pose", context=ctx),
            "/tf": fc.FrameTransformChannel("/tf", context=ctx),
            "/scan": fc.LaserScanChannel("/scan", context=ctx),
            "/map": fc.GridChannel("/map", context=ctx),
            "/path/global": fc.PosesInFrameChannel("/path/global", context=ctx),
            "/camera": fc.CompressedImageChannel("/camera", context=ctx),
            "/events": fc.LogChannel("/events", context=ctx),
            "/alarms": fc.LogChannel("/alarms", context=ctx),
        }
        live = self

        class _Listener(ServerListener):
            def on_subscribe(self, client: Any, channel: Any) -> None:
                if channel.topic == "/map" and live._map is not None:
                    live._log("/map", live._map[1], live._map[0])

        self.server = foxglove.start_server(name=name, host=host, port=int(port),
                                            context=ctx, server_listener=_Listener())
        self._subs = [("values", self._on_values), ("pose", self._on_pose),
                      ("scan", self._on_scan), ("map", self._on_map),
                      ("path", self._on_path), ("frame", self._on_frame),
                      ("event", self._on_event), ("link_state", self._on_link_state),
                      ("alarm", self._on_alarm)]
        for kind, fn in self._subs:
            pipeline.listen(kind, fn)
        log.info("Foxglove WebSocket server on ws://%s:%d", host, self.port)

    @property
    def port(self) -> int:
        return int(self.server.port)

    def close(self) -> None:
        for kind, fn in self._subs:
            self.pipeline.unlisten(kind, fn)
        self.server.stop()

    # ------------------------------------------------------------ adapters
    def _channel_names(self) -> list[str]:
        from app.core.desk.channels import TELEMETRY_CHANNELS

        return [c.key for c in TELEMETRY_CHANNELS]

    def _log(self, topic: str, msg: Any, t: float) -> None:
        self._ch[topic].log(msg, log_time=round(t * 1e9))
        self.sent += 1

    def _on_values(self, values: dict) -> None:
        t = self.pipeline.latest_t
        t = self._clock() if t is None else t
        d = {k: (v if math.isfinite(v) else None) for k, v in values.items()}
        self._log("/telemetry", json.dumps(d).encode(), t)

    def _on_pose(self, p: Any) -> None:
        t = self._clock()
        x, y, th = float(p.x_m), float(p.y_m), float(p.theta_rad)
        self._log("/pose", fx.pose_in_frame(t, x, y, th), t)
        self._log("/tf", fx.frame_transform(t, x, y, th), t)

    def _on_scan(self, s: Any) -> None:
        t = self._clock()
        self._log("/scan", fx.laser_scan(t, s.ranges_m, s.angle_min_rad,
                                         s.angle_increment_rad), t)

    def _on_map(self, m: Any) -> None:
        import cv2

        img = cv2.imdecode(np.frombuffer(m.png, np.uint8), cv2.IMREAD_GRAYSCALE)
        if img is None:
            log.warning("map not sent to Foxglove: unreadable PNG")
            return
        t = self._clock()
        grid = fx.occupancy_grid(t, img, float(m.resolution_m), float(m.origin_x_m),
                                 float(m.origin_y_m))
        self._map = (t, grid)
        self._log("/map", grid, t)

    def _on_path(self, p: Any) -> None:
        if p.kind != 0:  # the global plan only, as the archive keeps it
            return
        t = self._clock()
        self._log("/path/global", fx.poses_in_frame(t, p.points_xy), t)

    def _on_frame(self, frame: Any) -> None:
        jpeg = getattr(frame, "jpeg", None)
        if jpeg:
            t = self._clock()
            self._log("/camera", fx.jpeg_image(t, jpeg, "camera"), t)

    def _on_event(self, ev: Any) -> None:
        t = self._clock()
        level = str(ev.level).lower()
        self._log("/events", fx.log_message(t, level, str(ev.code),
                                            f"{ev.text} {json.dumps(ev.data, default=str)}"), t)

    def _on_link_state(self, state: str) -> None:
        t = self._clock()
        self._log("/events", fx.log_message(t, "warning" if state in ("lost", "reconnecting")
                                            else "info", "link_state", state), t)

    def _on_alarm(self, tr: Any) -> None:
        rec = tr.as_record()
        t = float(rec.get("t") or self._clock())
        self._log("/alarms", fx.alarm_log(t, rec), t)
