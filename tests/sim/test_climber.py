"""The wall climber's body (slip, limits) and its wall (thickness, probe,
obstacles, seams)."""

import math

import numpy as np
import pytest

from app.core.planner.coverage.wall import Band, Disc, WallSpec
from sim_robot.climber import ClimberBody, ClimberParams, ClimberState, Patch, WallWorld


def drive(body, v, w, seconds, dt=0.01):
    enc = 0.0
    yaw_enc = 0.0
    for _ in range(int(round(seconds / dt))):
        vl, vr, _ = body.step(v, w, dt)
        enc += (vl + vr) / 2 * dt
        yaw_enc += (vr - vl) / body.p.track_m * dt
    return enc, yaw_enc


def test_limits_of_table3():
    body = ClimberBody(state=ClimberState(1.0, 1.0, 0.0))
    v, w = body.limit(1.0, 2.0, 0.1)
    assert v == pytest.approx(0.05) and w == pytest.approx(0.35)  # 0.5 m/s², 3.5 rad/s²
    drive(body, 1.0, 0.0, 2.0)
    assert body.s.v_mps == pytest.approx(0.15)
    drive(body, 0.0, 5.0, 2.0)
    assert abs(body.s.omega_rps) == pytest.approx(0.5)


def test_climbing_slips_back_and_descending_overruns():
    up = ClimberBody(state=ClimberState(1.0, 1.0, math.pi / 2), seed=1)
    wheels, _ = drive(up, 0.12, 0.0, 5.0)
    assert 0 < up.s.y_m - 1.0 < wheels
    down = ClimberBody(state=ClimberState(1.0, 5.0, -math.pi / 2), seed=1)
    wheels, _ = drive(down, 0.12, 0.0, 5.0)
    assert 5.0 - down.s.y_m > wheels


def test_driving_across_the_wall_creeps_down():
    body = ClimberBody(state=ClimberState(1.0, 2.0, 0.0), seed=2)
    drive(body, 0.12, 0.0, 5.0)
    assert body.s.y_m < 2.0 and body.s.x_m > 1.5


def test_turning_slips_so_encoders_overstate_the_turn():
    errors = []
    for seed in range(10):
        body = ClimberBody(state=ClimberState(1.0, 1.0, 0.0), seed=seed)
        _, yaw_enc = drive(body, 0.0, 0.35, math.pi / 2 / 0.35)
        _, more = drive(body, 0.0, 0.0, 0.5)
        errors.append(math.degrees(yaw_enc + more - body.s.theta_rad))
    assert all(e > 0 for e in errors)
    assert 5.0 < np.mean(errors) < 20.0  # Table 2 "before fusion": 12.8–14.4° at the maxima
    no_slip = ClimberBody(ClimberParams(s_turn=0.0), ClimberState(1.0, 1.0, 0.0))
    _, yaw_enc = drive(no_slip, 0.0, 0.35, math.pi / 2 / 0.35)
    drive(no_slip, 0.0, 0.0, 0.5)
    assert abs(no_slip.s.theta_rad - math.pi / 2) < math.radians(3)


def test_x_wraps_round_the_tank():
    body = ClimberBody(state=ClimberState(9.95, 1.0, 0.0), circumference_m=10.0)
    drive(body, 0.12, 0.0, 2.0)
    assert 0.0 <= body.s.x_m < 0.3


def _small_wall():
    spec = WallSpec(
        6.0 / math.pi,
        3.0,
        0.1,
        manholes=(Disc(2.0, 1.0, 0.6),),
        seams=(Band(4.0, 0.5, 4.0, 2.5, 0.02, crossable=False),),
    )
    return WallWorld(spec, nominal_mm=10.0, patches=(Patch(1.05, 2.05, 0.2, 3.0),), seed=3)


def test_thickness_and_probe():
    w = _small_wall()
    t, (r, c) = w.thinnest()
    assert t == pytest.approx(7.0, abs=0.1)
    x, y = w.cell_centre(r, c)
    assert (x, y) == pytest.approx((1.05, 2.05))
    reads = [w.probe(x, y) for _ in range(200)]
    assert np.mean(reads) == pytest.approx(w.thickness[r, c], abs=0.01)
    assert w.probe(2.0, 1.0) is None  # over the manhole
    assert w.probe(1.0, 5.0) is None  # off the top of the wall
    assert w.probe(0.5, 0.5) == pytest.approx(10.0, abs=0.2)


def test_footprint_and_seams():
    w = _small_wall()
    p = ClimberParams()
    assert w.footprint_free(1.0, 0.6, 0.0, p.length_m, p.width_m)
    assert not w.footprint_free(2.0, 1.4, 0.0, p.length_m, p.width_m)  # over the manhole's rim
    assert not w.footprint_free(1.0, 0.05, 0.0, p.length_m, p.width_m)  # off the bottom
    assert not w.footprint_free(4.0, 1.5, 0.0, p.length_m, p.width_m)  # on the seam
    seen = w.seams_in_view(3.7, 1.5, 0.5)
    assert len(seen) == 1 and seen[0][1] == pytest.approx(0.3)
    assert w.seams_in_view(1.0, 1.5, 0.5) == []


