"""DeskPipeline: the one model of the operator's desk (no Qt).

The window, the headless desk and replay all run this object; Qt code only
adapts it (app/session.py feeds it a link's messages, app/ui turns its
listener calls into signals for the views)::

    link / replay rows ──ingest(kind, msg)──▶ DeskPipeline
        telemetry ─▶ series (ring buffers), latest values, mode
                  ─▶ AlarmMonitor (every telemetry channel, so any rule alarms)
        link state ─▶ link lost / restored (the one decision) ─▶ link.lost alarm
        frames    ─▶ newest frame (the robot's JPEG kept) ─▶ DeskMeters (sessions)
        acks      ─▶ CommandGateway (e-stop delivery)
        everything ─▶ DeskRecording (results folder, archive) — not in replay
    views' intents ─▶ CommandGateway ─▶ the link (journaled: sent/refused/not delivered)
    listeners ◀── values, mode, alarm, link_state, link_restored, frame, event, ...

A message that does not have the expected shape is logged, counted in
``malformed`` and announced to the ``malformed`` listeners; it never raises
into the caller. Alarm timers (delays, stale data, shelving) run on the
telemetry's time base: :meth:`alarm_time` is the last sample's time plus the
monotonic time since it arrived, so a replay judges them on its own clock.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

from app.core.alarms import AlarmConfig, AlarmMonitor, Priority, default_alarm_config
from app.core.alarms.service import ServiceLog, service_alarms
from app.core.desk.channels import TELEMETRY_CHANNELS
from app.core.desk.fws import TEB_EVENT, FwsModel
from app.core.desk.gateway import CommandGateway
from app.core.desk.meters import DeskMeters, run_inline
from app.core.desk.recording import DeskRecording
from app.core.desk.wall import WALL_EVENT, WallModel, archive_record
from app.core.estop import ALARM_ID as ESTOP_ALARM
from app.core.estop import EstopReport
from app.core.i18n import translate
from app.core.meter_service import OUT_OF_BAND, MeterService
from app.core.series import RingBuffer, SeriesSet

__all__ = ["DeskPipeline", "KINDS", "LINK_ABNORMAL"]

log = logging.getLogger(__name__)

KINDS = ("telemetry", "pose", "scan", "frame", "event", "ack", "link_state", "link_stats",
         "map", "path", "patrol_status", "obstacles", "control", "wall", "fws")
SERVICE_CHECK_S = 60.0  # how often the bump-test / calibration record is read again
LINK_ABNORMAL = ("lost", "reconnecting", "disconnected")
_CHANNELS = tuple(c.key for c in TELEMETRY_CHANNELS)
WALL_ARCHIVE_S = 60.0  # a running inspection's record is archived at most this often


class DeskPipeline:
    """``sender``: the link commands go to (None: none; ``replay``: a view-only desk that
    records nothing and sends nothing). ``recorder``/``archive``: where things are kept.
    ``clock``/``mono``: wall (UTC epoch) and monotonic seconds, injectable for tests."""

    def __init__(self, *, sender: Any = None, replay: bool = False, recorder: Any = None,
                 archive: Any = None, archive_error: str | None = None,
                 user: str = "operator", robot: Callable[[], str] | None = None,
                 alarm_config: AlarmConfig | None = None, rules: tuple | None = None,
                 monitor: AlarmMonitor | None = None, meter_service: MeterService | None = None,
                 submit: Callable = run_inline, capacity: int = 72_000,
                 gas_service: Any = None,
                 clock: Callable[[], float] = time.time,
                 mono: Callable[[], float] = time.monotonic) -> None:
        self.replay = replay
        self._clock, self._mono = clock, mono
        self._robot = robot or (lambda: "")
        self._listeners: dict[str, list[Callable]] = defaultdict(list)
        cfg = alarm_config or default_alarm_config()
        if rules is not None:
            cfg = dataclasses.replace(cfg, limits=list(rules))
        self.alarm_config = cfg
        self.monitor = monitor if monitor is not None else AlarmMonitor.from_config(cfg)
        self.monitor.add_listener(self._on_transition)
        self.series = SeriesSet(_CHANNELS, capacity)
        self.record = None if replay else DeskRecording(recorder, archive, user,
                                                        clock=clock, mono=mono)
        self.gateway = CommandGateway(sender, replay=replay, clock=clock, mono=mono,
                                      journal=self._journal, estop_report=self._on_estop)
        self.meters = DeskMeters(meter_service if meter_service is not None
                                 else MeterService(), self.monitor, emit=self._emit,
                                 send=lambda n, a: self.gateway.send(n, a), submit=submit,
                                 mono=mono)
        self.latest: dict[str, float] = {}
        self.latest_t: float | None = None
        self._last_data_mono = 0.0
        self.alarm_flags = 0
        self.mode: int | None = None
        self.samples = 0
        self.frame: Any = None  # the newest camera frame (with the robot's JPEG)
        self.frames = 0
        self.link_state = "disconnected"
        self._was_lost = False
        self.restored_count = 0
        self.malformed = 0
        self.counts: dict[str, int] = defaultdict(int)
        self.wall = WallModel()  # a wall climber's inspection (app/core/desk/wall.py)
        self._wall_archived: tuple[float, str] = (-math.inf, "")
        self.fws = FwsModel()  # a 4WS robot's wheels and TEB plan (app/core/desk/fws.py)
        self.listen("meter_reading", self.record_meter_reading)
        self.listen("meter_record", self.record_meter_record)
        # bump tests and calibrations (app/core/alarms/service.py): a file path, or None
        self.gas_service = None if (replay or gas_service is None) else Path(gas_service)
        self._service_checked = -math.inf
        self.check_gas_service()
        if archive_error is not None:
            self.archive_alarm("archive.open", True,
                               translate("Desk", "Archive not available, nothing is archived: "
                                         "{why}").format(why=archive_error))

    # ------------------------------------------------------------ listeners
    def listen(self, kind: str, fn: Callable) -> None:
        """Call ``fn(*args)`` on ``kind``: values, mode, alarm, link_state, link_restored,
        stats, frame, event, ack, pose, scan, map, path, patrol_status, obstacles, control,
        estop, command, meter_reading, meter_record, meter_session, meter_status, log,
        malformed."""
        self._listeners[kind].append(fn)

    def unlisten(self, kind: str, fn: Callable) -> None:
        if fn in self._listeners.get(kind, []):
            self._listeners[kind].remove(fn)

    def _emit(self, kind: str, *args: Any) -> None:
        for fn in list(self._listeners.get(kind, ())):
            try:
                fn(*args)
            except Exception:  # noqa: BLE001 - one broken view must not stop the desk
                log.exception("desk listener for %s failed", kind)

    # ------------------------------------------------------------ input
    def ingest(self, kind: str, msg: Any) -> bool:
        """One received message (live or replayed). Returns False when it was malformed."""
        handler = getattr(self, f"_on_{kind}", None)
        if handler is None:
            return self._bad(f"unknown message kind {kind!r}")
        try:
            handler(msg)
        except Exception as e:  # anything a bad message provokes
            return self._bad(f"{kind}: {type(e).__name__}: {e}", e)
        self.counts[kind] += 1
        return True

    def _bad(self, why: str, exc: BaseException | None = None) -> bool:
        self.malformed += 1
        log.warning("desk: malformed message ignored (%s); %d so far", why, self.malformed,
                    exc_info=exc if exc is not None and log.isEnabledFor(logging.DEBUG)
                    else None)
        self._emit("malformed", why)
        return False

    def _on_telemetry(self, msg: Any) -> None:
        values = {c: float(getattr(msg, c)) for c in _CHANNELS}
        flags, mode = int(msg.alarm_flags), int(msg.mode)
        t = getattr(msg, "received_s", None)
        t = float(t) if t is not None else self._clock()
        if not math.isfinite(t):
            raise ValueError(f"received_s is {t}")
        self.series.append(t, values)
        self.latest, self.latest_t = values, t
        self._last_data_mono = self._mono()
        self.alarm_flags = flags
        self.samples += 1
        if self.record is not None:
            self.record.telemetry(msg, t)
        # every channel: whatever channel a rule names (now or after a settings change)
        self.monitor.update_many(values, t)
        self.monitor.update_flags(flags, t)
        self._emit("values", values)
        if mode != self.mode:
            self.mode = mode
            self._emit("mode", mode)

    def _on_link_state(self, state: Any) -> None:
        if not isinstance(state, str):
            raise TypeError(f"link state is a {type(state).__name__}, not a str")
        if state in ("lost", "reconnecting"):
            self._was_lost = True
        prev, self.link_state = self.link_state, state
        self.gateway.on_link_state(state)
        if self.record is not None:
            self.record.link_state(state, self._robot())
        if state in ("lost", "reconnecting", "connected") and not self.replay:
            self.monitor.set_condition("link.lost", state != "connected", self.alarm_time(),
                                       source="link", priority=Priority.HIGH,
                                       text="Link to the robot lost")
        if state != prev:
            self._emit("link_state", state)
        if state == "connected" and self._was_lost:
            self._was_lost = False
            self.restored_count += 1
            self._emit("link_restored")

    def _on_link_stats(self, stats: Any) -> None:
        if self.record is not None:
            self.record.link_stats(stats)
        self._emit("stats", stats)
        state = getattr(stats, "state", None)
        if isinstance(state, str) and state and state != self.link_state \
                and not self.replay:
            self._on_link_state(state)

    def _on_frame(self, frame: Any) -> None:
        image = frame.image
        if not (getattr(image, "ndim", 0) == 3 and image.shape[2] == 3 and image.size
                and str(image.dtype) == "uint8"):
            raise ValueError(f"frame image is not HxWx3 uint8 "
                             f"({type(image).__name__} {getattr(image, 'shape', '')})")
        self.frame = frame
        self.frames += 1
        if self.record is not None:
            self.record.frame(frame)
        if not self.replay:  # a replay shows the readings recorded, it reads none
            self.meters.on_frame(frame)
        self._emit("frame", frame)

    def _on_event(self, ev: Any) -> None:
        level, code, text = str(ev.level), str(ev.code), str(ev.text)
        if self.record is not None:
            self.record.event("robot_event", level=level, code=code, text=text, data=ev.data)
        if not self.replay:
            self.meters.on_event(ev)
        self._emit("event", ev)

    def _on_ack(self, a: Any) -> None:
        seq, ok, reason = int(a.cmd_seq), bool(a.ok), str(a.reason)
        if self.record is not None:
            self.record.ack(a)
        self.gateway.on_ack(seq, ok, reason)
        self._emit("ack", a)

    def _on_pose(self, p: Any) -> None:
        float(p.x_m), float(p.y_m), float(p.theta_rad)  # a malformed pose stops here
        if self.record is not None:
            self.record.pose(p)
        self._emit("pose", p)

    def _on_scan(self, s: Any) -> None:
        if self.record is not None:
            self.record.scan(s)
        self._emit("scan", s)

    def _on_map(self, m: Any) -> None:
        if self.record is not None:
            self.record.map(m)
        self._emit("map", m)

    def _on_path(self, p: Any) -> None:
        if self.record is not None:
            self.record.path(p)
        self._emit("path", p)

    def _on_patrol_status(self, st: Any) -> None:
        if self.record is not None:
            self.record.patrol(st)
        self._emit("patrol_status", st)

    def _on_obstacles(self, o: Any) -> None:
        if self.record is not None:
            self.record.count("obstacles")
        self._emit("obstacles", o)

    def _on_control(self, c: Any) -> None:
        self._emit("control", c)

    def _on_wall(self, msg: Any) -> None:
        """A wall climber's message (wall and plan, coverage, probe, pose). A reading
        below the wall's limit raises a HIGH alarm ``wall.thin.r<row>c<col>`` naming
        the place (one per corroded patch); it stays for the operator to acknowledge —
        the steel does not grow back."""
        what = self.wall.ingest(msg)
        if self.record is not None:
            self.record.count(f"wall_{what}")
        thin = []
        if what == "probe" and not self.replay:
            thin = self.wall.new_thin_spots()
            for alarm_id, text, spot in thin:
                self.monitor.set_condition(alarm_id, True, self.alarm_time(), source="wall",
                                           priority=Priority.HIGH, text=text,
                                           value=spot.thickness_mm)
        if what in ("coverage", "probe") and self.record is not None:
            self._archive_wall(bool(thin))
        self._emit("wall", what)

    def _on_fws(self, msg: Any) -> None:
        """A 4WS robot's wheel state or TEB plan (counted in the recording, and kept
        in compact records: FwsModel.wheel_record and teb_record)."""
        what = self.fws.ingest(msg)
        if self.record is not None:
            self.record.count(f"fws_{what}")
            if what == "wheels":  # on a mode change, every 2 s while moving
                rec, kind = self.fws.wheel_record(self._clock()), "fws_wheels"
            else:  # on turning in place or not, else on a change at most every 1 s
                rec, kind = self.fws.teb_record(self._clock()), TEB_EVENT
            if rec is not None:
                self.record.event(kind, **rec)
        self._emit("fws", what)

    def _archive_wall(self, news: bool) -> None:
        """The inspection's record (figures, thickness map, thinnest spots) goes to the
        archive for the report: on a change of state, a new thin place, and at most
        every ``WALL_ARCHIVE_S`` while it runs."""
        now, state = self._clock(), self.wall.state
        last_t, last_state = self._wall_archived
        if news or state != last_state or now - last_t >= WALL_ARCHIVE_S:
            self._wall_archived = (now, state)
            self.record.event(WALL_EVENT, wall=archive_record(self.wall))

    # ------------------------------------------------------------ meters (records)
    def record_meter_reading(self, gauge_id: str, reading: Any) -> None:
        """One frame's reading goes on record (raw)."""
        if self.record is not None:
            self.record.meter_reading(gauge_id, reading)

    def record_meter_record(self, rec: Any) -> None:
        """A fused reading goes on record with the frame it was read from."""
        if self.record is None:
            return
        ref = None
        if rec.state == OUT_OF_BAND and getattr(rec, "reference_image", None):
            ref = self.meters.service.reference_image(rec.reference_image)
        self.record.meter_record(rec, self.meters.snapshot_of(rec), ref)

    # ------------------------------------------------------------ alarms
    def _on_transition(self, tr: Any) -> None:
        if self.record is not None:
            f = self.frame
            snap = None if f is None else (getattr(f, "jpeg", None) or f.image)
            self.record.alarm(tr, snap)
        self._emit("alarm", tr)

    def _on_estop(self, report: EstopReport) -> None:
        if report.alarm is not None:
            self.monitor.set_condition(ESTOP_ALARM, report.alarm, self.alarm_time(),
                                       source="desk", priority=Priority.EMERGENCY,
                                       text=report.text)
        self._emit("estop", report)

    def _journal(self, entry: Any) -> None:
        if self.record is not None:
            self.record.command(entry)
        self._emit("command", entry)

    def alarm_time(self) -> float:
        """Now on the telemetry's time base (the last sample's time plus the time since
        it arrived), so delays and stale data are judged on one clock."""
        if self.latest_t is None:
            return self._clock()
        return self.latest_t + max(0.0, self._mono() - self._last_data_mono)

    def tick(self) -> list:
        """Run the timers (every second or so): alarm delays, stale data and shelving,
        the e-stop's ack timeout, a meter session's timeout."""
        self.gateway.tick()
        self.meters.tick()
        if self._mono() - self._service_checked >= SERVICE_CHECK_S:
            self.check_gas_service()
        return self.monitor.tick(self.alarm_time())

    def check_gas_service(self) -> None:
        """Raise or clear the bump-test and calibration overdue alarms of every gas
        rule from the service record (read afresh, so a test recorded from the
        command line shows within a minute)."""
        self._service_checked = self._mono()
        if self.gas_service is None or not self.monitor.gas_rules:
            return
        book = ServiceLog(self.gas_service)
        if book.problem:
            log.error("gas service record: %s", book.problem)
        for a in service_alarms(book, self.monitor.gas_rules, self._clock()):
            self.monitor.set_condition(a.alarm_id, a.active, self._clock(), source=a.source,
                                       priority=a.priority, text=a.text)

    def archive_alarm(self, alarm_id: str, active: bool, text: str) -> None:
        """The archive failing (or recovered) is a HIGH alarm of the desk."""
        if self.record is not None and alarm_id == "archive.open":
            self.record.archive_status(False, text)
        self.monitor.set_condition(alarm_id, active, self._clock(), source="archive",
                                   priority=Priority.HIGH, text=text)

    def on_archive_status(self, ok: bool, message: str) -> None:
        if self.record is not None:
            self.record.archive_status(ok, message)
        (log.warning if ok else log.error)("archive: %s", message)
        self.archive_alarm("archive.write", not ok, message)

    def mirror_handling(self, tr: dict) -> bool:
        """Replay: repeat a recorded operator action on this desk's monitor."""
        from app.core.desk.replay_rows import mirror_handling
        return mirror_handling(self.monitor, tr)

    # ------------------------------------------------------------ queries
    def robot_id(self) -> str:
        """The robot this desk is connected to, as the link names it ("" when unknown)."""
        return self._robot()

    def window(self, channel: str, seconds: float):
        return self.series.window(channel, seconds)

    def series_of(self, channel: str) -> RingBuffer:
        return self.series[channel]

    def clear(self) -> None:
        """A replay's seek: drop the series and the alarms (the state is shown anew)."""
        self.series.clear()
        self.monitor.clear_all(self._clock())

    def apply_alarm_config(self, cfg: AlarmConfig) -> None:
        """New rules for the running monitor (standing alarms keep their state)."""
        self.alarm_config = cfg
        self.monitor.apply_config(cfg)

    def close(self) -> None:
        self.monitor.remove_listener(self._on_transition)
        if self.record is not None:
            self.record.close()
