"""``sim-robot --robot climber --serial DEVICE``: the relay drives a board on DEVICE,
with the wall file's map and nothing of the simulator's truth. The board here is the
climber's MCU model served on a loopback socket by the test, its URL given as DEVICE."""

from __future__ import annotations

import logging
import math
import time

import pytest

from app.comm import protocol as P
from app.comm.wall_protocol import CoverageState
from app.core.planner.coverage.wall import rasterise
from sim_robot.climber.contact import WallContact
from sim_robot.climber.kinematics import ClimberBody, ClimberParams, ClimberState
from sim_robot.climber.mcu import ClimberMcu, ClimberMcuThread
from sim_robot.climber.sim import ClimberSim, first_start
from sim_robot.climber.wall_world import WallWorld
from sim_robot.config import SimConfig
from sim_robot.mcu_port import SocketPort
from sim_robot.sim import SimClock

from .desk import SocketDesk
from .test_climber_link import TIME_SCALE, small_setup


class Board:
    """The climber's board and body on a wall of their own, served on a loopback
    socket (``url``): what a real robot on the tank would be to the relay."""

    def __init__(self, setup, seed: int = 5, time_scale: float = TIME_SCALE) -> None:
        p = ClimberParams()
        self.world = WallWorld(setup.spec, setup.nominal_mm, setup.patches, seed=seed)
        start = first_start(self.world.blocked, p, self.world.cell_m)
        x0, y0 = self.world.cell_centre(*start)
        contact = WallContact(setup.spec, self.world.blocked, p.length_m, p.width_m)
        self.body = ClimberBody(p, ClimberState(x0 - p.length_m / 2, y0, 0.0), self.world.circ_m,
                                seed=seed, height_m=setup.spec.height_m, contact=contact.depth)
        self.model = ClimberMcu(self.world, self.body, seed=seed)
        self.port = SocketPort()
        self.url = self.port.url
        self.thread = ClimberMcuThread(self.model, self.port, SimClock(time_scale))
        self.thread.start()

    def close(self) -> None:
        self.thread.stop()
        self.thread.join(timeout=2)
        self.port.close()


@pytest.fixture
def board():
    b = Board(small_setup())
    yield b
    b.close()


def test_the_climber_relay_drives_a_board_on_a_serial_device(board, caplog):
    cfg = SimConfig(video=False, seed=2, time_scale=TIME_SCALE, serial_device=board.url)
    with caplog.at_level(logging.WARNING, logger="sim_robot.climber.sim"):
        sim = ClimberSim(cfg, small_setup())
    # nothing simulated on this side: no wall truth, body, board model or camera
    assert sim.wall is None and sim.body is None and sim.model is None
    assert sim.mcu_thread is None and sim.relay.seams_seen is None
    assert sim.device == board.url and not hasattr(sim.map, "thickness")
    assert "no seam, shell-edge or rim fixes" in caplog.text and board.url in caplog.text
    sim.start()
    desk = SocketDesk(*sim.address)
    try:
        info = desk.wait_for(lambda: desk.of(P.MsgType.WALL_INFO), 10, "wall info")[0]
        assert (info.blocked_grid() == rasterise(small_setup().spec)).all()  # the file's map
        tel = desk.wait_for(lambda: desk.of(P.MsgType.TELEMETRY), 10, "telemetry")
        assert tel[-1].battery_v > 20  # the board's report, relayed
        assert sim.relay.inspection.detour is None  # no x fixes to wait for without a camera
        seq = desk.send(P.Command("start_inspection", {}))
        assert desk.wait_for(lambda: desk.ack(seq), 10, "start ack").ok

        def covered():
            c = desk.of(P.MsgType.COVERAGE)
            return c and c[-1].covered >= 40 and c[-1]

        prog = desk.wait_for(covered, 120, "40 cells covered")
        assert prog.state == CoverageState.RUNNING
        readings = desk.wait_for(lambda: desk.of(P.MsgType.PROBE), 10, "probe readings")
        assert sum(len(m.rows) for m in readings) >= 30
        # the board's body moved where the relay steered it, and read what it passed over
        assert board.model.probed.sum() >= 30
        pose = desk.of(P.MsgType.WALL_POSE)[-1]
        s = board.body.s
        assert math.hypot(pose.x_m - s.x_m % 3.0, pose.y_m - s.y_m) < 0.3
        counters = sim.relay.stats()["counters"]
        assert counters["seam_fixes"] == 0 and counters["rim_fixes"] == 0
    finally:
        desk.close()
        sim.close()


