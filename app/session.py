"""DeskSession: runs the desk pipeline on a link, in the Qt event loop.

The desk's logic lives in :class:`app.core.desk.DeskPipeline` (no Qt); this
class is only the Qt adapter that the window, the headless desk and replay all
use. It feeds the link's signals to ``pipeline.ingest`` (the one ingest path,
live or replayed), runs the pipeline's timers, reads meters on a one-thread
pool, queues the archive writer's status onto the GUI thread, and implements
the command gateway's sender with the link itself (the link's methods are
never replaced).
"""

from __future__ import annotations

import functools
import getpass
import logging
import sys
import weakref
from pathlib import Path
from typing import Any

from PySide6.QtCore import QObject, QTimer, Signal, Slot

from app.core.alarms import AlarmConfig, AlarmMonitor
from app.core.desk import DeskPipeline
from app.core.i18n import QT_TRANSLATE_NOOP
from app.core.records import Archive, ArchiveError, default_archive_path
from app.gui_gc import disconnect_all
from app.gui_jobs import GuiJobs

log = logging.getLogger(__name__)

# the pipeline's message kinds and the link signal each comes from
LINK_SIGNALS = {"telemetry": "telemetry_received", "pose": "pose_received",
                "scan": "scan_received", "frame": "frame_decoded", "event": "event_received",
                "ack": "ack_received", "link_state": "state_changed",
                "link_stats": "stats_changed", "map": "map_received", "path": "path_received",
                "patrol_status": "patrol_status_received",
                "obstacles": "obstacles_received", "control": "control_changed",
                "wall": "wall_received", "fws": "fws_received"}


# The archive writer only appends (and prunes once in a while): a small page cache
# serves it. SQLite's default (2000 KiB) filled over the desk's first minutes and
# stayed, part of the memory a fresh desk grew by; the file's pages stay in the
# system's cache for whatever reads them.
WRITER_CACHE_KIB = 256


def open_archive(data_dir: str | Path | None = None, *, retention_days: float | None = 30.0,
                 export_dir: str | Path | None = None,
                 path: str | Path | None = None) -> tuple[Archive | None, str | None]:
    """Open (or create) the desk's archive. Returns (archive, None), or (None, message)
    when the file cannot be used: the desk then runs without an archive and says so."""
    p = Path(path) if path is not None else default_archive_path(data_dir or None)
    try:
        archive = Archive(p, retention_days=retention_days, export_dir=export_dir)
    except ArchiveError as e:
        log.error("archive disabled: %s", e)
        return None, str(e)
    bound_writer_cache(archive)
    return archive, None


def bound_writer_cache(archive: Archive, kib: int = WRITER_CACHE_KIB) -> bool:
    """Set the archive writer's SQLite page cache to ``kib`` KiB (True when set; a
    writer that does not answer keeps SQLite's default, a bound too, and is logged)."""
    try:
        archive.call_in_writer(lambda con: con.execute(f"PRAGMA cache_size=-{int(kib)}"))
    except Exception as e:  # noqa: BLE001 - the archive works on with the default cache
        log.warning("archive writer's page cache left at SQLite's default: %s", e)
        return False
    return True


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


def start_foxglove(cfg: Any, pipeline: Any) -> Any:
    """The live Foxglove WebSocket view of ``pipeline`` when ``cfg.foxglove`` asks for it
    (None otherwise, or when it cannot start: then said on stderr, the desk runs on)."""
    fg = cfg.foxglove
    if not fg.enabled:
        return None
    try:
        from app.core.interop.foxglove_live import FoxgloveLive

        live = FoxgloveLive(pipeline, fg.port, fg.host)
    except Exception as e:  # a busy port, a bad host: the desk runs without it
        print(f"station-patrol: Foxglove server not started on {fg.host}:{fg.port}: {e}",
              file=sys.stderr, flush=True)
        return None
    print(f"station-patrol: Foxglove live view on ws://{fg.host}:{live.port}"
          + ("" if fg.host in ("127.0.0.1", "localhost", "::1") else
             " (reachable from the network: the protocol has no authentication)"),
          flush=True)
    return live


def _user() -> str:
    try:
        return getpass.getuser()
    except Exception:
        return "operator"


def desk_name(link: Any) -> str:
    name = getattr(link, "desk_name", None)
    if callable(name):
        try:
            name = name()
        except Exception:
            name = None
    return name if isinstance(name, str) and name else _user()


def _ingest(session: weakref.ref, kind: str, msg: Any = None) -> None:
    desk = session()
    if desk is not None:
        desk.pipeline.ingest(kind, msg)


