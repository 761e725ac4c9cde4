"""The full desk window on a tape, kept apart from the user's own desk.

The benches that play a recorded patrol into the window (``bench/desk_replay_ab.py``,
``bench/tape_memory.py``) build it the same way: the desk's data, key and config
folders (archive, station key, QSettings) point into a new temporary folder, Qt's
messages go to stderr but for the offscreen plugin's size-hint note, and the window is
built as ``station-patrol --connect`` builds it, with its archive, fed by a
:class:`bench.link_tape.TapePlayer`. :func:`open_desk` returns it shown, the meter
reader warmed up and the start-up heap frozen, with the tape not yet started: the
caller starts its probes, then ``link.start()``.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path


def _qt_message(_mode, _ctx, text: str) -> None:
    if "propagateSizeHints" not in text:  # the offscreen plugin's note, on every show
        print(f"Qt: {text}", file=sys.stderr)


def open_desk(tape_path: str | Path, prefix: str, app_class=None):
    """``(app, link, win)``: a new QApplication (``app_class``, QApplication by
    default) with the theme, the tape player ``link`` and the desk window ``win``.
    The temporary folder is named ``prefix`` and a random tail."""
    folder = Path(tempfile.mkdtemp(prefix=prefix))
    os.environ["STATION_PATROL_DATA_DIR"] = str(folder / "data")
    os.environ["STATION_PATROL_KEY_FILE"] = str(folder / "station.key")
    os.environ["XDG_CONFIG_HOME"] = str(folder / "config")  # QSettings, not the user's
    from PySide6.QtCore import qInstallMessageHandler
    from PySide6.QtWidgets import QApplication

    qInstallMessageHandler(_qt_message)
    from app.config import DeskConfig
    from app.session import open_desk_archive
    from app.ui.app import build_window, freeze_startup_heap
    from app.ui.theme import apply_theme
    from bench.link_tape import TapePlayer

    app = (app_class or QApplication)(sys.argv[:1])
    apply_theme(app)
    link = TapePlayer(tape_path)
    archive, archive_error = open_desk_archive(DeskConfig())
    win = build_window(link, None, archive, archive_error)
    win.resize(1440, 900)
    win.show()
    win.desk.pipeline.meters.warm_up()
    freeze_startup_heap()
    return app, link, win
