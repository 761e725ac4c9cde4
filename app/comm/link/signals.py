"""What the desk's robot link reports: its signals (named for what happened), its
statistics and who holds the control lease. Shared by the link's worker thread
(:mod:`.worker`), its GUI-thread facade (:class:`app.comm.link.RobotLink`) and
anything that stands in for a link (replay, the tests' fake link)."""

from __future__ import annotations

from dataclasses import dataclass, field

from PySide6.QtCore import QObject, Signal


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
    fws_received = Signal(object)  # a 4WS robot's message (app/comm/fws_protocol.py)

    RELAYED = ("state_changed", "telemetry_received", "pose_received", "scan_received",
               "event_received", "ack_received", "frame_decoded", "stats_changed",
               "link_restored", "map_received", "path_received", "patrol_status_received",
               "obstacles_received", "control_changed", "wall_received", "fws_received")
