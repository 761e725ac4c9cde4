"""RobotLink: the desk's end of the robot link, on QtNetwork.

The socket, the decoder, heartbeats, reconnection and JPEG decoding run in a
worker on their own thread; :class:`RobotLink` is the facade the GUI thread
uses. Everything reaches the views as Qt signals named for what happened.

States: ``disconnected`` → ``connecting`` → ``connected``; on a closed socket
or 3 s without a valid frame → ``lost``, then ``reconnecting`` until the robot
answers. Only a frame that decodes (length, checksum) refreshes the watchdog: a
peer that sends nothing but garbage is as lost as a silent one (as QGC counts
only valid MAVLink frames). An open TCP connection is not yet a link: the state
becomes ``connected`` (and ``link_restored`` fires) with the first valid frame
after it opened. Until then the link says hello (heartbeat, control request)
but stays ``connecting``/``reconnecting``, and a peer that sends no valid frame
within the silence limit is dropped and tried again, never shown connected.

Every command is signed with the station key (:mod:`app.comm.auth`). On
connecting the link asks for the control lease; ``control_changed`` tells
whether this desk holds it. A held drive command is renewed every 200 ms only
while the GUI thread is alive: a frozen window stops renewing, and the robot's
0.5 s deadman stops it. Telemetry sequence numbers show lost and reordered
samples; the robot's refusal counts arrive in its events.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from dataclasses import dataclass, field

from PySide6.QtCore import QObject, QThread, QTimer, Signal, Slot
from PySide6.QtNetwork import QAbstractSocket, QTcpSocket

from app.comm import auth
from app.comm import protocol as P
from app.comm.settings import LinkSettings
from app.core.video import DecodedFrame, LatestFrame, decode_jpeg_rgb

log = logging.getLogger(__name__)


@dataclass
class LinkStats:
    state: str = "disconnected"
    rtt_ms: float | None = None
    frames_dropped: int = 0  # decoder drops + video frames that did not decode
    msgs_per_s: float = 0.0
    video_fps: float = 0.0
    reconnects: int = 0
    rx_frames: int = 0
    tx_frames: int = 0
    last_error: str = ""
    by_reason: dict[str, int] = field(default_factory=dict)
    video_stale_dropped: int = 0  # decoded frames replaced before the GUI took them
    telemetry_lost: int = 0  # gaps in the robot's telemetry counter while connected
    telemetry_reordered: int = 0  # samples that came late or twice
    robot_rejections: dict[str, int] = field(default_factory=dict)  # the robot's counts
    key_fingerprint: str = ""


@dataclass
class ControlState:
    """Who holds the robot's control lease, as the robot last said."""

    holder: str | None = None  # desk name, None when control is free
    mine: bool = False
    requested_by: str | None = None
    text: str = ""

    @property
    def view_only(self) -> bool:
        return self.holder is not None and not self.mine


class LinkSignals(QObject):
    """What a link reports, named for what happened."""

    state_changed = Signal(str)
    telemetry_received = Signal(object)
    pose_received = Signal(object)
    scan_received = Signal(object)
    event_received = Signal(object)
    ack_received = Signal(object)
    frame_decoded = Signal(object)
    stats_changed = Signal(object)
    link_restored = Signal()
    map_received = Signal(object)  # protocol.MapImage
    path_received = Signal(object)  # protocol.Path
    patrol_status_received = Signal(object)  # protocol.PatrolStatus
    obstacles_received = Signal(object)  # protocol.Obstacles
    control_changed = Signal(object)  # ControlState
    wall_received = Signal(object)  # a wall climber's message (app/comm/wall_protocol.py)

    RELAYED = ("state_changed", "telemetry_received", "pose_received", "scan_received",
               "event_received", "ack_received", "frame_decoded", "stats_changed",
               "link_restored", "map_received", "path_received", "patrol_status_received",
               "obstacles_received", "control_changed", "wall_received")


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
        """Write the queued frames in their encoding order (worker thread)."""
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


