"""Where the archive lives: the platform's user-data folder, unless told otherwise."""

from __future__ import annotations

import os
import sys
from pathlib import Path

ENV_VAR = "STATION_PATROL_DATA_DIR"
ARCHIVE_NAME = "archive.sqlite3"


def default_data_dir() -> Path:
    """The desk's data folder.

    ``$STATION_PATROL_DATA_DIR`` wins; otherwise the platform convention:
    Linux ``$XDG_DATA_HOME/station-patrol`` (``~/.local/share/station-patrol``),
    macOS ``~/Library/Application Support/Station Patrol``, Windows
    ``%LOCALAPPDATA%\\Station Patrol``. The folder is not created here.
    """
    env = os.environ.get(ENV_VAR)
    if env:
        return Path(env).expanduser()
    home = Path.home()
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA")
        return (Path(base) if base else home / "AppData" / "Local") / "Station Patrol"
    if sys.platform == "darwin":
        return home / "Library" / "Application Support" / "Station Patrol"
    xdg = os.environ.get("XDG_DATA_HOME")
    return (Path(xdg) if xdg else home / ".local" / "share") / "station-patrol"


def default_archive_path(data_dir: str | Path | None = None) -> Path:
    return Path(data_dir if data_dir is not None else default_data_dir()) / ARCHIVE_NAME
