"""The robot's refusal summary is news only when something was refused: a clean
start logs and sends no "rejections" warning with an empty list (issue 12, C)."""

import logging

from app.comm import protocol as P
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot

from .conftest import Desk, wait_until


def test_no_empty_rejections_warning_at_start_and_a_real_one_after_a_refusal(caplog):
    caplog.set_level(logging.INFO, logger="sim_robot")
    robot = SimRobot(SimConfig(video=False, seed=3))
    robot.start()
    desk = None
    try:
        # three heartbeat ticks: the 1 Hz summary had three chances to speak
        wait_until(lambda: robot.relay.counters["heartbeat"] >= 3, 8)
        said = [r.getMessage() for r in caplog.records if "rejections" in r.getMessage()]
        assert said == [], said
        desk = Desk(*robot.address)
        wait_until(lambda: desk.of(P.MsgType.HEARTBEAT), 5)
        bad = bytearray(desk.enc.encode(P.Command("stop", {})))
        bad[-1] ^= 0xFF  # a wrong checksum: refused and counted
        desk.sock.sendall(bytes(bad))
        ev = desk.wait_for(lambda: desk.events("rejections"), 5, "a rejections summary")
        assert ev[0].text.startswith("refusals so far: frame:")
        assert ev[0].text != "refusals so far: "
    finally:
        if desk is not None:
            desk.close()
        robot.close()
