"""Patrol: route files, obstacle tracking, the executor run
in lock-step with the world and the MCU model (no threads, no sockets)."""

from __future__ import annotations

import copy
import json
import math
import re

import numpy as np
import pytest

from sim_robot.config import SimConfig
from sim_robot.patrol import DONE, PAUSED
from sim_robot.patrol_sim import OfflinePatrol
from sim_robot.route import DEFAULT_ROUTE, load_route, parse_route
from sim_robot.tracker import ObstacleTracker
from sim_robot.world import Walker, World

GAUGES = {"PG-101", "PG-102", "PG-201", "CG-301", "PG-302"}
GOOD = {"name": "r", "points": [
    {"name": "a", "kind": "waypoint", "x_m": 61.5, "y_m": 45.0, "gauge": None, "dwell_s": 0.5},
    {"name": "PG-302", "kind": "meter", "x_m": 58.6, "y_m": 38.0, "gauge": "PG-302",
     "dwell_s": 1.0}]}


def _bad(mutate):
    r = copy.deepcopy(GOOD)
    mutate(r)
    return r


@pytest.mark.parametrize("route, message", [
    ([], "JSON object"),
    (_bad(lambda r: r.pop("name")), "'name'"),
    (_bad(lambda r: r.update(points=[])), "empty route"),
    (_bad(lambda r: r["points"][0].update(kind="door")), "'kind' must be one of"),
    (_bad(lambda r: r["points"][0].pop("x_m")), "point 1 ('a'): missing field 'x_m'"),
    (_bad(lambda r: r["points"][0].update(y_m="north")), "'y_m' must be a number"),
    (_bad(lambda r: r["points"][0].update(x_m=float("nan"))), "finite"),
    (_bad(lambda r: r["points"][0].update(x_m=120.0)), "point 1 ('a'): (120, 45) lies outside"),
    (_bad(lambda r: r["points"][1].update(gauge=None)), "needs a 'gauge'"),
    (_bad(lambda r: r["points"][1].update(gauge="PG-999")),
     "point 2 ('PG-302'): no gauge 'PG-999'"),
    (_bad(lambda r: r["points"][1].update(gauge=" ")), "point 2 ('PG-302'): a meter point needs"),
    (_bad(lambda r: r["points"][1].update(dwell_s=-1)), "'dwell_s'"),
    (_bad(lambda r: r["points"][1].update(name="a")), "duplicate"),
])
def test_route_validation_names_the_problem(route, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        parse_route(route, GAUGES, (80.0, 60.0))


def test_default_route_is_valid_and_visits_every_gauge(tmp_path):
    r = load_route(DEFAULT_ROUTE, GAUGES, (80.0, 60.0))
    assert {p.gauge for p in r.points if p.kind == "meter"} == GAUGES
    assert any(p.kind == "tank_wall" for p in r.points)
    w = World()
    for p in r.points:  # every stand-off pose is clear of the map by more than the robot
        assert w.clearance(p.x_m, p.y_m) > 0.5, p.name
    assert parse_route(r.to_dict(), GAUGES).to_dict() == r.to_dict()
    (tmp_path / "bad.json").write_text("{not json", encoding="utf-8")
    with pytest.raises(ValueError, match="bad.json: not valid JSON"):
        load_route(tmp_path / "bad.json")
    with pytest.raises(ValueError, match="cannot read"):
        load_route(tmp_path / "missing.json")
    json.loads(DEFAULT_ROUTE.read_text(encoding="utf-8"))


def _disc_scan(pose, cx, cy, r, beams=360, rng=None):
    """Ranges of a full-turn scan that sees only one disc (analytic ray-circle hits)."""
    ang = pose[2] - math.pi + 2 * math.pi / beams * np.arange(beams)
    dx, dy = cx - pose[0], cy - pose[1]
    b = dx * np.cos(ang) + dy * np.sin(ang)
    d2 = dx * dx + dy * dy - b * b
    h = np.sqrt(np.maximum(r * r - d2, 0.0))
    out = np.where((d2 <= r * r) & (b - h > 0), b - h, np.inf)
    if rng is not None:
        out = out + rng.normal(0, 0.015, beams)
    return out.astype(np.float32), -math.pi, 2 * math.pi / beams


def test_tracker_finds_a_moving_disc_with_its_velocity():
    free = np.full((200, 200), 10.0)  # 20 x 20 m, nothing static
    free[:, :5] = 0.0  # a wall along x < 0.5 m: its returns must be dropped
    trk = ObstacleTracker(free, 0.1)
    rng = np.random.default_rng(0)
    pose = (10.0, 10.0, 0.3)
    vx, vy = 0.4, -0.6
    for k in range(40):  # 4 s at 10 Hz
        t = 0.1 * k
        cx, cy = 14.0 + vx * t, 12.0 + vy * t
        ranges, amin, ainc = _disc_scan(pose, cx, cy, 0.3, rng=rng)
        wall = 10.0 - 0.45  # a return from the wall, to the west
        ranges[0] = wall
        trk.update(t, trk.detect(ranges, amin, ainc, pose))
    obs = trk.obstacles()
    assert len(obs) == 1
    x, y, ovx, ovy, orad = obs[0]
    assert math.hypot(x - cx, y - cy) < 0.1
    assert math.hypot(ovx - vx, ovy - vy) < 0.1
    assert 0.2 < orad < 0.5
    # it leaves the view: the track is dropped
    trk.update(5.0, [])
    assert len(trk.obstacles()) == 0


def _offline(seed=1, people=True):
    op = OfflinePatrol(SimConfig(seed=seed, video=False))
    if not people:
        op.world.walkers = []
        op.world.vehicles = []
    return op


def test_executor_patrols_a_short_route_and_returns_to_the_dock():
    op = _offline(people=False)
    state = op.run(parse_route(GOOD, GAUGES), max_sim_s=300)
    assert state == DONE
    assert [d["point"] for d in op.codes("point_reached")] == ["a", "PG-302"]
    assert op.codes("inspection_done")[-1]["gauge"] == "PG-302"
    assert op.camera_target is None  # the head looks ahead again
    assert op.world.collisions == []
    assert op.world.at_dock()
    assert op.nav.executor.status().progress == 1.0
    paths = [m for m in op.published if getattr(m, "kind", None) == 0]
    assert len(paths) == 3  # one global plan per leg, dock leg included


def test_pause_resume_abort_and_goto():
    op = _offline(people=False)
    ex = op.nav.executor
    assert ex.start(parse_route(GOOD, GAUGES))[0]
    assert not ex.start(parse_route(GOOD, GAUGES))[0]  # one mission at a time
    for _ in range(30):
        op.step()
    assert ex.owns_motors
    assert op.pause("operator")[0] and ex.state == PAUSED
    assert op.codes("patrol_paused")[-1]["reason"] == "operator"
    p0 = op.world.pose
    for _ in range(40):  # paused: stopped, the executor sends nothing
        op.step()
    p1 = op.world.pose
    assert math.hypot(p1.x - p0.x, p1.y - p0.y) < 0.6  # it braked, it does not drive on
    assert ex.resume()[0]
    assert op.run(None, max_sim_s=300) == DONE
    assert ex.abort()[0] is False  # nothing to abort
    assert not ex.goto(41.0, 36.0)[0]  # inside a tank
    assert ex.goto(62.0, 44.0, "spot")[0]
    assert op.run(None, max_sim_s=120) == DONE
    assert math.hypot(op.world.pose.x - 62.0, op.world.pose.y - 44.0) < 0.3
    assert ex.dock_now()[0]
    assert ex.abort("test")[0] and ex.state == "aborted"
    assert op.codes("patrol_aborted")[-1]["reason"] == "test"


def test_unreachable_point_is_skipped_with_a_reason():
    op = _offline(people=False)
    route = copy.deepcopy(GOOD)
    route["points"].insert(0, {"name": "in the tank", "kind": "waypoint", "x_m": 41.0,
                               "y_m": 36.0, "gauge": None, "dwell_s": 0.0})
    assert op.run(parse_route(route, GAUGES), max_sim_s=300) == DONE
    skipped = op.codes("point_skipped")
    assert skipped and skipped[0]["point"] == "in the tank" and "no path" in skipped[0]["reason"]
    assert [p["state"] for p in op.nav.executor.status().points] == ["skipped", "done", "done"]


def test_robot_avoids_a_walker_crossing_its_path_from_the_lidar():
    op = _offline(people=False)
    w = op.world
    # the robot drives west along the dock road (y = 45); a worker crosses it at x = 62
    w.walkers = [Walker({"id": "crosser", "path": [[62.0, 47.6], [62.0, 42.4]],
                         "speed_mps": 0.5, "pause_s": 2.0, "radius_m": 0.25}, phase_s=0.0)]
    route = {"name": "west", "points": [{"name": "w", "kind": "waypoint", "x_m": 58.0,
                                         "y_m": 45.0, "gauge": None, "dwell_s": 0.0}]}
    seen_moving = []

    def watch():
        obs = op.nav.obstacles
        if len(obs) and np.hypot(obs[:, 2], obs[:, 3]).max() > 0.3:
            seen_moving.append(obs.copy())

    ex = op.nav.executor
    assert ex.start(parse_route(route, GAUGES), op.t)[0]
    while ex.owns_motors and op.t < 200:
        op.step()
        watch()
    assert ex.state == DONE
    assert seen_moving, "the walker was never tracked as moving"
    assert op.codes("avoiding")
    assert w.collisions == []
    assert op.min_clearance_m > 0.35


def test_cart_yields_to_the_robot_and_contacts_are_recorded():
    w = World()
    w.walkers = []
    cart = w.vehicles[0]
    cart.wait = 0.0
    t = [0.0]
    w.clock = lambda: t[0]
    w.set_pose(10.0, 25.5, 0.0)  # standing in the cart's lane, 6 m ahead of it
    for k in range(200):
        t[0] = 0.1 * k
        w.people()
    x, _ = cart.position()
    assert cart.yielding and x < 10.0 - 0.9 - 0.35
    w.set_pose(10.0, 20.0, 0.0)  # out of its lane: it drives on
    t[0] += 2.0
    w.people()
    assert cart.position()[0] > x
    # driving into the pump house is a collision with the static map, recorded once
    w.set_pose(59.0, 35.0, 0.0)
    got = []
    w.on_collision = got.append
    for _ in range(20):
        w.move_robot(0.5, 0.0, 0.05, 0.35)
    assert [c["what"] for c in w.collisions] == ["static"] and got == w.collisions


def test_desk_route_files_and_robot_routes_agree():
    """The desk writes routes with app.core.route; the robot must take them as they are."""
    from app.core import route as desk_route

    r = desk_route.load_route(DEFAULT_ROUTE)
    robot = parse_route(json.loads(desk_route.dumps(r)), GAUGES, (80.0, 60.0))
    assert robot.to_dict() == load_route(DEFAULT_ROUTE).to_dict()
