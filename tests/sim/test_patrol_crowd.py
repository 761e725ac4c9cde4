"""Avoidance in the crowd: a walker setting off from standstill beside the
robot. His velocity must be known within a few scans (the planner predicts
him at constant velocity), and the patrol run in which a lagging estimate
let him catch the robot from behind must end without contact."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from sim_robot.config import SimConfig
from sim_robot.patrol import DONE
from sim_robot.patrol_sim import OfflinePatrol
from sim_robot.route import DEFAULT_ROUTE, load_route
from sim_robot.tracker import ObstacleTracker

from .test_patrol import _disc_scan

pytestmark = pytest.mark.slow(32)


def _bench():
    path = Path(__file__).resolve().parents[2] / "bench" / "patrol_bench.py"
    spec = importlib.util.spec_from_file_location("patrol_bench", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _speeds(start_s, stop_s, v=(0.0, 0.8), seed=0):
    """Scans at 10 Hz of a walker standing 1 m beside the robot (which faces
    north), walking off at ``v`` from start_s and standing again from
    stop_s; per scan
    (t, true velocity, tracked velocity or None)."""
    free = np.full((200, 200), 10.0)
    trk = ObstacleTracker(free, 0.1)
    rng = np.random.default_rng(seed)
    pose = (10.0, 10.0, math.pi / 2)
    x0, y0 = 9.0, 9.0
    out = []
    for k in range(int(stop_s * 10) + 30):
        t = 0.1 * k
        walked = min(max(t - start_s, 0.0), stop_s - start_s)
        moving = start_s <= t < stop_s
        cx, cy = x0 + v[0] * walked, y0 + v[1] * walked
        trk.update(t, trk.detect(*_disc_scan(pose, cx, cy, 0.25, rng=rng), pose))
        obs = trk.obstacles()
        est = (float(obs[0, 2]), float(obs[0, 3])) if len(obs) == 1 else None
        out.append((t, v if moving else (0.0, 0.0), est))
    return out


def test_tracker_velocity_follows_a_walker_setting_off_and_stopping():
    for seed, v in enumerate([(0.0, 0.8), (0.0, 0.8), (-0.5, 0.6), (0.0, -0.8), (0.0, 1.2)]):
        rows = _speeds(2.0, 5.0, v, seed)
        for t, true, est in rows:
            assert est is not None or t < 0.3
            if est is None:
                continue
            err = math.hypot(est[0] - true[0], est[1] - true[1])
            if t < 2.0 - 1e-9:  # standing: no phantom motion
                assert err < 0.1, (seed, t, est)
            elif 2.25 < t < 5.0 - 1e-9:  # 0.3 s after setting off (3 scans)
                assert err < 0.25, (seed, t, est)
            elif t > 5.25:  # stopped again
                assert err < 0.25, (seed, t, est)


def test_patrol_walker_setting_off_behind_the_robot_is_not_hit():
    """Lock-step seed 7 with five workers crossing the route's road and the
    meter stops as long as the relay makes them at 20x (50 s of sim time):
    crosser-3 stands at the end of his beat as the robot passes a metre
    from him, then walks off along his line towards where the robot goes."""
    route = load_route(DEFAULT_ROUTE)
    for p in route.points:
        if p.gauge:
            p.dwell_s = 50.0
    op = OfflinePatrol(SimConfig(seed=7, video=False))
    _bench().add_crowd(op.world, 6, 7)
    assert op.run(route, max_sim_s=1800) == DONE
    assert len(op.codes("point_reached")) == len(route.points)
    assert op.world.collisions == []