def test_sim_robot_takes_serial_for_the_climber(board, tmp_path):
    """The command line: ``sim-robot --robot climber --wall FILE --serial URL`` as a
    real process on an ephemeral port, the board served by this test."""
    from app.sim_process import SimRobotProcess

    f = tmp_path / "wall.toml"
    f.write_text("limit_mm = 8.0\n[wall]\ndiameter_m = 0.954929658551372\nheight_m = 1.2\n"
                 "nozzles = [{x_m = 2.2, y_m = 0.6, diameter_m = 0.3}]\n")
    proc = SimRobotProcess(seed=2, time_scale=TIME_SCALE,
                           extra=["--robot", "climber", "--wall", str(f), "--no-video",
                                  "--serial", board.url]).start()
    desk = SocketDesk(proc.host, proc.port)
    try:
        desk.wait_for(lambda: desk.of(P.MsgType.WALL_INFO), 10, "wall info")
        desk.wait_for(lambda: desk.of(P.MsgType.TELEMETRY), 10, "telemetry")
        seq = desk.send(P.Command("start_inspection", {}))
        assert desk.wait_for(lambda: desk.ack(seq), 10, "start ack").ok
        desk.wait_for(lambda: (c := desk.of(P.MsgType.COVERAGE)) and c[-1].covered >= 20,
                      120, "20 cells covered")
        assert board.model.probed.sum() >= 10
        out = "\n".join(proc.output)
        assert "no seam, shell-edge or rim fixes" in out and board.url in out
        assert "not supported" not in out
    finally:
        desk.close()
        proc.stop()


def test_a_seam_camera_on_a_board_fixes_the_estimate(tmp_path):
    """``--seam-camera-device``: with a real board the relay reads a real camera
    (here a video file of what the camera under the probe sees at the start: a
    girth seam 3 cm above it), finds the seam in its frames and fixes its
    estimate on it."""
    import dataclasses

    import cv2
    import numpy as np

    from app.core.planner.coverage.wall import Band
    from sim_robot.climber.camera_view import render_view

    plain = small_setup()
    spec = dataclasses.replace(plain.spec, seams=(Band(0.0, 0.38, 3.0, 0.38, 0.02, True),))
    setup = dataclasses.replace(plain, spec=spec)
    # a real board's clock runs at the host's pace: the board and relay at scale 1, so
    # that a frame's age in wall time is its age on the board's clock
    board = Board(setup, time_scale=1.0)
    assert first_start(board.world.blocked, ClimberParams(), 0.1) == (3, 4)  # probe y 0.35

    s = board.body.s
    lead = board.body.p.length_m / 2
    rng = np.random.default_rng(4)
    video = tmp_path / "seams.avi"
    # played at its own rate, as a camera would give them: 200 frames at 20 fps last 10 s
    out = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 20.0, (160, 160))
    assert out.isOpened()
    for _ in range(200):
        out.write(cv2.cvtColor(render_view(board.world, s.x_m + lead, s.y_m, 0.0, rng),
                               cv2.COLOR_GRAY2BGR))
    out.release()
    cfg = SimConfig(video=False, seed=2, time_scale=1.0, serial_device=board.url)
    with pytest.raises(ValueError, match="scale"):
        ClimberSim(cfg, setup, camera_device=str(video))
    with pytest.raises(ValueError, match="real board"):
        ClimberSim(SimConfig(video=False), small_setup(), camera_device=str(video),
                   camera_m_per_px=0.001)
    with pytest.raises(ValueError, match="cannot open"):
        ClimberSim(cfg, small_setup(), camera_device=str(tmp_path / "none.avi"),
                   camera_m_per_px=0.001)
    sim = ClimberSim(cfg, setup, camera_device=str(video), camera_m_per_px=0.001)
    sim.start()
    try:
        relay = sim.relay
        # until the first fix or the file's end (the camera thread stops there), with a
        # bound in case the relay never starts
        deadline = time.monotonic() + 60
        while (relay.counters["seam_fixes"] < 1 and not sim.camera.ended
               and time.monotonic() < deadline):
            time.sleep(0.05)
        assert sim.camera.frames > 0 and relay.counters["frames"] > 0
        assert relay.counters["seam_fixes"] >= 1, (relay.counters, relay.sightings.dropped)
    finally:
        sim.close()
        board.close()


def test_the_board_clock_keeps_the_least_delayed_report_and_the_relay_s_time_scale():
    """Frames are stamped on the board's clock as the relay hears it. A report taken
    in late (a busy host) must not stamp the frames after it late by as much: the
    estimate, on the reports that come on time, would pass them by and drop them.
    With a board at the relay's time scale, a wall second is that many board ones."""
    from types import SimpleNamespace

    from sim_robot.climber.camera_capture import board_clock

    for scale in (1.0, 40.0):
        host = [100.0]
        relay = SimpleNamespace(cfg=SimpleNamespace(time_scale=scale), report=None,
                                report_mono=0.0, report_stamp=None)
        clock = board_clock(relay, host_clock=lambda host=host: host[0])
        assert clock() is None  # no report yet

        def board_at(t_host, scale=scale):  # the board started 7 s before host time 100
            return 7.0 + scale * (t_host - 100.0)

        worst = 0.0
        for i in range(200):  # a report every 50 ms, one in ten taken in 0.2 s late
            sent = 100.0 + 0.05 * i
            got = sent + (0.2 if i % 10 == 3 else 0.001)
            host[0] = got
            relay.report = SimpleNamespace(mcu_time_ms=board_at(sent) * 1000.0)
            relay.report_mono = got
            relay.report_stamp = (board_at(sent), got)
            for dt in (0.0, 0.02, 0.04):  # frames between reports
                host[0] = got + dt
                worst = max(worst, abs(clock() - board_at(host[0])))
        # within the ordinary reports' 1 ms delay, in board time (the late ones: 0.2 s)
        assert worst <= 0.0011 * scale, (scale, worst)
