"""The desk without a window: the same desk pipeline as the window (app/session.py's
DeskSession over app/core/desk), recording what the robot sends, then a summary."""

from __future__ import annotations

import json
import logging
import signal
import sys
import time
from typing import Any

from PySide6.QtCore import QCoreApplication, QTimer

from app.comm.link import RobotLink
from app.config import DeskConfig
from app.core.alarms.service import default_service_path
from app.core.recorder import SessionRecorder
from app.gui_gc import collect_on_gui_thread
from app.session import DeskSession, OpcUaService, open_desk_archive, start_foxglove

log = logging.getLogger(__name__)


def build_headless_desk(link: Any, recorder: Any, archive: Any = None,
                        archive_error: str | None = None, **kw: Any) -> DeskSession:
    """The headless desk on ``link``: the window's desk pipeline without the window. The
    meters are read as with a window (on the session's worker thread, fused, recorded, an
    out-of-band reading an alarm), with the robot's default route's calibrated points."""
    from app.core.paths import default_route_file

    session = DeskSession(link, recorder, archive=archive, archive_error=archive_error, **kw)
    why = session.pipeline.meters.service.set_route(default_route_file())
    if why is not None:
        log.warning("route not used for meter profiles: %s", why)
    # the calibrated points' reference frames measured now, not on their first frames
    session.pipeline.meters.service.prepare_route()
    return session


def start_headless_app() -> QCoreApplication:
    """The headless desk's QCoreApplication (made once), with the garbage collector
    kept to its thread as the window's (app/gui_gc): a desk session or link caught in a
    reference cycle must never be deleted on the archive writer's or a pool's thread."""
    app = QCoreApplication.instance() or QCoreApplication(sys.argv[:1])
    collect_on_gui_thread(app)
    return app


def run_headless(cfg: DeskConfig) -> int:
    app = start_headless_app()
    link = RobotLink(cfg.link)
    recorder = SessionRecorder(cfg.out_dir)
    archive, archive_error = open_desk_archive(cfg)
    if archive_error:
        print(f"station-patrol: archive disabled: {archive_error}", file=sys.stderr, flush=True)
    session = build_headless_desk(link, recorder, archive, archive_error,
                                  gas_service=default_service_path(cfg.data_dir or None))
    session.pipeline.meters.warm_up()  # the first reading's growth now, not minutes in
    live = start_foxglove(cfg, session.pipeline)
    opcua = None
    if cfg.opcua.endpoint:  # the same pipeline served as the window serves it
        try:
            opcua = OpcUaService(cfg, session.pipeline)
        except (RuntimeError, OSError, ValueError) as e:
            print(f"station-patrol: {e}", file=sys.stderr)
            if live is not None:
                live.close()
            session.close()
            return 1
        print(f"station-patrol: OPC UA server on {opcua.server.url}", flush=True)
        for w in opcua.warnings():
            print(f"station-patrol: WARNING {w}", file=sys.stderr, flush=True)
    t0 = time.monotonic()

    def finish() -> None:
        app.quit()

    QTimer.singleShot(int(cfg.headless_duration_s * 1000), finish)
    # Ctrl+C ends the run early but still writes the summary
    signal.signal(signal.SIGINT, lambda *_: QTimer.singleShot(0, finish))
    signal.signal(signal.SIGTERM, lambda *_: QTimer.singleShot(0, finish))
    wake = QTimer()
    wake.timeout.connect(lambda: None)  # let Python see signals while Qt waits
    wake.start(200)
    states: set[str] = set()
    link.state_changed.connect(states.add)
    if cfg.start_patrol:
        session.gateway.send_when_connected("start_patrol", {})
    link.connect_to(cfg.host, cfg.port)
    app.exec()
    if opcua is not None:
        opcua.stop()
    link.shutdown()
    if live is not None:
        live.close()
    session.close()
    summary = recorder.summary()
    if "connected" not in states:
        why = link.last_error
        print(f"station-patrol: never connected to {cfg.host}:{cfg.port} in "
              f"{time.monotonic() - t0:.1f} s" + (f" ({why})" if why else "")
              + f"; results in {recorder.out.resolve()}", file=sys.stderr)
        return 1
    print(f"station-patrol: headless run of {time.monotonic() - t0:.1f} s finished; "
          f"results in {recorder.out.resolve()}")
    result = {"counts": summary["counts"], "active_alarms": summary["active_alarms"],
              "unacknowledged_alarms": [a.key for a in session.monitor.unacknowledged()],
              "video_latency_ms": summary["video_latency_ms"], "archive": summary["archive"]}
    if session.pipeline.wall.ready:  # a wall climber: its inspection's figures
        result["wall"] = session.pipeline.wall.summary()
    print(json.dumps(result, indent=None))
    return 0 if summary["counts"].get("telemetry", 0) > 0 else 1
