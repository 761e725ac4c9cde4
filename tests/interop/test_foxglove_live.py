"""The live Foxglove view: a WebSocket client (the ``websockets`` package) subscribes
to the desk's topics and receives what the desk pipeline is fed."""

from __future__ import annotations

import json

import numpy as np
import pytest
from waits import wait_until  # tests/ is on the path

from app.comm import protocol as P
from app.core.desk import DeskPipeline
from app.core.interop.foxglove_live import FoxgloveLive

from .fgclient import Client

TOPICS = ["/telemetry", "/pose", "/tf", "/scan", "/alarms", "/events", "/map"]


@pytest.fixture
def live():
    pipeline = DeskPipeline()
    server = FoxgloveLive(pipeline, port=0)
    yield pipeline, server
    server.close()
    pipeline.close()


def _telemetry(i: int, t: float, gas: float = 2.0) -> P.Telemetry:
    msg = P.Telemetry(gas_lel_pct=gas, temp_c=20.0 + i, humidity_pct=45.0, battery_v=24.6,
                      obstacle_front_m=3.0, obstacle_left_m=2.0, obstacle_right_m=2.0,
                      mode=int(P.RobotMode.PATROL), tel_seq=i)
    msg.received_s = t
    return msg


def test_client_subscribes_and_receives_the_desks_data(live):
    pipeline, server = live
    client = Client(server.port, TOPICS)
    try:
        wait_until(lambda: client.subscribed() == set(TOPICS), timeout=5)
        ads = {c["topic"]: c for c in client.channels.values()}
        assert ads["/pose"]["schemaName"] == "foxglove.PoseInFrame"
        assert ads["/scan"]["schemaName"] == "foxglove.LaserScan"
        assert ads["/telemetry"]["schemaName"] == "station_patrol.Telemetry"
        # the subscription is in place once the server answers a message on it
        t0 = 1_790_000_000.0
        wait_until(lambda: (pipeline.ingest("telemetry", _telemetry(0, t0))
                            and bool(client.of("/telemetry"))), timeout=5)
        n0 = len(client.of("/telemetry"))
        for i in range(1, 11):
            pipeline.ingest("telemetry", _telemetry(i, t0 + i * 0.1))
        pipeline.ingest("pose", P.Pose(1.0, 2.0, 0.5))
        pipeline.ingest("scan", P.LidarScan(0, -1.0, 0.01, 10.0,
                                            np.linspace(1, 2, 201).astype(np.float32)))
        pipeline.ingest("link_state", "connected")
        wait_until(lambda: len(client.of("/telemetry")) >= n0 + 10 and client.of("/pose")
                   and client.of("/tf") and client.of("/scan") and client.of("/events"),
                   timeout=5)
        last = client.of("/telemetry")[-1]
        assert json.loads(last[3])["temp_c"] == 30.0
        assert last[1] == round((t0 + 1.0) * 1e9)
        assert b"base_link" in client.of("/tf")[0][3] and b"map" in client.of("/tf")[0][3]
        # a gas alarm raised on the desk reaches the client as a Log on /alarms
        for i in range(11, 40):
            pipeline.ingest("telemetry", _telemetry(i, t0 + i * 0.1, gas=30.0))
            pipeline.tick()
        wait_until(lambda: client.of("/alarms"), timeout=5)
        assert any(b"gas" in m[3] for m in client.of("/alarms"))
    finally:
        client.close()


def test_the_flag_turns_it_on_and_picks_the_port():
    from app.cli import apply_flags, build_parser
    from app.config import DeskConfig

    for argv, enabled, port in ((["--demo"], False, 8765), (["--demo", "--foxglove"], True, 8765),
                                (["--demo", "--foxglove", "9001"], True, 9001)):
        cfg = DeskConfig()
        apply_flags(cfg, build_parser().parse_args(argv))
        assert (cfg.foxglove.enabled, cfg.foxglove.port, cfg.foxglove.host) == \
            (enabled, port, "127.0.0.1")


def test_a_busy_port_is_said_and_the_desk_runs_on(live, capsys):
    from app.config import DeskConfig
    from app.session import start_foxglove

    _pipeline, server = live
    cfg = DeskConfig()
    cfg.foxglove.enabled, cfg.foxglove.port = True, server.port
    other = DeskPipeline()
    assert start_foxglove(cfg, other) is None
    assert "Foxglove server not started" in capsys.readouterr().err
    other.close()


def test_a_late_client_gets_the_newest_map(live):
    import cv2

    pipeline, server = live
    img = np.full((10, 12), 255, np.uint8)
    img[0] = 0
    ok, png = cv2.imencode(".png", img)
    assert ok
    pipeline.ingest("map", P.MapImage(0.5, 1.0, 2.0, 12, 10, png.tobytes()))
    client = Client(server.port, TOPICS)  # /map among others, in one subscribe op
    try:
        wait_until(lambda: client.of("/map"), timeout=5)
        assert b"occupancy" in client.of("/map")[0][3]
    finally:
        client.close()


def test_the_toml_section(tmp_path):
    from app.config import ConfigError, load_config

    f = tmp_path / "desk.toml"
    f.write_text('[foxglove]\nenabled = true\nhost = "0.0.0.0"\nport = 9100\n')
    cfg = load_config(f)
    assert (cfg.foxglove.enabled, cfg.foxglove.host, cfg.foxglove.port) == \
        (True, "0.0.0.0", 9100)
    f.write_text('[foxglove]\nport = "x"\n')
    with pytest.raises(ConfigError, match="foxglove.port"):
        load_config(f)
