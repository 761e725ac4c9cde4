"""Reading against the profile's angles (no clicks), a needle found more than 5 deg below the
scale's minimum: resting on its stop pin in the scale's gap it reads the minimum, out to the
pin tolerance of :mod:`app.core.meter.stop_pin`, but only where the ring of scale marks is
bare round it (:func:`app.core.meter.stop_pin.gap_is_bare`); a needle among ticks below a
misplaced minimum (the scale found turned towards its maximum) is refused.  Dials of the
tuning families rendered upright, and the gap test on drawn evidence."""

from dataclasses import replace

import numpy as np
import pytest

from app.core.meter import angles, load_profile, read_gauge, reader
from app.core.meter.arc_fit import STEP
from app.core.meter.reading import refuse
from app.core.meter.stop_pin import PIN_SURE, gap_is_bare, widest_space
from sim_robot.gauge_dial import draw_dial
from sim_robot.gauge_styles import random_style

N = int(round(360.0 / STEP))


def _style(family, seed=5, **kw):
    st = random_style(family, np.random.default_rng(seed))
    return replace(st, **{"setpoint": None, "stop_pin": False, "min_angle_deg": -120.0,
                          "max_angle_deg": 120.0, **kw})


@pytest.mark.parametrize("family, ccw", [("process", False), ("plant", True), ("marine", False)])
def test_a_needle_on_its_stop_pin_below_the_minimum_reads_the_minimum(family, ccw):
    """The needle against its pin 11 deg below the zero mark, read against the profile's
    angles: the minimum, with a stop_pin score below 1 (it was refused beyond 5 deg)."""
    st = _style(family, stop_pin=True, pin_offset_deg=14.0, rest_at_max=False)
    if ccw:
        st = replace(st, min_angle_deg=120.0, max_angle_deg=-120.0)
    img, _t = draw_dial(st, st.min_value, size=320)
    r = read_gauge(img, load_profile(st.profile()), learned_fallback=False)
    assert r.value == pytest.approx(st.min_value), r.error
    assert r.method == "profile-angles" and PIN_SURE <= r.scores["stop_pin"] < 1.0


def test_a_needle_far_into_the_gap_is_still_refused():
    st = _style("plant", stop_pin=True, pin_offset_deg=38.0, rest_at_max=False)
    img, _t = draw_dial(st, st.min_value, size=320)
    r = read_gauge(img, load_profile(st.profile()), learned_fallback=False)
    assert r.value is None and "outside the scale" in r.error


@pytest.mark.parametrize("family, value_fs, turn_deg", [("plant", 0.04, 15.0),
                                                        ("process", 0.05, 18.0)])
def test_a_needle_among_ticks_below_a_misplaced_minimum_is_refused(monkeypatch, family,
                                                                   value_fs, turn_deg):
    """The scale found turned towards its maximum by ``turn_deg`` (the arc's fit replaced by
    one so turned), the needle on the scale ``value_fs`` of it above the true minimum: it
    lies 5-9 deg below the minimum found, as a needle on its stop pin would, but with the
    scale's ticks round it.  Refused; without the gap test it read the minimum, 4-5 % FS
    off."""
    st = _style(family)
    value = st.min_value + value_fs * (st.max_value - st.min_value)
    img, _t = draw_dial(st, value, size=320)
    fit = angles.fit_profile_arc

    def turned(*a, **kw):
        f = fit(*a, **kw)
        return f if f.rho_deg is None else replace(f, rho_deg=f.rho_deg + turn_deg)

    monkeypatch.setattr(angles, "fit_profile_arc", turned)
    # the scale path (which reads this dial by its own ticks) left out: the angles path reads
    monkeypatch.setattr(reader, "_scale_reading",
                        lambda res, prof, *a, **kw: refuse(prof.unit, "left out"))
    r = read_gauge(img, load_profile(st.profile()), learned_fallback=False)
    assert r.value is None and "below the minimum" in r.error, (r.value, r.error)
    monkeypatch.setattr(angles, "gap_is_bare", lambda *a, **kw: (True, ""))
    r = read_gauge(img, load_profile(st.profile()), learned_fallback=False)
    assert r.value == pytest.approx(st.min_value)  # what the gap test prevents


def _ring(ticks_deg, width_deg=1.0):
    """Evidence of a ring of ticks ``width_deg`` wide at ``ticks_deg``."""
    a = np.arange(N) * STEP
    e = np.zeros(N)
    for t in ticks_deg:
        e = np.maximum(e, np.clip(1.0 + 0.5 * width_deg - np.abs((a - t + 180) % 360 - 180),
                                  0, 1))
    return e


def _needle(e, at_deg, half_deg=1.0):
    a = np.arange(N) * STEP
    return np.where(np.abs((a - at_deg + 180) % 360 - 180) <= half_deg, 1.0, e)


def _bare(e, needle_deg, span=240.0, min_deg=240.0, seen=None):
    """gap_is_bare on a clockwise scale from ``min_deg`` (the minimum mark's image angle)."""
    seen = np.ones(N, bool) if seen is None else seen
    space = widest_space(e, seen, 0.4, STEP, min_deg, span)
    return gap_is_bare(e, seen, 0.4, STEP, min_deg, needle_deg, -1.0, span, space)


def test_the_gap_test_on_drawn_evidence():
    ticks = [240.0 + 3.0 * j for j in range(81)]  # every 3 deg over 240 deg, from 240
    # the needle 8 deg below the minimum, in the gap: bare
    assert _bare(_needle(_ring(ticks), 232.0), 232.0) == (True, "")
    # the scale goes on below the minimum found (turned by 12 deg): marks met
    more = ticks + [240.0 - 3.0 * j for j in range(1, 5)]
    ok, why = _bare(_needle(_ring(more), 232.0), 232.0)
    assert not ok and "scale marks" in why
    # a printed arc going on below the minimum found, under the needle, to the true end
    arc = np.maximum(_ring(ticks), _ring(np.arange(220.0, 480.0, 0.5)))
    ok, why = _bare(_needle(arc, 232.0), 232.0)
    assert not ok
    # a mark just past the needle, merged with it: it might hide the true minimum mark
    ok, why = _bare(_needle(_ring(ticks + [229.5]), 232.0), 232.0)
    assert not ok and ("touches the needle" in why or "scale marks" in why)
    # a ring of sparse marks (every 22 deg) on a scale of 330 deg: the 30 deg gap leaves no
    # bare run past the needle wider than the spaces between its marks
    sparse = [240.0 + 22.0 * j for j in range(16)]
    ok, why = _bare(_needle(_ring(sparse), 232.0), 232.0, span=330.0)
    assert not ok and "no wider than the spaces" in why
    # the ring unseen from the needle on (a colour zone over it): what it hides is unknown
    seen = np.ones(N, bool)
    seen[int(220 / STEP):int(231 / STEP)] = False
    ok, _ = _bare(_needle(_ring(ticks), 232.0), 232.0, seen=seen)
    assert not ok
    # ... and unseen again after a bare stretch past the needle too narrow to tell
    seen = np.ones(N, bool)
    seen[int(200 / STEP):int(229.5 / STEP)] = False
    ok, _ = _bare(_needle(_ring(ticks, width_deg=0.2), 232.0), 232.0, seen=seen)
    assert not ok
