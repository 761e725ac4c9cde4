"""Replay of a recorded patrol through the same desk pipeline and panels as live.

:class:`ReplayLink` has the real link's signals (it inherits
``app.comm.link.LinkSignals``) and emits, in recorded-time order, the message
objects that :class:`app.core.desk.replay_rows.ReplayFeed` rebuilds from the
archive's rows: telemetry as it was received, poses, snapshots as camera frames
(their JPEG kept), the map, planned paths, robot and patrol events. A desk
session built on it with ``replay=True`` feeds them to ``DeskPipeline.ingest``
— the one ingest path, live or replayed — and records and sends nothing; the
recorded alarm transitions are repeated as operator actions
(``alarm_transition_replayed``) and shown in the log. Its intents are refused
and counted: a replay is view-only.

Time comes from a :class:`~app.core.replay.ReplayClock`; a timer feeds it the
monotonic wall seconds that passed while playing, and :meth:`ReplayLink.step`
lets a test drive it by hand. After a seek the link emits ``rewound`` (views
drop what they hold) and then the state at the target; playing on emits what
lies after it. :func:`open_replay_window` opens a desk window on a recording.
"""

from __future__ import annotations

import functools
import logging
import time
import weakref
from datetime import UTC, datetime
from typing import Any

from PySide6.QtCore import QObject, QTimer, Signal

from app.comm.link import LinkSignals
from app.core.desk.replay_rows import ReplayFeed, transition_event
from app.core.i18n import translate
from app.core.replay import ReplayClock, ReplayCursor
from app.gui_gc import connect_for_life

log = logging.getLogger(__name__)

__all__ = ["ReplayLink", "attach_replay", "open_replay_window", "replay_banner_text"]

# the message kinds of the feed and the link signal each goes out on
_SIGNAL_OF = {"telemetry": "telemetry_received", "pose": "pose_received",
              "frame": "frame_decoded", "map": "map_received", "path": "path_received",
              "event": "event_received", "patrol_status": "patrol_status_received"}


