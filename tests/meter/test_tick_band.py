"""The ring of ticks found by their shape (:mod:`app.core.meter.tick_band`), the comb's
end marks when they are wide or covered by a colour zone, and an end tick restored by the
scale finder only where the pointer hides it."""

import math

import cv2
import numpy as np
import pytest

from app.core.meter.arc_fit import STEP, fit_profile_arc
from app.core.meter.tick_band import short_runs, tick_rings
from app.core.meter.tick_comb import comb_turn

N = int(round(360.0 / STEP))
C = (150.0, 150.0)


def test_short_runs_drops_rails_and_keeps_ticks_across_the_wrap():
    b = np.zeros((3, N), bool)
    b[0, :] = True  # a rail all round
    b[1, 100:130] = True  # a colour zone
    b[1, [10, 11, 200]] = True  # ticks
    b[2, N - 2:] = True  # a tick across the seam of the polar image
    b[2, :2] = True
    s = short_runs(b, 15)
    assert not s[0].any() and not s[1, 100:130].any()
    assert s[1, [10, 11, 200]].all() and s[2, [N - 2, N - 1, 0, 1]].all()


def _dial(rho: float, arc: bool = True, numerals: bool = True, wide_end_deg: float = 0.0,
          zone_deg: float = 0.0) -> np.ndarray:
    """Ink (200) on 0: 41 ticks over -120..120 deg turned by ``rho``, crossing a thick
    printed arc; numerals-like strokes nearer the hub; optionally wedge-wide end marks and
    a colour zone over the first ``zone_deg`` of the scale."""
    dark = np.zeros((300, 300), np.uint8)

    def xy(a, r):
        t = math.radians(a)
        return int(round(C[0] + r * math.sin(t))), int(round(C[1] - r * math.cos(t)))

    for j in range(41):
        a = -120.0 + 6.0 * j + rho
        cv2.line(dark, xy(a, 102), xy(a, 118), 200, 1)
        if wide_end_deg and j in (0, 40):
            for d in np.arange(-wide_end_deg / 2, wide_end_deg / 2 + 0.01, 0.25):
                cv2.line(dark, xy(a + d, 102), xy(a + d, 118), 200, 1)
    if arc:
        cv2.ellipse(dark, (150, 150), (110, 110), -90.0, -120.0 + rho, 120.0 + rho, 200, 6)
    if zone_deg:
        cv2.ellipse(dark, (150, 150), (110, 110), -90.0, -120.0 + rho - 2,
                    -120.0 + rho + zone_deg, 200, 20)
    if numerals:  # many short strokes, not in phase with the ticks
        rng = np.random.default_rng(5)
        for a in rng.uniform(-125.0, 125.0, 70):
            cv2.line(dark, xy(a + rho, 80), xy(a + rho, 90), 200, 1)
    return dark


@pytest.mark.parametrize("rho", [-6.2, 0.0, 4.5])
def test_ticks_crossing_a_printed_arc_are_found_beside_numerals(rho):
    """The band most runs cross is the numerals'; the arc covers the ticks' middle: the
    ring of short radial strokes still gives the comb and the turn."""
    dark = _dial(rho)
    fit = fit_profile_arc([(dark, 50)], C, 135.0, None, 240.0, 240.0)
    assert fit.rho_deg is not None, fit.error
    assert fit.method == "comb"
    assert fit.rho_deg == pytest.approx(rho, abs=0.3)


