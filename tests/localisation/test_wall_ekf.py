"""The wall climber's EKF: gravity slip in the motion model (its Jacobian),
the accelerometer's absolute heading, and weld seams as landmarks that make
the slip observable."""

import math

import numpy as np
import pytest

from app.core.localisation.wall_ekf import (
    B_X,
    B_Y,
    G_MPS2,
    K_CREEP,
    K_DOWN,
    K_UP,
    TH,
    WallEkf,
    WallNoise,
)


class Seam:
    def __init__(self, x0, y0, x1, y1):
        self.x0_m, self.y0_m, self.x1_m, self.y1_m = x0, y0, x1, y1


@pytest.mark.parametrize("theta", [1.2, -1.4, 0.3, 2.9, -2.0])
def test_jacobian_matches_finite_differences(theta):
    ekf = WallEkf(1.0, 2.0, theta)
    st = np.array([1.0, 2.0, theta, 0.12, 0.01, 0.2, 0.04, 0.02, 0.01, 0.02, -0.01, 0.003])
    dt = 0.05
    a = ekf.jacobian(st, dt)
    f0 = ekf.motion(st, dt)
    for j in range(len(st)):
        d = np.zeros(len(st))
        d[j] = 1e-6
        col = (ekf.motion(st + d, dt) - f0) / 1e-6
        col[2] = (col[2] + math.pi / 1e-6) % (2 * math.pi / 1e-6) - math.pi / 1e-6
        assert np.allclose(a[:, j], col, atol=1e-5), j


def test_slip_moves_the_prediction_down():
    """Same wheel speed, straight up: the slip coefficients take distance off."""
    plain, slipping = WallEkf(0, 0, math.pi / 2), WallEkf(0, 0, math.pi / 2)
    slipping._x[K_UP] = 0.05
    for e in (plain, slipping):
        for _ in range(100):
            e.predict(0.05)
            e.update_body_velocity(0.1, 0.0)
    assert slipping.pose[1] == pytest.approx(0.95 * plain.pose[1], rel=0.02)
    down = WallEkf(0, 1.0, -math.pi / 2)
    down._x[K_DOWN] = 0.02
    across = WallEkf(0, 1.0, 0.0)
    across._x[K_CREEP] = 0.01
    for e in (down, across):
        for _ in range(100):
            e.predict(0.05)
            e.update_body_velocity(0.1, 0.0)
    assert 1.0 - down.pose[1] == pytest.approx(0.5 * 1.02, rel=0.02)  # overruns
    assert across.pose[1] == pytest.approx(1.0 - 0.01 * 0.5, abs=1e-3)  # creeps down


def test_gravity_heading_removes_yaw_error_and_gates_jolts():
    # believes 10° and is sure of it, truly 0°: the first headings are refused
    # as jolts, then the run of disagreement opens the belief and it follows
    ekf = WallEkf(0, 0, math.radians(10.0))
    taken = []
    for _ in range(200):
        ekf.predict(0.05)
        ekf.update_body_velocity(0.1, 0.0)
        ekf.update_imu_yaw_rate(0.0)
        taken.append(ekf.update_gravity_heading(math.radians(0.0)))
    assert not any(taken[:19]) and all(taken[19:])
    assert ekf.rejected["gravity"] == 20 and ekf.resets["gravity"] == 1  # the 20th: a reset
    assert abs(math.degrees(ekf.pose[2])) < 0.5
    before, refused = ekf.pose, ekf.rejected["gravity"]
    assert not ekf.update_gravity_heading(math.radians(40.0))  # a jolt, not a heading
    assert ekf.rejected["gravity"] == refused + 1 and ekf.pose == before
    # across ±π the innovation wraps
    ekf = WallEkf(0, 0, math.radians(179.0))
    ekf._p[2, 2] = math.radians(5.0) ** 2  # unsure: the measurement dominates
    assert ekf.update_gravity_heading(math.radians(-179.0), sigma_rad=math.radians(0.1))
    assert abs(math.degrees(ekf.pose[2]) + 179.0) < 0.1  # 2° across ±π, not 358° back


