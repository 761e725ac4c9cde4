"""Replay of a recorded patrol through the same panels as live.

:class:`ReplayLink` has the real link's signals (it inherits
``app.comm.link.LinkSignals``) and emits them from archived rows: telemetry as
it was received, poses, snapshots as camera frames, the map, planned paths,
robot and patrol events, and the recorded alarm transitions (as alarm events).
A main window built on it looks exactly as it did live. Its intents (drive,
stop, commands) are refused and counted: a replay is view-only.

Time comes from a :class:`~app.core.replay.ReplayClock`; a timer feeds it the
monotonic wall seconds that passed while playing, and :meth:`ReplayLink.step`
lets a test drive it by hand. After a seek the link emits ``rewound`` (views
drop what they hold) and then the state at the target: the last map, path,
pose and snapshot up to it, the telemetry of the ``prime_s`` up to it and the
events at that moment; playing on emits what lies after it.

``run_replay(...)`` opens the desk window in replay mode (``station-patrol
--replay``).
"""

from __future__ import annotations

import logging
import math
import struct
import time
from datetime import UTC, datetime
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal

from app.comm import protocol as P
from app.comm.link import LinkSignals
from app.core.replay import ReplayClock, ReplayCursor, Window
from app.core.video import DecodedFrame, decode_jpeg_rgb

log = logging.getLogger(__name__)

__all__ = ["ReplayLink", "attach_replay", "mirror_handling", "replay_banner_text", "replay_main",
           "run_replay"]

_TELEMETRY_INT = {"alarm_flags", "mode", "mcu_time_ms"}
_TELEMETRY_FIELDS = {f for f in P.Telemetry.__dataclass_fields__}
_PATH_KINDS = {"global": P.Path.GLOBAL, "plan": P.Path.GLOBAL, "0": P.Path.GLOBAL,
               "local": P.Path.LOCAL, "1": P.Path.LOCAL}
LOOKBACK_S = 6 * 3600.0  # how far back a seek looks for the last map, path, snapshot