def test_square_runs_wheel_odometry_drift_and_its_fusion_as_in_table2():
    from sim_robot.climber.square import square_table

    rows = square_table(5)  # bench/climber_square_bench.py runs the paper's 10
    wheel = np.array([d["wheel"] for _, d in rows])
    fused = np.array([d["fused"] for _, d in rows])
    assert (wheel[:, 0] >= wheel[:, 1]).all()
    assert 4.0 < wheel[:, 1].mean() < 10.0  # Table 2: 7.03° mean before fusion
    # the EKF (app/core/localisation) trusts the gyro while turning: ≥ 90 % lower
    assert fused[:, 1].mean() <= 0.1 * wheel[:, 1].mean()


def test_inspection_probes_every_reachable_cell_and_finds_the_thinnest():
    from sim_robot.climber.inspection import inspect_wall

    spec = WallSpec(
        3.0 / math.pi,
        1.2,
        0.1,
        manholes=(Disc(1.0, 0.6, 0.4),),
        stairs=(Band(2.0, 0.0, 2.6, 1.2, 0.25),),
    )
    world = WallWorld(
        spec, patches=(Patch(2.85, 0.95, 0.15, 2.0), Patch(0.35, 0.25, 0.3, 1.0)), seed=4
    )
    res = inspect_wall(world, (0, 0), seed=4)
    free = int((~world.blocked).sum())
    assert res.planned == free  # the wrap joins both sides of the stair
    assert res.probed == res.planned
    true_mm, (tr, tc) = world.thinnest()
    r, c = res.thinnest_cell
    assert max(abs(r - tr), min(abs(c - tc), world.cols - abs(c - tc))) <= 1
    assert res.thinnest_mm == pytest.approx(true_mm, abs=0.15)


def test_a_star_and_dwa_take_the_climber_round_the_pipe():
    from sim_robot.climber.navigate import mud_tank_wall, navigate

    params = ClimberParams()
    res = navigate(mud_tank_wall((1.0, 0.8)), (0.3, 0.8, 0.0), (1.7, 0.8), params)
    assert res.reached, res.status
    x, y, _ = res.trajectory[-1]
    assert math.hypot(x - 1.7, y - 0.8) < 0.15
    radius = math.hypot(params.length_m, params.width_m) / 2
    assert res.min_clearance_m > radius - 0.05  # the body never touches the pipe or the edges
    ys = [p[1] for p in res.trajectory if 0.9 < p[0] < 1.1]
    assert ys and all(abs(y - 0.8) > 0.15 for y in ys)  # it went round the pipe, not through


def test_inspection_steered_by_the_ekf_drifts_without_an_absolute_reference():
    from sim_robot.climber.inspection import inspect_wall

    spec = WallSpec(2.0 / math.pi, 1.0, 0.1, nozzles=(Disc(1.0, 0.5, 0.2),))
    world = WallWorld(spec, patches=(Patch(0.45, 0.45, 0.2, 2.0),), seed=5)
    with pytest.raises(ValueError, match="localise"):
        inspect_wall(world, (0, 0), localise="gps")
    truth = inspect_wall(world, (0, 0), seed=5)
    ekf = inspect_wall(world, (0, 0), seed=5, localise="ekf")
    assert truth.final_error_m == 0.0 and truth.coverage == 1.0
    assert ekf.final_error_m > 0.0  # gravity slip is not observable by encoders and gyro
    assert ekf.probed <= ekf.planned
    filed = np.isfinite(ekf.filed)
    assert filed.any() and not (filed & world.blocked).any()


def test_seam_fix_pulls_the_belief_onto_the_seam_and_gates_far_ones():
    from app.core.localisation.ekf import OdometryEkf
    from sim_robot.climber.inspection import seam_fix

    def driven():
        ekf = OdometryEkf(1.0, 2.0, math.pi / 2, track_m=0.22)
        for _ in range(200):  # 10 s up the wall at 0.03 m/s: the belief grows uncertain
            ekf.predict(0.05)
            ekf.update_encoders(0.0015, 0.0015, 0.05)
        return ekf

    lead = 0.144
    girth = (Band(0.0, 2.6, 10.0, 2.6, 0.01, crossable=True),)
    ekf = driven()
    _, y0, _ = ekf.pose
    cam = y0 + lead
    assert seam_fix(ekf, girth, True, lead, 10.0)
    after = ekf.pose[1] + lead
    assert cam < after < 2.6  # towards the seam, weighted by the belief's uncertainty
    assert 2.6 - after < 0.75 * (2.6 - cam)
    far = (Band(0.0, 4.0, 10.0, 4.0, 0.01, crossable=True),)
    ekf = driven()
    before = ekf.pose
    assert not seam_fix(ekf, far, True, lead, 10.0)
    assert ekf.pose == before
    # a vertical seam seen at 80° in the image while the belief says 90° heading
    ekf = driven()
    seam_fix(
        ekf, (Band(1.0, 0.0, 1.0, 5.0, 0.01, crossable=True),), False, lead, 10.0, math.radians(10)
    )
    after = math.degrees(ekf.pose[2])
    assert 80.0 < after < 89.5  # towards the seen heading, weighted by the belief
