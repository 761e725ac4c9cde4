"""DeskSession: wires a RobotLink to the session recorder, the archive and the alarm rules.

Used by the headless desk and by the window. The rules, the recorder and the archive
are Qt-free (app/core); this class is only the glue. Everything the desk receives and
every command it sends goes into the archive (when one is open); the results folder of
:class:`~app.core.recorder.SessionRecorder` is written beside it when asked for.
Nothing here keeps a per-message list: memory stays flat over a long run.
"""

from __future__ import annotations

import getpass
import hashlib
import logging
import math
import time
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

from PySide6.QtCore import QObject, QTimer, Signal, Slot

from app.comm import protocol as P
from app.comm.link import RobotLink
from app.core.alarms import AlarmChange, AlarmConfig, AlarmMonitor, Priority, default_alarm_config
from app.core.meter_service import OUT_OF_BAND, REFERENCE_SNAPSHOT_REASON
from app.core.recorder import SessionRecorder
from app.core.records import Archive, ArchiveError, default_archive_path

log = logging.getLogger(__name__)

CHANNELS = ("gas_lel_pct", "temp_c", "humidity_pct", "battery_v")
# every numeric telemetry field goes into the archive
TELEMETRY_CHANNELS = tuple(f.name for f in fields(P.Telemetry))


def open_archive(data_dir: str | Path | None = None, *, retention_days: float | None = 30.0,
                 export_dir: str | Path | None = None,
                 path: str | Path | None = None) -> tuple[Archive | None, str | None]:
    """Open (or create) the desk's archive. Returns (archive, None), or (None, message)
    when the file cannot be used: the desk then runs without an archive and says so."""
    p = Path(path) if path is not None else default_archive_path(data_dir or None)
    try:
        return Archive(p, retention_days=retention_days, export_dir=export_dir), None
    except ArchiveError as e:
        log.error("archive disabled: %s", e)
        return None, str(e)


def open_desk_archive(cfg: Any) -> tuple[Archive | None, str | None]:
    """The archive as the desk configuration says (``cfg``: app.config.DeskConfig)."""
    a = cfg.archive
    if not a.enabled:
        return None, None
    data_dir = Path(cfg.data_dir) if cfg.data_dir else None
    export = None
    if a.export_before_prune:
        export = a.export_dir or default_archive_path(data_dir).parent / "exported"
    return open_archive(data_dir, retention_days=a.retention_days or None, export_dir=export)


def _user() -> str:
    try:
        return getpass.getuser()
    except Exception:
        return "operator"


