import os

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _station_key_in_tmp(tmp_path_factory, monkeypatch):
    """Every test signs and checks commands with a station key of its own,
    never the one in the user's config folder."""
    d = tmp_path_factory.mktemp("station-key")
    monkeypatch.setenv("STATION_PATROL_KEY_FILE", str(d / "station.key"))


@pytest.fixture(autouse=True, scope="session")
def _data_dir_in_tmp(tmp_path_factory):
    """No test writes the archive, routes, profiles, logs or the desk's settings
    (QSettings, under $XDG_CONFIG_HOME on Linux) into the user's folders."""
    from app.core.paths import DATA_ENV, LOG_ENV

    folder = tmp_path_factory.mktemp("station-patrol-data")
    old = {k: os.environ.get(k) for k in (DATA_ENV, LOG_ENV, "XDG_CONFIG_HOME")}
    os.environ[DATA_ENV] = str(folder)
    os.environ[LOG_ENV] = str(folder / "log")
    os.environ["XDG_CONFIG_HOME"] = str(folder / "config")
    yield folder
    for k, v in old.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


@pytest.fixture(autouse=True)
def _desk_logging_undone():
    """A test that starts the desk installs its console and file log handlers on the
    root logger; they go with the test (and so does their folder), so later threads
    do not write into other tests' output and a later test's log folder is its own."""
    from app.logs import stop_logging

    yield
    stop_logging()