def climb(ekf, truth_y, k_true, seconds, dt=0.05, v=0.1, girths=(), lead=0.144):
    """Straight up at wheel speed v while the body slips back by k_true; the
    camera reports girth seams within 5 cm with their offset. Returns the
    body's true y and the largest |believed − true| just before each fix."""
    errors = []
    for _ in range(int(seconds / dt)):
        truth_y += v * (1 - k_true) * dt
        ekf.predict(dt)
        ekf.update_body_velocity(v, 0.0)
        ekf.update_gravity_heading(math.pi / 2)
        cam = truth_y + lead
        for g in girths:
            if abs(g.y0_m - cam) < 0.05:
                err = ekf.pose[1] - truth_y
                if ekf.seam_seen(girths, True, lead, 100.0, -math.pi / 2, g.y0_m - cam):
                    errors.append(err)
    return truth_y, errors


def test_girth_seams_make_the_climbing_slip_observable():
    """Climbing 6 m at 4 % slip with girth seams every 1.2 m: the fixes pull
    the belief back and teach the filter k_up, so the error found at each
    later seam is far smaller than at the first."""
    girths = tuple(Seam(0.0, 1.2 * k, 100.0, 1.2 * k) for k in range(1, 6))
    ekf = WallEkf(1.0, 0.0, math.pi / 2)
    y, errors = climb(ekf, 0.0, 0.04, 60.0, girths=girths)
    assert errors[0] > 0.03  # 1.2 m at 4 %: the belief is ~4.8 cm high at the first seam
    late = [abs(e) for e in errors[-20:]]
    assert max(late) < 0.3 * errors[0]
    assert 0.02 < ekf.slip[0] < 0.06  # k_up learnt near the true 0.04
    assert abs(ekf.pose[1] - y) < 0.02
    # without seams the same climb ends ~24 cm high
    blind = WallEkf(1.0, 0.0, math.pi / 2)
    y2, _ = climb(blind, 0.0, 0.04, 60.0)
    assert blind.pose[1] - y2 > 0.2


def test_seam_offset_and_gate():
    ekf = WallEkf(2.0, 1.0, math.pi / 2)
    ekf._p[0, 0] = ekf._p[1, 1] = 0.1**2  # unsure where it is
    seams = (Seam(0.0, 1.2, 10.0, 1.2), Seam(3.0, 0.0, 3.0, 2.4))
    lead = 0.144
    # the camera (at y 1.144 believed) sees the girth seam 2 cm above its centre:
    # the belief moves so that the camera sits 1.18 m high
    assert ekf.seam_seen(seams, True, lead, 10.0, 0.0, 0.02)
    assert ekf.pose[1] + lead == pytest.approx(1.18, abs=0.01)
    # the nearest vertical seam 2.5 m from the camera: beyond the 1 m gate, refused
    before = ekf.pose
    far = (Seam(4.5, 0.0, 4.5, 2.4),)
    assert not ekf.seam_seen(far, False, lead, 10.0, None, 0.0)
    assert ekf.pose == before and ekf.rejected["seam"] == 1


def test_staggered_vertical_seam_is_not_taken_for_the_next_one_round():
    """Vertical seams end at the girth seam and are staggered by half a plate
    from course to course. A camera that truly sees the lower course's seam
    5 cm to its left while the belief puts it 1 cm into the upper course must
    not snap x to the upper course's seam 0.75 m away (a fix of 1 cm σ)."""
    seams = (Seam(0.0, 0.6, 3.0, 0.6), Seam(0.0, 0.0, 0.0, 0.6), Seam(1.5, 0.0, 1.5, 0.6),
             Seam(0.75, 0.6, 0.75, 1.2), Seam(2.25, 0.6, 2.25, 1.2))
    lead = 0.144
    ekf = WallEkf(0.07, 0.61 - lead, math.pi / 2)  # camera believed at (0.07, 0.61)
    ekf._p[0, 0] = ekf._p[1, 1] = 0.01**2
    # seen 5 cm left: at x = 0.02 as believed, the seam at x = 0 (course 0) is 2 cm off
    assert ekf.seam_seen(seams, False, lead, 3.0, None, -0.05)
    assert 0.04 < ekf.pose[0] < 0.07  # pulled towards 0.05, no jump of 0.75 m
    # believed well inside the upper course: the nearest seam there is 0.75 m off,
    # far beyond the belief's σ, so the sighting is refused
    far = WallEkf(0.05, 1.0 - lead, math.pi / 2)
    before = far.pose
    assert not far.seam_seen(seams, False, lead, 3.0, None, -0.05)
    assert far.pose == before and far.rejected["seam"] == 1


