"""Route files and map-frame geometry (Qt-free)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from app.comm import protocol as P
from app.core import mapimage as M
from app.core import route as R


def _obj(**over):
    obj = {"name": "loop", "points": [
        {"name": "A", "kind": "meter", "x_m": 1.0, "y_m": 2.0, "gauge": "PG-1", "dwell_s": 4.0},
        {"name": "B", "kind": "waypoint", "x_m": 3, "y_m": -1.5, "gauge": None, "dwell_s": 0},
    ]}
    obj.update(over)
    return obj


# ------------------------------------------------------------------ route


def test_route_round_trip(tmp_path):
    r = R.route_from_dict(_obj())
    assert r.names() == ["A", "B"]
    assert r.points[1].x_m == 3.0 and isinstance(r.points[1].x_m, float)
    f = tmp_path / "r.json"
    R.save_route(r, f)
    back = R.load_route(f)
    assert back == r
    assert json.loads(f.read_text()) == R.route_to_dict(r)
    assert not list(tmp_path.glob(".*.tmp"))  # the temporary file is gone


def test_optional_fields_default():
    obj = _obj(points=[{"name": "A", "kind": "valve", "x_m": 0, "y_m": 0}])
    p = R.route_from_dict(obj).points[0]
    assert p.gauge is None and p.dwell_s == 0.0


@pytest.mark.parametrize("obj, words", [
    ([], "JSON object"),
    ({"points": []}, "missing field 'name'"),
    ({"name": "x"}, "missing field 'points'"),
    ({"name": "x", "points": []}, "empty route"),
    ({"name": "x", "points": {}}, "must be a list"),
    ({"name": "", "points": [{}]}, "non-empty string"),
    (_obj(points=[{"name": "A", "kind": "meter"}]), "point 1 ('A'): missing fields 'x_m', 'y_m'"),
    (_obj(points=[{"name": "A", "kind": "pump", "x_m": 0, "y_m": 0}]), "'kind' must be one of"),
    (_obj(points=[{"name": "A", "kind": "meter", "x_m": "1", "y_m": 0}]),
     "'x_m' must be a number, got str"),
    (_obj(points=[{"name": "A", "kind": "meter", "x_m": True, "y_m": 0}]),
     "'x_m' must be a number, got bool"),
    (_obj(points=[{"name": "A", "kind": "meter", "x_m": 0, "y_m": math.nan}]), "finite"),
    (_obj(points=[{"name": "A", "kind": "meter", "x_m": 0, "y_m": 0, "gauge": 5}]),
     "'gauge' must be a string or null"),
    (_obj(points=[{"name": "A", "kind": "valve", "x_m": 0, "y_m": 0, "dwell_s": -1}]),
     "'dwell_s' must be 0..600 s"),
    (_obj(points=[{"name": "A", "kind": "meter", "x_m": 0, "y_m": 0}]),
     "a meter point needs a 'gauge'"),
    (_obj(points=[{"name": f"P{i}", "kind": "valve", "x_m": 0, "y_m": 0} for i in range(201)]),
     "at most 200"),
    (_obj(points=[{"name": "A", "kind": "valve", "x_m": 0, "y_m": 0},
                  {"name": "A", "kind": "valve", "x_m": 1, "y_m": 0}]), "duplicate point name 'A'"),
    (_obj(points=["A"]), "point 1: must be an object"),
])
def test_bad_routes_give_clear_messages(obj, words):
    with pytest.raises(ValueError) as e:
        R.route_from_dict(obj)
    assert words in str(e.value)


def test_bad_files_name_the_file(tmp_path):
    f = tmp_path / "broken.json"
    f.write_text("{not json")
    with pytest.raises(ValueError, match="broken.json: not valid JSON"):
        R.load_route(f)
    with pytest.raises(ValueError, match="cannot read"):
        R.load_route(tmp_path / "missing.json")


def test_save_refuses_invalid_route(tmp_path):
    f = tmp_path / "r.json"
    with pytest.raises(ValueError, match="empty route"):
        R.save_route(R.Route("x", []), f)
    assert not f.exists()


def test_heading_kept_when_present():
    obj = _obj(points=[{"name": "A", "kind": "valve", "x_m": 0, "y_m": 0, "heading_rad": 1.5}])
    r = R.route_from_dict(obj)
    assert r.points[0].heading_rad == 1.5
    assert R.route_to_dict(r)["points"][0]["heading_rad"] == 1.5
    assert "heading_rad" not in R.route_to_dict(R.route_from_dict(_obj()))["points"][0]


def test_shipped_routes_load():
    """Every route the robot ships is accepted by the desk."""
    from app.core.paths import resource

    files = sorted(resource("routes").glob("*.json"))
    if not files:
        pytest.skip("no shipped routes yet")
    for f in files:
        r = R.load_route(f)
        assert r.points and R.route_from_dict(R.route_to_dict(r)) == r


def test_unique_name():
    r = R.route_from_dict(_obj(points=[{"name": "P2", "kind": "valve", "x_m": 0, "y_m": 0}]))
    assert r.unique_name() == "P3"
    r.points.append(R.RoutePoint("P3"))
    assert r.unique_name() == "P4"


# ------------------------------------------------------------------ map geometry


def test_cell_world_round_trip_ros_convention():
    res, ox, oy, h = 0.05, -2.0, 1.0, 40
    # row 0 is the top: its centre has the largest y; the origin is the lower-left corner
    x, y = M.cell_to_world(h - 1, 0, res, ox, oy, h)
    assert x == pytest.approx(ox + 0.025) and y == pytest.approx(oy + 0.025)
    x, y = M.cell_to_world(0, 0, res, ox, oy, h)
    assert y == pytest.approx(oy + h * res - 0.025)
    rows, cols = np.mgrid[0:h, 0:30]
    xs, ys = M.cell_to_world(rows, cols, res, ox, oy, h)
    r2, c2 = M.world_to_cell(xs, ys, res, ox, oy, h)
    assert np.array_equal(r2, rows) and np.array_equal(c2, cols)
    # a point just inside the lower-left corner is the bottom-left cell
    r, c = M.world_to_cell(ox + 1e-6, oy + 1e-6, res, ox, oy, h)
    assert (int(r), int(c)) == (h - 1, 0)


def test_decode_map_and_extent():
    img = np.full((30, 50), M.FREE, np.uint8)
    img[0, :] = M.BLOCKED  # top wall
    img[5:10, 5:10] = M.UNKNOWN
    msg = P.MapImage(0.1, 1.0, 2.0, 50, 30, M.encode_png(img))
    g = M.decode_map(P.MapImage.unpack(msg.pack()))
    assert (g.width, g.height) == (50, 30)
    assert g.extent == pytest.approx((1.0, 2.0, 6.0, 5.0))
    assert np.array_equal(g.image, img)
    assert g.blocked()[0].all() and not g.blocked()[1:].any()
    # the top wall is at the largest y
    x, y = g.cell_to_world(0, 10)
    assert y == pytest.approx(4.95)


def test_decode_map_rejects_bad_input():
    img = np.zeros((10, 20), np.uint8)
    with pytest.raises(ValueError, match="header says"):
        M.decode_map(P.MapImage(0.1, 0, 0, 10, 20, M.encode_png(img)))
    with pytest.raises(ValueError, match="does not decode"):
        M.decode_map(P.MapImage(0.1, 0, 0, 20, 10, b"\x89PNG garbage"))


def test_scan_to_map_uses_pose():
    ranges = np.array([1.0, np.inf, 2.0, 0.0, 50.0], np.float32)
    pts = M.scan_to_map(ranges, -math.pi / 2, math.pi / 4, 10.0, 1.0, 2.0, math.pi / 2)
    # beams at -90°, 0° (1 m, 2 m after dropping inf) rotated by +90°
    assert pts.shape == (2, 2)
    assert pts[0] == pytest.approx([2.0, 2.0], abs=1e-6)  # -90° + 90° = 0°: +x
    a = -math.pi / 2 + 2 * math.pi / 4 + math.pi / 2  # third beam: +90° in the map
    assert pts[1] == pytest.approx([1.0 + 2.0 * math.cos(a), 2.0 + 2.0 * math.sin(a)], abs=1e-5)
