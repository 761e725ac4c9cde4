"""The wall climber served through the relay, the serial MCU model and the link:
``sim-robot --robot climber`` in-process on port 0, a plain-socket desk."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.comm import protocol as P
from app.comm.wall_protocol import CoverageState
from app.core.planner.coverage.wall import Band, Disc, WallSpec
from sim_robot.climber.sim import ClimberSetup, ClimberSim, load_setup
from sim_robot.climber.wall_world import Patch
from sim_robot.config import SimConfig

from .desk import SocketDesk

TIME_SCALE = 40.0


def small_setup() -> ClimberSetup:
    """A 3 m × 1.2 m wall with a nozzle, a seam and one deep patch (7 mm left of 10)."""
    spec = WallSpec(3.0 / math.pi, 1.2, 0.1, nozzles=(Disc(2.2, 0.6, 0.3),),
                    seams=(Band(0.0, 0.6, 3.0, 0.6, 0.02, crossable=True),))
    return ClimberSetup(spec, 10.0, 8.0, None, (Patch(1.05, 0.85, 0.15, 3.0),), "test-wall")


def test_climber_over_the_link_covers_probes_and_never_sends_truth(climber):
    desk = SocketDesk(*climber.address)
    try:
        info = desk.wait_for(lambda: desk.of(P.MsgType.WALL_INFO), 10, "wall info")[0]
        blocked = info.blocked_grid()
        assert blocked.shape == (12, 30) and blocked.any()
        path = info.path_cells()
        assert not blocked[path[:, 0], path[:, 1]].any()
        assert info.limit_mm == 8.0
        desk.wait_for(lambda: desk.of(P.MsgType.WALL_POSE), 10, "wall pose")
        desk.wait_for(lambda: desk.of(P.MsgType.TELEMETRY), 10, "telemetry")
        seq = desk.send(P.Command("start_inspection", {}))
        ack = desk.wait_for(lambda: desk.ack(seq), 10, "start ack")
        assert ack.ok, ack.reason

        def covered():
            c = desk.of(P.MsgType.COVERAGE)
            return c and c[-1].coverage_pct >= 30.0 and c[-1]

        prog = desk.wait_for(covered, 120, "30 % coverage")
        assert prog.state == CoverageState.RUNNING
        # the lane changes so far were made turning in place (sim_robot/climber/turns.py)
        assert climber.relay.stats()["turns_in_place"] >= 4
        mask = prog.mask(info.rows, info.cols)
        assert mask.sum() == prog.covered and not (mask & blocked).any()
        readings = np.concatenate([m.rows for m in desk.of(P.MsgType.PROBE)])
        assert len(readings) >= prog.covered * 0.9
        assert ((readings[:, 2] > 6.0) & (readings[:, 2] < 10.3)).all()
        # the desk sees readings, never the true thickness grid: no message carries it
        truth = climber.wall.thickness
        assert not any(getattr(f.message, "rows", None) is not None
                       and np.shape(f.message.rows) == truth.shape for f in desk.frames)
        seq = desk.send(P.Command("pause_inspection", {}))
        assert desk.wait_for(lambda: desk.ack(seq), 10, "pause ack").ok
        desk.wait_for(lambda: desk.of(P.MsgType.COVERAGE)[-1].state == CoverageState.PAUSED,
                      10, "paused coverage")
    finally:
        desk.close()


def test_wall_file_and_its_errors(tmp_path):
    f = tmp_path / "w.toml"
    f.write_text('limit_mm = 7.5\nstart = [3, 5]\n[wall]\ndiameter_m = 1.0\nheight_m = 1.0\n'
                 '[[patches]]\nx_m = 1.0\ny_m = 0.5\nradius_m = 0.1\nloss_mm = 2.0\n')
    s = load_setup(f)
    assert s.limit_mm == 7.5 and s.start == (3, 5) and len(s.patches) == 1
    f.write_text('[wall]\ndiameter_m = -1\n')
    with pytest.raises(ValueError, match="w.toml"):
        load_setup(f)


def test_executor_files_the_reading_nearest_each_cell_centre_once():
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    blocked = np.zeros((4, 10), bool)
    blocked[2, 5] = True
    ex = InspectionExecutor(blocked, 0.1, (1, 1), ClimberParams())
    ex.start(0.0)
    lead = ex.lead

    def at(x, y, mm):  # the probe at (x, y), the body heading +x
        ex.reading((x - lead, y, 0.0), mm)

    at(0.12, 0.15, 9.0)  # in cell (1, 1), 3 cm from its centre: a visit
    at(0.15, 0.15, 8.0)  # its centre: the best reading
    at(0.18, 0.15, 9.5)
    at(0.199, 0.199, 7.0)  # the corner of (1, 1): outside its core, not filed
    at(0.201, 0.201, 7.0)  # the corner of (2, 2): outside its core, no visit
    at(0.25, 0.15, 9.9)  # the core of (1, 2): (1, 1) is filed on the way out
    rows = ex.take_readings()
    assert rows.tolist() == [pytest.approx([0.15, 0.15, 8.0])]
    assert ex.visits == 2 and ex.covered.sum() == 1
    at(0.55, 0.25, 5.0)  # believed over the obstacle: dropped
    at(0.15, 0.15, 6.0)  # back in (1, 1): a repeat visit, its reading stays
    at(0.45, 0.35, 9.0)
    assert ex.filed[1, 1] == 8.0 and ex.filed[1, 2] == pytest.approx(9.9)
    assert ex.visits == 4 and not ex.covered[2, 5]
    assert ex.progress().repetition_pct == pytest.approx(100 * (4 - 2) / ex.reachable)


def test_sim_robot_command_refuses_a_bad_wall_file(tmp_path, caplog):
    import signal

    from sim_robot.cli import main

    f = tmp_path / "bad.toml"
    f.write_text("[wall]\nheight_m = 0\n")
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert main(["--robot", "climber", "--wall", str(f), "--no-video"]) == 2
    finally:
        for s, h in saved.items():  # main() installs its own handlers
            signal.signal(s, h)
    assert "bad.toml" in caplog.text and "height_m" in caplog.text


def test_executor_goes_back_for_the_cells_its_record_missed():
    """The sweep ends with a cell the record has no reading for (the probe
    never entered its core); the executor routes back to it before it reports
    the inspection done, and a second start forgets the mop-up."""
    from app.comm.wall_protocol import CoverageState
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    blocked = np.zeros((3, 8), bool)
    blocked[1, 4] = True
    ex = InspectionExecutor(blocked, 0.1, (0, 0), ClimberParams())
    skip = ex.cells[len(ex.cells) // 2]
    ex.start(0.0)
    lead, t = ex.lead, 0.0

    def drive(skipping):
        nonlocal t
        for _ in range(10 * len(ex.cells) + 50):
            if ex.state != CoverageState.RUNNING:
                return
            target = ex.cells[min(ex.index, len(ex.cells) - 1)]
            x, y = (target[1] + 0.5) * 0.1, (target[0] + 0.5) * 0.1
            pose = (x - lead, y, 0.0)  # the probe exactly on the target
            missed = skipping and target == skip and ex.index < ex.planned
            ex.reading(pose, None if missed else 9.0)  # the probe reads, then the step
            ex.step(pose, t)
            t += 0.05

    drive(skipping=True)
    assert ex.state == CoverageState.DONE
    assert ex.mop_ups == 1 and len(ex.cells) > ex.planned
    assert ex.covered[skip] and ex.covered.sum() == ex.reachable
    assert ex.cells[-1] == skip
    ex.start(t)
    assert len(ex.cells) == ex.planned and ex.mop_ups == 0


def test_executor_slows_on_a_stale_estimate():
    """Far from its target the probe is sent at full speed on a fresh
    estimate, and slower in proportion when the estimate is older than
    FRESH_S (a starved relay)."""
    from sim_robot.climber.executor import FRESH_S, InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams

    p = ClimberParams()
    ex = InspectionExecutor(np.zeros((3, 30), bool), 0.1, (1, 1), p)
    ex.start(0.0)
    far = ex.cells[5]
    ex.index = 5
    pose = ((far[1] + 0.5) * 0.1 - 1.0 - ex.lead, (far[0] + 0.5) * 0.1, 0.0)  # 1 m short, facing it
    v_fresh, _ = ex.step(pose, 10.0, 10.0 - FRESH_S / 2)
    v_stale, _ = ex.step(pose, 10.0, 10.0 - 4 * FRESH_S)
    assert v_fresh == pytest.approx(p.v_max_mps)
    assert v_stale == pytest.approx(p.v_max_mps / 4)
    assert ex.step(pose, 10.0)[0] == pytest.approx(p.v_max_mps)  # no time given: as before


def test_camera_frames_carry_the_time_of_the_body_they_show():
    """A seam sighting is stamped with the MCU model's last step (the body's
    state it shows), not the sim clock: on a loaded machine the model lags the
    clock, and the relay carries each offset back over the time between the
    frame and its estimate."""
    sim = ClimberSim(SimConfig(video=False, seed=2, time_scale=TIME_SCALE), small_setup())
    try:
        body = sim.body.s
        lead = sim.body.p.length_m / 2
        body.x_m, body.y_m, body.theta_rad = 1.0 - lead, 0.58, 0.0  # camera 2 cm below the seam
        sim.model.step(123.25, 0.01)
        t_frame, seen = sim._seams_seen()
        assert t_frame == pytest.approx(123.25)
        assert abs(sim.clock.now() - t_frame) > 100  # the clock has not run that far
        assert any(horizontal and offset == pytest.approx(0.02, abs=0.015)
                   for horizontal, _, offset in seen)
    finally:
        sim.close()


def test_executor_plans_the_default_wall_round_the_seam_with_fewer_turns():
    """On the default 24 m × 9.6 m tank the executor's plan (lane tours across
    the seam beside the walker, coverage/seam.py) covers every reachable cell,
    each step to a free 8-neighbour across the seam without cutting a corner,
    keeps its lanes up and down the wall, and turns less than the walker's
    plan alone (what the executor flew before) with fewer repeats."""
    from app.core.planner.coverage import figures, plan_coverage, rasterise
    from app.core.planner.coverage.wall import default_wall
    from sim_robot.climber.executor import InspectionExecutor
    from sim_robot.climber.kinematics import ClimberParams
    from sim_robot.climber.sim import first_start

    blocked = rasterise(default_wall())
    params = ClimberParams()
    start = first_start(blocked, params, 0.1)
    ex = InspectionExecutor(blocked, 0.1, start, params)
    cells = np.array(ex.cells)
    w = blocked.shape[1]
    assert tuple(cells[0]) == start
    dr = np.diff(cells[:, 0])
    dc = np.diff(cells[:, 1])
    dc = np.where(dc == w - 1, -1, np.where(dc == 1 - w, 1, dc))  # across the seam
    assert np.abs(dr).max() <= 1 and np.abs(dc).max() <= 1 and ((dr != 0) | (dc != 0)).all()
    assert not blocked[cells[:, 0], cells[:, 1]].any()
    diag = (dr != 0) & (dc != 0)
    r0, c0 = cells[:-1, 0][diag], cells[:-1, 1][diag]
    assert not blocked[r0 + dr[diag], c0].any()  # no corner cut
    assert not blocked[r0, (c0 + dc[diag]) % w].any()
    assert np.mean(dc == 0) > 0.95  # lanes up and down the wall
    before = figures(blocked, start, plan_coverage(blocked, start, wrap=True, regions=False,
                                                   axis=1).cells, wrap=True)
    after = figures(blocked, start, ex.cells, wrap=True)
    assert after.coverage == 1.0 and after.reachable == before.reachable == ex.reachable
    assert after.repetition <= min(0.019, before.repetition)
    assert after.turns < 0.85 * before.turns


def test_sim_time_waits_for_the_relay_so_the_body_does_not_drive_blind():
    """The tank's contact logs: the true pose ran 0.2–0.7 m within a second of sim time
    of a recoil (faster than the body drives) while the estimate stood still: the relay
    was reading the board's reports seconds late (a contact fix under its lock takes
    30–190 ms of wall time on a loaded machine, 1–6 s of sim time at 30x), the recoil
    never ended on the stale estimate, and the climber's clock ran on. Sim time now waits
    for the climber's board and for the estimate the navigation steers on (its last
    report's time), as the patrol robot's waits for its loops (SimClock.control_step).
    At 20x, the board driving at 5 cm/s: (1) the relay slow to read its reports (4 ms of
    wall time each); (2) the relay's lock held for 0.4 s of wall time."""
    import time

    sim = ClimberSim(SimConfig(video=False, seed=1, time_scale=20.0), small_setup())
    relay = sim.relay
    handle = relay._on_report

    def slow(rep):
        time.sleep(0.004)
        handle(rep)

    relay._on_report = slow
    sim.start()
    lags, errs = [], []
    try:
        t_end = time.monotonic() + 20
        while relay.counters["nav_steps"] < 5 and time.monotonic() < t_end:
            time.sleep(0.02)
        sim.model.target_v = 0.05  # (the last command the board had)
        for _ in range(8):
            time.sleep(0.1)
            with relay._lock:
                lags.append(sim.clock.now() - relay.odom.t_s)
                errs.append(abs(sim.wall.wrap_dx(sim.body.s.x_m - relay.odom.x)))
        relay._on_report = handle
        with relay._lock:  # the relay stalled: its navigation, reports and keepalives wait
            t0, x0 = sim.clock.now(), sim.body.s.x_m
            time.sleep(0.4)
            t1, x1 = sim.clock.now(), sim.body.s.x_m
            sim.model.target_v = 0.0
    finally:
        sim.close()
    assert relay.counters["nav_steps"] >= 5
    assert max(lags) < 1.0 and max(errs) < 0.05  # before: 8 s and 0.4 m behind
    assert t1 - t0 <= sim.cfg.control_lead_s + 1e-6  # before: 8 s
    assert sim.wall.wrap_dx(x1 - x0) < 0.03  # before: 0.4 m
