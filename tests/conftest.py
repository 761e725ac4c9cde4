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
    """No test writes the archive into the user's data folder."""
    from app.core.records.paths import ENV_VAR

    folder = tmp_path_factory.mktemp("station-patrol-data")
    old = os.environ.get(ENV_VAR)
    os.environ[ENV_VAR] = str(folder)
    yield folder
    if old is None:
        os.environ.pop(ENV_VAR, None)
    else:
        os.environ[ENV_VAR] = old
