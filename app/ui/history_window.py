"""The desk's Review menu: history, replay and the patrol report, each in a
window of its own beside the live desk.

``install_review_menu(window)`` adds the menu to a main window. The archive is
the live session's (``window.session.archive``) or the replayed one
(``window.link.archive``) when there is one, otherwise the archive in the data
folder (``window.data_dir`` or the platform's).

Each reads one desk session (a desk run with one robot): this desk's own, or in
a replay window the replayed one; the window's title says which. The history
window's "Session" box picks another (or all, mixed, said so).

Keys: Ctrl+H history, Ctrl+Shift+P replay of the last hour, Ctrl+Shift+E patrol
report of the last 24 hours.
"""

from __future__ import annotations

import functools
import logging
import math
import time
import weakref
from pathlib import Path
from typing import Any

from PySide6.QtCore import QObject, Qt, Signal
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QComboBox, QFileDialog, QLabel, QMainWindow, QToolBar, QWidget

from app.core.i18n import translate
from app.gui_jobs import GuiJobs
from app.ui.history_model import HistoryModel
from app.ui.history_view import HistoryView

log = logging.getLogger(__name__)

__all__ = ["HistoryWindow", "ReviewActions", "install_review_menu"]


class HistoryWindow(QMainWindow):
    def __init__(self, archive: Any, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(self.tr("Station Patrol — history"))
        self.model = HistoryModel(archive, self)
        self.view = HistoryView(self.model, self)
        self.setCentralWidget(self.view)
        a = QAction(self.tr("Export CSV…"), self)
        a.setShortcut(QKeySequence("Ctrl+E"))
        a.triggered.connect(self.view.export_button.click)
        self.addAction(a)
        a = QAction(self.tr("Close"), self)
        a.setShortcut(QKeySequence("Ctrl+W"))
        a.triggered.connect(self.close)
        self.addAction(a)
        self.resize(1300, 750)
        self._base: Any = None
        self.session_box: QComboBox | None = None

    def offer_sessions(self, archive: Any, current: int | None) -> None:
        """A "Session" box over ``archive``'s sessions (and "all, mixed"), on
        ``current``; choosing one reloads the history from it alone."""
        from app.core.records.queries import describe_session

        self._base = archive
        bar = QToolBar(self.tr("Session"), self)
        bar.setObjectName("sessionBar")
        bar.addWidget(QLabel(self.tr("Session: "), bar))
        box = QComboBox(bar)
        for s in reversed(archive.sessions()):  # newest first
            box.addItem(describe_session(s), s["id"])
        box.addItem(self.tr("all sessions mixed (desks and robots not told apart)"), "all")
        i = box.findData(current)
        box.setCurrentIndex(max(i, 0))
        box.currentIndexChanged.connect(lambda _i: self.choose_session(box.currentData()))
        bar.addWidget(box)
        self.addToolBar(bar)
        self.session_box = box

    def choose_session(self, which: Any) -> str:
        """Read session ``which`` (a number or "all") and reload; returns its line."""
        from app.core.records.queries import choose_session

        rows, line = choose_session(self._base, which)
        self.model.set_archive(rows)
        self.setWindowTitle(self.tr("Station Patrol — history of {which}").format(which=line))
        self.show_recent()
        return line

    def show_recent(self, preset: str = "Last hour") -> None:
        self.view.refresh_channels()
        self.view.select_preset(preset)

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        self.model.shutdown()
        super().closeEvent(event)


def _forget_on_close(windows: list, w: QWidget) -> None:
    """``w`` is deleted when closed and leaves ``windows`` then: a desk that runs for
    days and opens a history or replay now and then keeps only the open ones (each a
    window of plots, tens of MB; a closed replay also stops playing)."""
    w.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
    w.destroyed.connect(functools.partial(_drop, windows, weakref.ref(w)))


def _drop(windows: list, ref: weakref.ref, *_: Any) -> None:
    w = ref()
    windows[:] = [x for x in windows if x is not w]


def _gather(archive: Any, t0: float, t1: float, which: str = "") -> Any:
    """The report's data (on the review menu's pool; app/gui_jobs)."""
    from app.report.data import gather

    source = str(archive.path) + (f", {which}" if which else "")
    return gather(archive, t0, t1, source=source)


class ReviewActions(QObject):
    """The Review menu's actions and the windows they opened."""

    report_written = Signal(str)

    def __init__(self, window: QMainWindow, replay_window: Any = None) -> None:
        super().__init__(window)
        self.window = window
        self.replay_window = replay_window
        self.history_windows: list[HistoryWindow] = []
        self.replay_windows: list[QMainWindow] = []
        self._own_archive: Any = None
        # a report is gathered on the menu's own pool; one being gathered when the
        # window goes is waited for and written nowhere (app/gui_jobs)
        self._jobs = GuiJobs(self)
        menu = window.menuBar().addMenu(self.tr("Re&view"))
        self.history_action = QAction(self.tr("History…"), window)
        self.history_action.setShortcut(QKeySequence("Ctrl+H"))
        self.history_action.triggered.connect(self.open_history)
        self.replay_action = QAction(self.tr("Replay the last hour…"), window)
        self.replay_action.setShortcut(QKeySequence("Ctrl+Shift+P"))
        self.replay_action.triggered.connect(lambda: self.open_replay())
        self.report_action = QAction(self.tr("Patrol report (last 24 h)…"), window)
        self.report_action.setShortcut(QKeySequence("Ctrl+Shift+E"))
        self.report_action.triggered.connect(lambda: self.ask_report())
        for a in (self.history_action, self.replay_action, self.report_action):
            menu.addAction(a)
            window.addAction(a)
        window.destroyed.connect(self.close_archive)

    def close_archive(self) -> None:
        """Close the archive this menu opened itself (not the live session's)."""
        if self._own_archive is not None:
            self._jobs.wait(10000)
            self._own_archive.close()
            self._own_archive = None

    # ------------------------------------------------------------ archive
    def archive(self) -> Any:
        live = getattr(getattr(self.window, "session", None), "archive", None)
        if live is None:  # a replay window reviews the archive it replays
            live = getattr(getattr(self.window, "link", None), "archive", None)
        if live is not None:
            return live
        if self._own_archive is None:
            from app.core.records import Archive
            from app.core.records.paths import default_archive_path

            path = default_archive_path(getattr(self.window, "data_dir", None) or None)
            if not path.exists():
                self._say(self.tr("no archive at {path}").format(path=path))
                return None
            try:
                self._own_archive = Archive(path)
            except Exception as e:
                self._say(self.tr("cannot open the archive: {why}").format(why=e))
                return None
        return self._own_archive

    def scoped(self, t0: float = -math.inf, t1: float = math.inf) -> tuple[Any, str]:
        """The rows to review and a line saying which: this desk's own session (a
        replay window: the session it replays; no live session: the latest)."""
        from app.core.records.queries import SessionView, choose_session

        archive = self.archive()
        if archive is None:
            return None, ""
        if isinstance(archive, SessionView):
            return archive, archive.describe()
        own = getattr(archive, "session_id", None)
        try:
            return choose_session(archive, "latest" if own is None else own, t0, t1)
        except ValueError as e:  # the live session's row is not readable (yet)
            log.warning("review: %s; showing every session", e)
            return archive, "all sessions mixed"

    def _say(self, text: str) -> None:
        log.info("review: %s", text)
        self.window.statusBar().showMessage(text, 8000)

    # ------------------------------------------------------------ actions
    def open_history(self) -> HistoryWindow | None:
        archive, which = self.scoped()
        if archive is None:
            return None
        w = HistoryWindow(archive)
        w.setWindowTitle(translate("HistoryWindow", "Station Patrol — history of {which}")
                         .format(which=which))
        base = getattr(archive, "archive", archive)  # a session view's archive
        if hasattr(base, "sessions"):
            w.offer_sessions(base, getattr(archive, "scope_session", "all"))
        self.history_windows.append(w)
        _forget_on_close(self.history_windows, w)
        w.show()
        w.show_recent()
        return w

    def open_replay(self, t0: float | None = None, t1: float | None = None) -> Any:
        """A replay in a window of the desk's own kind (no import of the main window:
        the window module imports this one)."""
        from app.ui.replay import open_replay_window

        archive, which = self.scoped()
        if archive is None:
            return None
        rec = archive.time_range()
        if rec is None:
            self._say(self.tr("the archive holds no recording yet"))
            return None
        t1 = rec[1] if t1 is None else t1
        t0 = max(rec[0], t1 - 3600.0) if t0 is None else t0
        if self.replay_window is None:
            self._say(self.tr("this window cannot open a replay"))
            return None
        win, link = open_replay_window(self.replay_window, archive, which, t0, t1)
        win.resize(1440, 900)
        self.replay_windows.append(win)
        _forget_on_close(self.replay_windows, win)
        win.destroyed.connect(link.shutdown)
        win.show()
        link.start()
        return win

    def ask_report(self, path: str | None = None, t0: float | None = None,
                   t1: float | None = None) -> bool:
        """Write a report (default: the last 24 hours); asks where when no path."""
        archive, which = self.scoped()
        if archive is None:
            return False
        if path is None:
            path, _ = QFileDialog.getSaveFileName(
                self.window, self.tr("Patrol report"), "patrol-report.pdf",
                self.tr("PDF (*.pdf);;HTML (*.html)"))
            if not path:
                return False
        if Path(path).suffix.lower() not in (".pdf", ".html", ".htm"):
            path += ".pdf"
        t1 = time.time() if t1 is None else t1
        t0 = t1 - 86400.0 if t0 is None else t0
        self._say(self.tr("gathering the report…"))
        self._jobs.start(functools.partial(_gather, archive, t0, t1, which),
                         functools.partial(self._write_report, path=path),
                         self._gather_failed)
        return True

    def _gather_failed(self, e: BaseException) -> None:
        log.error("report: gathering failed", exc_info=(type(e), e, e.__traceback__))
        self._say(self.tr("report failed: {why}").format(why=f"{type(e).__name__}: {e}"))

    def _write_report(self, data: Any, path: str) -> None:
        from app.report.render import write_report

        try:
            write_report(data, path)
        except (OSError, ValueError) as e:
            self._say(self.tr("report failed: {why}").format(why=e))
            return
        self._say(self.tr("report written: {path}").format(path=path))
        self.report_written.emit(path)

    def wait(self, timeout_ms: int = 10000) -> bool:
        return self._jobs.wait(timeout_ms)


def install_review_menu(window: QMainWindow, replay_window: Any = None) -> ReviewActions:
    """``replay_window``: the desk window class a replay opens in (MainWindow passes
    itself, so this module never imports the window module that imports it)."""
    return ReviewActions(window, replay_window)
