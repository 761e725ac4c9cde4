"""Where Station Patrol finds its files.

Two kinds, kept apart so that an installed wheel works from any folder:

* **Shipped resources** (alarm rules, the station's layout and map, gauge profiles, the
  default route) live inside the package, in ``app/resources``, and are found with
  :mod:`importlib.resources` — never by a path relative to the source tree or to the
  working directory. They are read-only: nothing writes there.
* **User files** (routes, calibrated profiles, site alarm files, the station key, the
  archive, logs) live in the platform's per-user folders (:mod:`platformdirs`):
  Linux ``~/.local/share/station-patrol`` (data), ``~/.config/station-patrol`` (keys),
  ``~/.local/state/station-patrol/log`` (logs), ``~/.cache/station-patrol`` (caches);
  macOS ``~/Library/Application Support/Station Patrol`` and ``~/Library/Logs/Station Patrol``;
  Windows ``%LOCALAPPDATA%\\Station Patrol`` (data, logs) and ``%APPDATA%\\Station Patrol`` (keys).
  Each folder can be overridden by an environment variable (below) and, where the desk
  has one, by its flag or TOML setting. Nothing is created here.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import shutil
import sys
from importlib import resources
from pathlib import Path

import platformdirs

__all__ = ["CACHE_ENV", "DATA_ENV", "LOG_ENV", "ROUTES_ENV", "app_name", "cache_dir",
           "config_dir", "data_dir",
           "default_route_file", "is_shipped", "log_dir", "resource", "resources_root",
           "user_gauges_dir", "user_routes_dir", "writable_route"]

CACHE_ENV = "STATION_PATROL_CACHE_DIR"
DATA_ENV = "STATION_PATROL_DATA_DIR"
LOG_ENV = "STATION_PATROL_LOG_DIR"
ROUTES_ENV = "STATION_PATROL_ROUTES_DIR"

_extracted = contextlib.ExitStack()  # only used when the package is not on a file system
atexit.register(_extracted.close)
_ROOT: Path | None = None


def resources_root() -> Path:
    """The shipped resources folder as a real path (a zipped install is extracted once)."""
    global _ROOT
    if _ROOT is None:
        tree = resources.files("app") / "resources"
        if isinstance(tree, Path):
            _ROOT = tree
        else:  # e.g. a zip import: OpenCV and friends want real files
            _ROOT = Path(_extracted.enter_context(resources.as_file(tree)))
    return _ROOT


def resource(*parts: str) -> Path:
    """A shipped resource, e.g. ``resource("gauges", "paper_0_4mpa.json")``."""
    return resources_root().joinpath(*parts)


def is_shipped(path: str | os.PathLike) -> bool:
    """True when ``path`` lies inside the shipped (read-only) resources."""
    try:
        Path(path).resolve().relative_to(resources_root().resolve())
    except ValueError:
        return False
    return True


def app_name() -> str:
    """The folder name: ``station-patrol`` on Linux and other Unixes, ``Station Patrol``
    on Windows and macOS (as the desk has always used)."""
    return "Station Patrol" if sys.platform in ("win32", "darwin") else "station-patrol"


def _env(name: str) -> Path | None:
    value = os.environ.get(name)
    return Path(value).expanduser() if value else None


def _dirs(*, roaming: bool = False) -> platformdirs.PlatformDirsABC:
    """platformdirs' folders for the platform as ``sys.platform`` says now (its own
    ``platformdirs.user_*_dir`` fix the platform at import time)."""
    if sys.platform == "win32":
        from platformdirs.windows import Windows as Dirs
    elif sys.platform == "darwin":
        from platformdirs.macos import MacOS as Dirs
    else:
        from platformdirs.unix import Unix as Dirs
    return Dirs(app_name(), appauthor=False, roaming=roaming)


def data_dir() -> Path:
    """The desk's data folder (archive, routes, calibrated profiles):
    ``$STATION_PATROL_DATA_DIR`` or the platform's user-data folder (local, not roaming,
    on Windows)."""
    return _env(DATA_ENV) or Path(_dirs().user_data_dir)


def config_dir() -> Path:
    """The per-user configuration folder (the station key; roaming on Windows)."""
    return Path(_dirs(roaming=True).user_config_dir)


def cache_dir() -> Path:
    """Where the desk keeps what it can make again (e.g. the OPC UA server's standard
    address space): ``$STATION_PATROL_CACHE_DIR`` or the platform's user-cache folder.
    Deleting it loses nothing but time."""
    return _env(CACHE_ENV) or Path(_dirs().user_cache_dir)


def log_dir() -> Path:
    """The log folder: ``$STATION_PATROL_LOG_DIR`` or the platform's user-log folder."""
    return _env(LOG_ENV) or Path(_dirs().user_log_dir)


def user_routes_dir() -> Path:
    """Where the operator's routes are saved: ``$STATION_PATROL_ROUTES_DIR`` or
    ``<data dir>/routes``."""
    return _env(ROUTES_ENV) or data_dir() / "routes"


def user_gauges_dir() -> Path:
    """Where gauge profiles calibrated by the operator are saved: ``<data dir>/gauges``.
    A profile there overrides the shipped one of the same name."""
    return data_dir() / "gauges"


def default_route_file() -> Path:
    """The desk's default route: the operator's ``default.json`` when there is one, else
    the shipped route (the robot's default)."""
    mine = user_routes_dir() / "default.json"
    return mine if mine.is_file() else resource("routes", "default.json")


def writable_route(path: str | os.PathLike) -> Path:
    """``path`` itself, unless it is a shipped route: that is first copied to the user's
    routes folder (an existing copy there is kept) and the copy is returned."""
    path = Path(path)
    if not is_shipped(path):
        return path
    target = user_routes_dir() / path.name
    if not target.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, target)
    return target
