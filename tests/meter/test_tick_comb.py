"""The dial's turn from the comb of its ticks (:mod:`app.core.meter.tick_comb`), and the
needle finder's centres kept off numerals that touch the needle."""

import math

import cv2
import numpy as np
import pytest

from app.core.meter import pointer, read_gauge
from app.core.meter.arc_fit import STEP, fit_profile_arc
from app.core.meter.needle import find_needle
from app.core.meter.tick_comb import comb_turn, tick_positions
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import DialStyle

N = int(round(360.0 / STEP))


def _ring(start: float, span: float, n_int: int, rho: float, width_deg: float = 1.0,
          extra=()) -> np.ndarray:
    """Circular evidence (one value per polar column) with ``n_int + 1`` ticks over the arc
    turned by ``rho``, and extra marks at the angles ``extra``."""
    a = np.arange(N) * STEP
    e = np.zeros(N)
    for t in [start + rho + j * span / n_int for j in range(n_int + 1)] + list(extra):
        e = np.maximum(e, np.clip(1.0 - np.abs((a - t + 180) % 360 - 180) / width_deg, 0, 1))
    return e


def test_ticks_are_found_at_their_centres_above_a_printed_arc():
    e = _ring(0.0, 90.0, 9, 0.0) * 0.6 + 0.35  # ticks over a printed arc (a raised floor)
    t = tick_positions(e, np.ones(N, bool), STEP) * STEP
    assert len(t) == 10
    assert np.allclose(np.sort(t), np.arange(0.0, 90.01, 10.0), atol=0.05)


@pytest.mark.parametrize("rho", [-7.3, 0.0, 3.3, 11.8])
def test_the_comb_gives_the_turn_to_a_fraction_of_a_degree(rho):
    start, span = -135.0 % 360.0, 270.0
    e = _ring(start, span, 50, rho)
    # the coarse turn may be several degrees out, less than half a pitch
    fit = comb_turn(e, np.ones(N, bool), STEP, start, span, rho + 2.4, 25.0)
    assert fit is not None and fit.ends == 2
    assert fit.rho_deg == pytest.approx(rho, abs=0.05)
    assert fit.pitch_deg == pytest.approx(5.4)


def test_one_hidden_end_and_a_stop_pin_do_not_move_the_turn():
    """The needle over the minimum mark, a stop pin 7 deg below it: the maximum end and
    the comb still fix the turn; the end-mark estimate alone could not."""
    start, span, rho = -120.0 % 360.0, 240.0, 2.0
    e = _ring(start, span, 40, rho, extra=[start + rho - 7.0])
    known = np.ones(N, bool)
    a_min = (start + rho) / STEP
    known[int(a_min) - 3:int(a_min) + 4] = False  # the needle's columns
    fit = comb_turn(e, known, STEP, start, span, rho - 1.5, 25.0)
    assert fit is not None and fit.ends == 1
    assert fit.rho_deg == pytest.approx(rho, abs=0.05)


def test_ticks_all_round_or_a_wrong_span_give_no_comb():
    start, span = -135.0 % 360.0, 270.0
    everywhere = _ring(0.0, 360.0, 66, 0.0)  # no gap: the scale's extent is unknown
    assert comb_turn(everywhere, np.ones(N, bool), STEP, start, span, 0.0, 25.0) is None
    dial = _ring(-130.0 % 360.0, 260.0, 52, 0.0)  # the dial's span is 10 deg short
    assert comb_turn(dial, np.ones(N, bool), STEP, start, span, 0.0, 25.0) is None


def test_arc_fit_uses_the_comb_when_the_end_marks_disagree():
    """A synthetic dial of ticks with a stop-pin dot beside the minimum: the end marks'
    estimates disagree by the pin's offset, the comb does not care."""
    size, c, r_ring = 300, (150.0, 150.0), 100.0
    dark = np.zeros((size, size), np.uint8)
    for a in list(np.arange(-135.0, 135.01, 5.4)):
        t = math.radians(a + 4.0)
        for rr in np.arange(r_ring - 8, r_ring + 0.5, 0.5):
            dark[int(round(c[1] - rr * math.cos(t))), int(round(c[0] + rr * math.sin(t)))] = 200
    t = math.radians(-135.0 + 4.0 - 7.0)
    cv2.circle(dark, (int(round(c[0] + 96 * math.sin(t))), int(round(c[1] - 96 * math.cos(t)))),
               4, 200, -1)
    fit = fit_profile_arc([(dark, 50)], c, 135.0, None, -135.0 % 360.0, 270.0)
    assert fit.rho_deg == pytest.approx(4.0, abs=0.2)
    assert fit.method == "comb" and fit.turn_err_deg < 0.2


def test_a_needle_on_its_minimum_end_mark_is_read_against_the_profile(monkeypatch):
    """The needle covers the minimum's end mark (the scale finder is made to fail): the
    comb and the maximum end mark place the scale; the reading is within its bound."""
    monkeypatch.setattr(pointer, "find_scale", lambda *a, **k: (None, "no tick marks found"))
    st = DialStyle(name="plant_0_10bar", min_angle_deg=-120.0, max_angle_deg=120.0,
                   major_step=1.0, minor_per_major=5)
    value = 0.05
    img, _ = draw_dial(st, value, 300)
    r = read_gauge(img, st.profile())
    assert r.value is not None, r.error
    assert r.method == "profile-angles"
    err = abs(r.value - value) / 10.0 * 100
    assert err <= r.error_bound_fs < 1.0


