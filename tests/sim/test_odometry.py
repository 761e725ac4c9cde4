import math

from sim_robot.config import RobotParams
from sim_robot.mcu import McuModel
from sim_robot.mcu_link import McuFrame, McuType, MotorCmd
from sim_robot.odometry import Odometry
from sim_robot.world import World


def test_odometry_tracks_truth_and_drifts_a_little():
    w = World(seed=4)
    w.set_pose(62.0, 12.0, 0.0)  # open yard south of the pump house, heading east
    r = RobotParams()
    m = McuModel(w, r, seed=4, link_clock=lambda: 0.0)
    m.last_rx = 0.0
    odo = Odometry(r.ticks_per_rev / (2 * math.pi * r.wheel_radius_m), r.track_m,
                   62.0, 12.0, 0.0)
    t = 0.0
    plan = [(0.5, 0.0, 8.0), (0.0, 0.6, 2.0), (0.4, 0.2, 6.0), (0.5, 0.0, 5.0)]
    for v, om, dur in plan:
        m.handle(McuFrame(McuType.MOTOR_CMD, 0, MotorCmd(v, om)))
        for _ in range(int(dur / 0.05)):
            t += 0.05
            rep = m.step(t, 0.05)
            odo.update(rep.mcu_time_ms, rep.enc_left_ticks, rep.enc_right_ticks,
                       rep.yaw_rate_rps, rep.imu_yaw_rad)
    p = w.pose
    travelled = 0.5 * 8 + 0.4 * 6 + 0.5 * 5
    err = math.hypot(odo.x - p.x, odo.y - p.y)
    assert travelled * 0.4 < math.hypot(p.x - 62.0, p.y - 12.0)
    assert err < 0.05 * travelled  # within 5 % of the distance driven
    dth = abs((odo.theta - p.theta + math.pi) % (2 * math.pi) - math.pi)
    assert dth < 0.1


def test_mcu_reports_at_its_own_rate_in_sim_time_up_to_a_wall_cap():
    """The relay's odometry is as fresh as the board's 20 Hz at a time scale
    (one report per sampling period of sim time), but a very high scale is
    capped at 500 reports a second of wall time."""
    import os

    from sim_robot.mcu import McuThread
    from sim_robot.sim import SimClock

    w = World(seed=1)
    m = McuModel(w, RobotParams(), seed=1, link_clock=lambda: 0.0)
    master, slave = os.openpty()
    try:
        period = {s: McuThread(m, master, SimClock(s), 20.0).min_report_wall_s
                  for s in (1.0, 20.0, 1000.0)}
    finally:
        os.close(master)
        os.close(slave)
    assert math.isclose(period[1.0], 0.9 * 0.05)
    assert math.isclose(period[20.0], 0.9 * 0.05 / 20)  # 18 sim ms: every 50 ms sample goes
    assert period[1000.0] == 0.002


def test_a_stalled_mcu_catching_up_still_reports_every_fifth_of_a_second():
    """When the MCU model's thread falls seconds of sim time behind (a busy
    host at 20x), it catches up in a burst; its reports then go out at least
    every 0.2 s of sim time, so the relay's odometry never integrates seconds
    of turning as one arc (the estimate jumped metres after such a stall)."""
    import os
    import select
    import time
    import tty

    from sim_robot.mcu import REPORT_GAP_MAX_S, McuThread
    from sim_robot.mcu_link import McuDecoder, McuType

    class StalledClock:
        time_scale = 1.0
        t = 0.0

        def now(self):
            return self.t

        def wall_until(self, t_sim):
            return t_sim - self.t

    w = World(seed=1)
    m = McuModel(w, RobotParams(), seed=1, link_clock=lambda: 0.0)
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    clock = StalledClock()
    th = McuThread(m, master, clock, 20.0)
    times: list[int] = []
    dec = McuDecoder()
    try:
        th.start()
        clock.t = 3.0  # the thread wakes 3 s of sim time late
        end = time.monotonic() + 10
        while time.monotonic() < end and (not times or times[-1] < 2950):
            if select.select([slave], [], [], 0.1)[0]:
                for fr in dec.feed(os.read(slave, 4096)):
                    if fr.msg_type == McuType.SENSOR_REPORT:
                        times.append(fr.message.mcu_time_ms)
    finally:
        th.stop()
        th.join(timeout=2)
        os.close(master)
        os.close(slave)
    assert times and times[-1] >= 2950
    gaps = [b - a for a, b in zip([0, *times[:-1]], times, strict=True)]
    assert max(gaps) <= REPORT_GAP_MAX_S * 1000 + 50 + 1, gaps
