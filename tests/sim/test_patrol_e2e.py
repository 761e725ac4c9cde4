"""A real ``python -m sim_robot`` process at 20x patrols a short route by itself."""

from __future__ import annotations

import pytest

from app.comm import protocol as P
from app.sim_process import SimRobotProcess

from .desk import SocketDesk

SHORT_ROUTE = {
    "name": "near-dock",
    "points": [
        {"name": "road west", "kind": "waypoint", "x_m": 61.5, "y_m": 45.0, "gauge": None,
         "dwell_s": 1.0},
        {"name": "PG-302", "kind": "meter", "x_m": 58.6, "y_m": 38.0, "gauge": "PG-302",
         "dwell_s": 2.0},
    ],
}


@pytest.mark.e2e
def test_robot_patrols_a_short_route_at_20x():
    with SimRobotProcess(seed=1, time_scale=20.0, extra=["--no-video"]) as sim:
        desk = SocketDesk(sim.host, sim.port, heartbeat_s=0.5)
        try:
            desk.wait_for(lambda: desk.of(P.MsgType.MAP), 20, "MapImage")
            bad = desk.send(P.Command("start_patrol", {"route": {"name": "x", "points": []}}))
            ack = desk.wait_for(lambda: desk.ack(bad), 10, "ack of a bad route")
            assert not ack.ok and "points" in ack.reason
            seq = desk.send(P.Command("start_patrol", {"route": SHORT_ROUTE}))
            ack = desk.wait_for(lambda: desk.ack(seq), 10, "ack of start_patrol")
            assert ack.ok, ack.reason
            desk.wait_for(lambda: desk.events("patrol_done") or desk.events("patrol_failed"),
                          60, "patrol_done")
            assert not desk.events("patrol_failed")
            reached = [e.data["point"] for e in desk.events("point_reached")]
            assert reached == ["road west", "PG-302"]
            insp = [e.data for e in desk.events("inspection_done")]
            assert {"point": "PG-302", "gauge": "PG-302"}.items() <= insp[-1].items()
            started = [e.data for e in desk.events("inspection_started")]
            assert [d["gauge"] for d in started] == ["PG-302"]
            assert desk.events("collision") == []
            statuses = desk.of(P.MsgType.PATROL_STATUS)
            assert {s.state for s in statuses} >= {"driving", "inspecting", "docking"}
            desk.wait_for(lambda: desk.of(P.MsgType.PATROL_STATUS)[-1].state == "done", 10,
                          "status done")
            final = desk.of(P.MsgType.PATROL_STATUS)[-1]
            assert [p["state"] for p in final.points] == ["done", "done"]
            assert final.progress == 1.0
            paths = desk.of(P.MsgType.PATH)
            glob = [p for p in paths if p.kind == P.Path.GLOBAL]
            assert glob and all(0 < len(p.points_xy) <= 2000 for p in glob)
            assert any(p.kind == P.Path.LOCAL for p in paths)
            m = desk.of(P.MsgType.MAP)[0]
            assert (m.width, m.height) == (800, 600) and m.png.startswith(b"\x89PNG")
            modes = {t.mode for t in desk.of(P.MsgType.TELEMETRY)}
            assert int(P.RobotMode.PATROL) in modes
            pose = desk.of(P.MsgType.POSE)[-1]  # back at the dock (66, 45)
            assert abs(pose.x_m - 66.0) < 0.6 and abs(pose.y_m - 45.0) < 0.6
            assert desk.dec.stats.dropped == 0
        finally:
            desk.close()
