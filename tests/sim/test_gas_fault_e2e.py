"""A faulty gas sensor on the robot reads below zero; the reading crosses the MCU's
serial link (signed since the gas field became i16) and the relay's TCP link, and
the desk's gas model raises its sensor-fault state."""

from __future__ import annotations

import pytest

from app.comm import protocol as P
from app.core.desk.pipeline import DeskPipeline
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot

from .desk import SocketDesk


@pytest.fixture
def faulty_robot():
    r = SimRobot(SimConfig(video=False, seed=5, gas_offset_lel=-9.0))
    r.start()
    yield r
    r.close()


def test_negative_gas_from_the_robot_raises_the_sensor_fault(faulty_robot):
    desk = SocketDesk(*faulty_robot.address)
    pipe = DeskPipeline()
    fed = 0

    def feed() -> bool:
        nonlocal fed
        tel = desk.of(P.MsgType.TELEMETRY)
        for m in tel[fed:]:
            pipe.ingest("telemetry", m)
        fed = len(tel)
        return pipe.monitor.stage("gas_lel_pct") == "fault"

    try:
        desk.wait_for(feed, 15.0, "gas sensor fault on the desk")
    finally:
        desk.close()
    gas = [m.gas_lel_pct for m in desk.of(P.MsgType.TELEMETRY)]
    assert min(gas) < -5.0  # below the fault band: signed all the way
    fault = pipe.monitor.get("gas_lel_pct.fault")
    assert fault is not None and fault.active
    assert "below" in fault.text
