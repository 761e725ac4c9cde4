"""An end mark found coarsely by the keypoint network, moved onto its printed tick only
where the tick is unambiguous; the learned fallback reads gauges whose end marks alone
were too uncertain before."""

import math

import cv2
import numpy as np

from app.core.meter import keypoints, load_profile
from app.core.meter.keypoints import read_keypoints
from app.core.meter.mark_snap import snap_end_mark
from app.core.meter.needle import angle_cw
from bench.meter_rows import ROW_IDS
from sim_robot.gauge_scene import LEVELS, render_sample
from sim_robot.gauge_styles import TUNING_FAMILIES

PIVOT = (150.0, 150.0)
R_TICK = 100.0  # the ticks' middle radius


def _at(deg: float, r: float = R_TICK) -> tuple[float, float]:
    t = math.radians(deg)
    return PIVOT[0] + r * math.sin(t), PIVOT[1] - r * math.cos(t)


def _dial(tick_degs, face=235, ink=30, width=2) -> np.ndarray:
    """A light face with dark radial ticks (8 px long, about R_TICK) at ``tick_degs``."""
    img = np.full((300, 300), face, np.uint8)
    sh = 4  # sub-pixel drawing
    for a in tick_degs:
        p, q = _at(a, R_TICK - 4.0), _at(a, R_TICK + 4.0)
        cv2.line(img, (round(p[0] * 16), round(p[1] * 16)), (round(q[0] * 16), round(q[1] * 16)),
                 ink, width, cv2.LINE_AA, sh)
    return cv2.GaussianBlur(img, (0, 0), 0.7)


def _arc_px(p, deg: float) -> float:
    """How far ``p`` lies along the arc (px at R_TICK) from the angle ``deg``."""
    a = angle_cw(p[0] - PIVOT[0], p[1] - PIVOT[1])
    return math.radians((a - deg + 180.0) % 360.0 - 180.0) * R_TICK


# a clockwise scale from 225 deg (min) to 135 deg (max), a tick every 5 deg
SCALE = [225.0 + 5.0 * k for k in range(55)]


def test_a_mark_a_few_pixels_off_moves_onto_its_end_tick():
    img = _dial(SCALE)
    end = SCALE[-1] % 360.0  # the maximum mark, 135 deg
    guess = _at(end + math.degrees(2.5 / R_TICK))  # 2.5 px along the arc off
    got = snap_end_mark(img, PIVOT, guess, 2.0, +1.0)
    assert got is not None
    (pt, sigma) = got
    assert abs(_arc_px(pt, end)) < 0.3
    assert sigma < 1.0
    # the minimum mark, outward anticlockwise
    guess = _at(225.0 - math.degrees(2.0 / R_TICK))
    pt, _ = snap_end_mark(img, PIVOT, guess, 2.0, -1.0)
    assert abs(_arc_px(pt, 225.0)) < 0.3


def test_no_move_where_the_comb_goes_on_beyond_the_region():
    """A guess on an inner tick with the true end a tick further out: the end is not in the
    network's uncertainty region, and the tick beyond it says the guess's tick is no end."""
    img = _dial(SCALE)
    inner = SCALE[-2] % 360.0  # a tick before the end (the end is 5 deg = 8.7 px further)
    assert snap_end_mark(img, PIVOT, _at(inner), 1.5, +1.0) is None


def test_no_move_where_no_tick_agrees_with_the_network():
    img = _dial(SCALE)
    far = SCALE[-1] % 360.0 + math.degrees(10.0 / R_TICK)  # 10 px beyond the end
    assert snap_end_mark(img, PIVOT, _at(far), 2.0, +1.0) is None


