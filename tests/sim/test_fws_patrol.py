"""The 4WS robot's patrol in lock-step (no threads, no sockets): its board and
navigator (optimised A*, TEB, pure pursuit) on the station's default route with
the crowd of six workers crossing the road, as the skid-steer robot's crowd
test runs it."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from sim_robot.config import SimConfig
from sim_robot.fws_robot import FwsOfflinePatrol
from sim_robot.patrol import DONE
from sim_robot.route import DEFAULT_ROUTE, load_route

pytestmark = pytest.mark.slow(72)


def _add_crowd():
    path = Path(__file__).resolve().parents[2] / "bench" / "patrol_bench.py"
    spec = importlib.util.spec_from_file_location("patrol_bench", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.add_crowd


@pytest.mark.timeout(900)  # ~35 s of CPU; far longer on a loaded shared machine
def test_fws_patrol_inspects_every_point_in_the_crowd_without_contact():
    route = load_route(DEFAULT_ROUTE)
    for p in route.points:
        if p.gauge:
            p.dwell_s = 50.0
    op = FwsOfflinePatrol(SimConfig(seed=7, video=False))
    _add_crowd()(op.world, 6, 7)
    modes = set()
    step = op.step

    def stepped():
        step()
        modes.add(op.mcu.steer_mode)

    op.step = stepped
    assert op.run(route, max_sim_s=1800) == DONE
    ex = op.nav.executor
    assert [p["state"] for p in ex.mission.points] == ["done"] * len(route.points)
    assert len(op.codes("inspection_done")) == len(route.points)
    assert op.world.collisions == []
    assert op.min_clearance_m >= 0.35  # the robot's radius: it never touched the plant
    assert ex.status().local_planner == "teb" and op.fws_nav.teb_cycles > 100
    assert {"counter", "pivot", "stopped"} <= modes  # arcs, turns in place, stops
    w = op.world.pose
    assert abs(w.x - 66.0) < 0.3 and abs(w.y - 45.0) < 0.3  # back at the dock