def test_the_candidate_rings_include_the_ticks_and_the_numerals():
    dark = _dial(0.0).astype(np.float32)
    from app.core.meter.scale import polar

    pol, rs = polar(dark, C, 0.45 * 135.0, 0.97 * 135.0)
    b = pol > 50
    rings = tick_rings(b, np.zeros_like(b), STEP)
    radii = [rs[(lo + hi) // 2] for _, _, (lo, hi) in rings]
    assert any(100 <= r <= 120 for r in radii)  # the ticks (either side of the arc)


def test_a_wide_end_mark_is_verified_beyond_its_own_width():
    """End marks wider than the pitch (wedges): the bare gap is looked for beyond the
    wedge, so both ends verify the turn."""
    a = np.arange(N) * STEP
    e = np.zeros(N)
    start, span, rho = 240.0, 240.0, 1.5
    for j in range(49):
        t = start + rho + 5.0 * j
        w = 2.75 if j in (0, 48) else 0.5
        e = np.maximum(e, (np.abs((a - t + 180) % 360 - 180) <= w).astype(float))
    fit = comb_turn(e, np.ones(N, bool), STEP, start, span, rho + 1.0, 25.0)
    assert fit is not None and fit.ends == 2
    assert fit.rho_deg == pytest.approx(rho, abs=0.1)


def test_a_colour_zone_over_the_minimum_leaves_the_maximum_to_place_the_scale():
    """A colour zone covers the first ticks and the minimum mark: those columns are unseen,
    not bare, and the maximum end with the comb places the scale."""
    rho = 2.0
    dark = _dial(rho, numerals=False, zone_deg=30.0)
    fit = fit_profile_arc([(dark, 50)], C, 135.0, None, 240.0, 240.0)
    assert fit.rho_deg is not None, fit.error
    assert fit.method == "comb"
    assert fit.rho_deg == pytest.approx(rho, abs=0.3)


def _ticks_image(angles, r0=100, r1=118) -> np.ndarray:
    dark = np.zeros((300, 300), np.uint8)
    for a in angles:
        t = math.radians(a)
        p0 = (int(round(C[0] + r0 * math.sin(t))), int(round(C[1] - r0 * math.cos(t))))
        p1 = (int(round(C[0] + r1 * math.sin(t))), int(round(C[1] - r1 * math.cos(t))))
        cv2.line(dark, p0, p1, 200, 2)
    return dark


def test_an_end_tick_is_restored_only_under_the_pointer():
    """A scale of 21 ticks over 180 deg whose last tick is lost (a colour zone over it):
    with the pointer two ticks inside the minimum, restoring a tick below the minimum
    would shift the scale by a tick (a confident reading 5 % FS off); it is refused.  With
    the pointer on the lost tick itself, that end is restored."""
    from app.core.meter.scale import find_scale

    ticks = [-90.0 + 9.0 * j for j in range(21)]
    dark = _ticks_image(ticks[:-1])
    fit, why = find_scale(dark, 50, C, 135.0, None, -90.0 + 18.0, 180.0)
    assert fit is None and "hidden" in why
    fit, why = find_scale(dark, 50, C, 135.0, None, 90.0, 180.0)
    assert fit is not None, why
    assert fit.extended == 1
    assert fit.start_deg % 360.0 == pytest.approx(270.0, abs=0.3)
    assert fit.end_deg - fit.start_deg == pytest.approx(180.0, abs=0.5)


def test_a_short_arc_of_strokes_does_not_move_the_scale_ring_centre():
    """Ticks all round a 240 deg scale about (150, 150), and a 30 deg patch of short strokes
    on a circle about another centre (a zone's ragged edge, a word): the ring's centre
    stays the scale's, not the tightly fitting short arc's."""
    from app.core.meter.ring_centre import ring_centre

    dark = _dial(0.0, arc=False, numerals=False)
    for a in np.arange(20.0, 50.0, 1.0):  # strokes on a circle of radius 90 about (162, 150)
        t = math.radians(a)
        x, y = 162 + 90 * math.sin(t), 150 - 90 * math.cos(t)
        cv2.line(dark, (int(round(x)), int(round(y))),
                 (int(round(x + 4 * math.sin(t))), int(round(y - 4 * math.cos(t)))), 200, 1)
    c, rms = ring_centre(dark, 50, C, 135.0, None)
    assert math.hypot(c[0] - 150.0, c[1] - 150.0) < 1.0


def test_strokes_running_through_their_ring_do_not_confirm_a_wrong_start():
    """Ticks crossing a printed arc about (150, 150), the fit started 4.5 px off (a
    counterweight taken for the hub): a ring of strokes whose ends are its own rows would
    fit a circle about the start exactly; it is not used, and the centre moves back to
    the scale's."""
    from app.core.meter.ring_centre import ring_centre

    dark = np.zeros((300, 300), np.uint8)
    for j in range(41):
        a = math.radians(-120.0 + 6.0 * j)
        cv2.line(dark, (int(round(150 + 100 * math.sin(a))), int(round(150 - 100 * math.cos(a)))),
                 (int(round(150 + 112 * math.sin(a))), int(round(150 - 112 * math.cos(a)))),
                 200, 1)
    cv2.ellipse(dark, (150, 150), (106, 106), -90.0, -120.0, 120.0, 200, 4)
    c, _ = ring_centre(dark, 50, (154.0, 152.0), 135.0, None)
    assert math.hypot(c[0] - 150.0, c[1] - 150.0) < 2.0


def test_a_comb_whose_teeth_mostly_meet_nothing_is_no_comb():
    """Twelve marks that happen to sit on teeth of a 50-interval comb (noise, dots) with
    both end teeth among them: the comb holds them in phase, but most of its teeth where
    the ring is seen meet no tick, so it does not place the scale."""
    a = np.arange(N) * STEP
    e = np.zeros(N)
    start, span = 225.0, 270.0
    for j in (0, 3, 4, 11, 17, 18, 26, 31, 37, 42, 44, 50):
        t = start + j * span / 50
        e = np.maximum(e, (np.abs((a - t + 180) % 360 - 180) <= 0.5).astype(float))
    assert comb_turn(e, np.ones(N, bool), STEP, start, span, 0.5, 25.0) is None
