"""A stand-in for app.comm.link.RobotLink: the same signals, intents recorded."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from app.comm import protocol as P
from app.comm.link import LinkSignals


class FakeLink(LinkSignals):
    """The real link's signals (inherited, so they cannot drift apart); the
    intents are recorded instead of sent."""

    def __init__(self) -> None:
        super().__init__()
        self.calls: list[tuple] = []
        self.state = "disconnected"
        self._seq = 0

    def drive(self, linear_mps: float, angular_rps: float) -> None:
        self.calls.append(("drive", linear_mps, angular_rps))

    def stop(self) -> None:
        self.calls.append(("stop",))

    def estop(self) -> int:
        self.calls.append(("estop",))
        self._seq += 1
        return self._seq

    def reset_estop(self) -> None:
        self.calls.append(("reset_estop",))

    def send_command(self, name: str, args: dict | None = None) -> int:
        self.calls.append(("command", name, args))
        self._seq += 1
        return self._seq

    def names(self) -> list[str]:
        return [c[0] for c in self.calls]

    # ---------------------------------------------------------- emitting
    def set_state(self, state: str) -> None:
        self.state = state
        self.state_changed.emit(state)

    def send_telemetry(self, received_s: float | None = None, **values) -> P.Telemetry:
        base = dict(gas_lel_pct=1.0, temp_c=25.0, humidity_pct=50.0, battery_v=24.5,
                    obstacle_front_m=3.0, mode=int(P.RobotMode.TELEOP))
        base.update(values)
        msg = P.Telemetry(**base)
        msg.received_s = time.time() if received_s is None else received_s
        self.telemetry_received.emit(msg)
        return msg


@dataclass
class Frame:
    """Shaped like app.core.video.DecodedFrame."""

    frame_id: int
    capture_ts_us: int
    image: np.ndarray
    latency_ms: float
    width: int
    height: int
    camera_pan_rad: float = 0.0


def make_frame(frame_id: int = 1, w: int = 64, h: int = 48, latency_ms: float = 42.0) -> Frame:
    img = np.zeros((h, w, 3), np.uint8)
    img[:, : w // 2, 0] = 200
    return Frame(frame_id, P.now_us(), img, latency_ms, w, h)


@dataclass
class Stats:
    """Shaped like app.comm.link.LinkStats."""

    state: str = "connected"
    rtt_ms: float | None = 12.5
    frames_dropped: int = 3
    msgs_per_s: float = 42.0
    video_fps: float = 10.0
    reconnects: int = 0
    rx_frames: int = 100