def test_a_numeral_touching_the_needle_does_not_tilt_its_line():
    """A block of print against one side of the needle over part of its length: the
    sections there are wider than the needle and are left out of its line."""
    img = np.full((300, 300), 235, np.uint8)
    c, ang = (150.0, 150.0), 93.0
    u = (math.sin(math.radians(ang)), -math.cos(math.radians(ang)))
    tip = (c[0] + 100 * u[0], c[1] + 100 * u[1])
    cv2.line(img, (int(c[0] * 16), int(c[1] * 16)), (int(tip[0] * 16), int(tip[1] * 16)), 20, 4,
             cv2.LINE_AA, 4)
    cv2.circle(img, (150, 150), 12, 20, -1, cv2.LINE_AA)
    # a numeral-sized block against the needle's lower side, 55-80 px out
    x0, x1 = int(c[0] + 55 * u[0]), int(c[0] + 80 * u[0])
    y = int(c[1] + 67 * u[1])
    cv2.rectangle(img, (x0, y + 1), (x1, y + 12), 20, -1)
    nf = find_needle(img, c, 110.0)
    assert nf.ok, nf.error
    assert abs((nf.angle_deg - ang + 180) % 360 - 180) < 0.6


def test_a_needle_resting_on_its_stop_pin_is_never_read_confidently_wrong():
    """Process gauges (counter-clockwise scales among them) with the needle on the stop
    pin below the minimum, upright and in field views: a reading, when there is one, is
    the minimum within 2 % of full scale (the scale finder's end marks near the needle are
    not trusted unless the profile's angles confirm them)."""
    from sim_robot.gauge_scene import Look, Pose, compose
    from sim_robot.gauge_styles import random_style

    rng = np.random.default_rng(93)
    styles = [s for s in (random_style("process", rng) for _ in range(40)) if s.stop_pin][:6]
    assert len(styles) == 6
    read = 0
    for st in styles:
        clean, _ = draw_dial(st, st.min_value, 300)
        field, _ = compose(st, st.min_value, rng, frame_size=(320, 320),
                           pose=Pose(fill=0.88, tilt_deg=12.0, tilt_axis_deg=40.0, roll_deg=5.0),
                           look=Look(glare=0.3, noise_sigma=3.0, jpeg_quality=80),
                           backdrop="wall")
        for img in (clean, field):
            r = read_gauge(img, st.profile())
            if r.value is not None:
                read += 1
                err = abs(r.value - st.min_value) / (st.max_value - st.min_value) * 100
                assert err <= 2.0, (st.name, r.method, r.value)
    assert read >= 3  # the minimum is read where it can be verified


def test_the_scale_paths_restored_end_ticks_beyond_the_needle_are_in_doubt():
    from types import SimpleNamespace

    from app.core.meter.scale_checks import restored_ends as _needle_on_end

    def scale(extended):  # 225 .. 135 deg clockwise, ticks 5 deg apart
        return SimpleNamespace(start_deg=225.0, end_deg=495.0, step_deg=5.0,
                               extended=extended)

    # restored ends 10-11 deg past the needle: not under it
    assert _needle_on_end(125.0, scale(2)) and _needle_on_end(236.0, scale(1))
    # restored ends under the needle (within a step), or far from it, or not restored
    assert _needle_on_end(131.0, scale(2)) is None and _needle_on_end(228.0, scale(1)) is None
    assert _needle_on_end(0.0, scale(2)) is None and _needle_on_end(180.0, scale(1)) is None
    assert _needle_on_end(125.0, scale(0)) is None


def _needle_over_min(start: float, rho: float) -> np.ndarray:
    known = np.ones(N, bool)
    a_min = (start + rho) / STEP
    known[int(a_min) - 3:int(a_min) + 4] = False  # the needle's columns
    return known


def test_a_tie_the_scales_extent_leaves_is_settled_by_the_one_verified_end():
    """The needle over the minimum mark and a mark in the gap (a stop pin, a numeral) three
    pitches below it: the comb a tooth higher scores as well as the true one (the true
    one's gap teeth meet the mark, the other's last tooth misses in the maximum's gap);
    only the true turn verifies an end (the maximum, bare beyond), so it is chosen."""
    start, span, rho = -120.0 % 360.0, 240.0, 2.0
    e = _ring(start, span, 32, rho, extra=[start + rho - 22.5])
    fit = comb_turn(e, _needle_over_min(start, rho), STEP, start, span, rho + 2.0, 25.0)
    assert fit is not None and fit.ends == 1
    assert fit.rho_deg == pytest.approx(rho, abs=0.05)


def test_a_tie_between_two_turns_that_each_verify_an_end_is_refused():
    """Both ends seen, a mark one pitch below the minimum: the true turn verifies the
    maximum, the turn a tooth lower verifies the mark as its minimum.  Nothing tells them
    apart, so there is no comb (a reading could be a tooth off)."""
    start, span, rho = -120.0 % 360.0, 240.0, 2.0
    e = _ring(start, span, 32, rho, extra=[start + rho - 7.5])
    assert comb_turn(e, np.ones(N, bool), STEP, start, span, rho + 2.0, 25.0) is None


def test_a_tie_on_a_comb_that_does_not_fit_the_ring_is_not_settled():
    """As above, but most of the arc's ticks are missing where the ring is seen (marks that
    are not the scale's ticks): the comb scores low for every turn, and one verified end
    among its candidates does not make it a scale, so there is no comb."""
    start, span, rho = -120.0 % 360.0, 240.0, 2.0
    e = _ring(start, span, 32, rho, extra=[start + rho - 22.5])
    a = np.arange(N) * STEP
    gone = ((a - (start + rho)) % 360.0 > 40.0) & ((a - (start + rho)) % 360.0 < 170.0)
    e[gone] = 0.0
    assert comb_turn(e, _needle_over_min(start, rho), STEP, start, span, rho + 2.0,
                     25.0) is None
