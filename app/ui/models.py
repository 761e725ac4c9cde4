"""Qt models between the link and the views.

They hold state (ring buffers, latest values, standing alarms, frame rate), turn
raw link messages into signals named for what happened, and survive malformed
input: a message that does not have the expected shape is logged, counted in
``malformed_count`` and announced with ``malformed(str)``; it never raises into
the event loop. The rules themselves live in app/core (alarms, series).
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal

from app.comm.protocol import RobotMode
from app.core.alarms import (
    Alarm,
    AlarmChange,
    AlarmConfig,
    AlarmMonitor,
    FlagRule,
    LimitRule,
    Priority,
    default_alarm_config,
)
from app.core.series import RingBuffer, SeriesSet

log = logging.getLogger(__name__)

__all__ = [
    "ChannelSpec", "LinkModel", "TelemetryModel", "VideoModel", "battery_percent",
    "flag_rules", "mode_name", "PLOT_CHANNELS", "TELEMETRY_CHANNELS",
]


@dataclass(frozen=True)
class ChannelSpec:
    key: str
    label: str
    unit: str
    fmt: str = "{:.1f}"


# Telemetry fields kept as series, with how they are shown
TELEMETRY_CHANNELS: tuple[ChannelSpec, ...] = (
    ChannelSpec("gas_lel_pct", "Gas", "%LEL"),
    ChannelSpec("temp_c", "Temperature", "°C"),
    ChannelSpec("humidity_pct", "Humidity", "%RH", "{:.0f}"),
    ChannelSpec("battery_v", "Battery", "V", "{:.2f}"),
    ChannelSpec("obstacle_left_m", "Obstacle left", "m", "{:.2f}"),
    ChannelSpec("obstacle_front_m", "Obstacle front", "m", "{:.2f}"),
    ChannelSpec("obstacle_right_m", "Obstacle right", "m", "{:.2f}"),
    ChannelSpec("wheel_left_mps", "Wheel left", "m/s", "{:.2f}"),
    ChannelSpec("wheel_right_mps", "Wheel right", "m/s", "{:.2f}"),
    ChannelSpec("yaw_rate_rps", "Yaw rate", "rad/s", "{:.2f}"),
    ChannelSpec("cmd_linear_mps", "Commanded speed", "m/s", "{:.2f}"),
    ChannelSpec("cmd_angular_rps", "Commanded turn", "rad/s", "{:.2f}"),
)
PLOT_CHANNELS: tuple[str, ...] = ("gas_lel_pct", "temp_c", "humidity_pct")
SPECS: dict[str, ChannelSpec] = {c.key: c for c in TELEMETRY_CHANNELS}

def flag_rules(config: AlarmConfig | None = None) -> list[FlagRule]:
    """The MCU's alarm flag bits as alarm rules (priorities from the alarm file)."""
    return (config or default_alarm_config()).flag_rules()


def mode_name(mode: int) -> str:
    try:
        return RobotMode(int(mode)).name
    except ValueError:
        return f"UNKNOWN({mode})"


def battery_percent(v: float, empty_v: float = 21.0, full_v: float = 25.5) -> float:
    """A rough state of charge of the 24 V pack from its voltage: a straight
    line from ``empty_v`` (0 %) to ``full_v`` (100 %), clipped. Under load the
    voltage sags, so this is a hint for the operator, not a fuel gauge."""
    if not math.isfinite(v):
        return float("nan")
    return float(np.clip((v - empty_v) / (full_v - empty_v) * 100.0, 0.0, 100.0))


def guarded(fn: Callable) -> Callable:
    """Wrap a slot so that a malformed message is logged and counted, not raised."""

    @functools.wraps(fn)
    def slot(self, *args):
        try:
            return fn(self, *args)
        except Exception as e:  # anything a bad message provokes
            self._note_malformed(f"{fn.__name__}: {type(e).__name__}: {e}", e)
            return None

    return slot


