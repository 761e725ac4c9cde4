"""The pivot on the needle's line from which the scale's end marks lie the profile's span
apart (:mod:`app.core.meter.span_pivot`): where the ring of marks fixes no centre, the
angles path unwraps the dial about a point a few pixels off the pivot, and both end marks
then miss the profile's span.  An `atlas` field crop of bench/meter_why.py's draw (seed 2,
#33, a 100 deg scale) was refused so ("the scale's end marks lie +2.1 deg off the
profile's span"), its candidate 0.49 % FS off."""

import math

import numpy as np

import app.core.meter.learned as learned
from app.core.meter import load_profile, read_gauge
from app.core.meter.learned_checks import learned_ends_agree
from app.core.meter.span_pivot import pivot_doubt_px, span_pivot
from sim_robot.gauge_scene import render_sample
from tests.meter.stored_frames import fs_off, spy_angles, stored


def _angle(c, p) -> float:
    return math.degrees(math.atan2(p[0] - c[0], -(p[1] - c[1])))


def _on_ring(c, a_deg, r):
    a = math.radians(a_deg)
    return (c[0] + r * math.sin(a), c[1] - r * math.cos(a))


def _seen_from(c, pivot, span, turn, r):
    """The two end marks of a ``span`` deg scale about ``pivot`` (its middle at ``turn``
    deg), seen from ``c``: their angles and mean radius."""
    m_lo = _on_ring(pivot, turn - span / 2.0, r)
    m_hi = _on_ring(pivot, turn + span / 2.0, r)
    radius = 0.5 * (math.dist(c, m_lo) + math.dist(c, m_hi))
    return _angle(c, m_lo), _angle(c, m_hi), radius


def _line_point(c, pivot, needle_deg):
    """The point of the needle's line (through ``pivot``) nearest ``c``."""
    ux, uy = math.sin(math.radians(needle_deg)), -math.cos(math.radians(needle_deg))
    t = (c[0] - pivot[0]) * ux + (c[1] - pivot[1]) * uy
    return (pivot[0] + t * ux, pivot[1] + t * uy)


def test_the_pivot_is_found_on_the_needles_line_where_the_ends_span_the_arc():
    # a 110 deg scale about (150, 146) seen from 4 px below it (along the gap's axis) and
    # 1.5 px aside: the end marks miss the span by degrees there
    pivot, c, span, turn, needle = (150.0, 146.0), (151.5, 150.0), 110.0, 8.0, 35.0
    a_lo, a_hi, radius = _seen_from(c, pivot, span, turn, 100.0)
    assert abs(((a_hi - a_lo) % 360.0) - span) > 3.0
    q = _line_point(c, pivot, needle)
    p = span_pivot(c, a_lo, a_hi, radius, span, q, needle)
    assert p is not None and math.dist(p, pivot) < 0.3
    # an end mark a polar column off moves it by a fraction of a pixel, which the bound
    # carries
    assert 0.0 < pivot_doubt_px(c, a_lo, a_hi, radius, span, q, needle, p, 0.5) < 1.0


def test_no_pivot_where_the_line_meets_none_near():
    # end marks 40 deg short of the span: no point within the search along the line
    pivot, c, needle = (150.0, 146.0), (150.0, 150.0), 20.0
    a_lo, a_hi, radius = _seen_from(c, pivot, 70.0, 0.0, 100.0)
    assert span_pivot(c, a_lo, a_hi, radius, 110.0, _line_point(c, pivot, needle),
                      needle) is None


def test_the_learned_end_marks_confirm_each_end_within_the_tolerance():
    c = (150.0, 150.0)
    kp = {"min_mark": _on_ring(c, -50.0, 100.0), "max_mark": _on_ring(c, 50.0, 100.0)}
    assert learned_ends_agree(kp, c, -51.0, 51.5, 2.5)
    assert not learned_ends_agree(kp, c, -51.0, 55.0, 2.5)  # one end a tick off
    assert not learned_ends_agree(None, c, -50.0, 50.0, 2.5)


def test_a_crop_whose_ring_fixes_no_centre_is_read_about_the_pivot_on_the_needle(
        monkeypatch):
    seen = spy_angles(monkeypatch)
    img, truth = stored("atlas-field-2-33")
    r = read_gauge(img, load_profile(truth["profile"]))
    assert r.value is not None and r.method == "profile-angles"
    # first read about the pivot on the needle's line, moved off the ring's centre (which
    # stayed where its fit started) by px, both end marks found again about it ...
    first = seen[0]
    assert "span_pivot_px" in first and first["arc"].ends == 2
    assert math.dist(first["centre"], first["ring_centre"]) > 1.0
    # ... then, the view being oblique, read again with the perspective removed about that
    # pivot, where the ring of marks is centred on it
    last = seen[-1]
    assert "span_pivot_px" not in last and "frac" in last
    assert fs_off(r, truth) <= r.error_bound_fs < 0.625


def test_the_second_look_is_made_about_the_pivot_on_the_needle(monkeypatch):
    # a `colour` field view whose crop was rectified about the ring's centre, where its end
    # marks miss the span: the second look, once skipped as the same warp again
    # (test_same_warp.py), is made about the pivot on the needle's line and reads there.
    # (With the learned keypoints asked after the classical retries; asked first, as by
    # default, they read this view themselves.)
    monkeypatch.setattr(learned, "LEARNED_BEFORE_RETRIES", False)
    img, truth = render_sample("colour", "field", np.random.default_rng(20))
    r = read_gauge(img, load_profile(truth["profile"]))
    assert r.value is not None and r.method == "profile-angles"
    assert fs_off(r, truth) <= r.error_bound_fs < 0.625


def test_an_unlooked_reading_about_the_moved_pivot_confirms_no_scale(monkeypatch):
    # the 38th hard frame of bench/meter_bench.py's stock row (seed 1), an oblique view: the
    # scale path's reading is in doubt and asks the profile's angles to confirm it; they
    # read about the pivot on the needle's line, 1.4 % FS off against a stated 0.44, with
    # the perspective left about it.  Unlooked at, that reading neither confirms the scale
    # path's nor stands in for it
    from bench import meter_rows
    from bench.meter_bench import GOALS, make_case

    seen = spy_angles(monkeypatch)
    rng = np.random.default_rng(1000 + list(GOALS).index("hard"))
    for _ in range(38):
        spec, value, img = make_case("hard", rng)
    prof = load_profile(spec.profile())
    r = read_gauge(img, prof, **meter_rows.READ_KW)
    moved = [o for o in seen if "span_pivot_px" in o]
    assert moved and abs(prof.value_at_fraction(moved[0]["frac"]) - value) \
        / prof.full_scale * 100 > 2.0 * moved[0]["bound_fs"]
    assert r.method != "scale"
    assert r.value is None or abs(r.value - value) / prof.full_scale * 100 <= 0.5