class DeskSession(QObject):
    alarm_changed = Signal(object)  # AlarmChange
    archive_status = Signal(bool, str)  # ok, message (from the archive's writer thread)

    def __init__(self, link: RobotLink, recorder: SessionRecorder | None,
                 monitor: AlarmMonitor | None = None, *, own_alarms: bool = True,
                 archive: Archive | None = None, archive_error: str | None = None,
                 user: str | None = None, alarm_config: AlarmConfig | None = None,
                 tick_ms: int = 1000) -> None:
        """``own_alarms``: evaluate the alarm rules here (headless). With a window
        the telemetry model evaluates them and :meth:`record_alarm` is connected
        to it instead, so the rules run once.

        ``archive``: where everything goes (None: no archive). ``archive_error``: why
        the archive could not be opened; raised as an alarm.

        Headless, the session drives the monitor itself: telemetry and flags in,
        the link state as the ``link.lost`` condition, and a timer (``tick_ms``)
        for delays, stale data and shelving expiry; every transition is recorded
        by :meth:`record_alarm` (a monitor listener)."""
        super().__init__()
        self.link = link
        self.recorder = recorder
        self.monitor = monitor or AlarmMonitor.from_config(alarm_config or default_alarm_config())
        self.own_alarms = own_alarms
        self.archive = archive
        self.user = user or self._desk_name(link)
        self.archive_session: int | None = None
        self._robot_named = False
        if archive is not None:
            # every row this desk writes belongs to this session (docs/archive.md)
            try:
                self.archive_session = archive.begin_session(self.user)
            except Exception as e:  # noqa: BLE001 - a failing archive is its own alarm
                log.warning("archive session not started: %s", e)
        self.bad_messages = 0
        self.commands_sent = 0
        self._last_image: Any = None
        self._map_digest = b""
        self._path_digest = b""
        self._patrol_key: tuple = ()
        self._archive_failing = False
        rec = recorder
        self._links: list[tuple[Any, Any]] = []  # (signal, slot), undone by close()
        self._connect(link.telemetry_received, self._on_telemetry)
        self._connect(link.pose_received, self._on_pose)
        if rec is not None:
            self._connect(link.scan_received, rec.scan)
        self._connect(link.stats_changed, self._on_link_stats)
        self._connect(link.frame_decoded, self._on_frame)
        self._connect(link.event_received, self._on_robot_event)
        self._connect(link.ack_received, self._on_ack)
        self._connect(link.state_changed, self._on_link_state)
        for name, slot in (("map_received", self._on_map),
                           ("path_received", self._on_path),
                           ("patrol_status_received", self._on_patrol),
                           ("obstacles_received", self._on_obstacles)):
            if hasattr(link, name):
                self._connect(getattr(link, name), slot)
        self._wrap_send_command()
        if hasattr(self.monitor, "add_listener"):
            self.monitor.add_listener(self._on_transition)
            if own_alarms:
                self.monitor.add_listener(self.record_alarm)
        self._last_data_t: float | None = None
        self._last_data_mono = 0.0
        self._tick = QTimer(self)
        self._tick.setInterval(tick_ms)
        self._tick.timeout.connect(self.tick_alarms)
        if own_alarms:
            self._tick.start()
        self.archive_status.connect(self._on_archive_status)
        if archive is not None:
            archive.on_status = self.archive_status.emit
        if archive_error is not None:
            self._archive_alarm("archive.open", True,
                                f"Archive not available, nothing is archived: {archive_error}")

    def _connect(self, signal: Any, slot: Any) -> None:
        signal.connect(slot)
        self._links.append((signal, slot))

    @staticmethod
    def _desk_name(link: Any) -> str:
        name = getattr(link, "desk_name", None)
        if callable(name):
            try:
                name = name()
            except Exception:
                name = None
        return name if isinstance(name, str) and name else _user()

    # ------------------------------------------------------------ inputs
    def _event(self, kind: str, t: float | None = None, **data: Any) -> None:
        if self.recorder is not None:
            self.recorder.event(kind, **data)
        if self.archive is not None:
            self.archive.add_event(time.time() if t is None else t, kind, data)

    def _on_telemetry(self, t: P.Telemetry) -> None:
        try:
            ts = getattr(t, "received_s", None) or time.time()
            if self.recorder is not None:
                self.recorder.telemetry(t)
            if self.archive is not None:
                self.archive.add_telemetry(ts, {c: getattr(t, c) for c in TELEMETRY_CHANNELS},
                                           seq=getattr(t, "seq", None))
            if self.own_alarms:  # the transitions reach record_alarm as a listener
                self._last_data_t, self._last_data_mono = ts, time.monotonic()
                self.monitor.update_many({c: getattr(t, c) for c in CHANNELS}, ts)
                self.monitor.update_flags(int(t.alarm_flags), ts)
        except (AttributeError, TypeError, ValueError) as e:
            self.bad_messages += 1
            log.warning("telemetry message not usable (%s); %d so far", e, self.bad_messages)

    def _on_pose(self, p: P.Pose) -> None:
        if self.recorder is not None:
            self.recorder.pose(p)
        if self.archive is not None:
            self.archive.add_pose(time.time(), p.x_m, p.y_m, p.theta_rad)

    def _on_frame(self, f: Any) -> None:
        self._last_image = f.image  # only the newest frame is kept, for snapshots
        if self.recorder is not None:
            self.recorder.frame(f.frame_id, f.latency_ms, f.image)

    def _on_robot_event(self, e: P.Event) -> None:
        self._event("robot_event", level=e.level, code=e.code, text=e.text, data=e.data)

    def _on_ack(self, a: P.CommandAck) -> None:
        if self.recorder is not None:
            self.recorder.event("command_ack", cmd_seq=a.cmd_seq, ok=a.ok, reason=a.reason)
        if self.archive is not None:
            self.archive.ack_command(a.cmd_seq, a.ok, a.reason, time.time())

    LINK_STATS_EVERY_S = 60.0

    def _on_link_stats(self, stats: Any) -> None:
        """The link's figures (RTT, rates, drops, telemetry gaps) go on record once a
        minute, and when its telemetry loss count changes."""
        if self.recorder is not None:
            self.recorder.link_stats(stats)
        if self.archive is None:
            return
        now = time.monotonic()
        lost = getattr(stats, "telemetry_lost", None)
        if now - getattr(self, "_stats_at", -math.inf) >= self.LINK_STATS_EVERY_S or \
                lost != getattr(self, "_stats_lost", None):
            self._stats_at, self._stats_lost = now, lost
            try:
                data = asdict(stats) if hasattr(stats, "__dataclass_fields__") else dict(stats)
            except (TypeError, ValueError):
                return
            self.archive.add_event(time.time(), "link_stats", data)

    def _on_link_state(self, s: str) -> None:
        self._event("link_state", state=s)
        if s == "connected" and self.archive is not None and not self._robot_named:
            robot = getattr(self.link, "address", "")
            if robot:
                self._robot_named = True
                self.archive.set_session_robot(robot)
        if self.own_alarms and s in ("lost", "reconnecting", "connected"):
            self.monitor.set_condition("link.lost", s != "connected", self.alarm_time(),
                                       source="link", priority=Priority.HIGH,
                                       text="Link to the robot lost")

    def _on_map(self, m: P.MapImage) -> None:
        if self.recorder is not None:
            self.recorder.map_png(m.png)
        digest = hashlib.blake2b(m.png, digest_size=16).digest()
        if self.archive is not None and digest != self._map_digest:  # only when it changed
            self._map_digest = digest
            t = time.time()
            self.archive.add_map(t, m.png)
            # the geometry beside the picture, so replay and reports place poses on it
            self.archive.add_event(t, "map", {
                "resolution_m": float(m.resolution_m), "origin_x_m": float(m.origin_x_m),
                "origin_y_m": float(m.origin_y_m), "width": int(m.width),
                "height": int(m.height)})

    def _on_obstacles(self, _o: Any) -> None:
        if self.recorder is not None:
            self.recorder.count("obstacles")

    def _on_path(self, p: P.Path) -> None:
        if p.kind == P.Path.GLOBAL:
            pts = p.points_xy
            if self.recorder is not None:
                self.recorder.event("global_path", points=len(pts),
                                    start=pts[0].round(2).tolist() if len(pts) else None,
                                    end=pts[-1].round(2).tolist() if len(pts) else None)
            digest = hashlib.blake2b(pts.tobytes(), digest_size=16).digest()
            if self.archive is not None and digest != self._path_digest:
                self._path_digest = digest
                self.archive.add_path(time.time(), "global", pts)
        elif self.recorder is not None:
            self.recorder.count("local_path")

    def _on_patrol(self, st: P.PatrolStatus) -> None:
        """Patrol progress goes on record when its state or point changes."""
        key = (st.state, st.route, st.index, st.reason)
        if key != self._patrol_key:
            self._patrol_key = key
            self._event("patrol_status", state=st.state, route=st.route, index=st.index,
                        progress=st.progress, reason=st.reason)

    # ------------------------------------------------------------ commands
    def _wrap_send_command(self) -> None:
        """Every command sent through this link (the window's too) goes on record
        with who sent it; the robot's ack later completes the row."""
        original = self.link.send_command

        def send_command(*args: Any, **kwargs: Any) -> int:
            seq = original(*args, **kwargs)
            name = args[0] if args else kwargs.get("name", "?")
            cargs = args[1] if len(args) > 1 else kwargs.get("args")
            self.on_command_sent(name, cargs, seq)
            return seq

        self.link.send_command = send_command
        wrapped = ["send_command"]
        # teleop: the drive set-point is renewed many times a second; what goes on
        # record is each change of it (start, new speed or turn, stop)
        self._drive_setpoint = (0.0, 0.0)
        for name in ("drive", "stop"):
            original_drive = getattr(self.link, name, None)
            if callable(original_drive):
                setattr(self.link, name, self._drive_recorder(name, original_drive))
                wrapped.append(name)
        self._unwrap = lambda: [self.link.__dict__.pop(n, None) for n in wrapped]

    def _drive_recorder(self, name: str, original: Any) -> Any:
        def call(*args: Any) -> Any:
            out = original(*args)
            setpoint = (round(float(args[0]), 3), round(float(args[1]), 3)) \
                if name == "drive" and len(args) >= 2 else (0.0, 0.0)
            if setpoint != self._drive_setpoint:
                self._drive_setpoint = setpoint
                self.on_command_sent("drive", {"linear_mps": setpoint[0],
                                               "angular_rps": setpoint[1]}, None)
            return out
        return call

    def on_command_sent(self, name: str, args: dict | None, seq: int | None) -> None:
        self.commands_sent += 1
        if name == "estop":
            self._drive_setpoint = (0.0, 0.0)  # the e-stop zeroes the set-point too
        if self.recorder is not None:
            self.recorder.event("command_sent", command=name, args=args or {}, seq=seq,
                                user=self.user)
        if self.archive is not None:
            self.archive.add_command(time.time(), self.user, name, args or {}, seq=seq)

    # ------------------------------------------------------------ meter readings
    def attach_meter_model(self, model: Any) -> None:
        """Archive the meter model's readings: every frame's reading (raw) and each
        fused record with a small snapshot of the frame it was read from."""
        self._meter_model = model
        self._connect(model.reading_ready, self._on_meter_raw)
        self._connect(model.record_added, self._on_meter_record)

    def _on_meter_raw(self, gauge_id: str, reading: Any) -> None:
        if self.archive is None:
            return
        value = reading.value if reading.value is not None else None
        self.archive.add_meter_reading(
            time.time(), gauge_id, value, reading.unit, reading.confidence, fused=False,
            state="read" if reading.ok else "refused", error=reading.error)

    def _on_meter_record(self, rec: Any) -> None:
        if self.recorder is not None:
            self.recorder.event("meter_reading", gauge=rec.gauge_id, point=rec.point,
                                value=rec.value, unit=rec.unit, state=rec.state,
                                confidence=rec.confidence, reason=rec.reason)
        if self.archive is None:
            return
        image = getattr(getattr(self, "_meter_model", None), "last_image", None)
        if image is None:
            image = self._last_image  # made into a small JPEG in the archive's writer
        conf = rec.confidence if rec.confidence is not None and \
            math.isfinite(rec.confidence) else None
        self.archive.add_meter_reading(rec.t, rec.gauge_id, rec.value, rec.unit, conf,
                                       fused=True, state=rec.state, error=rec.reason,
                                       snapshot_jpeg=image)
        ref_path = getattr(rec, "reference_image", None)
        service = getattr(getattr(self, "_meter_model", None), "service", None)
        if rec.state == OUT_OF_BAND and ref_path and service is not None:
            # a calibrated point out of band: its reference frame goes beside the reading,
            # so the report can show then and now side by side
            ref = service.reference_image(ref_path)
            if ref is not None:
                self.archive.add_snapshot(rec.t, ref, REFERENCE_SNAPSHOT_REASON,
                                          ref=rec.gauge_id)

    # ------------------------------------------------------------ alarms
    def _on_transition(self, tr: Any) -> None:
        """The alarm manager's listener: every transition goes into the archive; a
        raised alarm also gets a snapshot of the current camera frame."""
        if self.archive is None:
            return
        try:
            rec = tr.as_record()
        except Exception as e:
            log.warning("alarm transition not recordable: %s", e)
            return
        self.archive.add_alarm_transition(rec)
        if getattr(tr, "raised", False) and self._last_image is not None:
            # the frame as it is; the archive's writer makes the small JPEG
            self.archive.add_snapshot(rec["t"], self._last_image, "alarm", ref=rec["alarm"])

    def alarm_time(self) -> float:
        """Now on the telemetry's time base (the last sample's time plus the time
        since it arrived), so delays and stale data are judged on one clock."""
        if self._last_data_t is None:
            return time.time()
        return self._last_data_t + max(0.0, time.monotonic() - self._last_data_mono)

    def tick_alarms(self) -> list[AlarmChange]:
        return self.monitor.tick(self.alarm_time())

    def record_alarm(self, change: AlarmChange) -> None:
        a = change.alarm
        if self.recorder is not None:
            if change.raised:
                kind = "alarm_raised"
            elif getattr(change, "cleared", False):
                kind = "alarm_cleared"
            else:  # acknowledged, shelved, out of service, ...
                kind = "alarm_transition"
            self.recorder.event(kind, source=a.key, priority=a.priority.name, value=a.value,
                                limit=a.limit, unit=a.unit, text=a.text,
                                from_state=change.from_state.value,
                                to_state=change.to_state.value, user=change.user,
                                reason=change.reason)
        if self.archive is not None and not hasattr(self.monitor, "add_listener"):
            # a monitor without listeners: archive its changes here
            self.archive.add_alarm_transition({
                "t": time.time(), "alarm": a.key, "source": a.key.split(".")[0],
                "priority": a.priority.name, "from_state": None,
                "to_state": "UNACK" if change.raised else "NORMAL", "value": a.value,
                "limit": a.limit, "unit": a.unit, "text": a.text})
        self.alarm_changed.emit(change)

    @Slot(bool, str)
    def _on_archive_status(self, ok: bool, message: str) -> None:
        """Archive writes failing / recovered (queued here from the writer thread)."""
        self._archive_failing = not ok
        if self.recorder is not None:
            self.recorder.event("archive_status", ok=ok, message=message)
        (log.warning if ok else log.error)("archive: %s", message)
        self._archive_alarm("archive.write", not ok, message)

    def _archive_alarm(self, alarm_id: str, active: bool, text: str) -> None:
        if self.recorder is not None and alarm_id == "archive.open":
            self.recorder.event("archive_status", ok=False, message=text)
        set_condition = getattr(self.monitor, "set_condition", None)
        if set_condition is None:
            return
        try:
            # the transitions reach the recorder and the window through the listeners
            set_condition(alarm_id, active, time.time(), source="archive",
                          priority=Priority.HIGH, text=text)
        except Exception:  # the alarm manager's API may differ; the log still says it
            log.exception("could not raise the %s alarm", alarm_id)

    # ------------------------------------------------------------ end
    def archive_summary(self) -> dict[str, Any] | None:
        if self.archive is None:
            return None
        st = self.archive.stats()
        return {"path": str(self.archive.path), "written": st["written"],
                "pending": st["pending"], "failures": st["failures"],
                "dropped": st["dropped"]}

    def close(self) -> None:
        """Stop listening (the link and the monitor may live on), then close the
        archive (writing what is pending) and the results folder."""
        self._tick.stop()
        for signal, slot in self._links:
            try:
                signal.disconnect(slot)
            except (RuntimeError, TypeError):  # already gone with its owner
                pass
        self._links.clear()
        self._unwrap()
        remove = getattr(self.monitor, "remove_listener", None)
        if remove is not None:
            remove(self._on_transition)
            remove(self.record_alarm)
        if self.archive is not None:
            self.archive.close()
            self.archive.on_status = None  # a writer still retrying must not call back
        if self.recorder is not None:
            if self.archive is not None:
                self.recorder.archive = self.archive_summary()
            self.recorder.close()

    @staticmethod
    def describe(obj) -> dict:
        return asdict(obj)
