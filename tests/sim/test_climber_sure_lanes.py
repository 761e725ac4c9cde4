"""Lanes surely in their columns (sim_robot/climber/sure_lanes.py): the cells filed
since the last x fix are judged by the correction the next one makes, and those not
surely in their column are driven to again by the executor's mop-up."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.comm.wall_protocol import CoverageState
from app.core.planner.coverage.wall import Band, WallSpec, rasterise
from sim_robot.climber.executor import InspectionExecutor
from sim_robot.climber.kinematics import ClimberParams
from sim_robot.climber.odometry import ClimberOdometry
from sim_robot.climber.sim import ClimberSetup, ClimberSim
from sim_robot.climber.sure_lanes import SureLanes, probe_sigma_x
from sim_robot.config import SimConfig
from sim_robot.mcu_link import SensorReport

D = 0.1
CAMERA_M = 0.08  # the camera sees a seam this near its image centre
DRIFT = 0.015  # the belief's x runs ahead of the truth by this per metre driven ...


def test_a_fix_judges_the_cells_filed_since_the_last_one():
    lanes = SureLanes(D, 1.2)
    lanes.filed((3, 2), 0.25 + 0.01)  # believed 1 cm right of the centre of column 2
    lanes.filed((4, 2), 0.25 - 0.02)  # 2 cm left
    assert lanes.fixed(-0.02, 0.005) == []  # 2 cm back: the true probe 1 / 4 cm left
    assert lanes.since == []  # (judged once)
    lanes.filed((3, 2), 0.25 + 0.01)
    lanes.filed((4, 2), 0.25 - 0.02)
    lanes.filed((5, 2), 0.25 + 0.03)
    # 4 cm back: the first and third stay within D/2 − σ of the centre, the second not
    assert lanes.fixed(-0.04, 0.005) == [(4, 2)]
    lanes.filed((0, 11), 1.19)  # across the wall's seam: 4 cm right of column 11's centre
    assert lanes.fixed(0.02, 0.0) == [(0, 11)]
    assert (lanes.fixes, lanes.unsure, lanes.largest_m) == (2, 2, 0.04)


def test_cells_filed_since_the_lane_a_gravity_heading_was_refused_in_are_not_sure():
    """Whatever the fix's correction: from the start of the lane in which the estimate
    refused its gravity heading until the fix."""
    lanes = SureLanes(D, 1.2)
    lanes.filed((0, 5), 0.55)
    lanes.filed((1, 5), 0.55)  # lane 5 ...
    lanes.filed((1, 4), 0.45)
    lanes.filed((0, 4), 0.45)  # ... lane 4, in which the estimate refused its heading
    lanes.refused()
    lanes.filed((0, 3), 0.35)  # ... and the next lane
    assert lanes.fixed(0.0, 0.005) == [(1, 4), (0, 4), (0, 3)]
    lanes.filed((1, 3), 0.35)  # (after the fix, sure again)
    assert lanes.fixed(0.0, 0.005) == []
    assert lanes.refusals == 1


def test_probe_sigma_x_carries_the_heading_to_the_probe():
    cov = np.diag([0.01**2, 0.02**2, 0.05**2])
    assert probe_sigma_x(cov, 0.0, 0.144) == pytest.approx(0.01)
    assert probe_sigma_x(cov, math.pi / 2, 0.144) == pytest.approx(math.hypot(0.01, 0.0072))


def _fly(ex: InspectionExecutor, start: tuple[int, int], judge: bool,
         dt: float = 0.05, max_steps: int = 100_000) -> np.ndarray:
    """An ideal body driven by the executor on a belief whose x runs DRIFT a metre
    ahead of the truth until the camera (at the true probe point) first sees the
    vertical seam at x = 0; that fix puts the belief right, and it drifts no more
    (a filter that has learnt what leant it). The executor is told of each fix, with
    the probe's correction when ``judge`` (without it, as the relay told it before).
    Returns where the probe truly passed (the simulator's trace)."""
    lead, circ = ex.lead, ex.circ_m
    x, y, th = (start[1] + 0.5) * D - lead, (start[0] + 0.5) * D, 0.0
    err, drifting, t = 0.0, True, 0.0
    probed = np.zeros(ex.blocked.shape, bool)
    ex.start(t)
    for _ in range(max_steps):
        if ex.state != CoverageState.RUNNING:
            break
        belief = ((x + err) % circ, y, th)
        ex.reading(belief, 9.0)
        v, w = ex.step(belief, t, t, None)
        mid = th + w * dt / 2
        dx, dy = v * math.cos(mid) * dt, v * math.sin(mid) * dt
        x, y = (x + dx) % circ, y + dy
        th = (th + w * dt + math.pi) % (2 * math.pi) - math.pi
        if drifting:
            err += DRIFT * math.hypot(dx, dy)
        px, py = (x + lead * math.cos(th)) % circ, y + lead * math.sin(th)
        row = math.floor(py / D)
        if 0 <= row < probed.shape[0]:
            probed[row, math.floor(px / D) % probed.shape[1]] = True
        if min(px, circ - px) <= CAMERA_M:  # the seam seen: the belief's x is the truth's
            moved, err, drifting = -err, 0.0, False
            ex.x_fixed(moved, 0.005) if judge else ex.x_fixed()
        t += dt
    assert ex.state == CoverageState.DONE
    return probed


def test_lanes_driven_sideways_before_the_first_x_fix_are_driven_again():
    """A wall 1.2 m round and 1 m high with one vertical seam (x = 0): the lanes from
    the start (column 6) run down to column 0 before the camera first sees the seam,
    the belief's x running ahead of the truth by 1.5 cm a metre, 9 cm by then, so lanes
    were probed in their neighbours' columns while the executor believed them in their
    own. Told only that x was fixed, it believes the wall read in full and truly misses
    cells; told how far the fix moved its belief, it finds the cells filed since the
    start that were not surely in their column, drives to them again after the sweep,
    and every cell is truly probed."""
    spec = WallSpec(1.2 / math.pi, 1.0, D, seams=(Band(0.0, 0.0, 0.0, 1.0, 0.01),))
    blocked = rasterise(spec)
    before = InspectionExecutor(blocked, D, (0, 6), ClimberParams(), turns_in_place=True)
    probed = _fly(before, (0, 6), judge=False)
    assert before.covered.sum() == before.reachable  # believed read in full ...
    missed = ~probed & ~blocked
    assert missed.sum() >= 5  # ... yet not truly
    ex = InspectionExecutor(blocked, D, (0, 6), ClimberParams(), turns_in_place=True)
    probed = _fly(ex, (0, 6), judge=True)
    assert ex.lanes.unsure >= missed.sum()  # (the cells judged include those missed)
    assert ex.mop_ups >= 1
    assert not (~probed & ~blocked).any()
    assert ex.covered.sum() == ex.reachable


def _lane_up(ex: InspectionExecutor, x_m: float, rows: int, mm=lambda r: 9.0,
             step_m: float = 0.005) -> None:
    """The probe believed at ``x_m`` from the bottom edge up through ``rows`` rows, facing
    up (the axle ``lead`` below it), a sample every ``step_m``, row r reading ``mm(r)``."""
    for k in range(round(rows * D / step_m)):
        y = (k + 0.5) * step_m
        ex.reading((x_m, y - ex.lead, math.pi / 2), mm(math.floor(y / D)))
    ex._flush()  # (the last visit filed: the probe leaves the lane's top cell)


def test_a_lane_filed_before_a_small_x_correction_is_kept_at_its_corrected_place():
    """A lane up column 2 steered on its centre, then an x fix that moves the belief
    4.5 cm left (σ 1 cm after). The error grew along the lane from naught at the last
    fix: the cells filed early carried little of it. Spread back along the track, the
    lane's lower half is surely in column 2 and kept (its readings at the corrected x),
    only its upper end is taken back; judged by the whole correction (|offset + dx| +
    σ ≥ D/2), every cell of the lane was taken back."""
    ex = InspectionExecutor(np.zeros((12, 12), bool), D, (0, 2), ClimberParams())
    _lane_up(ex, 0.25, 12)
    assert ex.covered[:, 2].all() and ex.covered.sum() == 12
    ex.x_fixed(-0.045, 0.01)
    assert ex.covered[:6, 2].all()  # kept
    assert not ex.covered[9:, 2].any()  # taken back, for the mop-up
    assert ex.lanes.unsure == 12 - int(ex.covered[:, 2].sum()) <= 6
    for r in range(6):  # the kept readings at their corrected x: 0.25 − 4.5 cm · s/S
        x, y, _ = ex.lanes.refiled[(r, 2)]
        assert x == pytest.approx(0.25 - 0.045 * (y - 0.0025) / 1.195, abs=1e-6)
    assert ex.covered.sum() == int(ex.covered[:, 2].sum())  # nothing filed elsewhere


def test_samples_the_belief_put_outside_every_core_are_filed_at_their_corrected_cell():
    """The probe believed 4.1 cm right of column 2's centre all up the lane (outside
    its core: nothing filed), and a fix that moves the belief 3 cm right: the samples
    near the lane's top end, which carried most of the error, lie in column 3's core on
    the corrected track, surely so, and are filed there with their own readings and
    sent at the corrected x; the lower ones, no surer in either column, are not."""
    ex = InspectionExecutor(np.zeros((12, 12), bool), D, (0, 2), ClimberParams())
    _lane_up(ex, 0.291, 10, mm=lambda r: 9.0 - 0.1 * r)
    assert not ex.covered.any()
    ex.take_readings()
    ex.x_fixed(0.03, 0.005)
    assert ex.covered[8:10, 3].all() and not ex.covered[:5].any()
    assert not ex.covered[:, 2].any()
    for r in np.nonzero(ex.covered[:, 3])[0]:
        assert ex.filed[r, 3] == pytest.approx(9.0 - 0.1 * r)
    sent = ex.take_readings()
    assert len(sent) == int(ex.covered.sum()) and ex.anew == len(sent)
    assert ((sent[:, 0] > 0.3) & (sent[:, 0] < 0.4)).all()  # in column 3, corrected


def test_a_lane_since_a_refused_gravity_heading_is_not_filed_again():
    """The refused gravity heading's rule stands on the corrected track: the samples
    from the lane it came in until the fix are not filed again, whatever the
    correction."""
    ex = InspectionExecutor(np.zeros((12, 12), bool), D, (0, 2), ClimberParams())
    _lane_up(ex, 0.25, 6)
    for k in range(6 * 20):  # the next lane, down column 3, in which a heading is refused
        y = 0.6 - (k + 0.5) * 0.005
        ex.reading((0.35, y + ex.lead, -math.pi / 2), 9.0)
        if k == 30:  # (in its second cell)
            ex.lanes.refused()
    ex.x_fixed(0.0, 0.005)
    assert ex.covered[:6, 2].all() and not ex.covered[:, 3].any()


def _relay_facing_up(x_m: float):
    """A relay prepared on a 3 m wall with one vertical seam at 1 m, its estimate at
    (``x_m``, 0.5 m) facing up: ``(sim, relay, executor)``."""
    spec = WallSpec(3.0 / math.pi, 1.2, D, seams=(Band(1.0, 0.0, 1.0, 1.2, 0.01),))
    sim = ClimberSim(SimConfig(video=False, seed=2), ClimberSetup(spec, 10.0, 8.0, None, (),
                                                                  "test-wall"))
    relay = sim.relay
    relay.prepare()
    relay.odom = ClimberOdometry(relay.params, x_m, 0.5, math.pi / 2)
    return sim, relay, relay.inspection


def test_the_relay_tells_the_executor_what_its_estimate_does():
    """The relay's part: an x fix's correction of the probe's believed x and its σ
    after reach the executor (a cell filed 3 cm left of its centre is not sure once
    a fix moves the belief about 3 cm left), and a gravity heading the estimate
    refuses marks the lane being driven as not sure."""
    sim, relay, ex = _relay_facing_up(1.04)
    try:
        relay.odom.ekf._p[0, 0] = 0.03**2  # (x unsure by 3 cm)
        for cell, x in (((4, 10), 1.02), ((5, 10), 1.07)):
            ex.covered[cell] = True
            ex.lanes.filed(cell, x)
        relay._seam_fix((False, 0.0, -0.01), None)  # the seam 1 cm left of the camera
        assert ex.lanes.largest_m == pytest.approx(0.027, abs=0.003)
        assert not ex.covered[4, 10] and ex.covered[5, 10]
        ex.lanes.filed((6, 10), 1.05)
        report = dict(enc_left_ticks=0, enc_right_ticks=0, yaw_rate_rps=0.0)
        relay._on_report(SensorReport(mcu_time_ms=1000, imu_yaw_rad=math.pi / 2, **report))
        relay._on_report(SensorReport(mcu_time_ms=1050, imu_yaw_rad=math.pi / 2 + 0.3,
                                      **report))  # 0.3 rad off: refused as a jolt
        assert ex.lanes.refusals == 1
        assert ex.lanes.fixed(0.0, 0.0) == [(6, 10)]
    finally:
        sim.close()


def test_a_run_of_refusals_mended_by_the_reset_where_the_belief_hardly_moved_is_not_counted():
    """A turn in place through the link can leave the belief's heading 30-60 mrad off:
    the filter refuses the gravity heading twenty times in a row and takes it with its
    reset, the body hardly moved. Moved 2 cm with the heading 50 mrad off, x can be at
    most 1 mm wrong: the lanes stay sure. The same run while driving 30 cm, a run that
    ends without the reset (a jolt, or a lean the belief came back from) and a run an x
    fix comes in are counted, from the lane the run began in."""
    def lanes_with_run(step_m: float, reset: bool) -> SureLanes:
        lanes = SureLanes(D, 1.2)
        lanes.filed((0, 5), 0.55)
        lanes.filed((0, 4), 0.45)  # lane 4, in which the run begins
        for _ in range(19):
            lanes.moved(step_m)
            lanes.refused(0.05)
        lanes.filed((1, 4), 0.45)
        lanes.moved(step_m)
        lanes.refused(0.05)
        lanes.resolved(reset)
        lanes.filed((1, 3), 0.35)
        return lanes

    lanes = lanes_with_run(0.001, reset=True)
    assert lanes.fixed(0.0, 0.005) == []
    assert (lanes.refusals, lanes.mended, lanes.counted) == (20, 1, 0)
    driving = lanes_with_run(0.015, reset=True)
    assert driving.fixed(0.0, 0.005) == [(0, 4), (1, 4), (1, 3)]
    assert (driving.mended, driving.counted) == (0, 1)
    jolt = lanes_with_run(0.001, reset=False)
    assert jolt.fixed(0.0, 0.005) == [(0, 4), (1, 4), (1, 3)]
    pending = SureLanes(D, 1.2)
    pending.filed((0, 4), 0.45)
    pending.refused(0.05)
    assert pending.fixed(0.0, 0.005) == [(0, 4)]
    pending.filed((1, 3), 0.35)  # the run goes on past the fix and ends in the reset
    pending.refused(0.05)
    pending.resolved(True)
    assert pending.fixed(0.0, 0.005) == []


@pytest.mark.parametrize("ticks, counted", [(0, False), (40, True)])
def test_the_relay_does_not_count_a_burst_the_reset_mends_where_the_body_stood(ticks, counted):
    """Through the relay: the belief's heading 0.1 rad off the gravity heading, the
    filter refuses it until its reset. With the encoders still (a turn in place's end)
    the lane filed before stays sure; driving 7 mm a report (15 cm over the run, up to
    1.5 cm of x) it does not."""
    sim, relay, ex = _relay_facing_up(1.05)
    try:
        ex.lanes.filed((5, 10), 1.05)
        ekf = relay.odom.ekf
        for k in range(40):
            relay._on_report(SensorReport(mcu_time_ms=1000 + 50 * k, enc_left_ticks=k * ticks,
                                          enc_right_ticks=k * ticks, yaw_rate_rps=0.0,
                                          imu_yaw_rad=relay.odom.theta + 0.1))
            if ekf.resets["gravity"]:
                break
        assert ekf.resets["gravity"] == 1 and ekf.rejected["gravity"] >= 19
        assert ex.lanes.refusals == ekf.rejected["gravity"]
        assert ex.lanes.fixed(0.0, 0.0) == ([(5, 10)] if counted else [])
    finally:
        sim.close()


def test_a_lean_the_first_fix_does_not_show_leaves_no_lane_filed_before_it():
    """The first lanes through the link can lean (the accelerometer's bias learnt wrong
    in the first turns): a heading 15 mrad off moves the x error by 15 mrad times the
    believed height climbed, out on an up lane and back on a down lane. Here a lane up
    column 4 and one down column 3 of a 4.8 m wall, steered on their centres: the true
    probe runs up to 7 cm off at the top, outside column 3 above about 3.3 m, and back
    at the bottom, where the first x fix finds the belief 3 mm off. Spread along the
    distance driven, that correction kept every cell (the trace of a link run: 17 cells
    of a column filed and never probed); the first fix now takes back all filed before
    it, for the mop-up (the relay's option ``first_fix_whole``; off, the cells stay)."""
    rows, lean = 48, 0.015
    ex = InspectionExecutor(np.zeros((rows, 12), bool), D, (0, 4), ClimberParams(),
                            first_fix_whole=True)
    truly = np.zeros((rows, 12), bool)

    def sample(x_m: float, y_m: float, th: float) -> None:
        ex.reading((x_m, y_m - ex.lead * math.sin(th), th), 9.0)
        truly[math.floor(y_m / D), math.floor((x_m + lean * y_m) / D)] = True

    n = round(rows * D / 0.005)
    for k in range(n):  # up column 4, then down column 3
        sample(0.45, (k + 0.5) * 0.005, math.pi / 2)
    ex._flush()
    for k in range(n):
        sample(0.35, rows * D - (k + 0.5) * 0.005, -math.pi / 2)
    ex._flush()
    assert ex.covered[:, 3].all() and ex.covered[:, 4].all()
    assert not truly[34:, 3].all()  # column 3's upper cells never truly probed ...
    ex.x_fixed(0.003, 0.01)  # ... and the first fix, at the bottom, finds 3 mm
    assert not (ex.covered & ~truly).any()
    assert not ex.covered.any() and ex.lanes.unsure == 2 * rows
    for k in range(120):  # the fixes after it judge as before: a lane up column 2 ...
        ex.reading((0.25, (k + 0.5) * 0.005 - ex.lead, math.pi / 2), 9.0)
    ex._flush()
    ex.x_fixed(-0.045, 0.01)  # ... its lower cells kept on the corrected track
    assert ex.covered[:4, 2].all() and not ex.covered[10:12, 2].any()
    off = InspectionExecutor(np.zeros((rows, 12), bool), D, (0, 4), ClimberParams())
    for k in range(n):
        off.reading((0.35, rows * D - (k + 0.5) * 0.005 + off.lead, -math.pi / 2), 9.0)
    off._flush()
    off.x_fixed(0.003, 0.01)
    assert off.covered[:, 3].all()  # (the option off: kept, as before)