def test_seam_sightings_that_keep_disagreeing_reopen_the_belief():
    """The belief is 10 cm off with a 1 cm σ: the first sightings are refused
    as another seam's, but when they keep coming the belief gives way."""
    seams = (Seam(2.0, 0.0, 2.0, 2.4),)
    lead = 0.144
    ekf = WallEkf(2.10, 1.0, math.pi / 2)
    ekf._p[0, 0] = 0.01**2
    taken = [ekf.seam_seen(seams, False, lead, 10.0, None, 0.0) for _ in range(25)]
    assert not any(taken[:19]) and taken[19]
    assert ekf.pose[0] == pytest.approx(2.0, abs=0.01)


@pytest.mark.parametrize("theta", [1.5, -1.6, 0.2, 3.0])
def test_gravity_heading_model_jacobian_matches_finite_differences(theta):
    ekf = WallEkf(0.0, 0.0, theta)
    ekf._x[B_X], ekf._x[B_Y] = 0.03, -0.02
    h0, row = ekf._gravity_model()
    for j in (TH, B_X, B_Y):
        ekf._x[j] += 1e-6
        h1, _ = ekf._gravity_model()
        ekf._x[j] -= 1e-6
        assert row[0, j] == pytest.approx((h1 - h0) / 1e-6, abs=1e-5), j


def _lanes(ekf, bias, lanes, rng, v=0.12, lane_s=40.0, dt=0.05):
    """Up and down lanes joined by 180° turns; the gyro is exact, the gravity
    heading carries the accelerometer's bias (b_x cos θ − b_y sin θ)/g.
    Returns each lane's sideways walk per metre: steering on the belief, the
    body truly heads θ − e (e = belief − truth), so it drifts by e sin θ
    across the lane per metre driven (+e climbing, −e descending)."""
    th, out = math.pi / 2, []
    for _ in range(lanes):
        for w, steps in ((0.0, int(lane_s / dt)), (0.5, int(math.pi / 0.5 / dt))):
            err = 0.0
            for _ in range(steps):
                th = (th + w * dt + math.pi) % (2 * math.pi) - math.pi
                ekf.predict(dt)
                ekf.update_imu_yaw_rate(w)
                ekf.update_body_velocity(v if w == 0.0 else 0.0, w)
                meas = th + (bias[0] * math.cos(th) - bias[1] * math.sin(th)) / G_MPS2
                ekf.update_gravity_heading(meas + math.radians(0.3) * rng.standard_normal())
                e = (ekf.pose[2] - th + math.pi) % (2 * math.pi) - math.pi
                err += e * math.sin(th)
            if w == 0.0:
                out.append(err / steps)
    return out


def test_accelerometer_bias_is_learnt_from_up_and_down_lanes():
    """A 2 mg bias along the body's y turns the gravity heading by −b_y/g
    climbing and +b_y/g descending (0.12°): the true path leans the same way
    up and down, and vertical lanes walk sideways. The gyro sees the turns
    between them, so the filter learns b_y and the heading error goes."""
    bias = (0.01, -0.02)
    ekf = WallEkf(0.0, 0.0, math.pi / 2)
    walk = _lanes(ekf, bias, 12, np.random.default_rng(3))
    # the same filter told the accelerometer has no bias
    blind = WallEkf(0.0, 0.0, math.pi / 2, wall=WallNoise(accel_bias_prior=1e-9,
                                                         accel_bias_walk=0.0))
    blind_walk = _lanes(blind, bias, 12, np.random.default_rng(3))
    face_value = abs(bias[1]) / G_MPS2  # 2 mrad: 2 cm across per 10 m lane
    assert abs(sum(blind_walk[-4:])) > 4 * 0.4 * face_value  # the same way, lane after lane
    assert abs(sum(walk[-4:])) < 0.25 * abs(sum(blind_walk[-4:]))
    assert ekf.accel_bias[1] == pytest.approx(bias[1], abs=0.008)


class Rim:
    def __init__(self, x, y, diameter):
        self.x_m, self.y_m, self.diameter_m = x, y, diameter


