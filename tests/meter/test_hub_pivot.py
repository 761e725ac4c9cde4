"""The profile-angles path's try about the hub, where the scale ring's centre slid.

A ring of scale marks over a short arc fixes its circle's centre poorly along the gap's
axis: the fit can slide a few pixels along it, and both end marks then turn inward
together and miss the profile's span, although the pivot is plain to see.  The hub is a
second estimate of the pivot; about it the end marks must match the span, and across the
axis it must agree with the ring's centre."""

import math

import pytest

from app.core.meter import angles, pointer, read_gauge
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import DialStyle

_RING_CENTRE = angles.ring_centre


@pytest.fixture
def no_scale_finder(monkeypatch):
    """The dial's own scale is never found, so the reading is the profile angles'."""
    monkeypatch.setattr(pointer, "find_scale", lambda *a, **k: (None, "no tick marks found"))


def _short_dark_arc() -> DialStyle:
    """A dark face with wedge major ticks over a 129 deg arc and colour zones: its ring of
    marks' centre is found 2-4 px below the pivot, and the end marks ~1.7 deg inward."""
    return DialStyle(
        family="dark", name="dark_0_300psi", unit="psi", max_value=300.0,
        min_angle_deg=-64.429, max_angle_deg=64.429, major_step=50.0, face_kind="black",
        face_bgr=(17, 33, 41), ink_bgr=(235, 235, 235), face_radius=0.47, font=4,
        text_h=0.046, text_weight=0.006, brand="SIGMA", logo="diamond", bezel_kind="chrome",
        bezel_bgr=(160, 160, 165), scale_radius=0.401, tick_len=0.066, tick_width=0.0072,
        major_kind="wedge", zones=((121.3, 181.3, (60, 170, 60)), (181.3, 211.3, (40, 200, 235)),
                                   (211.3, 300.0, (40, 40, 210))),
        needle_bgr=(30, 200, 240), needle_len=0.376, needle_width=0.0247, tail_len=0.0167,
        hub_radius=0.0473, hub_bgr=(150, 150, 155))


def _err_fs(r, value: float) -> float:
    return abs(r.value - value) / 300.0 * 100.0


@pytest.mark.parametrize("value", [20.0, 60.0, 150.0, 190.0, 235.3])
def test_a_ring_centre_slid_along_the_gap_axis_gives_way_to_the_hub(no_scale_finder, value):
    st = _short_dark_arc()
    img, _ = draw_dial(st, value, 300)
    r = read_gauge(img, st.profile(), learned_fallback=False)
    assert r.value is not None, r.error
    assert r.method == "profile-angles"
    assert _err_fs(r, value) <= r.error_bound_fs < 1.0
    assert math.dist(r.dial_centre_xy, (150, 150)) < 1.0  # the hub, not the slid ring


def _ring_moved(monkeypatch, dx: float, dy: float) -> None:
    def moved(*a, **k):
        out = _RING_CENTRE(*a, **k)
        if out is None:
            return None
        (x, y), *rest = out
        return ((x + dx, y + dy), *rest)

    monkeypatch.setattr(angles, "ring_centre", moved)


def test_a_hub_off_the_ring_across_the_axis_does_not_replace_it(no_scale_finder,
                                                                   monkeypatch):
    """Across the gap's axis a ring's centre is firm: a hub that disagrees with it there by
    more than the centres' tolerance is no pivot, and the reading is refused."""
    st = _short_dark_arc()
    _ring_moved(monkeypatch, 4.5, 0.0)
    img, _ = draw_dial(st, 190.0, 300)
    r = read_gauge(img, st.profile(), learned_fallback=False)
    assert r.value is None
    assert "profile angles:" in r.error


def test_the_centres_disagreement_across_the_axis_widens_the_bound(no_scale_finder,
                                                                    monkeypatch):
    st = _short_dark_arc()
    img, _ = draw_dial(st, 190.0, 300)
    r0 = read_gauge(img, st.profile(), learned_fallback=False)
    _ring_moved(monkeypatch, 2.0, 0.0)
    r1 = read_gauge(img, st.profile(), learned_fallback=False)
    assert r0.value is not None, r0.error
    assert r1.value is None or r1.error_bound_fs > r0.error_bound_fs
    assert r1.value is None or _err_fs(r1, 190.0) <= r1.error_bound_fs
