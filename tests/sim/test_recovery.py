"""A robot that touches a wall (a bump on a starved host, a pose a few
centimetres off) backs away and drives its leg, instead of standing there for
good (the soak's robot stood at the bund's east opening, every patrol after
failing on "blocked: no progress")."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim_robot.config import SimConfig
from sim_robot.patrol import DONE
from sim_robot.patrol_sim import OfflinePatrol
from sim_robot.recovery import Recovery
from sim_robot.world import World

T102_EAST = (47.6, 37.0)  # the default route's "T-102 east wall" stand-off point
PG302 = (58.6, 38.0)


def _placed(x: float, y: float, theta: float) -> OfflinePatrol:
    cfg = SimConfig(seed=1, video=False)
    w = World(cfg.station_file, cfg.seed)
    w.walkers, w.vehicles = [], []
    w.set_pose(x, y, theta)
    return OfflinePatrol(cfg, world=w)


@pytest.mark.parametrize("pose, goal", [
    # where the soak's robot stood: the end of the bund's east wall by its
    # opening, the body 1 cm off the wall (world physics), facing away and towards it
    ((52.25, 40.85, 2.67), T102_EAST),
    ((52.25, 40.85, -2.2), T102_EAST),
    # against tank T-101's wall, facing it (the MCU's front ranger stops any
    # forward motion), the goal behind
    ((24.15, 34.65, 2.89), T102_EAST),
])
def test_a_robot_touching_a_wall_backs_away_and_completes_its_leg(pose, goal):
    op = _placed(*pose)
    ex = op.nav.executor
    g = ex.planner.grid  # by the map the body touches the wall
    assert g.distance_m[g.world_to_cell(*pose[:2])] <= ex.cfg.robot_radius_m
    assert ex.goto(*goal, "goal")[0]
    assert op.run(None, max_sim_s=120) == DONE
    assert [d["point"] for d in op.codes("point_reached")] == ["goal"]
    assert op.codes("point_skipped") == [] and op.codes("blocked") == []
    rec = op.codes("recovering")
    assert len(rec) == 1  # reported once
    assert rec[0]["clearance_m"] <= 0.0 and rec[0]["point"] == "goal"
    p = World.pose.fget(op.world)  # the test may read the truth
    assert math.hypot(p.x - goal[0], p.y - goal[1]) < 0.3
    assert op.world.collisions == []  # it backed away without touching again


def test_a_robot_clear_of_the_walls_does_not_recover():
    op = _placed(56.0, 38.0, 0.0)
    assert op.nav.executor.goto(*PG302, "goal")[0]
    assert op.run(None, max_sim_s=60) == DONE
    assert op.codes("recovering") == []


def _wall_recovery() -> Recovery:
    """A 10 m × 4 m room whose south wall is rows 0..4 (y < 0.5 m)."""
    from app.core.planner import GridMap
    b = np.zeros((40, 100), bool)
    b[:5, :] = True
    g = GridMap(b, 0.1, (0.0, 0.0))
    return Recovery(g.distance_m, g.inflate(0.45).blocked, 0.1, (0.0, 0.0), 0.35, 0.1)


def test_the_way_out_leads_away_from_the_wall_and_backs_when_it_faces_it():
    rec = _wall_recovery()
    x, y = 5.0, 0.76  # the body 10 cm into the wall by the map (an estimate off)
    assert rec.touching(x, y) and not rec.free(x, y)
    out = rec.way_out(x, y)
    assert out is not None and abs(out[0] - x) < 0.11 and out[1] > y + 0.1
    assert rec.free(*out)
    e = rec.begin((x, y, -math.pi / 2), 0.0)  # facing the wall: reverse, no turn
    assert e.reverse
    v, w, status = rec.command((x, y, -math.pi / 2), 0.1)
    assert status == "recovering" and v < 0  # backs straight off, no turn first
    e = rec.begin((x, y, 0.0), 0.0)  # along the wall: turn on the spot first
    v, w, status = rec.command((x, y, 0.0), 0.1)
    assert status == "recovering" and v == 0.0 and w != 0.0
    assert rec.command((x, out[1], 0.0), 1.0)[2] == "done"  # free: plan from here
    assert rec.command((x, y, 0.0), 100.0)[2] == "timeout"