def test_rim_seen_pulls_the_belief_to_the_rims_centre_as_seen():
    """Climbing past a nozzle (r 0.1 m at (5, 1)) on its left: the camera,
    truly 0.15 m from its centre, sees the rim 5 cm to its left and the centre
    15 cm to its left. The belief is 3 cm too far right (σ 5 cm): the fix moves
    x back, leaves y be."""
    nozzle = Rim(5.0, 1.0, 0.2)
    lead = 0.144
    ekf = WallEkf(5.15 + 0.03, 1.0 - lead, math.pi / 2)
    ekf._p[0, 0] = ekf._p[1, 1] = 0.05**2
    # heading up, the body's left is −x: the rim point 5 cm left of the image centre
    assert ekf.rim_seen((nozzle,), lead, 75.0, 0.0, 0.05, 0.0, 0.15)
    assert ekf.pose[0] == pytest.approx(5.15, abs=0.005)
    assert ekf.pose[1] == pytest.approx(1.0 - lead, abs=0.005)
    # a rim seen where the map has none within the gate, or one of another
    # radius (the centre seen 12 cm away: r 0.07): refused, nothing moves
    before = ekf.pose
    assert not ekf.rim_seen((Rim(7.0, 1.0, 0.2),), lead, 75.0, 0.0, 0.05, 0.0, 0.15)
    assert not ekf.rim_seen((nozzle,), lead, 75.0, 0.0, 0.05, 0.0, 0.12)
    assert ekf.pose == before and ekf.rejected["rim"] == 2


MANHOLE = Rim(40.0, 0.9, 0.6)  # the tank's, at its bottom edge (r 0.3 m)
LEAD = 0.144


def _settle_on_rim(camera, theta, near, centre, off, n=40):
    """A filter whose camera truly sits at ``camera`` facing ``theta``, its
    belief ``off`` (dx, dy) from the truth (σ 2 cm each), given the same rim
    sighting ``n`` times (more than ``seam_reset_after``): its final error."""
    ax, ay = camera[0] - LEAD * math.cos(theta), camera[1] - LEAD * math.sin(theta)
    ekf = WallEkf(ax + off[0], ay + off[1], theta)
    ekf._p[0, 0] = ekf._p[1, 1] = 0.02**2
    for _ in range(n):
        ekf.rim_seen((MANHOLE,), LEAD, 75.4, *near, *centre)
    return ekf.pose[0] - ax, ekf.pose[1] - ay, ekf


def test_a_rim_fix_does_not_pull_a_belief_across_the_opening():
    """Above the manhole, facing down, the camera 5 cm above its top rim: the
    rim 5 cm ahead, the centre 35 cm ahead. A belief 0.4 m low puts the camera
    inside the opening; a range alone, ‖p − C‖ = r, was met there by the
    rim's bottom (the camera below it, looking up at it) and the filter went
    to that mirror point, 0.6 m low, and stayed. With the centre's direction
    the sighting is refused (that belief is beyond the gate), and a belief
    within the gate is brought back to the truth."""
    down = -math.pi / 2
    dx, dy, ekf = _settle_on_rim((40.0, 1.25), down, (0.05, 0.0), (0.35, 0.0), (0.0, -0.4))
    assert (dx, dy) == pytest.approx((0.0, -0.4), abs=1e-6)  # not moved to −0.6
    assert ekf.rejected["rim"] == 40 and ekf.resets["rim"] == 0
    dx, dy, ekf = _settle_on_rim((40.0, 1.25), down, (0.05, 0.0), (0.35, 0.0), (0.0, -0.2))
    assert (dx, dy) == pytest.approx((0.0, 0.0), abs=0.003)


def test_a_rim_fix_beside_the_opening_corrects_the_height_too():
    """Beside the manhole, facing down, the camera 5 cm left of its rim (rim
    5 cm and centre 35 cm to the body's left, +x). A belief 0.2 m low: a range
    alone is met by sliding round the rim (it left y 0.19 m low and moved x
    6.6 cm wrong); the centre's direction puts both right."""
    dx, dy, ekf = _settle_on_rim((39.65, 0.9), -math.pi / 2, (0.0, 0.05), (0.0, 0.35),
                                 (0.05, -0.2))
    assert (dx, dy) == pytest.approx((0.0, 0.0), abs=0.003)
    assert ekf.resets["rim"] == 1  # 20 refused, then the belief was the one at fault



def _exact_lanes(ekf, lanes, v=0.1, lane_s=60.0, w=0.5, dt=0.05, track=0.22):
    """Up and down lanes joined by in-place turns of 180°, every sensor exact:
    the wheel arcs, the gyro's rate and the gravity heading (no bias). The EKF
    is stepped with :meth:`advance`. Returns the true heading at the end."""
    th = math.pi / 2
    for _ in range(lanes):
        for rate, steps in ((0.0, int(lane_s / dt)), (w, round(math.pi / w / dt))):
            for _ in range(steps):
                th = (th + rate * dt + math.pi) % (2 * math.pi) - math.pi
                speed = v if rate == 0.0 else 0.0
                ekf.advance(dt, (speed - rate * track / 2) * dt, (speed + rate * track / 2) * dt,
                            rate)
                ekf.update_gravity_heading(th)
    return th


