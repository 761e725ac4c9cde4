"""Where the archive lives: the platform's user-data folder, unless told otherwise."""

from __future__ import annotations

from pathlib import Path

from app.core import paths

ENV_VAR = paths.DATA_ENV
ARCHIVE_NAME = "archive.sqlite3"


def default_data_dir() -> Path:
    """The desk's data folder.

    ``$STATION_PATROL_DATA_DIR`` wins; otherwise the platform convention:
    Linux ``$XDG_DATA_HOME/station-patrol`` (``~/.local/share/station-patrol``),
    macOS ``~/Library/Application Support/Station Patrol``, Windows
    ``%LOCALAPPDATA%\\Station Patrol``. The folder is not created here.
    """
    return paths.data_dir()


def default_archive_path(data_dir: str | Path | None = None) -> Path:
    return Path(data_dir if data_dir is not None else default_data_dir()) / ARCHIVE_NAME
