"""Qt adapters between the desk pipeline and the views.

The desk's logic (series, alarms, link state, meters, commands, recording) is
:class:`app.core.desk.DeskPipeline`, with no Qt. These models only turn the
pipeline's listener calls into signals named for what happened and answer the
views' queries from it; a message that does not have the expected shape is
logged, counted in ``malformed_count`` and announced with ``malformed(str)``.
Built without a pipeline (a view on its own, tests), a model makes its own.
"""

from __future__ import annotations

import functools
import logging
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal

from app.core.alarms import (
    Alarm,
    AlarmChange,
    AlarmConfig,
    FlagRule,
    LimitRule,
    Priority,
    default_alarm_config,
)
from app.core.desk import (
    PLOT_CHANNELS,
    SPECS,
    TELEMETRY_CHANNELS,
    ChannelSpec,
    DeskPipeline,
    battery_percent,
    mode_name,
)
from app.core.series import RingBuffer

log = logging.getLogger(__name__)

__all__ = [
    "ChannelSpec", "LinkModel", "TelemetryModel", "VideoModel", "battery_percent",
    "flag_rules", "mode_name", "PLOT_CHANNELS", "SPECS", "TELEMETRY_CHANNELS",
]


def flag_rules(config: AlarmConfig | None = None) -> list[FlagRule]:
    """The MCU's alarm flag bits as alarm rules (priorities from the alarm file)."""
    return (config or default_alarm_config()).flag_rules()


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

    def _feed(self, kind: str, msg: Any) -> bool:
        """Hand a message to the pipeline; count it here when it is malformed."""
        ok = self.pipeline.ingest(kind, msg)
        if not ok:
            self.malformed_count += 1
            self.malformed.emit(f"{kind} message malformed")
        return ok


class TelemetryModel(_GuardedModel):
    """The pipeline's series, latest values, mode and alarm monitor, as signals."""

    values_changed = Signal(object)  # dict channel -> float (latest sample)
    alarm_raised = Signal(object)  # core.alarms.Alarm, annunciated (to UNACK)
    alarm_cleared = Signal(object)  # core.alarms.Alarm, its condition returned to normal
    alarm_changed = Signal(object)  # core.alarms.Transition: every ISA-18.2 transition
    mode_changed = Signal(int)  # RobotMode value

    def __init__(self, parent: QObject | None = None, *, pipeline: DeskPipeline | None = None,
                 capacity: int = 72_000, rules: tuple[LimitRule, ...] | None = None,
                 alarm_config: AlarmConfig | None = None,
                 clock: Callable[[], float] = time.time, tick_ms: int = 1000) -> None:
        """Without ``pipeline`` the model makes its own (``capacity`` samples per channel,
        the alarm rules of ``alarm_config``, ``rules`` replacing its limit rules) and runs
        its timers every ``tick_ms``; with one, whoever owns the pipeline runs them."""
        super().__init__(parent)
        if pipeline is None:
            pipeline = DeskPipeline(capacity=capacity, rules=rules,
                                    alarm_config=alarm_config, clock=clock)
            self._tick = QTimer(self)
            self._tick.setInterval(tick_ms)
            self._tick.timeout.connect(self.tick_alarms)
            self._tick.start()
        self.pipeline = pipeline
        self.monitor = pipeline.monitor
        pipeline.listen("values", self.values_changed.emit)
        pipeline.listen("mode", self.mode_changed.emit)
        pipeline.listen("alarm", self._on_transition)

    # ------------------------------------------------------------- inputs
    def on_telemetry(self, msg: Any) -> None:
        self._feed("telemetry", msg)

    def clear_series(self) -> None:
        """Empty the ring buffers (they take time in order only: a replay that
        seeks back starts them again)."""
        self.pipeline.series.clear()

    # ------------------------------------------------------------- queries
    @property
    def alarm_config(self) -> AlarmConfig:
        return self.pipeline.alarm_config

    @property
    def latest(self) -> dict[str, float]:
        return self.pipeline.latest

    @property
    def latest_t(self) -> float | None:
        return self.pipeline.latest_t

    @property
    def mode(self) -> int | None:
        return self.pipeline.mode

    @property
    def alarm_flags(self) -> int:
        return self.pipeline.alarm_flags

    @property
    def samples(self) -> int:
        return self.pipeline.samples

    def series(self, channel: str) -> RingBuffer:
        return self.pipeline.series[channel]

    def window(self, channel: str, seconds: float) -> tuple[np.ndarray, np.ndarray]:
        return self.pipeline.series.window(channel, seconds)

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

    def gas_stage(self, channel: str) -> str | None:
        """normal / A1 / A2 / over-range / fault, or None for a channel without a gas rule."""
        return self.monitor.stage(channel)

    def clear_alarms(self) -> list[AlarmChange]:
        return self.monitor.clear_all(self.pipeline.alarm_time())

    def apply_alarm_config(self, cfg: AlarmConfig) -> None:
        """New rules for the running monitor (standing alarms keep their state)."""
        self.pipeline.apply_alarm_config(cfg)

    def alarm_time(self) -> float:
        return self.pipeline.alarm_time()

    def tick_alarms(self) -> list[AlarmChange]:
        """Run the monitor's timers now."""
        return self.monitor.tick(self.pipeline.alarm_time())

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
    """The pipeline's link state and the link's figures, as signals."""

    STATES = ("disconnected", "connecting", "connected", "lost", "reconnecting",
              "replay")  # replay: the archive plays back, no robot is connected
    ABNORMAL = ("lost", "reconnecting", "disconnected")

    state_changed = Signal(str)
    link_restored = Signal()
    stats_changed = Signal(object)  # dict of the figures below

    def __init__(self, parent: QObject | None = None, *,
                 pipeline: DeskPipeline | None = None) -> None:
        super().__init__(parent)
        self.pipeline = pipeline if pipeline is not None else DeskPipeline()
        self.stats: dict[str, Any] = {"rtt_ms": None, "frames_dropped": 0, "msgs_per_s": 0.0,
                                      "video_fps": 0.0, "reconnects": 0, "rx_frames": 0}
        self.pipeline.listen("link_state", self._on_state)
        self.pipeline.listen("link_restored", self.link_restored.emit)
        self.pipeline.listen("stats", self._on_stats)

    @property
    def state(self) -> str:
        return self.pipeline.link_state

    @property
    def restored_count(self) -> int:
        return self.pipeline.restored_count

    def on_state(self, state: Any) -> None:
        self._feed("link_state", state)

    def on_stats(self, stats: Any) -> None:
        self._feed("link_stats", stats)

    def _on_state(self, state: str) -> None:
        if state not in self.STATES:
            log.warning("unknown link state %r shown as is", state)
        self.state_changed.emit(state)

    @guarded
    def _on_stats(self, stats: Any) -> None:
        rtt = getattr(stats, "rtt_ms", None)
        self.stats = {
            "rtt_ms": None if rtt is None else float(rtt),
            "frames_dropped": int(getattr(stats, "frames_dropped", 0)),
            "video_stale_dropped": int(getattr(stats, "video_stale_dropped", 0)),
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
        self.stats_changed.emit(self.stats)