class _GuardedModel(QObject):
    malformed = Signal(str)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.malformed_count = 0

    def _note_malformed(self, why: str, exc: BaseException | None = None) -> None:
        self.malformed_count += 1
        log.warning("%s: malformed message ignored (%s); %d so far",
                    type(self).__name__, why, self.malformed_count,
                    exc_info=exc if exc is not None and log.isEnabledFor(logging.DEBUG) else None)
        self.malformed.emit(why)


class TelemetryModel(_GuardedModel):
    """Ring buffers per channel, latest values, robot mode and the alarm monitor."""

    values_changed = Signal(object)  # dict channel -> float (latest sample)
    alarm_raised = Signal(object)  # core.alarms.Alarm, annunciated (to UNACK)
    alarm_cleared = Signal(object)  # core.alarms.Alarm, its condition returned to normal
    alarm_changed = Signal(object)  # core.alarms.Transition: every ISA-18.2 transition
    mode_changed = Signal(int)  # RobotMode value

    def __init__(self, parent: QObject | None = None, *, capacity: int = 72_000,
                 rules: tuple[LimitRule, ...] | None = None,
                 alarm_config: AlarmConfig | None = None,
                 clock: Callable[[], float] = time.time, tick_ms: int = 1000) -> None:
        """``capacity`` samples per channel: 72 000 keep 60 min at 20 Hz (1.2 MB each).
        The alarm rules come from ``alarm_config`` (default: resources/alarms.toml);
        ``rules`` replaces its limit rules. Every transition of the monitor, whoever
        caused it (telemetry, the operator, a timer, the meter model), is announced
        as ``alarm_changed``; a timer runs the monitor's delays, stale-data checks
        and shelving expiry every ``tick_ms``."""
        super().__init__(parent)
        self._clock = clock
        self._series = SeriesSet([c.key for c in TELEMETRY_CHANNELS], capacity)
        cfg = alarm_config or default_alarm_config()
        if rules is not None:
            cfg = dataclasses.replace(cfg, limits=list(rules))
        self.alarm_config = cfg
        self.monitor = AlarmMonitor.from_config(cfg)
        self.monitor.add_listener(self._on_transition)
        self._tick = QTimer(self)
        self._tick.setInterval(tick_ms)
        self._tick.timeout.connect(self.tick_alarms)
        self._tick.start()
        self.latest: dict[str, float] = {}
        self.latest_t: float | None = None
        self.alarm_flags = 0
        self.mode: int | None = None
        self.samples = 0

    # ------------------------------------------------------------- inputs
    def on_telemetry(self, msg: Any) -> None:
        """Slot for ``RobotLink.telemetry_received``."""
        got = self._ingest(msg)
        if got is None:
            return
        values, _changes, mode = got  # the transitions went out through the listener
        self.values_changed.emit(values)
        if mode != self.mode:
            self.mode = mode
            self.mode_changed.emit(mode)

    @guarded
    def _ingest(self, msg: Any) -> tuple[dict[str, float], list[AlarmChange], int]:
        values = {}
        for spec in TELEMETRY_CHANNELS:
            values[spec.key] = float(getattr(msg, spec.key))
        flags = int(msg.alarm_flags)
        mode = int(msg.mode)
        t = getattr(msg, "received_s", None)
        t = float(t) if t is not None else self._clock()
        if not math.isfinite(t):
            raise ValueError(f"received_s is {t}")
        self._series.append(t, values)
        self.latest = values
        self.latest_t = t
        self._latest_mono = time.monotonic()
        self.alarm_flags = flags
        self.samples += 1
        changes = self.monitor.update_many(
            {r.channel: values[r.channel] for r in self.monitor.rules if r.channel in values}, t)
        changes += self.monitor.update_flags(flags, t)
        return values, changes, mode

    def clear_series(self) -> None:
        """Empty the ring buffers (they take time in order only: a replay that
        seeks back starts them again)."""
        self._series.clear()

    # ------------------------------------------------------------- queries
    def series(self, channel: str) -> RingBuffer:
        return self._series[channel]

    def window(self, channel: str, seconds: float) -> tuple[np.ndarray, np.ndarray]:
        return self._series.window(channel, seconds)

    def active_alarms(self) -> list[Alarm]:
        return self.monitor.active()

    def most_severe(self) -> Alarm | None:
        return self.monitor.most_severe()

    def channel_priority(self, channel: str) -> Priority | None:
        return self.monitor.channel_priority(channel)

    def value_priority(self, channel: str) -> Priority | None:
        """The priority a value tile shows: limits and rates, not stale data."""
        return self.monitor.value_priority(channel)

    def rule(self, channel: str) -> LimitRule | None:
        return self.monitor.rule(channel)

    def clear_alarms(self) -> list[AlarmChange]:
        return self.monitor.clear_all(self._clock())

    def apply_alarm_config(self, cfg: AlarmConfig) -> None:
        """New rules for the running monitor (standing alarms keep their state)."""
        self.alarm_config = cfg
        self.monitor.apply_config(cfg)

    def alarm_time(self) -> float:
        """Now, on the time base of the telemetry: the latest sample's time plus
        the time elapsed since it arrived (so delays and stale data are judged on
        one clock even when the samples carry another base, as in replay)."""
        if self.latest_t is None:
            return self._clock()
        return self.latest_t + max(0.0, time.monotonic() - self._latest_mono)

    def tick_alarms(self) -> list[AlarmChange]:
        """Run the monitor's timers now (the timer calls this every second)."""
        return self.monitor.tick(self.alarm_time())

    def _on_transition(self, tr: AlarmChange) -> None:
        self.alarm_changed.emit(tr)
        if tr.raised:
            self.alarm_raised.emit(tr.alarm)
        elif tr.cleared:
            self.alarm_cleared.emit(tr.alarm)


