"""The wall climber end to end: ``sim-robot --robot climber`` as a real process on
port 0 at a high time scale, the headless desk (the desk pipeline behind a real
RobotLink) on it: the plan arrives, coverage rises as the robot inspects, probe
readings fill the thickness map, and the corroded patch below the wall's limit
raises the thin-wall alarm at its place."""

from __future__ import annotations

import pytest
from pytestqt.exceptions import TimeoutError as WaitTimedOut

from app.comm.link import LinkSettings, RobotLink
from app.sim_process import SimRobotProcess

pytestmark = [pytest.mark.e2e]

WALL = """\
limit_mm = 8.0
nominal_mm = 10.0

[wall]
diameter_m = 0.954929658551372   # 3 m round
height_m = 1.2
cell_m = 0.1
nozzles = [{x_m = 2.2, y_m = 0.6, diameter_m = 0.3}]

[[patches]]   # 3 mm lost at its centre: 7 mm of 10, under the 8 mm limit
x_m = 1.05
y_m = 0.85
radius_m = 0.15
loss_mm = 3.0
"""


@pytest.fixture
def climber(tmp_path):
    f = tmp_path / "wall.toml"
    f.write_text(WALL)
    sim = SimRobotProcess(seed=2, time_scale=40.0,
                          extra=["--robot", "climber", "--wall", str(f), "--no-video"]).start()
    yield sim
    sim.stop()


def test_headless_desk_sees_coverage_rise_readings_and_the_thin_patch_alarm(qtbot, climber,
                                                                             tmp_path):
    from app.core.recorder import SessionRecorder
    from app.headless import build_headless_desk

    link = RobotLink(LinkSettings(reconnect_every_s=0.3))
    session = build_headless_desk(link, SessionRecorder(tmp_path / "out"))
    wall = session.pipeline.wall
    try:
        link.connect_to(climber.host, climber.port)
        qtbot.waitUntil(lambda: link.state == "connected", timeout=15000)
        qtbot.waitUntil(lambda: wall.ready, timeout=10000)
        assert wall.blocked.shape == (12, 30) and wall.blocked.any() and len(wall.path)
        link.send_when_connected("start_inspection", {})
        qtbot.waitUntil(lambda: wall.state == "running", timeout=10000)
        first = wall.coverage_pct
        qtbot.waitUntil(lambda: wall.coverage_pct > first + 20, timeout=60000)
        assert wall.readings > 50 and wall.unplaced <= wall.readings * 0.05

        def thin_alarm():
            return [a for a in session.monitor.active() if a.key.startswith("wall.thin")]

        try:
            qtbot.waitUntil(lambda: bool(thin_alarm()), timeout=120000)
        except WaitTimedOut as e:  # what the robot said of its run, for the reader
            raise AssertionError(f"no thin-wall alarm: {wall.state}, {wall.coverage_pct:.0f} % "
                                 f"covered, {wall.readings} readings; the robot printed:\n"
                                 + "\n".join(list(climber.output)[-40:])) from e
        (alarm,) = thin_alarm()
        spot = wall.alarmed[0]
        # the patch's centre is at (1.05 m, 0.85 m): the alarm names a cell near it
        assert abs(spot.x_m - 1.05) <= 0.25 and abs(spot.y_m - 0.85) <= 0.25
        assert spot.thickness_mm < 8.0 and "below limit 8 mm" in alarm.description
        assert wall.pose is not None and 0 <= wall.pose.x_m < 3.0
        assert session.pipeline.malformed == 0
    finally:
        link.shutdown()
        session.close()