class DeskSession(QObject):
    """``DeskSession(link, recorder, monitor=None, *, archive=..., replay=...)``: a desk
    pipeline fed by ``link``. ``replay``: a view-only desk (nothing recorded or sent)."""

    alarm_changed = Signal(object)  # AlarmChange
    archive_status = Signal(bool, str)  # ok, message (from the archive's writer thread)

    def __init__(self, link: Any, recorder: Any = None, monitor: AlarmMonitor | None = None,
                 *, archive: Archive | None = None, archive_error: str | None = None,
                 user: str | None = None, alarm_config: AlarmConfig | None = None,
                 tick_ms: int = 1000, replay: bool = False, meter_service: Any = None,
                 parent: QObject | None = None, **pipeline_kw: Any) -> None:
        super().__init__(parent)
        self.link = link
        self.recorder = recorder
        self.archive = archive
        # the meter worker's pool; results come back queued on this thread (app/gui_jobs)
        self.jobs = GuiJobs(self)
        self.pool = self.jobs.pool
        self.pipeline = DeskPipeline(
            sender=None if replay else link, replay=replay, recorder=recorder,
            archive=archive, archive_error=archive_error,
            user=user or desk_name(link), robot=lambda: getattr(link, "address", ""),
            alarm_config=alarm_config, monitor=monitor, meter_service=meter_service,
            submit=self._submit, **pipeline_kw)
        self.monitor = self.pipeline.monitor
        self.gateway = self.pipeline.gateway
        self.user = self.pipeline.record.user if self.pipeline.record else (user or "")
        self.archive_session = self.pipeline.record.session if self.pipeline.record else None
        self.pipeline.listen("alarm", self.alarm_changed.emit)
        # (signal, slot), undone by close() or when the session is deleted. The slots
        # hold the session weakly: a link that outlives the session (or sits in a cycle
        # with it) would otherwise keep it, its window and their plots alive through
        # the connection, which the garbage collector cannot see
        self._links: list[tuple[Any, Any]] = []
        self.destroyed.connect(functools.partial(disconnect_all, self._links))
        me = weakref.ref(self)
        for kind, name in LINK_SIGNALS.items():
            sig = getattr(link, name, None)
            if sig is not None:
                self._connect(sig, functools.partial(_ingest, me, kind))
        self._tick = QTimer(self)
        self._tick.setInterval(min(int(tick_ms), 250))  # the e-stop ack timer too
        self._tick.timeout.connect(self.tick)
        self._tick.start()
        self.archive_status.connect(self._on_archive_status)
        if archive is not None:
            archive.on_status = self.archive_status.emit

    def _connect(self, signal: Any, slot: Any) -> None:
        signal.connect(slot)
        self._links.append((signal, slot))

    def _submit(self, job: Any, done: Any) -> None:
        self.jobs.start(job, done)  # done(result) on this (the desk's) thread

    # ------------------------------------------------------------ API
    @property
    def bad_messages(self) -> int:
        return self.pipeline.malformed

    @property
    def commands_sent(self) -> int:
        return self.gateway.counts["sent"]

    def ingest(self, kind: str, msg: Any) -> bool:
        return self.pipeline.ingest(kind, msg)

    def tick(self) -> list:
        return self.pipeline.tick()

    tick_alarms = tick

    def alarm_time(self) -> float:
        return self.pipeline.alarm_time()

    @Slot(bool, str)
    def _on_archive_status(self, ok: bool, message: str) -> None:
        """Archive writes failing / recovered (queued here from the writer thread)."""
        self.pipeline.on_archive_status(ok, message)

    def archive_summary(self) -> dict[str, Any] | None:
        rec = self.pipeline.record
        return rec.summary() if rec is not None else None

    def wait_idle(self, timeout_ms: int = 5000) -> bool:
        """Wait for the meter worker to finish its frame (tests, shutdown)."""
        return self.jobs.wait(timeout_ms)

    def close(self) -> None:
        """Stop listening (the link may live on), then close the archive (writing what
        is pending) and the results folder."""
        self._tick.stop()
        disconnect_all(self._links)
        self.jobs.wait(3000)
        self.pipeline.close()


class OpcUaService:
    """The desk's OPC UA server on ``pipeline`` as ``cfg.opcua`` says (app/interop/opcua),
    with the timer that runs the control room's calls on this (the desk's) thread."""

    def __init__(self, cfg: Any, pipeline: Any) -> None:
        from app.core.records.paths import default_data_dir
        from app.interop.opcua.server import OpcUaDeskServer
        from app.interop.opcua.users import UserStore, default_users_file

        o = cfg.opcua
        base = Path(cfg.data_dir) if cfg.data_dir else default_data_dir()
        users = UserStore(o.users_file or default_users_file(cfg.data_dir))
        self.server = OpcUaDeskServer(o, users=users, pki_dir=base / "opcua" / "pki")
        self.server.attach(pipeline)
        self.server.start()
        self._timer = QTimer()
        self._timer.timeout.connect(self.server.drain)
        self._timer.start(50)

    def warnings(self) -> list[str]:
        """What the operator must be told loudly (anonymous or None security on)."""
        o = self.server.settings
        out = []
        if o.allow_anonymous:
            out.append(QT_TRANSLATE_NOOP("OpcUa", "OPC UA: ANONYMOUS ACCESS ON"))
        if o.allow_none_security:
            out.append(QT_TRANSLATE_NOOP("OpcUa", "OPC UA: SECURITY NONE ON"))
        return out

    def stop(self) -> None:
        self._timer.stop()
        self.server.stop()
