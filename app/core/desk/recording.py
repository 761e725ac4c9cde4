"""What the desk keeps: the results folder (SessionRecorder) and the archive (no Qt).

:class:`DeskRecording` is the pipeline's output side. Everything the desk
receives and every command it sends goes into the archive (when one is open)
and into the results folder (when one is written). Nothing here keeps a
per-message list: memory stays flat over a long run. Times come from the
pipeline's clock, so a replayed or synthetic stream is stored as given.
"""

from __future__ import annotations

import hashlib
import logging
import math
from collections.abc import Callable
from dataclasses import asdict, fields
from typing import Any

from app.comm import protocol as P
from app.core.meter_service import OUT_OF_BAND, REFERENCE_SNAPSHOT_REASON

__all__ = ["ARCHIVED_TELEMETRY", "DeskRecording"]

log = logging.getLogger(__name__)

# every numeric telemetry field goes into the archive
ARCHIVED_TELEMETRY = tuple(f.name for f in fields(P.Telemetry))
LINK_STATS_EVERY_S = 60.0


class DeskRecording:
    """``recorder``: app.core.recorder.SessionRecorder or None; ``archive``:
    app.core.records.Archive or None; ``user``: who the commands are journaled for."""

    def __init__(self, recorder: Any, archive: Any, user: str, *,
                 clock: Callable[[], float], mono: Callable[[], float]) -> None:
        self.recorder = recorder
        self.archive = archive
        self.user = user
        self._clock, self._mono = clock, mono
        self.session: int | None = None
        self._robot_named = False
        self._map_digest = b""
        self._path_digest = b""
        self._patrol_key: tuple = ()
        self._stats_at = -math.inf
        self._stats_lost: Any = None
        if archive is not None:
            # every row this desk writes belongs to this session (docs/archive.md)
            try:
                self.session = archive.begin_session(user)
            except Exception as e:  # noqa: BLE001 - a failing archive is its own alarm
                log.warning("archive session not started: %s", e)

    def event(self, kind: str, t: float | None = None, **data: Any) -> None:
        if self.recorder is not None:
            self.recorder.event(kind, **data)
        if self.archive is not None:
            self.archive.add_event(self._clock() if t is None else t, kind, data)

    def telemetry(self, msg: Any, t: float) -> None:
        if self.recorder is not None:
            self.recorder.telemetry(msg)
        if self.archive is not None:
            self.archive.add_telemetry(t, {c: getattr(msg, c) for c in ARCHIVED_TELEMETRY},
                                       seq=getattr(msg, "seq", None))

    def pose(self, p: Any) -> None:
        if self.recorder is not None:
            self.recorder.pose(p)
        if self.archive is not None:
            self.archive.add_pose(self._clock(), p.x_m, p.y_m, p.theta_rad)

    def scan(self, s: Any) -> None:
        if self.recorder is not None:
            self.recorder.scan(s)

    def frame(self, f: Any) -> None:
        """The robot's own JPEG bytes when the frame carries them (no re-encoding)."""
        if self.recorder is not None:
            jpeg = getattr(f, "jpeg", None)
            self.recorder.frame(f.frame_id, f.latency_ms, jpeg if jpeg else f.image)

    def ack(self, a: Any) -> None:
        if self.recorder is not None:
            self.recorder.event("command_ack", cmd_seq=a.cmd_seq, ok=a.ok, reason=a.reason)
        if self.archive is not None:
            self.archive.ack_command(a.cmd_seq, a.ok, a.reason, self._clock())

    def command(self, entry: Any) -> None:
        """One journaled intent (app.core.desk.gateway.JournalEntry), with who asked."""
        user = getattr(entry, "user", "") or self.user
        if self.recorder is not None:
            self.recorder.event("command_sent", command=entry.name, args=entry.args,
                                seq=entry.seq, user=user, outcome=entry.outcome,
                                why=entry.why)
        if self.archive is not None:
            args = dict(entry.args)
            if entry.outcome != "sent":  # the archive's command row says what became of it
                args["outcome"] = entry.outcome + (f": {entry.why}" if entry.why else "")
            self.archive.add_command(entry.t, user, entry.name, args, seq=entry.seq,
                                     acked=False if entry.outcome != "sent" else None)

    def link_stats(self, stats: Any) -> None:
        """The link's figures go on record once a minute, and when its telemetry loss
        count changes."""
        if self.recorder is not None:
            self.recorder.link_stats(stats)
        if self.archive is None:
            return
        now = self._mono()
        lost = getattr(stats, "telemetry_lost", None)
        if now - self._stats_at >= LINK_STATS_EVERY_S or lost != self._stats_lost:
            self._stats_at, self._stats_lost = now, lost
            try:
                data = asdict(stats) if hasattr(stats, "__dataclass_fields__") else dict(stats)
            except (TypeError, ValueError):
                return
            self.archive.add_event(self._clock(), "link_stats", data)

    def link_state(self, state: str, robot: str) -> None:
        self.event("link_state", state=state)
        if state == "connected" and self.archive is not None and robot \
                and not self._robot_named:
            self._robot_named = True
            self.archive.set_session_robot(robot)

    def map(self, m: Any) -> None:
        if self.recorder is not None:
            self.recorder.map_png(m.png)
        digest = hashlib.blake2b(m.png, digest_size=16).digest()
        if self.archive is not None and digest != self._map_digest:  # only when it changed
            self._map_digest = digest
            t = self._clock()
            self.archive.add_map(t, m.png)
            # the geometry beside the picture, so replay and reports place poses on it
            self.archive.add_event(t, "map", {
                "resolution_m": float(m.resolution_m), "origin_x_m": float(m.origin_x_m),
                "origin_y_m": float(m.origin_y_m), "width": int(m.width),
                "height": int(m.height)})

    def path(self, p: Any) -> None:
        if p.kind != P.Path.GLOBAL:
            if self.recorder is not None:
                self.recorder.count("local_path")
            return
        pts = p.points_xy
        if self.recorder is not None:
            self.recorder.event("global_path", points=len(pts),
                                start=pts[0].round(2).tolist() if len(pts) else None,
                                end=pts[-1].round(2).tolist() if len(pts) else None)
        digest = hashlib.blake2b(pts.tobytes(), digest_size=16).digest()
        if self.archive is not None and digest != self._path_digest:
            self._path_digest = digest
            self.archive.add_path(self._clock(), "global", pts)

    def patrol(self, st: Any) -> None:
        """Patrol progress goes on record when its state or point changes."""
        key = (st.state, st.route, st.index, st.reason)
        if key != self._patrol_key:
            self._patrol_key = key
            # with the route's points (and their states), so a replay draws the route
            self.event("patrol_status", state=st.state, route=st.route, index=st.index,
                       progress=st.progress, reason=st.reason,
                       local_planner=getattr(st, "local_planner", ""),
                       points=[dict(p) for p in (st.points or []) if isinstance(p, dict)])

    def count(self, kind: str) -> None:
        if self.recorder is not None:
            self.recorder.count(kind)

    # ------------------------------------------------------------ meters
    def meter_reading(self, gauge_id: str, reading: Any) -> None:
        if self.archive is None:
            return
        self.archive.add_meter_reading(
            self._clock(), gauge_id, reading.value, reading.unit, reading.confidence,
            fused=False, state="read" if reading.ok else "refused", error=reading.error)

    def meter_record(self, rec: Any, snapshot: Any, reference: Any) -> None:
        """A fused reading with the frame it was read from (JPEG bytes or RGB); a calibrated
        point out of band gets its reference frame beside it, for the report."""
        if self.recorder is not None:
            self.recorder.event("meter_reading", gauge=rec.gauge_id, point=rec.point,
                                value=rec.value, unit=rec.unit, state=rec.state,
                                confidence=rec.confidence, reason=rec.reason)
        if self.archive is None:
            return
        conf = rec.confidence if rec.confidence is not None and \
            math.isfinite(rec.confidence) else None
        self.archive.add_meter_reading(rec.t, rec.gauge_id, rec.value, rec.unit, conf,
                                       fused=True, state=rec.state, error=rec.reason,
                                       snapshot_jpeg=snapshot)
        if rec.state == OUT_OF_BAND and reference is not None:
            self.archive.add_snapshot(rec.t, reference, REFERENCE_SNAPSHOT_REASON,
                                      ref=rec.gauge_id)

    # ------------------------------------------------------------ alarms
    def alarm(self, change: Any, frame_jpeg: Any) -> None:
        """Every alarm transition into the archive (a raised alarm with a snapshot of the
        current camera frame) and the results folder."""
        a = change.alarm
        if self.recorder is not None:
            kind = "alarm_raised" if change.raised else (
                "alarm_cleared" if getattr(change, "cleared", False) else "alarm_transition")
            self.recorder.event(kind, source=a.key, priority=a.priority.name, value=a.value,
                                limit=a.limit, unit=a.unit, text=a.text,
                                from_state=change.from_state.value,
                                to_state=change.to_state.value, user=change.user,
                                reason=change.reason)
        if self.archive is None:
            return
        try:
            rec = change.as_record()
        except Exception as e:  # noqa: BLE001 - one odd transition must not stop the desk
            log.warning("alarm transition not recordable: %s", e)
            return
        self.archive.add_alarm_transition(rec)
        if change.raised and frame_jpeg is not None:
            self.archive.add_snapshot(rec["t"], frame_jpeg, "alarm", ref=rec["alarm"])

    def archive_status(self, ok: bool, message: str) -> None:
        if self.recorder is not None:
            self.recorder.event("archive_status", ok=ok, message=message)

    # ------------------------------------------------------------ end
    def summary(self) -> dict[str, Any] | None:
        if self.archive is None:
            return None
        st = self.archive.stats()
        return {"path": str(self.archive.path), "written": st["written"],
                "pending": st["pending"], "failures": st["failures"],
                "dropped": st["dropped"]}

    def close(self) -> None:
        """Close the archive (writing what is pending), then the results folder."""
        if self.archive is not None:
            self.archive.close()
            self.archive.on_status = None  # a writer still retrying must not call back
        if self.recorder is not None:
            if self.archive is not None:
                self.recorder.archive = self.summary()
            self.recorder.close()
