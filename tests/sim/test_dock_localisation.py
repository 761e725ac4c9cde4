"""A robot on its charger stays localised, and a loss always ends in an event.

The desk soak at 36x, robot hour 64: the robot, back on its dock after its
107th patrol, raised "localisation lost" there: its gyro's bias had wandered
to -0.117 rad/s (the archive's yaw-rate telemetry while it stood), the
odometry turned the estimate by that much each second, and once the scan
matches lapsed the heading was too far off for them; 8 failed matches later
it was lost. Its odometry's turn rate (the same bias) was read as "not
standing still", so it never searched for itself, and no event ever said it
was found or not: the desk refused every later patrol.
(bench/dock_bench.py plays it for hours.)"""

from __future__ import annotations

import math

import numpy as np

from app.comm.protocol import RobotMode
from sim_robot.config import SimConfig
from sim_robot.navigation import RELOC_RETRY_S, RELOC_TRIES, RELOC_WAIT_S, Navigation
from sim_robot.odometry import Odometry
from sim_robot.patrol_sim import OfflinePatrol
from sim_robot.world import World

SOAK_BIAS_RPS = -0.117  # the soak's gyro on the dock at robot hour 64
TICKS_PER_M = 2000.0


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def test_odometry_standing_still_holds_its_heading_and_learns_the_gyro_bias():
    odo = Odometry(TICKS_PER_M, 0.5, 0.0, 0.0, 1.0)
    rng = np.random.default_rng(3)
    yaw, t_ms = 0.0, 0
    for _ in range(30 * 20):  # 30 s on the charger: the encoders do not move
        t_ms += 50
        yaw = _wrap(yaw + (SOAK_BIAS_RPS + 0.004 * rng.standard_normal()) * 0.05)
        odo.update(t_ms, 100, 100, SOAK_BIAS_RPS, yaw)
    # the gyro alone says 3.5 rad of turn; the wheels say none (0.5 s to settle)
    assert abs(_wrap(odo.theta - 1.0)) < 0.07
    assert odo.omega == 0.0 and odo.v == 0.0
    assert abs(odo.gyro_bias_rps - SOAK_BIAS_RPS) < 0.005
    # driving straight on afterwards, the learnt bias is taken off the gyro
    ticks, th0 = 100.0, odo.theta
    for _ in range(10 * 20):  # 10 s at 0.5 m/s
        t_ms += 50
        ticks += 0.5 * 0.05 * TICKS_PER_M
        yaw = _wrap(yaw + SOAK_BIAS_RPS * 0.05)
        odo.update(t_ms, int(ticks), int(ticks), SOAK_BIAS_RPS, yaw)
    assert abs(_wrap(odo.theta - th0)) < 0.02, "the bias was not taken off while driving"
    assert odo.v > 0.4


def test_a_robot_on_its_dock_with_a_wandered_gyro_outlasts_a_lapse_of_scan_matches():
    """The soak's robot, in lock-step: on its charger, the gyro's bias at the
    soak's value, stepped as the relay steps it between missions (a scan
    matched every 0.2 s, the board's DOCKED flag passed on), with one lapse
    of 10 s of sim time in which no scan was matched (a starved host)."""
    cfg = SimConfig(seed=1, video=False)
    w = World(cfg.station_file, cfg.seed)
    w.walkers, w.vehicles = [], []
    op = OfflinePatrol(cfg, world=w)
    op.mcu.imu.bias = SOAK_BIAS_RPS
    nav, loc = op.nav, op.nav.localiser
    worst = 0.0
    while op.t < 90.0:
        op.step()
        nav.docked = op.mcu.report.mode == RobotMode.DOCKED
        if not 30.0 <= op.t < 40.0 and (nav.scan_t is None or op.t - nav.scan_t >= 0.2 - 1e-6):
            nav.perceive(op.t)
        truth = World.pose.fget(w)  # the test may read the truth
        worst = max(worst, abs(_wrap(loc.pose[2] - truth.theta)))
    assert nav.docked
    assert op.codes("localisation_lost") == [] and not loc.lost
    assert worst < math.radians(4), f"heading {math.degrees(worst):.0f}° off on the dock"


def _lost(docked: bool, omega, until_s: float) -> tuple[Navigation, list[tuple[float, str, dict]]]:
    """A robot standing on its dock that lost itself with its heading 100° off,
    stepped standing still while its odometry reports the turn rate
    ``omega(t)`` (a gyro's bias, noise); ``docked``: what its board says."""
    cfg = SimConfig(seed=1, video=False)
    w = World(cfg.station_file, cfg.seed)
    w.walkers, w.vehicles = [], []
    events: list[tuple[float, str, dict]] = []
    clock = [0.0]
    nav = Navigation(w, cfg.seed,
                     lambda level, code, text, **data: events.append((clock[0], code, data)),
                     lambda msg: None, lambda gauge: None)
    d = w.dock
    nav.localiser.set_pose(d[0], d[1], d[2] + math.radians(100))
    nav.localiser.map.lost = True
    nav.docked = docked
    while clock[0] < until_s:
        nav.step(clock[0], 0.1, (0.0, 0.0, 0.0), (0.0, omega(clock[0])))
        clock[0] += 0.1
    return nav, events


def test_a_robot_lost_on_its_dock_finds_itself_whatever_its_odometry_speeds_say():
    rng = np.random.default_rng(5)
    for omega in (lambda t: SOAK_BIAS_RPS, lambda t: 0.05 * rng.standard_normal()):
        nav, events = _lost(True, omega, 10.0)
        codes = [c for _, c, _ in events]
        assert codes == ["localisation_lost", "localisation_recovered"], codes
        truth = World.pose.fget(nav.world)  # the test may read the truth
        x, y, th = nav.localiser.pose
        assert math.hypot(x - truth.x, y - truth.y) < 0.1
        assert abs(_wrap(th - truth.theta)) < math.radians(3)


def test_a_lost_robot_that_never_stands_still_still_ends_the_episode_on_schedule():
    # off its charger, its odometry says it turns: no search can be made, and
    # after the retry schedule the episode ends in relocalisation_failed
    until = (RELOC_TRIES - 1) * RELOC_RETRY_S + RELOC_TRIES * RELOC_WAIT_S + 2.0
    nav, events = _lost(False, lambda t: 0.1, until)
    codes = [c for _, c, _ in events]
    assert codes == ["localisation_lost", "relocalisation_failed"], codes
    t_failed, _, data = events[-1]
    assert data["unsearched"] == RELOC_TRIES and data["tries"] == RELOC_TRIES
    # each search waited for stillness, and the searches kept their spacing
    assert t_failed >= (RELOC_TRIES - 1) * RELOC_RETRY_S + RELOC_WAIT_S - 1e-6
    assert nav.localiser.reloc_tries == 0 and nav.localiser.lost


def test_a_lost_robot_that_comes_to_a_stand_searches_then():
    # turning for the first 3 s (within the wait), then standing: it searches
    nav, events = _lost(False, lambda t: 0.1 if t < 3.0 else 0.0, 20.0)
    assert nav.localiser.reloc_tries >= 1
    assert [c for _, c, _ in events][-1] in ("localisation_recovered", "relocalisation_failed")