class RobotLink(LinkSignals):
    """The desk's connection to one robot. Methods are safe to call from the GUI
    thread; the work happens on the link thread."""

    _open = Signal(str, int)
    _close = Signal()
    _flush = Signal()
    _set_drive = Signal(float, float)

    def __init__(self, settings: LinkSettings | None = None, parent: QObject | None = None):
        super().__init__(parent)
        self.settings = settings or LinkSettings()
        self._thread = QThread()
        self._thread.setObjectName("robot-link")
        self._worker = _LinkWorker(self.settings)
        self._worker.moveToThread(self._thread)
        self._thread.started.connect(self._worker.setup)
        # the worker, its socket and timers are deleted on their own thread
        self._thread.finished.connect(self._worker.deleteLater)
        w = self._worker
        for name in self.RELAYED:
            if name != "frame_decoded":  # frames come through the newest-frame box
                getattr(w, name).connect(getattr(self, name))
        w.frame_waiting.connect(self._take_frame)
        self._open.connect(w.open)
        self._close.connect(w.close)
        self._flush.connect(w.flush)
        self._set_drive.connect(w.set_drive)
        self.state = "disconnected"
        self.address = ""  # "host:port" once connect_to was called
        self.state_changed.connect(self._remember_state)
        self.control = ControlState()
        self.control_changed.connect(self._remember_control)
        # the deadman's GUI half: a held drive is renewed only while this ticks
        self._gui_alive = self._worker.gui_alive
        self._signer = self._worker.signer
        self._alive_timer = QTimer(self)
        self._alive_timer.timeout.connect(self._gui_tick)
        self._alive_timer.start(100)
        self._thread.start()

    def _gui_tick(self) -> None:
        self._gui_alive.t = time.monotonic()

    @Slot()
    def _take_frame(self) -> None:
        frame = self._worker.frames.take()
        if frame is not None:
            self.frame_decoded.emit(frame)

    @Slot(object)
    def _remember_control(self, c: ControlState) -> None:
        self.control = c

    @property
    def desk_name(self) -> str:
        s = self._signer
        return s.desk if s is not None else ""

    @property
    def key_fingerprint(self) -> str:
        s = self._signer
        return s.fingerprint if s is not None else ""

    @property
    def last_error(self) -> str:
        """The link's last socket or decoder error ("" when none)."""
        return self._worker.stats.last_error

    @Slot(str)
    def _remember_state(self, s: str) -> None:
        self.state = s

    # ----------------------------------------------------------------- intents
    def connect_to(self, host: str, port: int) -> None:
        self.address = f"{host}:{int(port)}"  # the robot, as the archive's session names it
        self._open.emit(host, int(port))

    def close(self) -> None:
        self._close.emit()

    def shutdown(self) -> None:
        """Close the socket and stop the link thread (call once, on exit)."""
        self._alive_timer.stop()
        if self._thread.isRunning():
            self._close.emit()
            self._thread.quit()
            self._thread.wait(3000)

    def send_command(self, name: str, args: dict | None = None) -> int:
        seq = self._worker.encode_queued(P.Command(name, dict(args or {})))
        self._flush.emit()
        return seq

    def send_when_connected(self, name: str, args: dict | None = None) -> None:
        """Send a command as soon as the link is (next) connected, once."""
        if self.state == "connected":
            self.send_command(name, args)
            return

        def once(state: str) -> None:
            if state == "connected":
                self.state_changed.disconnect(once)
                self.send_command(name, args)

        self.state_changed.connect(once)

    def request_control(self) -> int:
        return self.send_command("request_control")

    def release_control(self) -> int:
        return self.send_command("release_control")

    def hand_over(self, to: str | None = None) -> int:
        """Hand control to the named desk, by default the last one that asked."""
        return self.send_command("hand_over", {"to": to} if to else {})

    def drive(self, linear_mps: float, angular_rps: float) -> None:
        self._gui_alive.t = time.monotonic()
        self._set_drive.emit(float(linear_mps), float(angular_rps))

    def stop(self) -> None:
        self._set_drive.emit(0.0, 0.0)

    def estop(self) -> int:
        """Send the e-stop; returns its frame sequence number (the robot's ack
        names it). Sent only if the link is connected: the caller checks."""
        self._set_drive.emit(0.0, 0.0)
        return self.send_command("estop")

    def reset_estop(self) -> None:
        self.send_command("reset_estop")
