"""Calibrated inspection points stored with the route: round trip, atomic writes, refusals,
and the meter service choosing the point's profile (Qt-free)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from app.core import route as R
from app.core.inspection_points import calibrate_point, point_file_stem, suggest_points
from app.core.meter import load_profile
from app.core.meter_service import DEFAULT_GAUGE_DIR, MeterService
from sim_robot import gauge_render
from sim_robot.route import parse_route

BASE = load_profile(DEFAULT_GAUGE_DIR / "pressure_0_1p6mpa.json")
ROUTE = {"name": "north", "points": [
    {"name": "PG-101", "kind": "meter", "x_m": 30.0, "y_m": 28.4, "gauge": "PG-101",
     "dwell_s": 4.0},
    {"name": "T-101 south wall", "kind": "tank_wall", "x_m": 19.0, "y_m": 29.9,
     "gauge": None, "dwell_s": 3.0},
    {"name": "PG-101 again", "kind": "meter", "x_m": 30.2, "y_m": 28.4, "gauge": "PG-101",
     "dwell_s": 2.0},
]}
CLICKS = ((320.0, 240.0), (220.0, 320.0), (400.0, 340.0))


def _frame(value: float = 0.9, seed: int = 3) -> np.ndarray:
    spec = gauge_render.stock_spec("pressure_0_1p6mpa")
    bgr, _ = gauge_render.render_view(spec, value, rng=np.random.default_rng(seed),
                                      frame_size=(640, 480), fill=0.6, offset_frac=(0, 0))
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


@pytest.fixture
def route_file(tmp_path: Path) -> Path:
    p = tmp_path / "routes" / "north.json"
    p.parent.mkdir()
    p.write_text(json.dumps(ROUTE), encoding="utf-8")
    return p


def _gauges() -> dict:
    from app.core.meter_service import load_station_gauges

    return load_station_gauges()


def test_calibrated_point_round_trip(route_file):
    img = _frame()
    done = calibrate_point(route_file, "PG-101", BASE, img, *CLICKS)
    # the route names the profile relative to its own folder; other points are untouched
    route = R.load_route(route_file)
    by_name = {p.name: p for p in route.points}
    assert by_name["PG-101"].profile == "north.points/PG-101.json" == done.relative
    assert by_name["PG-101 again"].profile is None
    assert done.profile == route_file.parent / "north.points" / "PG-101.json"
    # the profile: the gauge type's values and band, the clicks, the reference frame
    prof = load_profile(done.profile)
    assert (prof.unit, prof.min_value, prof.max_value) == (BASE.unit, 0.0, 1.6)
    assert (prof.normal_min, prof.normal_max) == (BASE.normal_min, BASE.normal_max)
    assert prof.calibration.center == CLICKS[0]
    assert prof.calibration.min_point == CLICKS[1]
    assert prof.calibration.max_point == CLICKS[2]
    assert prof.calibration.clockwise is True
    assert prof.calibration.image_path == done.image == done.profile.with_suffix(".png")
    assert json.loads(done.profile.read_text())["calibration"]["image"] == "PG-101.png"
    ref = cv2.cvtColor(cv2.imread(str(done.image)), cv2.COLOR_BGR2RGB)
    assert np.array_equal(ref, img)  # PNG: the frame exactly as it was frozen
    # saved again by the desk's route code: the key stays; the robot accepts the file
    R.save_route(route, route_file)
    assert R.load_route(route_file).points[0].profile == "north.points/PG-101.json"
    robot_route = parse_route(json.loads(route_file.read_text()))
    assert [p.name for p in robot_route.points] == [p["name"] for p in ROUTE["points"]]


def test_recalibrating_a_point_replaces_its_files(route_file):
    first = calibrate_point(route_file, "PG-101", BASE, _frame(0.5), *CLICKS)
    moved = ((322.0, 241.0), (221.0, 322.0), (402.0, 338.0))
    second = calibrate_point(route_file, "PG-101", BASE, _frame(1.2), *moved)
    assert second.profile == first.profile and second.image == first.image
    assert load_profile(second.profile).calibration.center == moved[0]
    assert sorted(f.name for f in second.profile.parent.iterdir()) == \
        ["PG-101.json", "PG-101.png"]  # no temporary files left behind


def test_point_names_become_safe_distinct_file_names(route_file):
    assert point_file_stem("T-101 south wall") == "T-101_south_wall"
    assert point_file_stem("../../etc/passwd") == "etc_passwd"
    assert point_file_stem("///") == "point"
    r = dict(ROUTE, points=[dict(ROUTE["points"][0], name="a b"),
                            dict(ROUTE["points"][2], name="a/b")])
    route_file.write_text(json.dumps(r), encoding="utf-8")
    one = calibrate_point(route_file, "a b", BASE, _frame(), *CLICKS)
    two = calibrate_point(route_file, "a/b", BASE, _frame(), *CLICKS)
    assert one.relative == "north.points/a_b.json"
    assert two.relative == "north.points/a_b-2.json"
    assert load_profile(two.profile).calibration.image_path.name == "a_b-2.png"


@pytest.mark.parametrize("bad, why", [
    ("/etc/passwd.json", "relative"),
    ("../other/PG-101.json", ".."),
    ("north.points/../../x.json", ".."),
    ("C:/profiles/x.json", "relative"),
    ("north.points\\x.json", "backslash"),
    ("", "non-empty"),
    ("  x.json", "non-empty"),
    (".", "does not name a file"),
    (5, "string"),
])
def test_bad_profile_paths_are_refused(bad, why):
    obj = json.loads(json.dumps(ROUTE))
    obj["points"][0]["profile"] = bad
    with pytest.raises(ValueError, match="'profile'") as e:
        R.route_from_dict(obj)
    assert why in str(e.value)
    assert "PG-101" in str(e.value)  # names the point


def test_a_profile_needs_the_points_gauge():
    obj = json.loads(json.dumps(ROUTE))
    obj["points"][1]["profile"] = "north.points/wall.json"
    with pytest.raises(ValueError, match="needs the point's 'gauge'"):
        R.route_from_dict(obj)


@pytest.mark.parametrize("point, clicks, image, why", [
    ("nowhere", CLICKS, None, "no point named"),
    ("T-101 south wall", CLICKS, None, "has no gauge"),
    ("PG-101", ((320.0, 240.0), (220.0, 320.0), (700.0, 340.0)), None, "outside"),
    ("PG-101", ((320.0, 240.0), (220.0, 320.0), ("x", 1)), None, "pair of numbers"),
    ("PG-101", CLICKS, np.zeros((480, 640), np.uint8), "RGB image"),
    ("PG-101", ((320.0, 240.0), (320.0, 240.0), (400.0, 340.0)), None, "from the center"),
])
def test_refusals_leave_the_route_as_it_was(route_file, point, clicks, image, why):
    before = route_file.read_bytes()
    with pytest.raises(ValueError, match=why):
        calibrate_point(route_file, point, BASE, _frame() if image is None else image,
                        *clicks)
    assert route_file.read_bytes() == before
    assert not (route_file.parent / "north.points").exists()  # nothing written


def test_route_write_is_atomic(route_file, monkeypatch):
    """A failure while the route is replaced leaves the old route whole, no temp files."""
    before = route_file.read_bytes()

    def boom(src, dst):
        if Path(dst) == route_file:
            raise OSError("disk full")
        return real_replace(src, dst)

    real_replace = R.os.replace
    monkeypatch.setattr(R.os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        calibrate_point(route_file, "PG-101", BASE, _frame(), *CLICKS)
    assert route_file.read_bytes() == before
    leftovers = [f.name for f in route_file.parent.rglob("*") if f.name.endswith(".tmp")]
    assert leftovers == []


def test_meter_service_prefers_the_points_profile(route_file, tmp_path):
    svc = MeterService(_gauges())
    assert svc.set_route(route_file) is None
    assert svc.profile_for("PG-101", "PG-101").calibration is None  # not calibrated yet
    done = calibrate_point(route_file, "PG-101", BASE, _frame(), *CLICKS)
    assert svc.set_route(route_file) is None
    prof = svc.profile_for("PG-101", "PG-101")
    assert prof.calibration is not None and prof.calibration.image_path == done.image
    # another point, no point, or another gauge at that point: the gauge type's profile
    assert svc.profile_for("PG-101", "PG-101 again").calibration is None
    assert svc.profile_for("PG-101", None).calibration is None
    assert svc.profile_for("PG-102", "PG-101").calibration is None
    s = svc.start("PG-101", "PG-101")
    assert s.profile is prof
    # a profile file gone bad: counted, and the type's profile is used
    done.profile.write_text("{not json", encoding="utf-8")
    assert svc.profile_for("PG-101", "PG-101").calibration is None
    assert svc.profile_errors == 1
    # a route that cannot be read says why; its points read with the types' profiles
    why = svc.set_route(tmp_path / "missing.json")
    assert why is not None and "missing.json" in why
    assert svc.profile_for("PG-101", "PG-101").calibration is None


def test_suggested_points_lie_on_the_drawn_gauge():
    spec = gauge_render.stock_spec("pressure_0_1p6mpa")
    bgr, truth = gauge_render.render_view(spec, 0.9, rng=np.random.default_rng(5),
                                          frame_size=(640, 480), fill=0.6,
                                          offset_frac=(0, 0))
    pts = suggest_points(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), BASE)
    assert pts is not None
    centre, p0, p1 = pts
    assert np.hypot(*np.subtract(centre, truth["centre_xy"])) < 4.0
    # the minimum mark lies lower left, the maximum lower right of a 270-degree dial
    assert p0[0] < centre[0] < p1[0] and p0[1] > centre[1] and p1[1] > centre[1]
    assert suggest_points(np.zeros((480, 640, 3), np.uint8), BASE) is None


def test_reference_frame_is_reread_when_the_point_is_recalibrated(route_file):
    svc = MeterService(_gauges())
    done = calibrate_point(route_file, "PG-101", BASE, _frame(0.3), *CLICKS)
    first = svc.reference_image(done.image)
    assert np.array_equal(first, _frame(0.3))
    again = calibrate_point(route_file, "PG-101", BASE, _frame(1.3), *CLICKS)
    assert np.array_equal(svc.reference_image(again.image), _frame(1.3))
    assert svc.reference_image(route_file.parent / "gone.png") is None


def test_calibrating_the_shipped_route_writes_the_operators_copy(tmp_path, monkeypatch):
    from app.core import paths

    monkeypatch.setenv(paths.ROUTES_ENV, str(tmp_path / "routes"))
    shipped = paths.resource("routes", "default.json")
    before = shipped.read_bytes()
    done = calibrate_point(shipped, "PG-101", BASE, _frame(), *CLICKS)
    assert shipped.read_bytes() == before  # the package is never written to
    assert done.route == tmp_path / "routes" / "default.json"
    assert done.profile.is_relative_to(tmp_path / "routes")
    assert R.load_route(done.route).points[5].profile == "default.points/PG-101.json"
    assert paths.default_route_file() == done.route  # the desk's default from now on


def test_a_routes_references_are_measured_before_its_first_frame(route_file, monkeypatch):
    import app.core.meter.calibrated as calibrated
    from app.core.meter_service import read_frame

    svc = MeterService(_gauges())
    done = calibrate_point(route_file, "PG-101", BASE, _frame(), *CLICKS)
    assert svc.set_route(route_file) is None
    made = []  # the reference's geometry found (its rim looked for once per finding)
    real = calibrated.second_edge
    monkeypatch.setattr(calibrated, "second_edge",
                        lambda *a, **kw: made.append(1) or real(*a, **kw))
    calibrated._REFERENCES.clear()
    try:
        assert svc.prepare_route() == 1 and made == [1]
        r = read_frame(_frame(0.5, seed=4), svc.profile_for("PG-101", "PG-101"))
        assert made == [1]  # the point's first frame found it ready
        assert r.value is not None
        # a reference gone bad: counted and logged, never raised
        done.image.write_bytes(b"not an image")
        calibrated._REFERENCES.clear()
        assert svc.prepare_route() == 0 and svc.profile_errors == 1
    finally:
        calibrated._REFERENCES.clear()