def test_turns_with_exact_sensors_teach_the_filter_no_accelerometer_bias():
    """Each odometry interval's own rates carry the pose over it (``advance``),
    so at the end of a turn's every step the heading is where the gravity
    heading finds it. Predicting with the interval before's rates left the
    heading Δω·dt behind at each turn's start (25 mrad at 0.5 rad/s and 20 Hz):
    the gravity headings then found an error on every turn, which the filter
    put on the accelerometer's bias (b_x −0.06 m/s², b_y −0.027 after six
    lanes, with exact sensors), and the false bias leaned every later lane."""
    ekf = WallEkf(0.0, 0.0, math.pi / 2, track_m=0.22)
    th = _exact_lanes(ekf, 6)
    assert max(abs(b) for b in ekf.accel_bias) < 1e-3  # 0.1 mg
    assert abs((ekf.pose[2] - th + math.pi) % (2 * math.pi) - math.pi) < 1e-4



def test_a_gyro_sample_held_over_lost_reports_leaves_the_turn_to_the_encoders():
    """A turn in place reversed (+0.3 → −0.3 rad/s) half-way through a report
    of four board periods: the report's gyro sample is the last period's rate,
    the encoders' ticks count the whole interval (with the turn's slip). The
    interval's rate from the previous sample and this one, with the unseen
    part's spread, keeps the heading; the last sample held over all of it
    put the heading 27 mrad off in one report."""
    from app.core.localisation.ekf import interval_rate

    track, period = 0.22, 0.05
    assert interval_rate(0.3, -0.3, period, period) == (-0.3, 0.0)  # every report
    assert interval_rate(None, -0.3, 0.2, period) == (-0.3, 0.0)
    mean, unseen = interval_rate(0.3, -0.3, 0.2, period)
    assert mean == pytest.approx((0.05 * -0.3 + 0.15 * 0.0) / 0.2)
    assert unseen == pytest.approx(0.15 * 0.6 / (0.2 * math.sqrt(12)))

    def turn(held: bool) -> float:
        ekf = WallEkf(1.0, 1.0, math.pi / 2, track_m=track)
        truth, prev = math.pi / 2, None
        rates = [0.3] * 12 + [0.3, 0.3, -0.3, -0.3] + [-0.3] * 12  # per board period
        for k in range(0, len(rates), 4):
            seen = rates[k:k + 4]
            true_turn = sum(seen) * period * 0.9  # the body turns 10 % less than the wheels
            wheels = sum(seen) * period * track / 2
            truth += true_turn
            gyro = seen[-1] * 0.9
            if held:
                rate, extra = gyro, 0.0
            else:
                rate, extra = interval_rate(prev, gyro, 4 * period, period)
            prev = gyro
            ekf.advance(4 * period, -wheels, wheels, rate, extra)
        return abs(ekf.pose[2] - truth)

    assert turn(held=True) > 0.02  # 27 mrad: half the held sample's 54, the encoders the rest
    assert turn(held=False) < 0.005


def test_the_covariance_stays_symmetric_over_many_steps():
    """The multiplied-out Joseph form is symmetric only for a symmetric P; its rounding's
    asymmetry grew tenfold every 50 000-150 000 steps through the link, and the tank's
    runs later held negative variances. Turns, drives, gravity headings and seam fixes:
    P stays exactly symmetric and positive."""
    from app.core.planner.coverage.wall import plate_seams

    rng = np.random.default_rng(5)
    ekf = WallEkf(1.0, 1.0, 0.3)
    seams = plate_seams(3.0 / np.pi, 2.4, course_m=1.2, plates=2)
    for k in range(4000):
        v, w = rng.uniform(-0.1, 0.1), rng.uniform(-0.4, 0.4) * (k % 7 < 2)
        dl, dr = (v - w * 0.11) * 0.05, (v + w * 0.11) * 0.05
        ekf.advance(0.05, dl, dr, w + rng.normal(0, 0.005), rng.uniform(0, 0.02))
        ekf.update_gravity_heading(ekf.pose[2] + rng.normal(0, 0.005))
        if k % 10 == 0:
            ekf.seam_seen(seams, bool(k % 20), 0.144, 3.0, rng.normal(0, 0.01), 0.0)
        p = ekf.covariance
        assert np.array_equal(p, p.T), k
    assert np.linalg.eigvalsh(ekf.covariance).min() > 0.0


