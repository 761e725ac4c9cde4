import math

from app.comm import protocol as P
from app.comm.protocol import AlarmFlag, RobotMode
from sim_robot.config import RobotParams
from sim_robot.mcu import McuModel
from sim_robot.mcu_link import Estop, McuFrame, McuType, MotorCmd
from sim_robot.world import World

from .conftest import wait_until


class FakeClock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def _mcu(x=66.0, y=45.0, theta=math.pi):
    w = World(seed=2)
    w.set_pose(x, y, theta)
    clk = FakeClock()
    return McuModel(w, RobotParams(), seed=2, link_clock=clk), clk, w


def _run(m, clk, seconds, t0=0.0, keepalive=True):
    t = t0
    for _ in range(int(seconds / 0.05)):
        t += 0.05
        clk.t = t
        if keepalive:
            m.handle(McuFrame(McuType.KEEPALIVE, 0, None))
        m.step(t, 0.05)
    return t


def test_mcu_drives_and_stops_on_lost_relay():
    m, clk, w = _mcu()
    m.handle(McuFrame(McuType.MOTOR_CMD, 1, MotorCmd(0.5, 0.0)))
    t = _run(m, clk, 2.0)
    assert m.report.cmd_linear_mps == 0.5
    assert not m.report.alarm_flags & AlarmFlag.FAILSAFE_STOP
    x_moving = w.pose.x
    assert x_moving < 66.0 - 0.5  # heading west from the dock
    # the relay goes quiet: within 0.5 s (+ one period) the MCU stops by itself
    t = _run(m, clk, 0.6, t, keepalive=False)
    assert m.report.cmd_linear_mps == 0.0 and m.report.wheel_left_mps == 0.0
    assert m.report.alarm_flags & AlarmFlag.FAILSAFE_STOP
    assert m.report.mode == RobotMode.FAILSAFE
    x_stopped = w.pose.x
    _run(m, clk, 1.0, t, keepalive=False)
    assert w.pose.x == x_stopped
    # frames again: the flag clears but the robot waits for a new motor command
    _run(m, clk, 0.2, t + 1.0)
    assert not m.report.alarm_flags & AlarmFlag.FAILSAFE_STOP
    assert w.pose.x == x_stopped


def test_mcu_stops_before_an_obstacle():
    m, clk, w = _mcu(66.0, 46.5, math.pi / 2)  # control room wall at y = 49 ahead
    m.handle(McuFrame(McuType.MOTOR_CMD, 1, MotorCmd(0.4, 0.0)))
    _run(m, clk, 10.0)
    r = m.report
    assert r.obstacle_front_m < 0.36
    assert r.alarm_flags & AlarmFlag.OBSTACLE_NEAR and r.alarm_flags & AlarmFlag.FAILSAFE_STOP
    assert w.pose.y < 49.0 - 0.35 - 0.1  # stopped before touching the wall
    # reversing away is allowed
    m.handle(McuFrame(McuType.MOTOR_CMD, 2, MotorCmd(-0.3, 0.0)))
    y = w.pose.y
    _run(m, clk, 1.0, 10.0)
    assert w.pose.y < y - 0.1


def test_mcu_estop_latches_and_rejects_motion():
    m, clk, w = _mcu()
    m.handle(McuFrame(McuType.ESTOP, 1, Estop(True)))
    ack = m.handle(McuFrame(McuType.MOTOR_CMD, 2, MotorCmd(0.5, 0.0)))
    assert ack.status == 1
    _run(m, clk, 1.0)
    assert w.pose.x == 66.0 and m.report.alarm_flags & AlarmFlag.ESTOP
    m.handle(McuFrame(McuType.ESTOP, 3, Estop(False)))
    assert m.handle(McuFrame(McuType.MOTOR_CMD, 4, MotorCmd(0.5, 0.0))).status == 0


def _drive(desk, v=0.3):
    return desk.send(P.Command("drive", {"linear_mps": v, "angular_rps": 0.0}))


