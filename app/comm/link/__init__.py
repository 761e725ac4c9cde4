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

The package: :mod:`.signals` (what a link reports: signals, statistics, the
control lease), :mod:`.worker` (the link thread: socket, states, frames) and
here :class:`RobotLink`, the facade the GUI thread uses.
"""

from __future__ import annotations

import time

from PySide6.QtCore import QObject, QThread, QTimer, Signal, Slot

from app.comm import protocol as P
from app.comm.settings import LinkSettings

from .signals import ControlState, LinkSignals, LinkStats
from .worker import _LinkWorker

__all__ = ["ControlState", "LinkSettings", "LinkSignals", "LinkStats", "RobotLink",
           "_LinkWorker"]


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
