"""DeskSession: wires a RobotLink to the session recorder and the alarm rules.

Used by the headless desk and, with a window, beside the panels. The rules and
the recorder are Qt-free (app/core); this class is only the glue.
"""

from __future__ import annotations

import logging
from dataclasses import asdict

from PySide6.QtCore import QObject, Signal

from app.comm import protocol as P
from app.comm.link import RobotLink
from app.core.alarms import AlarmChange, AlarmMonitor
from app.core.recorder import SessionRecorder

log = logging.getLogger(__name__)

CHANNELS = ("gas_lel_pct", "temp_c", "humidity_pct", "battery_v")


class DeskSession(QObject):
    alarm_changed = Signal(object)  # AlarmChange

    def __init__(self, link: RobotLink, recorder: SessionRecorder,
                 monitor: AlarmMonitor | None = None, *, own_alarms: bool = True) -> None:
        """``own_alarms``: evaluate the alarm rules here (headless). With a window
        the telemetry model evaluates them and :meth:`record_alarm` is connected
        to it instead, so the rules run once."""
        super().__init__()
        self.link = link
        self.recorder = recorder
        self.monitor = monitor or AlarmMonitor()
        self.own_alarms = own_alarms
        self.bad_messages = 0
        link.telemetry_received.connect(self._on_telemetry)
        link.pose_received.connect(recorder.pose)
        link.scan_received.connect(recorder.scan)
        link.frame_decoded.connect(
            lambda f: recorder.frame(f.frame_id, f.latency_ms, f.image))
        link.event_received.connect(
            lambda e: recorder.event("robot_event", level=e.level, code=e.code, text=e.text,
                                     data=e.data))
        link.ack_received.connect(
            lambda a: recorder.event("command_ack", cmd_seq=a.cmd_seq, ok=a.ok,
                                     reason=a.reason))
        link.state_changed.connect(lambda s: recorder.event("link_state", state=s))
        self._patrol_key: tuple = ()
        for name, slot in (("map_received", lambda m: recorder.map_png(m.png)),
                           ("path_received", self._on_path),
                           ("patrol_status_received", self._on_patrol),
                           ("obstacles_received", lambda _o: recorder.count("obstacles"))):
            if hasattr(link, name):
                getattr(link, name).connect(slot)
        link.stats_changed.connect(recorder.link_stats)

    def _on_telemetry(self, t: P.Telemetry) -> None:
        try:
            self.recorder.telemetry(t)
            if self.own_alarms:
                ts = getattr(t, "received_s", None)
                changes = self.monitor.update_many({c: getattr(t, c) for c in CHANNELS}, ts)
                changes += self.monitor.update_flags(int(t.alarm_flags), ts)
                for ch in changes:
                    self.record_alarm(ch)
        except (AttributeError, TypeError, ValueError) as e:
            self.bad_messages += 1
            log.warning("telemetry message not usable (%s); %d so far", e, self.bad_messages)

    def _on_path(self, p: P.Path) -> None:
        if p.kind == P.Path.GLOBAL:
            pts = p.points_xy
            self.recorder.event("global_path", points=len(pts),
                                start=pts[0].round(2).tolist() if len(pts) else None,
                                end=pts[-1].round(2).tolist() if len(pts) else None)
        else:
            self.recorder.count("local_path")

    def _on_patrol(self, st: P.PatrolStatus) -> None:
        """Patrol progress goes on record when its state or point changes."""
        key = (st.state, st.route, st.index, st.reason)
        if key != self._patrol_key:
            self._patrol_key = key
            self.recorder.event("patrol_status", state=st.state, route=st.route,
                                index=st.index, progress=st.progress, reason=st.reason)

    def record_alarm(self, change: AlarmChange) -> None:
        a = change.alarm
        self.recorder.event("alarm_raised" if change.raised else "alarm_cleared",
                            source=a.key, priority=a.priority.name, value=a.value,
                            limit=a.limit, unit=a.unit, text=a.text)
        self.alarm_changed.emit(change)

    def close(self) -> None:
        self.recorder.close()

    @staticmethod
    def describe(obj) -> dict:
        return asdict(obj)
