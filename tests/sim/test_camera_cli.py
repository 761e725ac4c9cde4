import math

import cv2
import numpy as np
import pytest

from app.comm import protocol as P
from sim_robot.camera import Camera, draw_simple_dial
from sim_robot.cli import build_parser, config_from_args
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot
from sim_robot.world import World

from .conftest import Desk, wait_until


@pytest.fixture(scope="module")
def camera():
    return Camera(World(seed=0))


def test_camera_frame_is_a_640x480_jpeg_with_increasing_ids(camera):
    f1, j1 = camera.capture_jpeg(66.0, 45.0, math.pi)
    f2, _ = camera.capture_jpeg(66.0, 45.0, math.pi)
    assert f2 == f1 + 1
    img = cv2.imdecode(np.frombuffer(j1, np.uint8), cv2.IMREAD_COLOR)
    assert img.shape == (480, 640, 3)
    assert camera.last_ms > 0


def test_camera_draws_a_gauge_in_view_and_not_from_behind(camera):
    g = next(g for g in camera.world.gauges if g.id == "PG-102")  # faces east at x = 52.6
    front = camera.render(g.x + 2.5, g.y, math.pi)  # looking west at its face
    cx, cy = 320, int(240 - camera.f * (g.height_m - 0.6) / 2.5)
    patch = front[cy - 10:cy + 10, cx - 10:cx + 10].astype(int)
    assert patch.mean() > 150  # the light dial face
    assert (patch.min(axis=2) < 90).any()  # and something dark on it (ticks, pointer)
    behind = camera.render(g.x - 0.45, g.y + 0.0, 0.0)  # behind its post, facing away
    assert behind.shape == (480, 640, 3)


def test_simple_dial_pointer_moves():
    lo = draw_simple_dial(0, 1.6, 0.0, "MPa")
    hi = draw_simple_dial(0, 1.6, 1.6, "MPa")
    assert lo.shape == (200, 200, 3) and np.abs(lo.astype(int) - hi).sum() > 1000


def test_cli_options():
    ap = build_parser()
    a = ap.parse_args(["--listen", "0.0.0.0:5555", "--seed", "7", "--time-scale", "10",
                       "--no-video", "--fps", "5", "--log-truth", "t.jsonl"])
    cfg = config_from_args(a)
    assert (cfg.host, cfg.port, cfg.seed, cfg.time_scale) == ("0.0.0.0", 5555, 7, 10.0)
    assert not cfg.video and cfg.fps == 5.0 and cfg.log_truth == "t.jsonl"
    for bad in (["--listen", "nowhere"], ["--listen", "h:99999"]):
        with pytest.raises(SystemExit):
            ap.parse_args(bad)


def test_time_scale_speeds_up_sim_time_not_the_desk_rates():
    robot = SimRobot(SimConfig(video=False, time_scale=20.0))
    robot.start()
    desk = Desk(*robot.address)
    try:
        wait_until(lambda: [t for t in desk.of(P.MsgType.TELEMETRY) if t.mcu_time_ms > 8000], 5)
        tel = desk.of(P.MsgType.TELEMETRY)
        # 8 s of sim time took well under 8 s of wall time, at ~10 telemetry frames per second
        assert len(tel) < 30
    finally:
        desk.close()
        robot.close()
