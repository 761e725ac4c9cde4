"""``--serial DEVICE``: the relay drives an external MCU through the same code."""

import os
import select
import tty

from app.comm import protocol as P
from sim_robot.config import SimConfig
from sim_robot.mcu_link import McuDecoder, McuEncoder, McuType, MotorCmd, SensorReport
from sim_robot.sim import SimRobot

from .conftest import Desk, wait_until


def test_relay_talks_to_an_external_board_on_a_serial_device():
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    robot = SimRobot(SimConfig(video=False, serial_device=os.ttyname(slave)))
    assert robot.mcu_thread is None
    robot.start()
    desk = Desk(*robot.address)
    dec, enc = McuDecoder(), McuEncoder()
    seen: list = []

    def pump():
        while select.select([master], [], [], 0)[0]:
            seen.extend(dec.feed(os.read(master, 4096)))
        return seen

    try:
        # the relay keeps the board alive and sends its limits
        wait_until(lambda: {McuType.KEEPALIVE, McuType.CONFIG} <= {f.msg_type for f in pump()})
        # the board reports; the desk gets it as telemetry
        os.write(master, enc.encode(SensorReport(1000, gas_lel_pct=3.5, battery_v=12.2)))
        tel = wait_until(lambda: desk.of(P.MsgType.TELEMETRY))
        assert abs(tel[-1].gas_lel_pct - 3.5) < 0.01
        # a drive command reaches the board as MOTOR_CMD
        desk.send(P.Command("drive", {"linear_mps": 0.25, "angular_rps": 0.0}))
        cmd = wait_until(lambda: [f.message for f in pump() if f.msg_type == McuType.MOTOR_CMD
                                  and f.message.linear_mps > 0])
        assert isinstance(cmd[0], MotorCmd) and abs(cmd[0].linear_mps - 0.25) < 1e-3
        # missions are allowed with a real board: the robot localises on its own
        # lidar and odometry, no simulator truth is needed
        seq = desk.send(P.Command("goto", {"x_m": 62.0, "y_m": 45.0}))
        ack = wait_until(lambda: desk.ack(seq))
        assert ack.ok, ack.reason
        # garbage from the board is counted and reported, not fatal
        os.write(master, b"\xaa\x55\x01\x00\x29" + bytes(50))
        wait_until(lambda: desk.events("decoder_drop"))
    finally:
        desk.close()
        robot.close()
        os.close(master)
        os.close(slave)