def test_no_move_where_the_needle_may_lie_over_the_end():
    """A needle resting at the stop pin beside the end looks like one more tick: a strip
    the needle may lie in is not searched."""
    img = _dial(SCALE)
    end = SCALE[-1] % 360.0
    guess = _at(end)
    assert snap_end_mark(img, PIVOT, guess, 2.0, +1.0) is not None
    assert snap_end_mark(img, PIVOT, guess, 2.0, +1.0, needle_deg=(end + 2.0,),
                         needle_doubt_deg=3.0) is None
    # a two-ended needle's tail there too
    assert snap_end_mark(img, PIVOT, guess, 2.0, +1.0, needle_deg=(end - 178.0, end + 2.0),
                         needle_doubt_deg=3.0) is None


def test_light_ticks_on_a_dark_face():
    img = _dial(SCALE, face=25, ink=220)
    end = SCALE[-1] % 360.0
    pt, _ = snap_end_mark(img, PIVOT, _at(end - math.degrees(2.0 / R_TICK)), 2.0, +1.0)
    assert abs(_arc_px(pt, end)) < 0.3


def test_no_move_onto_a_tick_at_the_edge_of_a_filled_band():
    """An end tick joined to a filled band along the arc (as a "rail" scale fills every
    other interval) cannot be told from the band's edge: it is not trusted."""
    img = _dial(SCALE)
    end = SCALE[-1] % 360.0
    assert snap_end_mark(img, PIVOT, _at(end), 2.0, +1.0) is not None
    # a band under the ticks' inner half, from 20 deg before the end up to the end tick
    for a in np.arange(end - 20.0, end, 0.05):
        for r in np.arange(R_TICK - 4.0, R_TICK, 0.5):
            p = _at(float(a), float(r))
            img[round(p[1]), round(p[0])] = 30
    assert snap_end_mark(img, PIVOT, _at(end), 2.0, +1.0) is None


def test_no_move_onto_the_end_of_a_band_with_no_tick():
    """A filled band that simply ends (no tick across the ring there) has no point on it
    that is the end mark."""
    img = np.full((300, 300), 235, np.uint8)
    end = 135.0
    _arc(img, 225.0, end, R_TICK - 5.0, R_TICK + 5.0)
    assert snap_end_mark(img, PIVOT, _at(end), 2.0, +1.0) is None


def _arc(img, a0: float, a1: float, r_in: float, r_out: float, ink: int = 30) -> None:
    """A filled band between radii ``r_in`` and ``r_out``, clockwise from ``a0`` to ``a1``
    (deg, clockwise from up), drawn anti-aliased."""
    c = (round(PIVOT[0] * 16), round(PIVOT[1] * 16))
    r_mid, half = 0.5 * (r_in + r_out), 0.5 * (r_out - r_in)
    start = a0 - 90.0
    stop = a1 - 90.0 + (360.0 if a1 <= a0 else 0.0)
    ax = round(r_mid * 16)
    cv2.ellipse(img, c, (ax, ax), 0.0, start, stop, ink, max(1, round(2 * half)),
                cv2.LINE_AA, 4)


def _disc(img, deg: float, radius: float, ink: int = 30, thickness: int = -1) -> None:
    p = _at(deg)
    cv2.circle(img, (round(p[0] * 16), round(p[1] * 16)), round(radius * 16), ink, thickness,
               cv2.LINE_AA, 4)


def test_an_end_tick_joined_by_the_scale_arc_moves_onto_the_tick():
    """The common print of a real dial: the scale's arc line (3 px) runs through the ticks
    and stops at the end tick.  The arc's rows are not bare beside the tick, so the tick is
    placed from the rows either side of the arc where it stands alone."""
    img = _dial(SCALE)
    _arc(img, 225.0, 135.0, R_TICK - 1.5, R_TICK + 1.5)
    end = SCALE[-1] % 360.0
    pt, sigma = snap_end_mark(img, PIVOT, _at(end + math.degrees(2.5 / R_TICK)), 2.0, +1.0)
    assert abs(_arc_px(pt, end)) < 0.3 and sigma < 1.0
    pt, _ = snap_end_mark(img, PIVOT, _at(225.0 - math.degrees(2.0 / R_TICK)), 2.0, -1.0)
    assert abs(_arc_px(pt, 225.0)) < 0.3