def _png_size(png: bytes) -> tuple[int, int]:
    if len(png) >= 24 and png.startswith(b"\x89PNG\r\n\x1a\n"):
        w, h = struct.unpack(">II", png[16:24])
        return int(w), int(h)
    return 0, 0


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
        self.prime_s = float(prime_s)
        self.state = "replay"
        self.refused = 0
        self.emitted: dict[str, int] = {}
        self._last_values: dict[str, float] = {}
        self._map_geometry: dict[str, float] = {}
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
        self._last_values.clear()
        self.rewound.emit(pos)
        self._emit_state_at(pos)
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
            n = self._emit_window(w)
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
    def _count(self, kind: str, n: int = 1) -> None:
        self.emitted[kind] = self.emitted.get(kind, 0) + n

    def _emit_window(self, w: Window) -> int:
        a = self.archive
        n = 0
        t, seq, names, vals = a.telemetry_rows(w.start, w.end)
        keep = np.ones(len(t), bool) if w.inclusive else t > w.start
        n += self._emit_telemetry(t[keep], seq[keep], names, vals[keep])
        poses = a.poses(w.start, w.end)
        for row in poses:
            if w.contains(row[0]):
                self._emit_pose(row)
                n += 1
        for s in a.snapshots(w.start, w.end):
            if w.contains(s["t"]):
                n += self._emit_snapshot(s)
        for m in a.paths(w.start, w.end):
            if w.contains(m["t"]):
                self._emit_path(m)
                n += 1
        for ev in a.events(w.start, w.end):
            if w.contains(ev["t"]):
                n += self._emit_event(ev)
        for tr in a.alarm_transitions(w.start, w.end):
            if w.contains(tr["t"]):
                self._emit_transition(tr)
                n += 1
        return n

    def _emit_state_at(self, t: float) -> None:
        a = self.archive
        back = t - LOOKBACK_S
        for ev in a.events(back, t, kinds=["map"]):
            if isinstance(ev.get("data"), dict):
                self._map_geometry = ev["data"]
        png = a.latest_map(t)
        if png:
            self._emit_map(png)
        latest_paths: dict[str, dict] = {}
        for m in a.paths(back, t):
            latest_paths[str(m["kind"])] = m
        for m in latest_paths.values():
            self._emit_path(m)
        snaps = a.snapshots(back, t)
        if snaps:
            self._emit_snapshot(snaps[-1])
        poses = a.poses(t - self.prime_s, t)
        if len(poses):
            self._emit_pose(poses[-1])
        tt, seq, names, vals = a.telemetry_rows(t - self.prime_s, t)
        self._emit_telemetry(tt, seq, names, vals)
        for ev in a.events(t, t):  # what happened at that very moment
            self._emit_event(ev)
        for tr in a.alarm_transitions(t, t):
            self._emit_transition(tr)

    def _emit_telemetry(self, t: np.ndarray, seq: np.ndarray, names: list[str],
                        vals: np.ndarray) -> int:
        cols = [(j, n) for j, n in enumerate(names) if n in _TELEMETRY_FIELDS]
        last = self._last_values
        for i in range(len(t)):
            for j, name in cols:
                v = vals[i, j]
                if math.isfinite(v):
                    last[name] = float(v)
            msg = P.Telemetry(**{k: (int(v) if k in _TELEMETRY_INT else v)
                                 for k, v in last.items()})
            msg.received_s = float(t[i])
            msg.seq = int(seq[i])
            self.telemetry_received.emit(msg)
        self._count("telemetry", len(t))
        return len(t)

    def _emit_pose(self, row: np.ndarray) -> None:
        self.pose_received.emit(P.Pose(x_m=float(row[1]), y_m=float(row[2]),
                                       theta_rad=float(row[3])))
        self._count("pose")

    def _emit_snapshot(self, s: dict) -> int:
        jpeg = self.archive.snapshot(s["id"])
        img = decode_jpeg_rgb(jpeg) if jpeg else None
        if img is None:
            log.warning("replay: snapshot %s does not decode", s.get("id"))
            self._count("bad_snapshot")
            return 0
        self.frame_decoded.emit(DecodedFrame(int(s["id"]), int(float(s["t"]) * 1e6), img,
                                             float("nan"), img.shape[1], img.shape[0]))
        self._count("frame")
        return 1

    def _emit_map(self, png: bytes) -> None:
        g = self._map_geometry
        w, h = _png_size(png)
        try:
            res = float(g.get("resolution_m", 0.1))
            ox, oy = float(g.get("origin_x_m", 0.0)), float(g.get("origin_y_m", 0.0))
        except (TypeError, ValueError):
            res, ox, oy = 0.1, 0.0, 0.0
        self.map_received.emit(P.MapImage(res, ox, oy, w, h, bytes(png)))
        self._count("map")

    def _emit_path(self, m: dict) -> None:
        kind = _PATH_KINDS.get(str(m["kind"]).lower(), P.Path.GLOBAL)
        self.path_received.emit(P.Path(kind, np.asarray(m["points"], np.float32)))
        self._count("path")

    def _emit_event(self, ev: dict) -> int:
        kind = str(ev.get("kind", ""))
        d = ev.get("data") if isinstance(ev.get("data"), dict) else {"text": str(ev.get("data"))}
        if kind == "map":
            self._map_geometry = d
            return 0
        if kind in ("patrol", "patrol_status") and "state" in d:
            fields = P.PatrolStatus.__dataclass_fields__
            self.patrol_status_received.emit(
                P.PatrolStatus(**{k: v for k, v in d.items() if k in fields}))
            self._count("patrol_status")
        level = str(d.get("level", "info"))
        code = str(d.get("code", kind))
        text = str(d.get("text") or d.get("state") or "")
        if kind == "link_state":
            code, text = "link", f"link {d.get('state', '?')} (recorded)"
        extra = d.get("data") if kind == "robot_event" and isinstance(d.get("data"), dict) \
            else d
        self.event_received.emit(P.Event(level=level, code=code, text=text, data=extra))
        self._count("event")
        return 1

    def _emit_transition(self, tr: dict) -> None:
        to = str(tr.get("to_state", ""))
        who = f" by {tr['user']}" if tr.get("user") else ""
        text = f"{tr.get('text') or tr.get('alarm')}: {tr.get('from_state')} → {to}{who}"
        level = "alarm" if to == "UNACK" else "info"
        self.alarm_transition_replayed.emit(dict(tr))
        self.event_received.emit(P.Event(level=level, code=str(tr.get("alarm", "")), text=text,
                                         data={"replayed_alarm": True}))
        self._count("alarm_transition")


def mirror_handling(monitor: Any, tr: dict) -> bool:
    """Repeat a recorded operator action (acknowledge, shelve, unshelve, out of
    service and back) on the replay window's alarm monitor, so its alarm list
    shows the alarms as they were handled. The monitor raises and clears alarms
    itself from the replayed telemetry; an action on an alarm it does not hold
    is skipped. Returns True when the action was applied."""
    alarm, t = str(tr.get("alarm", "")), float(tr.get("t", 0.0))
    frm, to = str(tr.get("from_state", "")), str(tr.get("to_state", ""))
    user, reason = tr.get("user"), tr.get("reason") or "recorded"
    try:
        if to == "ACKED" or (frm in ("UNACK", "RTN_UNACK") and to == "NORMAL" and user):
            return bool(monitor.acknowledge(alarm, t, user))
        if to == "SHELVED":
            return bool(monitor.shelve(alarm, t, monitor.max_shelve_s, reason, user))
        if frm == "SHELVED":
            return bool(monitor.unshelve(alarm, t, user))
        if to == "OUT_OF_SERVICE":
            return bool(monitor.set_out_of_service(alarm, True, t, reason, user))
        if frm == "OUT_OF_SERVICE":
            return bool(monitor.set_out_of_service(alarm, False, t, reason, user))
    except (AttributeError, KeyError, TypeError, ValueError) as e:
        log.debug("replay: recorded %s of %s not repeated: %s", to, alarm, e)
    return False


