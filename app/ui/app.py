"""Start the desk with a window: ``run_window(cfg)`` (used by ``station-patrol``)."""

from __future__ import annotations

import logging
import signal
import sys

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QApplication

from app.comm.link import RobotLink
from app.config import DeskConfig
from app.ui.main_window import MainWindow
from app.ui.theme import apply_theme

log = logging.getLogger(__name__)


def show_and_run(app: QApplication, win, duration_s: float | None = None) -> int:
    """Show ``win`` and run the event loop until it closes; returns the exit code.

    ``duration_s``: close the window after this long (demos, screenshots). Ctrl+C
    closes it too: a slow timer wakes the loop so Python sees the signal."""
    win.resize(1440, 900)
    win.show()
    if duration_s is not None and duration_s > 0:
        QTimer.singleShot(int(duration_s * 1000), win.close)
    signal.signal(signal.SIGINT, lambda *_: QTimer.singleShot(0, win.close))
    wake = QTimer()
    wake.timeout.connect(lambda: None)
    wake.start(200)
    return app.exec()


def run_window(cfg: DeskConfig, *, duration_s: float | None = None,
               record: bool = False) -> int:
    """Open the desk connected to ``cfg.host:cfg.port``; returns the exit code.

    ``duration_s``: close the window after this long (demos, screenshots).
    ``record``: also write the session to ``cfg.out_dir`` (see app/core/recorder).
    """
    app = QApplication.instance() or QApplication(sys.argv[:1])
    apply_theme(app)
    link = RobotLink(cfg.link)
    win = MainWindow(link)
    from app.core.recorder import SessionRecorder
    from app.session import DeskSession, open_desk_archive

    # everything received and every command sent goes into the archive; the results
    # folder is written too when recording was asked for
    archive, archive_error = open_desk_archive(cfg)
    session = DeskSession(link, SessionRecorder(cfg.out_dir) if record else None,
                          win.telemetry_model.monitor, own_alarms=False, archive=archive,
                          archive_error=archive_error)
    win.telemetry_model.alarm_changed.connect(session.record_alarm)
    if hasattr(win, "meter_model"):
        session.attach_meter_model(win.meter_model)
    win.session = session
    if cfg.start_patrol:
        link.send_when_connected("start_patrol", {})
    link.connect_to(cfg.host, cfg.port)
    code = show_and_run(app, win, duration_s)
    link.shutdown()
    session.close()
    if record:
        log.info("session recorded in %s", cfg.out_dir)
    if archive is not None:
        log.info("archive: %s", archive.path)
    return code
