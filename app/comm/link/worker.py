"""The robot link's worker: lives on the link thread and owns the socket.

It opens and reopens the connection (the states and the silence watchdog of
:mod:`app.comm.link`), decodes the frames, turns them into signals, sends the
heartbeat, the signed commands in their encoding order and the held drive
command, and keeps the link's statistics. :class:`~app.comm.link.RobotLink` is
its facade on the GUI thread.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque

from PySide6.QtCore import QTimer, Signal, Slot
from PySide6.QtNetwork import QAbstractSocket, QTcpSocket

from app.comm import auth
from app.comm import protocol as P
from app.comm.settings import LinkSettings
from app.core.video import DecodedFrame, LatestFrame, decode_jpeg_rgb

from .signals import ControlState, LinkSignals, LinkStats

log = logging.getLogger("app.comm.link")  # one logger for the link, as before the split


class _Stamp:
    __slots__ = ("t",)

    def __init__(self) -> None:
        self.t = time.monotonic()


class _LinkWorker(LinkSignals):
    """Lives on the link thread; owns the socket."""

    frame_waiting = Signal()  # a decoded frame waits in ``frames`` (the box was empty)

    def __init__(self, settings: LinkSettings) -> None:
        super().__init__()
        self.settings = settings
        self.sock: QTcpSocket | None = None
        self.decoder = P.FrameDecoder()
        self.encoder_lock = threading.Lock()
        self._flush_lock = threading.Lock()
        # Encoded frames wait here in the order they were sealed. A command's
        # counter is sealed when it is encoded, so frames from the GUI thread
        # and from this worker must reach the socket in encoding order, or the
        # robot would see a falling counter and refuse the later one as a replay.
        self._outbox: deque[bytes] = deque()
        self.signer: auth.CommandSigner | None = None
        try:
            key, created = auth.load_or_create_key(settings.key_file)
            self.signer = auth.CommandSigner(key, settings.desk_name)
            log.info("commands signed as %s with the station key %s%s", self.signer.desk,
                     self.signer.fingerprint, " (created now)" if created else "")
        except (auth.KeyFileError, OSError) as e:
            log.error("commands go unsigned (the robot will refuse them): %s", e)
        self.encoder = P.FrameEncoder(signer=self.signer)
        # stamped by the GUI thread (RobotLink); a plain object, safe from either thread
        self.gui_alive = _Stamp()
        self.control = ControlState()
        self._last_tel_seq: int | None = None
        self.host = ""
        self.port = 0
        self.state = "disconnected"
        self.stats = LinkStats()
        if self.signer is not None:
            self.stats.key_fingerprint = self.signer.fingerprint
        self._want_open = False
        self._ever_connected = False
        self._tcp_open = False  # the socket is open; "connected" waits for a valid frame
        self._last_rx = 0.0  # monotonic
        self._peer_hb_ts_us = 0
        self._peer_hb_rx_mono = 0.0
        self._rx_times: deque[float] = deque()
        self._video_times: deque[float] = deque()
        self._video_bad = 0
        self._drive = (0.0, 0.0)
        # the newest decoded frame waits here for the GUI thread; a GUI that falls behind
        # gets the newest frame only (the older ones are dropped and counted)
        self.frames = LatestFrame()

    # ----------------------------------------------------------------- set-up
    @Slot()
    def setup(self) -> None:
        self.sock = QTcpSocket(self)
        self.sock.setSocketOption(QAbstractSocket.SocketOption.LowDelayOption, 1)
        self.sock.connected.connect(self._on_connected)
        self.sock.disconnected.connect(self._on_disconnected)
        self.sock.readyRead.connect(self._on_ready_read)
        self.sock.errorOccurred.connect(self._on_error)
        self.hb_timer = QTimer(self)
        self.hb_timer.timeout.connect(self._tick_heartbeat)
        self.hb_timer.start(int(self.settings.heartbeat_s * 1000))
        self.watch_timer = QTimer(self)
        self.watch_timer.timeout.connect(self._tick_watchdog)
        self.watch_timer.start(200)
        self.reconnect_timer = QTimer(self)
        self.reconnect_timer.setSingleShot(True)
        self.reconnect_timer.timeout.connect(self._try_connect)
        self.drive_timer = QTimer(self)
        self.drive_timer.timeout.connect(self._resend_drive)
        self.stats_timer = QTimer(self)
        self.stats_timer.timeout.connect(self._emit_stats)
        self.stats_timer.start(1000)

    def _set_state(self, state: str) -> None:
        if state != self.state:
            log.info("link %s:%s %s", self.host, self.port, state)
            self.state = state
            self.stats.state = state
            self.state_changed.emit(state)

    # ----------------------------------------------------------------- control
    @Slot(str, int)
    def open(self, host: str, port: int) -> None:
        self.host, self.port = host, port
        self._want_open = True
        self._try_connect()

    @Slot()
    def close(self) -> None:
        self._want_open = False
        self._tcp_open = False
        self.reconnect_timer.stop()
        self.drive_timer.stop()
        if self.sock is not None:
            self.sock.abort()
        self._set_state("disconnected")

    def _try_connect(self) -> None:
        if not self._want_open or self.sock is None:
            return
        self._tcp_open = False
        if self.sock.state() != QAbstractSocket.SocketState.UnconnectedState:
            self.sock.abort()
        self.decoder = P.FrameDecoder()
        self._set_state("reconnecting" if self._ever_connected else "connecting")
        self.sock.connectToHost(self.host, self.port)
        # if neither connected nor error comes in time, try again
        self.reconnect_timer.start(int(self.settings.connect_timeout_s * 1000))

    def _schedule_reconnect(self) -> None:
        if self._want_open:
            self.reconnect_timer.start(int(self.settings.reconnect_every_s * 1000))

    @Slot()
    def _on_connected(self) -> None:
        """The TCP connection is open: say hello, and wait for a valid frame before
        calling the link connected (a peer may answer with garbage only)."""
        self.reconnect_timer.stop()
        self._tcp_open = True
        self._last_rx = time.monotonic()
        self._peer_hb_ts_us = 0
        self._last_tel_seq = None
        self._tick_heartbeat()
        if self.settings.request_control:
            self._send(P.Command("request_control", {}))

    def _first_valid_frame(self) -> None:
        """The first valid frame since the connection opened: now it is a link."""
        restored = self._ever_connected
        if restored:
            self.stats.reconnects += 1
        self._ever_connected = True
        self._set_state("connected")
        if restored:
            self.link_restored.emit()

    @Slot()
    def _on_disconnected(self) -> None:
        self._tcp_open = False
        if self.state == "connected":
            self._set_state("lost")
        self._schedule_reconnect()

    @Slot(object)
    def _on_error(self, err) -> None:
        if self.sock is not None:
            self.stats.last_error = self.sock.errorString()
        if self.sock is None or self.sock.state() != QAbstractSocket.SocketState.ConnectedState:
            self._tcp_open = False
        if self.state == "connected":
            self._set_state("lost")
        unconnected = QAbstractSocket.SocketState.UnconnectedState
        if self.sock is not None and self.sock.state() == unconnected:
            self._schedule_reconnect()

    # ----------------------------------------------------------------- sending
    def encode_queued(self, msg) -> int:
        """Encode ``msg`` and queue it for sending, as one step (any thread)."""
        with self.encoder_lock:
            seq = self.encoder.seq
            self._outbox.append(self.encoder.encode(msg))
        return seq

    @Slot()
    def flush(self) -> None:
        """Write the queued frames in their encoding order (worker thread).

        A frame is taken and written under one lock, so that two flushes running
        at once can never write a later frame before an earlier one."""
        with self._flush_lock:
            while True:
                with self.encoder_lock:
                    if not self._outbox:
                        return
                    data = self._outbox.popleft()
                if self.sock is None or not (self._tcp_open or self.state == "connected"):
                    continue  # no connection: the frame is dropped, as before
                self.sock.write(data)
                self.stats.tx_frames += 1

    def _send(self, msg) -> int:
        seq = self.encode_queued(msg)
        self.flush()
        return seq

    def _tick_heartbeat(self) -> None:
        if not self._tcp_open:
            return
        hold = 0
        if self._peer_hb_ts_us:
            hold = int((time.monotonic() - self._peer_hb_rx_mono) * 1e6)
        self._send(P.Heartbeat(P.Heartbeat.ROLE_DESK, self._peer_hb_ts_us, hold,
                               self.stats.rx_frames))

    @Slot(float, float)
    def set_drive(self, linear_mps: float, angular_rps: float) -> None:
        self._drive = (linear_mps, angular_rps)
        moving = linear_mps != 0.0 or angular_rps != 0.0
        self._send(P.Command("drive" if moving else "stop",
                             {"linear_mps": linear_mps, "angular_rps": angular_rps}
                             if moving else {}))
        if moving:
            self.drive_timer.start(int(self.settings.drive_resend_s * 1000))
        else:
            self.drive_timer.stop()

    def _resend_drive(self) -> None:
        lin, ang = self._drive
        if time.monotonic() - self.gui_alive.t > self.settings.gui_alive_s:
            return  # the window is frozen: let the robot's deadman stop it
        if lin or ang:
            self._send(P.Command("drive", {"linear_mps": lin, "angular_rps": ang}))

    # ----------------------------------------------------------------- receiving
    def _on_ready_read(self) -> None:
        if self.sock is None:
            return
        data = self.sock.readAll().data()
        if not data:
            return
        now = time.monotonic()
        for fr in self.decoder.feed(data):
            self._last_rx = now  # only a valid frame shows the peer is alive
            if self.state != "connected" and self._tcp_open:
                self._first_valid_frame()
            self.stats.rx_frames += 1
            self._rx_times.append(now)
            self._dispatch(fr, now)

    def _dispatch(self, fr: P.Frame, now: float) -> None:
        m = fr.message
        t = fr.msg_type
        if t == P.MsgType.TELEMETRY:
            m.received_s = time.time()
            m.seq = fr.seq
            self._count_tel_seq(m.tel_seq)
            self.telemetry_received.emit(m)
        elif t == P.MsgType.VIDEO_FRAME:
            img = decode_jpeg_rgb(m.jpeg)
            if img is None:
                self._video_bad += 1
                self.stats.last_error = f"video frame {m.frame_id} did not decode"
                return
            self._video_times.append(now)
            lat = (P.now_us() - m.capture_ts_us) / 1000.0
            frame = DecodedFrame(m.frame_id, m.capture_ts_us, img, lat, img.shape[1],
                                 img.shape[0], m.camera_pan_rad, jpeg=bytes(m.jpeg))
            if self.frames.put(frame):
                self.frame_waiting.emit()
        elif t == P.MsgType.POSE:
            self.pose_received.emit(m)
        elif t == P.MsgType.LIDAR_SCAN:
            self.scan_received.emit(m)
        elif t == P.MsgType.EVENT:
            self._note_event(m)
            self.event_received.emit(m)
        elif t == P.MsgType.COMMAND_ACK:
            self.ack_received.emit(m)
        elif t == P.MsgType.MAP:
            self.map_received.emit(m)
        elif t == P.MsgType.PATH:
            self.path_received.emit(m)
        elif t == P.MsgType.PATROL_STATUS:
            self.patrol_status_received.emit(m)
        elif t == P.MsgType.OBSTACLES:
            self.obstacles_received.emit(m)
        elif t in P.WALL_TYPES:
            self.wall_received.emit(m)
        elif t in P.FWS_TYPES:
            self.fws_received.emit(m)
        elif t == P.MsgType.HEARTBEAT:
            self._peer_hb_ts_us = fr.timestamp_us
            self._peer_hb_rx_mono = now
            if m.echo_ts_us:
                rtt = (P.now_us() - m.echo_ts_us - m.echo_hold_us) / 1000.0
                if 0 <= rtt < 60_000:
                    self.stats.rtt_ms = rtt

    def _count_tel_seq(self, s: int) -> None:
        if not s:  # a robot that does not number its telemetry
            return
        last = self._last_tel_seq
        if last is not None:
            d = (s - last) & 0xFFFFFFFF
            if d == 0 or d >= 1 << 31:
                self.stats.telemetry_reordered += 1
                return
            self.stats.telemetry_lost += d - 1
        self._last_tel_seq = s

    def _note_event(self, ev: P.Event) -> None:
        data = ev.data if isinstance(ev.data, dict) else {}
        counts = data.get("counts")
        if isinstance(counts, dict):
            self.stats.robot_rejections = {str(k): int(v) for k, v in counts.items()
                                           if isinstance(v, int)}
        if ev.code == "lease":
            holder = data.get("holder")
            mine = (self.signer is not None and holder is not None
                    and data.get("holder_session") == self.signer.session)
            self.control = ControlState(holder if isinstance(holder, str) else None,
                                        bool(mine), data.get("requested_by"), ev.text)
            self.control_changed.emit(self.control)
        elif ev.code == "control_requested" and self.control.mine:
            self.control = ControlState(self.control.holder, True, data.get("by"), ev.text)
            self.control_changed.emit(self.control)

    # ----------------------------------------------------------------- health
    def _tick_watchdog(self) -> None:
        if not self._tcp_open or \
                time.monotonic() - self._last_rx <= self.settings.lost_after_s:
            return
        why = self.decoder.last_error
        self.stats.last_error = (f"no valid frame for {self.settings.lost_after_s:g} s"
                                 + ("" if self.state == "connected" else " after connecting")
                                 + (f" ({why})" if why else ""))
        self._tcp_open = False
        if self.state == "connected":
            self._set_state("lost")
        else:
            log.warning("link %s:%s: %s; trying again", self.host, self.port,
                        self.stats.last_error)
        if self.sock is not None:
            self.sock.abort()
        self._schedule_reconnect()

    def _emit_stats(self) -> None:
        now = time.monotonic()
        for q in (self._rx_times, self._video_times):
            while q and now - q[0] > 1.0:
                q.popleft()
        s = self.stats
        s.msgs_per_s = float(len(self._rx_times))
        s.video_fps = float(len(self._video_times))
        d = self.decoder.stats
        s.by_reason = {k: v for k, v in d.as_dict().items()
                       if k not in ("frames", "bytes_in", "dropped")}
        s.by_reason["video_undecodable"] = self._video_bad
        s.frames_dropped = d.dropped + self._video_bad
        s.video_stale_dropped = self.frames.dropped
        s.last_error = s.last_error or self.decoder.last_error
        self.stats_changed.emit(LinkStats(**{**s.__dict__, "by_reason": dict(s.by_reason),
                                             "robot_rejections": dict(s.robot_rejections)}))
