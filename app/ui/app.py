"""Start the desk with a window: ``run_window(cfg)`` (used by ``station-patrol``), or a
replay of the archive: ``replay_main(...)`` (``station-patrol --replay``).

This is the top of the window's imports: it imports the main window and the replay,
and nothing in app/ui imports it."""

from __future__ import annotations

import gc
import logging
import math
import signal
import sys
from typing import Any

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QApplication

from app.comm.link import RobotLink
from app.config import DeskConfig
from app.core.alarms.service import default_service_path
from app.core.i18n import translate
from app.gui_gc import collect_on_gui_thread
from app.i18n import start_language
from app.ui.main_window import MainWindow
from app.ui.replay import open_replay_window
from app.ui.theme import apply_theme

log = logging.getLogger(__name__)


def freeze_startup_heap() -> int:
    """Move every object alive now (modules, widgets, the desk's models: the
    start-up's heap) out of the garbage collector's way (``gc.freeze``), after one
    collection of what start-up left behind. A full collection of the desk's heap
    takes 50 ms of CPU and more (bench/stall_profile.py prints them), all of it on
    whichever thread allocates, most often the GUI thread; the objects made at
    start-up live as long as the desk, so the collector need not look at them again.
    Returns how many objects were frozen."""
    gc.collect()
    gc.freeze()
    return gc.get_freeze_count()


def start_app(lang: str | None = None) -> QApplication:
    """The desk's QApplication (made once): its language and theme, and the garbage
    collector kept to the GUI thread (app/gui_gc: a window or model in a reference
    cycle must never be deleted on the link, pool or archive writer's thread)."""
    app = QApplication.instance() or QApplication(sys.argv[:1])
    start_language(app, lang)
    apply_theme(app)
    collect_on_gui_thread(app)
    return app


def show_and_run(app: QApplication, win, duration_s: float | None = None, *,
                 resize: bool = True) -> int:
    """Show ``win`` and run the event loop until it closes; returns the exit code.

    ``duration_s``: close the window after this long (demos, screenshots). Ctrl+C
    closes it too: a slow timer wakes the loop so Python sees the signal. ``resize``:
    give the window its default size first (not when a saved layout was restored)."""
    if resize:
        win.resize(1440, 900)
    win.show()
    if duration_s is not None and duration_s > 0:
        QTimer.singleShot(int(duration_s * 1000), win.close)
    signal.signal(signal.SIGINT, lambda *_: QTimer.singleShot(0, win.close))
    wake = QTimer()
    wake.timeout.connect(lambda: None)
    wake.start(200)
    return app.exec()


def build_window(link: Any, recorder: Any = None, archive: Any = None,
                 archive_error: str | None = None, **kw: Any) -> MainWindow:
    """The desk window on ``link``: its desk session (the same pipeline as the headless
    desk's, app/headless.build_headless_desk) and the main window showing it."""
    from app.session import DeskSession

    desk = DeskSession(link, recorder, archive=archive, archive_error=archive_error, **kw)
    win = MainWindow(link, desk=desk)
    desk.setParent(win)
    return win


def _serve_opcua(cfg: DeskConfig, win: Any) -> Any:
    """The desk's OPC UA server on the window's pipeline; a failure to start is shown,
    never fatal. Anonymous or None security on: a red permanent note in the status bar."""
    from PySide6.QtWidgets import QLabel

    from app.session import OpcUaService

    try:
        svc = OpcUaService(cfg, win.desk.pipeline)
    except (RuntimeError, OSError, ValueError) as e:
        log.error("%s", e)
        win.statusBar().showMessage(
            translate("MainWindow", "OPC UA server not started: {why}").format(why=e))
        return None
    note = " · ".join(translate("OpcUa", w) for w in svc.warnings())
    if note:
        label = QLabel(note)
        label.setStyleSheet("color: white; background: #b00020; font-weight: bold; "
                            "padding: 0 6px;")
        win.statusBar().addPermanentWidget(label)
    return svc


def run_window(cfg: DeskConfig, *, duration_s: float | None = None,
               record: bool = False, lang: str | None = None) -> int:
    """Open the desk connected to ``cfg.host:cfg.port``; returns the exit code.

    ``duration_s``: close the window after this long (demos, screenshots).
    ``record``: also write the session to ``cfg.out_dir`` (see app/core/recorder).
    ``lang``: ``zh_CN`` or ``en`` (None: the stored setting, else the system's; app/i18n).
    """
    app = start_app(lang)
    link = RobotLink(cfg.link)
    from app.core.recorder import SessionRecorder
    from app.session import open_desk_archive, start_foxglove

    # one desk pipeline: everything received and every command sent goes into the
    # archive; the results folder is written too when recording was asked for
    archive, archive_error = open_desk_archive(cfg)
    win = build_window(link, SessionRecorder(cfg.out_dir) if record else None, archive,
                       archive_error, gas_service=default_service_path(cfg.data_dir or None))
    desk = win.desk
    desk.pipeline.meters.warm_up()  # the first reading's growth now, not minutes in
    restored = win.keep_layout()  # the layout of the last run; saved again on close
    live = start_foxglove(cfg, desk.pipeline)
    opcua = _serve_opcua(cfg, win) if cfg.opcua.endpoint else None
    if cfg.start_patrol:
        desk.gateway.send_when_connected("start_patrol", {})
    link.connect_to(cfg.host, cfg.port)
    freeze_startup_heap()
    code = show_and_run(app, win, duration_s, resize=not restored)
    if opcua is not None:
        opcua.stop()
    link.shutdown()
    if live is not None:
        live.close()
    desk.close()
    if record:
        log.info("session recorded in %s", cfg.out_dir)
    if archive is not None:
        log.info("archive: %s", archive.path)
    return code


def replay_main(cfg: Any, frm: str | None, to: str | None, *,
                duration_s: float | None = None, display: bool = True,
                session: str | int | None = "latest", lang: str | None = None) -> int:
    """``station-patrol --replay [--from] [--to] [--session] [--data-dir] [--lang]``; bad
    input exits 2."""
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
    return run_replay(str(path), t0, t1, duration_s=duration_s, session=session, lang=lang)


def run_replay(archive_path: str, t0: float | None = None, t1: float | None = None,
               *, speed: float = 1.0, autoplay: bool = True,
               duration_s: float | None = None, session: str | int | None = "latest",
               lang: str | None = None) -> int:
    """Open the desk window in replay mode over ``archive_path``; returns the exit code.
    ``session``: which desk session to replay (a number, "latest" with data in the
    range, or "all" mixed); the window's title says which."""
    from app.core.records import Archive

    app = start_app(lang)
    from app.core.records.queries import choose_session

    archive = Archive(archive_path)
    try:
        rows, which = choose_session(archive, session,
                                     -math.inf if t0 is None else t0,
                                     math.inf if t1 is None else t1)
        win, link = open_replay_window(MainWindow, rows, which, t0, t1)
    except ValueError as e:
        archive.close()
        print(f"station-patrol: {e}", file=sys.stderr)
        return 2
    print(f"station-patrol: replaying {which}", flush=True)
    link.start()
    link.set_speed(speed)
    if autoplay:
        link.play()
    code = show_and_run(app, win, duration_s)
    link.shutdown()
    archive.close()
    return code