def test_a_dot_on_the_scale_arc_as_end_mark():
    """End marks drawn as dots, the arc line through them: each moves onto its dot's centre
    with a quarter of its width as the error scale; on a dark face too."""
    for face, ink in ((235, 30), (25, 220)):
        img = np.full((300, 300), face, np.uint8)
        _arc(img, 225.0, 135.0, R_TICK - 0.75, R_TICK + 0.75, ink)
        for a in (225.0, 135.0):
            _disc(img, a, 3.0, ink)
        img = cv2.GaussianBlur(img, (0, 0), 0.7)
        pt, sigma = snap_end_mark(img, PIVOT, _at(135.0 - math.degrees(2.0 / R_TICK)), 2.0,
                                  +1.0)
        assert abs(_arc_px(pt, 135.0)) < 0.3 and 1.0 < sigma < 2.0
        pt, _ = snap_end_mark(img, PIVOT, _at(225.0 + math.degrees(1.5 / R_TICK)), 2.0, -1.0)
        assert abs(_arc_px(pt, 225.0)) < 0.3


def test_no_move_onto_a_ring_a_wedge_or_a_dot_with_print_beyond_it():
    """A ring drawn as the end mark, at the end of a filled band: the rows through its hole
    show only its outer wall, a short straight run that is not the ring's centre.  A wedge
    (a triangle whose width grows along the ring) is no mark symmetric about a radial line.
    A dot with print further out (a numeral, the scale going on) is no end."""
    for band in (False, True):
        img = np.full((300, 300), 235, np.uint8)
        if band:
            _arc(img, 225.0, 135.0, R_TICK - 5.0, R_TICK + 5.0)
        _disc(img, 135.0, 4.0, ink=235)
        _disc(img, 135.0, 4.5, thickness=2)
        img = cv2.GaussianBlur(img, (0, 0), 0.7)
        assert snap_end_mark(img, PIVOT, _at(135.0), 2.0, +1.0) is None
    img = np.full((300, 300), 235, np.uint8)
    tri = [_at(135.0, R_TICK - 6.0), _at(135.0, R_TICK + 6.0),
           _at(135.0 - math.degrees(7.0 / R_TICK), R_TICK + 6.0)]
    cv2.fillPoly(img, [np.round(np.array(tri) * 16).astype(np.int32)], 30, cv2.LINE_AA, 4)
    assert snap_end_mark(img, PIVOT, _at(135.0), 2.0, +1.0) is None
    img = np.full((300, 300), 235, np.uint8)
    _disc(img, 135.0, 3.0)
    assert snap_end_mark(img, PIVOT, _at(135.0), 2.0, +1.0) is not None
    _disc(img, 135.0 + math.degrees(9.0 / R_TICK), 2.5)  # 9 px further out, in the gap
    assert snap_end_mark(img, PIVOT, _at(135.0), 2.0, +1.0) is None


def _along(p, true, piv) -> float:
    """How far ``p`` lies from ``true`` along the arc about ``piv`` (px at ``true``)."""
    a = angle_cw(p[0] - piv[0], p[1] - piv[1])
    b = angle_cw(true[0] - piv[0], true[1] - piv[1])
    return abs(math.radians((a - b + 180.0) % 360.0 - 180.0)) * math.dist(piv, true)


