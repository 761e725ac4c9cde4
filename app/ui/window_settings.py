"""Settings that last from one run of the desk to the next, kept with ``QSettings``.

:func:`desk_settings` is the one place the desk's settings live (organisation
``Station Patrol``, application ``station-patrol``; the registry on Windows, a plist on
macOS, an INI file under ``~/.config`` on Linux). Keys:

- ``window/geometry``, ``window/state``: the main window's size, place and
  (dock/toolbar) state;
- ``window/splitter/<object name>``: the state of each of the window's splitters;
- ``window/plot_minutes``: the plots' time window;
- ``link/last_address``: the last robot the desk connected to (``--connect`` alone
  goes there again);
- ``ui/language`` belongs to the language setting and is left alone here.

:class:`WindowSettings` restores a window's layout, saves it when the window closes, and
resets it to the layout the window was built with ("Reset layout").
"""

from __future__ import annotations

import logging

from PySide6.QtCore import QByteArray, QCoreApplication, QSettings, QUrl
from PySide6.QtGui import QDesktopServices
from PySide6.QtWidgets import QMainWindow, QSplitter, QStatusBar

from app.logs import current_log_dir

__all__ = ["APP", "ORG", "WindowSettings", "desk_settings", "last_address",
           "open_log_folder", "remember_address"]

log = logging.getLogger(__name__)

ORG, APP = "Station Patrol", "station-patrol"
DEFAULT_SIZE = (1440, 900)


def desk_settings() -> QSettings:
    """The desk's settings store (tests point ``QSettings.setPath`` at a temporary
    folder and ``QSettings.setDefaultFormat`` at INI files)."""
    if not QCoreApplication.organizationName():
        QCoreApplication.setOrganizationName(ORG)
        QCoreApplication.setApplicationName(APP)
    return QSettings(QSettings.defaultFormat(), QSettings.Scope.UserScope, ORG, APP)


def remember_address(host: str, port: int) -> None:
    s = desk_settings()
    s.setValue("link/last_address", f"{host}:{port}")
    s.sync()


def last_address() -> str | None:
    """The last robot address (``HOST:PORT``) the desk connected to, if any."""
    value = desk_settings().value("link/last_address")
    return str(value) if value else None


def open_log_folder(status: QStatusBar | None = None) -> str:
    """Open the desk's log folder (app.logs) in the system's file manager; when that
    fails, name the folder in ``status``. Returns the folder."""
    folder = current_log_dir()
    folder.mkdir(parents=True, exist_ok=True)
    if not QDesktopServices.openUrl(QUrl.fromLocalFile(str(folder))) and status is not None:
        status.showMessage(QCoreApplication.translate("WindowSettings", "Log folder: %1")
                           .replace("%1", str(folder)))
    return str(folder)


class WindowSettings:
    """The layout of ``window`` (a QMainWindow whose splitters have object names, and
    optionally a ``data_panel`` with a plot window) in :func:`desk_settings`."""

    def __init__(self, window: QMainWindow, settings: QSettings | None = None) -> None:
        self.window = window
        self.settings = settings if settings is not None else desk_settings()
        self._default = self._capture()  # the layout as built: what "Reset layout" gives

    def _splitters(self) -> dict[str, QSplitter]:
        return {s.objectName(): s for s in self.window.findChildren(QSplitter)
                if s.objectName()}

    def _plot_minutes(self) -> int | None:
        dp = getattr(self.window, "data_panel", None)
        return None if dp is None else round(dp.window_minutes())

    def _capture(self) -> dict:
        built = getattr(self.window, "default_splitter_sizes", None)
        return {"splitters": dict(built) if built else
                {k: s.sizes() for k, s in self._splitters().items()},
                "plot_minutes": self._plot_minutes()}

    def save(self) -> None:
        s = self.settings
        s.setValue("window/geometry", self.window.saveGeometry())
        s.setValue("window/state", self.window.saveState())
        for name, sp in self._splitters().items():
            s.setValue(f"window/splitter/{name}", sp.saveState())
        minutes = self._plot_minutes()
        if minutes is not None:
            s.setValue("window/plot_minutes", minutes)
        s.sync()
        log.debug("window layout saved to %s", s.fileName())

    def restore(self) -> bool:
        """Apply the saved layout; False when there is none (the caller sizes the
        window). A value that does not fit (another version's) is skipped, logged."""
        s = self.settings
        geometry = s.value("window/geometry")
        if not isinstance(geometry, QByteArray | bytes) or not geometry:
            return False
        if not self.window.restoreGeometry(QByteArray(geometry)):
            log.warning("saved window geometry not usable; default size kept")
            return False
        state = s.value("window/state")
        if isinstance(state, QByteArray | bytes) and state:
            self.window.restoreState(QByteArray(state))
        for name, sp in self._splitters().items():
            blob = s.value(f"window/splitter/{name}")
            if isinstance(blob, QByteArray | bytes) and blob:
                if not sp.restoreState(QByteArray(blob)):
                    log.warning("saved state of splitter %s not usable", name)
        minutes = s.value("window/plot_minutes")
        dp = getattr(self.window, "data_panel", None)
        if dp is not None and minutes is not None:
            try:
                dp.set_window_minutes(int(minutes))
            except (TypeError, ValueError):
                log.warning("saved plot window %r not usable", minutes)
        return True

    def reset(self) -> None:
        """Back to the layout the window was built with; the saved layout is forgotten
        (other settings, such as the language, are kept)."""
        self.settings.remove("window")  # the whole group, nothing else
        self.settings.sync()
        if self.window.isMaximized() or self.window.isFullScreen():
            self.window.showNormal()
        self.window.resize(*DEFAULT_SIZE)
        splitters = self._splitters()
        for name, sizes in self._default["splitters"].items():
            if name in splitters:
                splitters[name].setSizes(sizes)
        dp = getattr(self.window, "data_panel", None)
        if dp is not None and self._default["plot_minutes"] is not None:
            dp.set_window_minutes(self._default["plot_minutes"])