class ReplayLink(LinkSignals):
    """A link that plays an archive back. ``archive``: an ``app.core.records.Archive``
    (only its read API is used)."""

    position_changed = Signal(float)
    playing_changed = Signal(bool)
    speed_changed = Signal(float)
    rewound = Signal(float)  # a seek: views drop what they hold
    alarm_transition_replayed = Signal(object)  # the stored transition record (dict)
    command_refused = Signal(str)

    def __init__(self, archive: Any, t0: float | None = None, t1: float | None = None, *,
                 tick_ms: int = 100, prime_s: float = 60.0,
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.archive = archive
        rec = archive.time_range()
        if rec is None and (t0 is None or t1 is None):
            raise ValueError("the archive holds no recording to replay")
        t0 = float(rec[0]) if t0 is None else float(t0)
        t1 = float(rec[1]) if t1 is None else float(t1)
        self.clock = ReplayClock(t0, t1)
        self.cursor = ReplayCursor(self.clock)
        self.feed = ReplayFeed(archive, prime_s=prime_s)
        self.state = "replay"
        self.refused = 0
        self.emitted: dict[str, int] = {}
        self._timer = QTimer(self)
        self._timer.setInterval(int(tick_ms))
        self._timer.timeout.connect(self._on_tick)
        self._wall: float | None = None

    # ------------------------------------------------------------ transport
    @property
    def position(self) -> float:
        return self.clock.position

    @property
    def playing(self) -> bool:
        return not self.clock.paused

    def start(self) -> None:
        """Announce the replay and show the state at the start of the range."""
        self.state_changed.emit("replay")
        self.seek(self.clock.t0)

    def play(self) -> None:
        self.clock.play()
        self._wall = time.monotonic()
        self._timer.start()
        self.playing_changed.emit(True)

    def pause(self) -> None:
        self.clock.pause()
        self._timer.stop()
        self.playing_changed.emit(False)

    def toggle(self) -> None:
        self.pause() if self.playing else self.play()

    def set_speed(self, speed: float) -> float:
        s = self.clock.set_speed(speed)
        self.speed_changed.emit(s)
        return s

    def seek(self, t: float) -> float:
        """Jump to ``t`` (clamped to the range) and emit the state there."""
        pos = self.cursor.seek(t, inclusive=False)  # the state at pos is shown below
        self.feed.rewind()
        self.rewound.emit(pos)
        self._emit_items(self.feed.state_at(pos))
        self.position_changed.emit(pos)
        return pos

    def seek_fraction(self, f: float) -> float:
        return self.seek(self.clock.t0 + min(1.0, max(0.0, f)) * (self.clock.t1 - self.clock.t0))

    def step(self, wall_dt_s: float) -> int:
        """Let ``wall_dt_s`` seconds of wall time pass; emit what became due.
        Returns the number of rows emitted."""
        was_playing = self.playing
        w = self.cursor.advance(wall_dt_s)
        n = 0
        if w is not None:
            n = self._emit_items(self.feed.window(w))
            self.position_changed.emit(self.clock.position)
        if was_playing and not self.playing:  # reached the end
            self._timer.stop()
            self.playing_changed.emit(False)
        return n

    def _on_tick(self) -> None:
        now = time.monotonic()
        dt = 0.0 if self._wall is None else now - self._wall
        self._wall = now
        try:
            self.step(dt)
        except Exception:  # a damaged archive must not take the desk down
            log.exception("replay step failed")
            self.pause()

    def shutdown(self) -> None:
        self._timer.stop()

    def close(self) -> None:
        self.shutdown()

    # ------------------------------------------------------------ view-only intents
    def _refuse(self, what: str) -> None:
        self.refused += 1
        self.command_refused.emit(what)

    def drive(self, linear_mps: float, angular_rps: float) -> None:
        if linear_mps or angular_rps:
            self._refuse("drive")

    def stop(self) -> None:
        pass  # nothing moves in a replay; the window sends stop on close

    def estop(self) -> None:
        self._refuse("estop")

    def reset_estop(self) -> None:
        self._refuse("reset_estop")

    def send_command(self, name: str, args: dict | None = None) -> int:
        self._refuse(name)
        return -1

    def send_when_connected(self, name: str, args: dict | None = None) -> None:
        self._refuse(name)

    def connect_to(self, host: str, port: int) -> None:
        self._refuse("connect")

    # ------------------------------------------------------------ emitting
    def _emit_items(self, items: list[tuple[float, str, Any]]) -> int:
        for _t, kind, msg in items:
            if kind == "alarm_transition":
                self.alarm_transition_replayed.emit(msg)
                self.event_received.emit(transition_event(msg))
            else:
                getattr(self, _SIGNAL_OF[kind]).emit(msg)
            self.emitted[kind] = self.emitted.get(kind, 0) + 1
        return len(items)


def replay_banner_text(position_s: float, speed: float) -> str:
    """The banner's replay line: "REPLAY 15:17:21 ×2 — view only (UTC)"."""
    hms = datetime.fromtimestamp(position_s, UTC).strftime("%H:%M:%S")
    return translate("Replay", "REPLAY {time} ×{speed} — view only (UTC)").format(
        time=hms, speed=f"{speed:g}")


def attach_replay(window: Any, link: ReplayLink) -> None:
    """Make a main window built on ``link`` a replay window: commands off, the
    plots following the replay clock, views cleared on a seek, the recorded
    operator actions repeated on its alarm monitor."""
    # view only: no drive pad, no e-stop, no patrol or robot commands
    window.replay_mode = True
    window.control_panel.set_replay(True)
    window.map_panel.set_read_only(True)
    for a in window.robot_menu.actions():
        a.setEnabled(False)
    window.robot_menu.setEnabled(False)
    window.alarm_panel.set_read_only(True)
    # the event log is stamped with the recorded time being shown, not the wall clock
    window.alarm_panel.set_log_clock(lambda: link.clock.position)
    window.setWindowTitle(window.windowTitle() + translate("Replay", " — replay (view only)"))

    # the link may outlive the window: its slots hold the window weakly and are undone
    # when the window is deleted (connections the garbage collector cannot see kept
    # the window, and the link itself, alive: app/gui_gc)
    me = weakref.ref(window)
    strip = window.data_panel.strip
    # the live plots end their window at "now": in a replay, now is the replay clock
    strip.set_clock(lambda: link.clock.position)
    connect_for_life(window, [
        (link.position_changed, functools.partial(_show_where, me, link.clock)),
        (link.speed_changed, functools.partial(_show_where, me, link.clock)),
        (link.rewound, functools.partial(_reset_views, me)),
        (link.alarm_transition_replayed, functools.partial(_mirror_handling, me)),
        (link.command_refused, functools.partial(_say_refused, me)),
        (link.position_changed, functools.partial(_mark_plots, me)),
    ])
    _show_where(me, link.clock)


def _show_where(window: weakref.ref, clock: ReplayClock, _x: object = None) -> None:
    w = window()
    if w is not None:
        w.banner.set_replay(replay_banner_text(clock.position, clock.speed))


def _reset_views(window: weakref.ref, _t: float = 0.0) -> None:
    w = window()
    if w is not None:
        tm = w.telemetry_model
        tm.clear_alarms()
        tm.clear_series()
        w.data_panel.strip.mark_dirty()


def _mirror_handling(window: weakref.ref, transition: Any) -> None:
    w = window()
    if w is not None:
        w.pipeline.mirror_handling(transition)


def _say_refused(window: weakref.ref, what: str) -> None:
    w = window()
    if w is not None:
        w.statusBar().showMessage(
            translate("Replay", "replay is view-only: {what} not sent").format(what=what), 4000)


def _mark_plots(window: weakref.ref, _t: float = 0.0) -> None:
    w = window()
    if w is not None:
        w.data_panel.strip.mark_dirty()


def open_replay_window(window_cls: Any, archive: Any, which: str, t0: float | None = None,
                       t1: float | None = None) -> tuple[Any, ReplayLink]:
    """A desk window (``window_cls``: MainWindow) replaying ``archive`` (an Archive or a
    session view of one) from ``t0`` to ``t1``, on a view-only desk session."""
    from app.session import DeskSession
    from app.ui.replay_bar import ReplayBar

    link = ReplayLink(archive, t0, t1)
    desk = DeskSession(link, replay=True)
    win = window_cls(link, desk=desk, title=translate(
        "Replay", "Station Patrol — replay of {which}").format(which=which))
    desk.setParent(win)
    # the link dies with the window: its connections to the window's closures (which
    # the garbage collector cannot see) would otherwise keep the closed window alive
    link.setParent(win)
    attach_replay(win, link)
    win.addToolBar(ReplayBar(link, win).toolbar())
    return win, link