def replay_banner_text(position_s: float, speed: float) -> str:
    """The banner's replay line: "REPLAY 15:17:21 ×2 — view only (UTC)"."""
    hms = datetime.fromtimestamp(position_s, UTC).strftime("%H:%M:%S")
    return f"REPLAY {hms} ×{speed:g} — view only (UTC)"


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
    window.setWindowTitle(f"{window.windowTitle()} — replay (view only)")

    def show_where(_x: object = None) -> None:
        window.banner.set_replay(replay_banner_text(link.clock.position, link.clock.speed))

    link.position_changed.connect(show_where)
    link.speed_changed.connect(show_where)
    show_where()
    strip = window.data_panel.strip
    # the live plots end their window at "now": in a replay, now is the replay clock
    strip.set_clock(lambda: link.clock.position)

    def reset(_t: float) -> None:
        tm = window.telemetry_model
        tm.clear_alarms()
        tm.clear_series()
        strip.mark_dirty()

    link.rewound.connect(reset)
    link.alarm_transition_replayed.connect(
        lambda tr: mirror_handling(window.telemetry_model.monitor, tr))
    link.command_refused.connect(
        lambda what: window.statusBar().showMessage(f"replay is view-only: {what} not sent",
                                                    4000))
    link.position_changed.connect(lambda _t: strip.mark_dirty())


def replay_main(cfg: Any, frm: str | None, to: str | None, *,
                duration_s: float | None = None, display: bool = True,
                session: str | int | None = "latest") -> int:
    """``station-patrol --replay [--from] [--to] [--session] [--data-dir]``; bad input
    exits 2."""
    import sys

    from app.core.records.paths import default_archive_path
    from app.report.cli import parse_time

    def fail(msg: str) -> int:
        print(f"station-patrol: {msg}", file=sys.stderr)
        return 2

    path = default_archive_path(cfg.data_dir or None)
    if not path.exists():
        return fail(f"no archive at {path} to replay (give --data-dir)")
    try:
        t0 = parse_time(frm) if frm else None
        t1 = parse_time(to) if to else None
    except ValueError as e:
        return fail(str(e))
    if t0 is not None and t1 is not None and t1 <= t0:
        return fail("--to is not after --from")
    if not display:
        return fail("--replay needs a display (QT_QPA_PLATFORM=offscreen runs it without one)")
    return run_replay(str(path), t0, t1, duration_s=duration_s, session=session)


def run_replay(archive_path: str, t0: float | None = None, t1: float | None = None,
               *, speed: float = 1.0, autoplay: bool = True,
               duration_s: float | None = None, session: str | int | None = "latest") -> int:
    """Open the desk window in replay mode over ``archive_path``; returns the exit code.
    ``session``: which desk session to replay (a number, "latest" with data in the
    range, or "all" mixed); the window's title says which."""
    import sys

    from PySide6.QtWidgets import QApplication

    from app.core.records import Archive
    from app.ui.app import show_and_run
    from app.ui.main_window import MainWindow
    from app.ui.replay_bar import ReplayBar
    from app.ui.theme import apply_theme

    app = QApplication.instance() or QApplication(sys.argv[:1])
    apply_theme(app)
    from app.core.records.queries import choose_session

    archive = Archive(archive_path)
    try:
        rows, which = choose_session(archive, session,
                                     -math.inf if t0 is None else t0,
                                     math.inf if t1 is None else t1)
        link = ReplayLink(rows, t0, t1)
    except ValueError as e:
        archive.close()
        print(f"station-patrol: {e}", file=sys.stderr)
        return 2
    print(f"station-patrol: replaying {which}", flush=True)
    win = MainWindow(link, title=f"Station Patrol — replay of {which}")
    attach_replay(win, link)
    bar = ReplayBar(link, win)
    win.addToolBar(bar.toolbar())
    link.start()
    link.set_speed(speed)
    if autoplay:
        link.play()
    code = show_and_run(app, win, duration_s)
    link.shutdown()
    archive.close()
    return code