def test_relay_stops_when_every_desk_falls_silent(robot, desk_factory):
    desk = desk_factory(heartbeat=False)
    wait_until(lambda: desk.of(P.MsgType.TELEMETRY))
    seq = _drive(desk)
    wait_until(lambda: desk.ack(seq))
    assert desk.ack(seq).ok
    wait_until(lambda: robot.relay.cmd_v == 0.3, 2)
    # the drive command would hold 1.0 s; silence > 1.0 s trips the failsafe (or expiry)
    wait_until(lambda: robot.relay.cmd_v == 0.0, 3)
    wait_until(lambda: any(t.cmd_linear_mps == 0.0 for t in desk.of(P.MsgType.TELEMETRY)[-3:]),
               3)


def test_relay_failsafe_event_on_silence_while_driving(robot, desk_factory):
    desk = desk_factory(heartbeat=False)
    wait_until(lambda: desk.of(P.MsgType.TELEMETRY))
    robot.relay.cfg.drive_valid_s = 10.0  # keep the drive alive: only silence can stop it
    seq = _drive(desk)
    wait_until(lambda: desk.ack(seq))
    ev = wait_until(lambda: desk.events("failsafe_stop"), 4)
    assert ev[0].level == "warning" and "silent" in ev[0].text
    assert robot.relay.cmd_v == 0.0


def test_relay_failsafe_when_the_driving_desk_disconnects(robot, desk_factory):
    watcher = desk_factory()
    driver = desk_factory()
    robot.relay.cfg.drive_valid_s = 10.0
    wait_until(lambda: len(robot.relay.server.clients) == 2)
    seq = _drive(driver)
    wait_until(lambda: driver.ack(seq))
    assert robot.relay.cmd_v == 0.3
    driver.close()  # the watcher stays, but the desk that drove is gone: stop
    wait_until(lambda: robot.relay.cmd_v == 0.0, 3)
    assert wait_until(lambda: any(e.data.get("reason") == "the driving desk disconnected"
                                  for e in watcher.events("failsafe_stop")))


def test_a_watching_desk_leaving_does_not_stop_the_driver(robot, desk_factory):
    watcher = desk_factory()
    driver = desk_factory()
    robot.relay.cfg.drive_valid_s = 10.0
    robot.relay.cfg.client_silence_s = 10.0
    wait_until(lambda: len(robot.relay.server.clients) == 2)
    seq = _drive(driver)
    wait_until(lambda: driver.ack(seq))
    watcher.close()
    wait_until(lambda: len(robot.relay.server.clients) == 1)
    wait_until(lambda: driver.events("client_disconnected"))
    assert robot.relay.cmd_v == 0.3


def test_relay_commands_and_acks(robot, desk_factory):
    desk = desk_factory()
    wait_until(lambda: desk.of(P.MsgType.TELEMETRY))
    s1 = desk.send(P.Command("estop", {}))
    s2 = _drive(desk)
    s3 = desk.send(P.Command("reset_estop", {}))
    s4 = desk.send(P.Command("set_speed_limit", {"linear_mps": 0.2}))
    s5 = _drive(desk, 0.5)
    s6 = desk.send(P.Command("fly", {}))
    s7 = desk.send(P.Command("stop", {}))
    wait_until(lambda: desk.ack(s7))
    assert desk.ack(s1).ok and not desk.ack(s2).ok and "estop" in desk.ack(s2).reason
    assert desk.ack(s3).ok and desk.ack(s4).ok and desk.ack(s5).ok
    assert not desk.ack(s6).ok and "unknown" in desk.ack(s6).reason
    assert desk.ack(s7).ok
    assert wait_until(lambda: desk.events("estop"))
    assert robot.relay.speed_limit == 0.2


def test_mcu_alarm_events(robot, desk_factory):
    desk = desk_factory()
    wait_until(lambda: desk.of(P.MsgType.TELEMETRY))
    desk.send(P.Command("estop", {}))
    ev = wait_until(lambda: [e for e in desk.events("mcu_alarm") if e.data["flag"] == "ESTOP"])
    assert ev[0].data["active"] is True
    desk.send(P.Command("reset_estop", {}))
    wait_until(lambda: [e for e in desk.events("mcu_alarm")
                        if e.data["flag"] == "ESTOP" and not e.data["active"]])
    wait_until(lambda: desk.of(P.MsgType.TELEMETRY)[-1].mode != RobotMode.ESTOP)
