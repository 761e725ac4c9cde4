"""One route format, one parser: the desk (app.core.route) and the robot
(sim_robot.route) accept and refuse the same route files with the same message;
the robot adds only its station checks (gauge ids, the map's extent)."""

from __future__ import annotations

import copy
import json

import pytest

from app.core import route as desk
from sim_robot import route as robot

GAUGES = {"PG-101", "PG-302"}
SIZE_M = (80.0, 60.0)
GOOD = {"name": "north", "points": [
    {"name": "a", "kind": "waypoint", "x_m": 61.5, "y_m": 45.0, "gauge": None, "dwell_s": 0.5},
    {"name": "PG-302", "kind": "meter", "x_m": 58.6, "y_m": 38.0, "gauge": "PG-302",
     "dwell_s": 1.0, "heading_rad": 1.5, "profile": "north.points/PG-302.json"}]}


def _with(mutate):
    r = copy.deepcopy(GOOD)
    mutate(r)
    return r


ACCEPTED = {
    "as written": GOOD,
    "unknown keys on the route and a point": _with(lambda r: (
        r.update(author="ops", version=3), r["points"][0].update(colour="red", note={"x": 1}))),
    "a blank gauge on a waypoint": _with(lambda r: r["points"][0].update(gauge="  ")),
    "optional fields left out": _with(lambda r: [r["points"][0].pop(k) for k in ("gauge",
                                                                                 "dwell_s")]),
}
REFUSED = {
    "not an object": ([], "a route must be a JSON object"),
    "no points": (_with(lambda r: r.update(points=[])), "empty route"),
    "a blank meter gauge": (_with(lambda r: r["points"][1].update(gauge="")),
                            "point 2 ('PG-302'): a meter point needs a 'gauge'"),
    "a missing coordinate": (_with(lambda r: r["points"][0].pop("y_m")),
                             "point 1 ('a'): missing field 'y_m'"),
    "a text coordinate": (_with(lambda r: r["points"][1].update(x_m="1")),
                          "point 2 ('PG-302'): 'x_m' must be a number, got str"),
    "a duplicate name": (_with(lambda r: r["points"][1].update(name="a", gauge="PG-302")),
                         "duplicate point name 'a'"),
    "a profile that climbs out": (_with(lambda r: r["points"][1].update(profile="../x.json")),
                                  "point 2 ('PG-302'): 'profile'"),
    "a dwell too long": (_with(lambda r: r["points"][0].update(dwell_s=601)),
                         "point 1 ('a'): 'dwell_s' must be 0..600 s"),
}


def _outcome(read, *args):
    try:
        return "accepted", read(*args).to_dict()
    except ValueError as e:
        return "refused", str(e)


@pytest.mark.parametrize("obj", ACCEPTED.values(), ids=ACCEPTED.keys())
def test_both_accept_the_same_routes_alike(obj, tmp_path):
    d = desk.route_from_dict(copy.deepcopy(obj))
    r = robot.parse_route(copy.deepcopy(obj), GAUGES, SIZE_M)
    assert r == d
    f = tmp_path / "route.json"
    f.write_text(json.dumps(obj), encoding="utf-8")
    assert robot.load_route(f, GAUGES, SIZE_M) == desk.load_route(f) == d
    # written back, only the keys the schema names remain, and both read it again
    written = json.loads(desk.dumps(d))
    assert set(written) == set(desk.ROUTE_KEYS)
    for p in written["points"]:
        assert set(p) <= set(desk.POINT_KEYS)
    assert robot.parse_route(written, GAUGES, SIZE_M) == d


def test_unknown_keys_are_ignored_and_dropped_blank_gauges_are_none():
    obj = ACCEPTED["unknown keys on the route and a point"]
    written = robot.parse_route(obj).to_dict()
    assert "author" not in written and "colour" not in written["points"][0]
    assert robot.parse_route(ACCEPTED["a blank gauge on a waypoint"]).points[0].gauge is None


@pytest.mark.parametrize("obj, message", REFUSED.values(), ids=REFUSED.keys())
def test_both_refuse_the_same_routes_with_the_same_message(obj, message, tmp_path):
    d = _outcome(desk.route_from_dict, copy.deepcopy(obj))
    r = _outcome(robot.parse_route, copy.deepcopy(obj), GAUGES, SIZE_M)
    assert d == r
    assert d[0] == "refused" and message in d[1]
    f = tmp_path / "route.json"
    f.write_text(json.dumps(obj), encoding="utf-8")
    on_file = _outcome(robot.load_route, f, GAUGES, SIZE_M)
    assert on_file == _outcome(desk.load_route, f)
    assert on_file[1] == f"route.json: {d[1]}"  # the file's problems start with its name


@pytest.mark.parametrize("mutate, message", [
    (lambda r: r["points"][1].update(gauge="PG-999"), "point 2 ('PG-302'): no gauge 'PG-999'"),
    (lambda r: r["points"][0].update(x_m=81.0), "point 1 ('a'): (81, 45) lies outside the 80 x "),
    (lambda r: r["points"][0].update(y_m=-0.5), "point 1 ('a'): (61.5, -0.5) lies outside"),
], ids=["unknown gauge", "east of the map", "south of the map"])
def test_only_the_robot_refuses_what_only_the_station_knows(mutate, message, tmp_path):
    obj = _with(mutate)
    desk.route_from_dict(copy.deepcopy(obj))  # the desk knows no station: accepted
    with pytest.raises(ValueError) as e:
        robot.parse_route(copy.deepcopy(obj), GAUGES, SIZE_M)
    assert message in str(e.value)
    f = tmp_path / "far.json"
    f.write_text(json.dumps(obj), encoding="utf-8")
    with pytest.raises(ValueError) as e:
        robot.load_route(f, GAUGES, SIZE_M)
    assert str(e.value).startswith("far.json: " + message)
    assert robot.parse_route(copy.deepcopy(obj)).to_dict() == desk.route_from_dict(obj).to_dict()


def test_the_docs_name_exactly_the_schemas_keys():
    """docs/patrol.md is the one statement of the format: its table names the keys
    app.core.route reads and writes, no more and no fewer."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "patrol.md").read_text("utf-8")
    table = text.split("## Route files", 1)[1].split("Rules:", 1)[0]
    rows = [line.split("|")[1].strip() for line in table.splitlines()
            if line.startswith("| `")]
    named = set()
    for cell in rows:
        for key in cell.replace("`", "").split(","):
            named.add(key.strip().removeprefix("points[]."))
    assert named == set(desk.ROUTE_KEYS) | set(desk.POINT_KEYS)
