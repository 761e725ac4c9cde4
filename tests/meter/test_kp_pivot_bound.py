"""The learned fallback's error bound counts the pivot's error as it turns the end marks'
bisector: by |cos(span / 2)| across the bisector, so not at all on a 180 deg scale, where
the pivot and both marks lie on one line; where the dial's rim was not seen (its tilt
unmeasured) the pivot still counts in each mark's angle as before."""

import math

import numpy as np
import pytest

from app.core.meter import keypoints
from app.core.meter.keypoints import _bisector, _turn_sigma, read_keypoints
from app.core.meter.needle import angle_cw
from app.core.meter.oblique import Rectifier, find_rectifier
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import DialStyle

R = 100.0


def _marks(span: float, mid: float):
    """The two end marks on a ring of radius R about the origin, either side of ``mid``."""
    out = []
    for a in (mid - span / 2.0, mid + span / 2.0):
        t = math.radians(a)
        out.append((R * math.sin(t), -R * math.cos(t)))
    return out


def _bisector_about(p, marks) -> float:
    (x0, y0), (x1, y1) = marks
    return _bisector(angle_cw(x0 - p[0], y0 - p[1]), angle_cw(x1 - p[0], y1 - p[1]), True)


@pytest.mark.parametrize("span", [90.0, 120.0, 180.0, 240.0, 270.0, 300.0])
@pytest.mark.parametrize("mid", [0.0, 35.0, 200.0])
def test_pivot_term_is_how_far_a_moved_pivot_turns_the_bisector(span, mid):
    marks = _marks(span, mid)
    base = _bisector_about((0.0, 0.0), marks)
    sig_p = 1.5
    t = math.radians(mid)
    across = (sig_p * math.cos(t), sig_p * math.sin(t))  # the ring's tangent at the bisector
    along = (sig_p * math.sin(t), -sig_p * math.cos(t))
    turned = abs((_bisector_about(across, marks) - base + 180.0) % 360.0 - 180.0)
    slid = abs((_bisector_about(along, marks) - base + 180.0) % 360.0 - 180.0)
    sig = np.array([sig_p, 0.0, 0.0, 0.0])  # the pivot's error alone
    want = _turn_sigma(sig, R, R, span)
    assert turned == pytest.approx(want, rel=0.03, abs=1e-3)
    assert slid < 0.02 * math.degrees(sig_p / R)  # second order only
    # without the rim the pivot counts in each mark as if apart, at every span
    assert _turn_sigma(sig, R, R, None) == pytest.approx(
        math.degrees(math.sqrt(2.0) * sig_p / R) / 2.0)


def test_a_180_degree_scale_is_turned_by_a_moved_pivot_at_second_order_only():
    """Along or across the marks' line not at all; else by (d / R)^2 at most, where the
    270 deg scale turns by d / R (first order)."""
    marks = _marks(180.0, 20.0)
    base = _bisector_about((0.0, 0.0), marks)
    t = math.radians(20.0)
    line, normal = (math.cos(t), math.sin(t)), (math.sin(t), -math.cos(t))
    for k in (3.0, 9.0):
        for d in (line, normal):
            p = (k * d[0], k * d[1])
            assert abs((_bisector_about(p, marks) - base + 180.0) % 360.0 - 180.0) < 1e-9
        for p in [(k, 0.0), (0.0, -k), (-0.7 * k, 0.7 * k)]:
            turn = abs((_bisector_about(p, marks) - base + 180.0) % 360.0 - 180.0)
            assert turn <= math.degrees((math.hypot(*p) / R) ** 2)
            wide = _marks(270.0, 20.0)
            w = abs((_bisector_about(p, wide) - _bisector_about((0.0, 0.0), wide) + 180.0)
                    % 360.0 - 180.0)
            assert w > 5.0 * turn


def test_marks_errors_count_as_before():
    sig = np.array([0.0, 0.0, 2.0, 1.0])
    want = math.degrees(math.hypot(2.0 / 80.0, 1.0 / 120.0) / 2.0)
    for span in (180.0, 270.0, None):
        assert _turn_sigma(sig, 80.0, 120.0, span) == pytest.approx(want)


def _dial(span: float, value: float = 6.0):
    st = DialStyle(min_angle_deg=-span / 2, max_angle_deg=span / 2)
    img, _ = draw_dial(st, value, 300)
    return img, st


def _wider_pivot(monkeypatch, k: float):
    """The network's pivot k times less sure (its error scale only)."""
    combine = keypoints._combine

    def wider(a, b):
        kp, sig = combine(a, b)
        sig = sig.copy()
        sig[0] *= k
        return kp, sig

    monkeypatch.setattr(keypoints, "_combine", wider)


def test_pivot_doubt_leaves_a_180_degree_reading_and_bound_alone(monkeypatch):
    """On a head-on 180 deg dial (its rim seen round) a pivot three times less sure gives
    the same value and the same bound; on a 270 deg dial it widens the bound; with the rim
    not seen, it widens the 180 deg dial's bound too.  The end marks are left where the
    network put them: on their ticks, the turn would be the normal of the chord between
    them, which no pivot moves."""
    monkeypatch.setattr(keypoints, "_snap_marks", lambda *a: 0)
    img, st = _dial(180.0)
    assert find_rectifier(np.asarray(img[..., 1]), (150.0, 150.0), 100.0).rim_seen
    ok = read_keypoints(img, st.profile())
    assert ok.value is not None, ok.error
    assert abs(ok.value - 6.0) < 0.2
    with monkeypatch.context() as m:
        _wider_pivot(m, 3.0)
        same = read_keypoints(img, st.profile())
        assert same.value == pytest.approx(ok.value)
        assert same.error_bound_fs == pytest.approx(ok.error_bound_fs)
    img270, st270 = _dial(270.0)
    ok270 = read_keypoints(img270, st270.profile())
    assert ok270.value is not None, ok270.error
    with monkeypatch.context() as m:
        _wider_pivot(m, 3.0)
        wide270 = read_keypoints(img270, st270.profile())
        assert wide270.value is None or wide270.error_bound_fs > 1.2 * ok270.error_bound_fs
    with monkeypatch.context() as m:
        m.setattr(keypoints, "find_rectifier", lambda *a: Rectifier())  # no rim seen
        plain = read_keypoints(img, st.profile())
        assert plain.value is not None, plain.error
        assert plain.error_bound_fs >= ok.error_bound_fs
        _wider_pivot(m, 3.0)
        unseen = read_keypoints(img, st.profile())
        assert unseen.value is None or unseen.error_bound_fs > 1.2 * plain.error_bound_fs


def test_the_chord_gives_the_turn_only_on_a_rim_seen_round(monkeypatch):
    """With both end marks on their ticks, a head-on dial (its rim found round) takes its
    turn from the chord between them; where no rim was found the view may be tilted, and
    the turn stays the marks' bisector about the pivot."""
    img, st = _dial(270.0)
    seen = read_keypoints(img, st.profile())
    assert seen.value is not None, seen.error
    assert seen.scores.get("marks_on_ticks") == 2.0 and seen.scores.get("turn_from_chord")
    monkeypatch.setattr(keypoints, "find_rectifier", lambda *a: Rectifier())  # no rim seen
    unseen = read_keypoints(img, st.profile())
    assert unseen.value is not None, unseen.error
    assert "turn_from_chord" not in unseen.scores
    assert abs(unseen.value - 6.0) < 0.2