def test_snapped_marks_lie_nearer_the_truth_on_generated_gauges(monkeypatch):
    """On generated field and hard gauges of the tuning families, every mark moved onto a
    tick from a network mark within three of its error scales of the true mark lies within
    three of its new error scales of it (along the arc), and nearer it than the network's
    mark on the whole.  (A network mark far off, on another dial's print, can be moved onto
    a tick there: the later checks are what refuse such a box.)"""
    seen = []
    snap = keypoints._snap_marks

    def spy(gray, kp, sig, prof):
        before, sig0 = kp.points.copy(), sig.copy()
        n = snap(gray, kp, sig, prof)
        seen.append((before, kp.points.copy(), sig0, sig.copy(), n))
        return n

    monkeypatch.setattr(keypoints, "_snap_marks", spy)
    rng = np.random.default_rng([4, 9])
    moved = []
    for i in range(12):
        img, truth = render_sample(TUNING_FAMILIES[i % 4], ("field", "hard")[i % 2], rng)
        seen.clear()
        read_keypoints(img, load_profile(truth["profile"]))
        for before, after, sig0, sig, _n in seen:
            piv = truth["pivot_xy"]
            for j, key in ((2, "min_mark_xy"), (3, "max_mark_xy")):
                if np.array_equal(before[j], after[j]):
                    continue
                true = truth[key]
                if math.dist(before[j], true) > 3.0 * sig0[j]:
                    continue  # the network's mark is not where it says (see above)
                moved.append((_along(before[j], true, piv), _along(after[j], true, piv),
                              float(sig[j])))
    assert len(moved) >= 4, moved
    assert all(e1 <= 3.0 * s + 0.5 for _e0, e1, s in moved), \
        [m for m in moved if m[1] > 3.0 * m[2] + 0.5]
    assert np.mean([e1 for _e0, e1, _s in moved]) < np.mean([e0 for e0, _e1, _s in moved])


def test_reads_a_gauge_whose_network_marks_alone_were_too_uncertain():
    """A hard tuning gauge (seed 1, the bench's tuning stream) that the learned fallback
    refused with "marks_sure" before its end marks were moved onto their ticks: now read,
    within 2 % of full scale."""
    rng = np.random.default_rng([1, ROW_IDS["tuning"], LEVELS.index("hard")])
    for i in range(10):
        img, truth = render_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], "hard", rng)
    r = read_keypoints(img, load_profile(truth["profile"]))
    assert r.value is not None, r.error
    assert abs(r.value - truth["value"]) / truth["full_scale"] * 100 < 2.0
    assert r.scores.get("marks_on_ticks", 0) >= 1


def test_the_turn_from_the_chord_of_two_marks_on_their_ticks_ignores_the_pivot():
    """Two end marks symmetric about the bisector: the chord's normal is the bisector
    wherever the pivot is, and its error scale comes from the marks' alone."""
    for span, mid in ((180.0, 30.0), (270.0, 0.0), (120.0, 200.0)):
        pmin, pmax = _at(mid - span / 2.0), _at(mid + span / 2.0)
        for near in (mid - 20.0, mid + 20.0):  # a bisector about a pivot some px off
            got = keypoints._chord_bisector(pmin, pmax, near)
            assert abs((got - mid + 180.0) % 360.0 - 180.0) < 1e-6
    sig = np.array([3.0, 3.0, 0.5, 0.5])  # the pivot's error scale plays no part
    chord = 2.0 * R_TICK
    assert keypoints._chord_sigma(_at(270.0), _at(90.0), sig) == \
        math.degrees(math.hypot(0.5, 0.5) / chord)


def test_reads_gauges_whose_end_marks_are_dots_or_diamonds():
    """Two tuning gauges (seed 2, the bench's tuning stream) that the learned fallback
    refused with "marks_sure" while their end marks (diamonds on a marine dial, dots on a
    colour dial's arc) could not be moved onto a lone radial tick: both marks now placed
    on their print, and the readings within 2 % of full scale."""
    from tests.meter.stored_frames import stored

    for level, index in (("clean", 5), ("field", 30)):
        if level == "field":  # deep in the stream: stored (tests/meter/stored_frames.py)
            img, truth = stored("tuning-field-2-30")
        else:
            rng = np.random.default_rng([2, ROW_IDS["tuning"], LEVELS.index(level)])
            for i in range(index + 1):
                img, truth = render_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], level,
                                           rng)
        r = read_keypoints(img, load_profile(truth["profile"]))
        assert r.value is not None, r.error
        assert abs(r.value - truth["value"]) / truth["full_scale"] * 100 < 2.0
        assert r.scores.get("marks_on_ticks", 0) == 2
