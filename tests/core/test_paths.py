"""Shipped resources are found inside the package; user files go to the user's folders."""

from __future__ import annotations

import json
from pathlib import Path

from app.core import paths
from app.core.alarms import DEFAULT_ALARMS_FILE
from app.core.meter_service import DEFAULT_GAUGE_DIR, DEFAULT_STATION_FILE, MeterService


def test_resources_are_inside_the_package():
    root = paths.resources_root()
    import app

    assert root == Path(app.__file__).resolve().parent / "resources"
    for f in (DEFAULT_ALARMS_FILE, DEFAULT_STATION_FILE, paths.resource("routes", "default.json"),
              paths.resource("station", "station_map.png")):
        assert f.is_file(), f
        assert paths.is_shipped(f)
    assert sorted(p.name for p in DEFAULT_GAUGE_DIR.glob("*.json"))


def test_resources_do_not_depend_on_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert paths.resource("alarms.toml").is_file()
    assert paths.resource("alarms.toml").is_absolute()


def test_user_folders_follow_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv(paths.DATA_ENV, str(tmp_path / "d"))
    monkeypatch.setenv(paths.LOG_ENV, str(tmp_path / "l"))
    monkeypatch.delenv(paths.ROUTES_ENV, raising=False)
    assert paths.data_dir() == tmp_path / "d"
    assert paths.log_dir() == tmp_path / "l"
    assert paths.user_routes_dir() == tmp_path / "d" / "routes"
    assert paths.user_gauges_dir() == tmp_path / "d" / "gauges"
    monkeypatch.setenv(paths.ROUTES_ENV, str(tmp_path / "r"))
    assert paths.user_routes_dir() == tmp_path / "r"
    assert not paths.is_shipped(tmp_path / "r" / "default.json")


def test_a_shipped_route_is_copied_before_it_is_written(tmp_path, monkeypatch):
    monkeypatch.setenv(paths.ROUTES_ENV, str(tmp_path / "routes"))
    shipped = paths.resource("routes", "default.json")
    assert paths.default_route_file() == shipped  # no route of the operator's yet
    copy = paths.writable_route(shipped)
    assert copy == tmp_path / "routes" / "default.json"
    assert copy.read_bytes() == shipped.read_bytes()
    assert paths.default_route_file() == copy  # the operator's copy wins from now on
    mine = tmp_path / "elsewhere.json"
    assert paths.writable_route(mine) == mine  # not shipped: itself
    # an existing copy is kept, not overwritten by the shipped one
    copy.write_text(json.dumps({"name": "mine", "points": []}))
    assert json.loads(paths.writable_route(shipped).read_text())["name"] == "mine"


def test_an_operator_profile_overrides_the_shipped_one(tmp_path, monkeypatch):
    monkeypatch.setenv(paths.DATA_ENV, str(tmp_path))
    svc = MeterService()
    some = next(iter(svc.gauges.values())).type
    assert svc.profile_file(some) == DEFAULT_GAUGE_DIR / f"{some}.json"
    mine = tmp_path / "gauges" / f"{some}.json"
    mine.parent.mkdir()
    mine.write_text((DEFAULT_GAUGE_DIR / f"{some}.json").read_text())
    assert MeterService().profile_file(some) == mine
    # an explicit folder is the only one looked in
    assert MeterService(gauge_dir=DEFAULT_GAUGE_DIR).profile_file(some) == \
        DEFAULT_GAUGE_DIR / f"{some}.json"