class VideoModel(_GuardedModel):
    """The newest camera frame, the frame rate from arrivals, latency and staleness."""

    frame_changed = Signal(object)  # the frame (image: HxWx3 uint8 RGB)
    stats_changed = Signal(float, float)  # fps, latency_ms (NaN when unknown)
    stale_changed = Signal(bool)

    def __init__(self, parent: QObject | None = None, *, stale_after_s: float = 2.0,
                 fps_window_s: float = 2.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        super().__init__(parent)
        self._clock = clock
        self.stale_after_s = stale_after_s
        self.fps_window_s = fps_window_s
        self._arrivals: deque[float] = deque()
        self.frame: Any = None
        self.frames = 0
        self.fps = 0.0
        self.latency_ms = float("nan")
        self.stale = True
        self._last_arrival: float | None = None
        self._timer = QTimer(self)
        self._timer.setInterval(500)
        self._timer.timeout.connect(self.check_stale)
        self._timer.start()

    def on_frame(self, frame: Any) -> None:
        """Slot for ``RobotLink.frame_decoded``."""
        if not self._ingest(frame):
            return
        self.frame_changed.emit(frame)
        self.stats_changed.emit(self.fps, self.latency_ms)
        if self.stale:
            self.stale = False
            self.stale_changed.emit(False)

    @guarded
    def _ingest(self, frame: Any) -> bool:
        image = frame.image
        if not (isinstance(image, np.ndarray) and image.dtype == np.uint8
                and image.ndim == 3 and image.shape[2] == 3 and image.size):
            raise ValueError(f"frame image is not HxWx3 uint8 "
                             f"({type(image).__name__} {getattr(image, 'shape', '')})")
        latency = float(getattr(frame, "latency_ms", float("nan")))
        now = self._clock()
        self._arrivals.append(now)
        while self._arrivals and now - self._arrivals[0] > self.fps_window_s:
            self._arrivals.popleft()
        if len(self._arrivals) >= 2:
            self.fps = (len(self._arrivals) - 1) / max(now - self._arrivals[0], 1e-6)
        self.latency_ms = latency
        self._last_arrival = now
        self.frame = frame
        self.frames += 1
        return True

    def check_stale(self) -> None:
        if self._last_arrival is None:
            return
        if not self.stale and self._clock() - self._last_arrival > self.stale_after_s:
            self.stale = True
            self.fps = 0.0
            self._arrivals.clear()
            self.stats_changed.emit(0.0, self.latency_ms)
            self.stale_changed.emit(True)


def _int_dict(d: Any) -> dict[str, int]:
    if not isinstance(d, dict):
        return {}
    return {str(k): int(v) for k, v in d.items() if isinstance(v, int) and v}


def control_text(holder: str | None, mine: bool, requested_by: str | None = None) -> str:
    """The line the control panel shows about the robot's control lease."""
    if holder is None:
        return "control is free"
    if mine:
        return "you have control" + (f" — {requested_by} asks for it" if requested_by else "")
    return f"view only — {holder} has control"


def refusals_text(stats: dict) -> tuple[str, str]:
    """Status-bar text and tooltip for every refusal counted on both sides."""
    own = stats.get("by_reason", {})
    robot = stats.get("robot_rejections", {})
    lost = stats.get("telemetry_lost", 0)
    late = stats.get("telemetry_reordered", 0)
    # garbage is counted in bytes, not frames: in the tooltip, not the total
    n = sum(v for k, v in own.items() if k != "garbage_bytes") + sum(robot.values())
    tip = ["desk decoder: " + (", ".join(f"{k} {v}" for k, v in sorted(own.items()))
                               or "nothing refused"),
           "robot: " + (", ".join(f"{k} {v}" for k, v in sorted(robot.items()))
                        or "nothing refused"),
           f"telemetry lost {lost}, late or repeated {late}"]
    return f"refused {n} · tel lost {lost}", "\n".join(tip)


class LinkModel(_GuardedModel):
    """The link's state and figures; notices when a lost link comes back."""

    STATES = ("disconnected", "connecting", "connected", "lost", "reconnecting",
              "replay")  # replay: the archive plays back, no robot is connected
    ABNORMAL = ("lost", "reconnecting", "disconnected")

    state_changed = Signal(str)
    link_restored = Signal()
    stats_changed = Signal(object)  # dict of the figures below

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.state = "disconnected"
        self._was_lost = False
        self.restored_count = 0
        self.stats: dict[str, Any] = {"rtt_ms": None, "frames_dropped": 0, "msgs_per_s": 0.0,
                                      "video_fps": 0.0, "reconnects": 0, "rx_frames": 0}

    @guarded
    def on_state(self, state: Any) -> None:
        if not isinstance(state, str):
            raise TypeError(f"link state is a {type(state).__name__}, not a str")
        if state not in self.STATES:
            log.warning("unknown link state %r shown as is", state)
        if state in ("lost", "reconnecting"):
            self._was_lost = True
        prev, self.state = self.state, state
        if state != prev:
            self.state_changed.emit(state)
        if state == "connected" and self._was_lost:
            self._was_lost = False
            self.restored_count += 1
            self.link_restored.emit()

    @guarded
    def on_stats(self, stats: Any) -> None:
        rtt = getattr(stats, "rtt_ms", None)
        new = {
            "rtt_ms": None if rtt is None else float(rtt),
            "frames_dropped": int(getattr(stats, "frames_dropped", 0)),
            "msgs_per_s": float(getattr(stats, "msgs_per_s", 0.0)),
            "video_fps": float(getattr(stats, "video_fps", 0.0)),
            "reconnects": int(getattr(stats, "reconnects", 0)),
            "rx_frames": int(getattr(stats, "rx_frames", 0)),
            # refusals: this desk's decoder by reason, and the robot's own counts
            "by_reason": _int_dict(getattr(stats, "by_reason", None)),
            "robot_rejections": _int_dict(getattr(stats, "robot_rejections", None)),
            "telemetry_lost": int(getattr(stats, "telemetry_lost", 0)),
            "telemetry_reordered": int(getattr(stats, "telemetry_reordered", 0)),
        }
        self.stats = new
        self.stats_changed.emit(new)
        state = getattr(stats, "state", None)
        if isinstance(state, str) and state and state != self.state:
            self.on_state(state)