def test_a_covariance_found_indefinite_is_mended_before_the_next_update():
    """A negative variance makes the gain negative: a fix on x would push the belief
    away from the measurement. P is checked after every step, mended to the nearest
    positive-definite matrix and counted, and the next fix pulls the belief towards it."""
    ekf = WallEkf(1.0, 1.0, 0.3)
    ekf._p[0, 0] = -1e-4  # as rounding left it, seen in the tank's runs
    ekf.advance(0.02, 0.0, 0.0, 0.0)
    assert ekf.repairs == 1
    assert np.linalg.eigvalsh(ekf.covariance).min() > 0.0
    x0 = ekf.pose[0]
    h = np.zeros((1, ekf.n))
    h[0, 0] = 1.0
    ekf.update(np.array([x0 + 0.1]), h, np.array([[0.05**2]]))
    assert 0.0 < ekf.pose[0] - x0 <= 0.1
    ekf.advance(0.02, 0.001, 0.001, 0.0)  # a proper P is left alone
    assert ekf.repairs == 1


def test_rim_models_jacobian_is_its_derivative():
    """WallEkf.rim_model's Jacobian against central differences in x, y and θ."""
    ekf = WallEkf(39.6, 1.1, -2.0)
    _, h = ekf.rim_model(40.0, 0.9, LEAD, 75.4)
    for k, step in ((0, 1e-6), (1, 1e-6), (2, 1e-7)):
        plus, minus = WallEkf(39.6, 1.1, -2.0), WallEkf(39.6, 1.1, -2.0)
        plus._x[k] += step
        minus._x[k] -= step
        hp, _ = plus.rim_model(40.0, 0.9, LEAD, 75.4)
        hm, _ = minus.rim_model(40.0, 0.9, LEAD, 75.4)
        assert h[:, k] == pytest.approx((hp - hm) / (2 * step), abs=1e-6)


def test_a_gyro_bias_is_learnt_where_the_gravity_heading_holds_the_heading():
    """Straight up a lane, the gyro reading 10 mrad/s it does not turn: the filter
    takes it for the gyro's bias, not a turn nor the accelerometer's bias."""
    ekf = WallEkf(0.0, 0.0, math.pi / 2)
    for _ in range(600):  # 30 s at 20 Hz
        ekf.advance(0.05, 0.004, 0.004, 0.01)
        ekf.update_gravity_heading(math.pi / 2)
    assert abs(ekf.pose[2] - math.pi / 2) < 3 * math.sqrt(ekf.covariance[2, 2])
    assert max(abs(b) for b in ekf.accel_bias) < 0.02
    assert abs(ekf.gyro_bias - 0.01) < 0.001


def test_the_slip_coefficients_walk_with_the_distance_driven_not_with_time():
    """With a walk per metre, Q's slip block grows by walk² per metre of the farther
    wheel's arc: nothing while the body stands, a turn in place by its arc."""
    walk = 0.003
    ekf = WallEkf(1.0, 1.0, math.pi / 2, track_m=0.22,
                  wall=WallNoise(slip_walk=0.0, slip_walk_per_m=walk))
    var = [ekf.covariance[k, k] for k in (K_UP, K_DOWN, K_CREEP)]
    for _ in range(200):  # 10 s standing
        ekf.advance(0.05, 0.0, 0.0, 0.0)
    assert [ekf.covariance[k, k] for k in (K_UP, K_DOWN, K_CREEP)] == pytest.approx(var, rel=1e-9)
    for _ in range(200):  # 0.5 m straight up
        ekf.advance(0.05, 0.0025, 0.0025, 0.0)
    for _ in range(20):  # a turn in place, each wheel 2.75 mm a step (0.025 rad)
        ekf.advance(0.05, -0.00275, 0.00275, 0.05)
    arc = 0.5 + 20 * 0.00275
    got = [ekf.covariance[k, k] for k in (K_UP, K_DOWN, K_CREEP)]
    assert got == pytest.approx([v + walk * walk * arc for v in var], rel=1e-6)
