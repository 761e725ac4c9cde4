"""The freshness tracker: ages on the monotonic clock, 'last known' in UTC."""

from datetime import datetime

import pytest

from app.core.freshness import Age, FreshnessTracker, age_text, last_known_text


class Clock:
    def __init__(self, t: float = 100.0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t


def _tracker(**kw):
    mono, utc = Clock(100.0), Clock(1_800_000_000.0)
    tr = FreshnessTracker(mono=mono, utc=utc, **kw)
    return tr, mono, utc


def _advance(mono, utc, dt):
    mono.t += dt
    utc.t += dt


def test_nothing_received_is_none_not_stale():
    tr, _, _ = _tracker()
    tr.set_link_up(True)
    f = tr.freshness("telemetry")
    assert f.age is Age.NONE and not f.stale and f.text() == ""


def test_a_periodic_source_goes_old_after_a_few_of_its_periods_with_the_link_up():
    tr, mono, utc = _tracker(old_after_periods=3.0, min_old_s=0.5)
    tr.set_link_up(True)
    for _ in range(10):  # 10 Hz
        tr.note("telemetry", {"gas_lel_pct": 1.0})
        _advance(mono, utc, 0.1)
    assert tr.old_after_s("telemetry") == pytest.approx(0.5)  # 3 x 0.1 s, floor 0.5 s
    _advance(mono, utc, 0.3)  # 0.4 s since the last one
    assert tr.freshness("telemetry").age is Age.LIVE
    _advance(mono, utc, 0.2)  # 0.6 s
    f = tr.freshness("telemetry")
    assert f.age is Age.OLD and f.stale
    assert f.age_s == pytest.approx(0.6)
    assert tr.value("telemetry") == {"gas_lel_pct": 1.0}
    tr.note("telemetry", {"gas_lel_pct": 2.0})
    assert tr.freshness("telemetry").age is Age.LIVE


def test_a_slow_source_is_judged_on_its_own_interval():
    tr, mono, utc = _tracker(old_after_periods=3.0, min_old_s=0.5)
    tr.set_link_up(True)
    for _ in range(4):  # 1 Hz
        tr.note("heartbeat")
        _advance(mono, utc, 1.0)
    _advance(mono, utc, 1.5)  # 2.5 s of silence: fine for a 1 Hz source
    assert tr.freshness("heartbeat").age is Age.LIVE
    _advance(mono, utc, 1.0)
    assert tr.freshness("heartbeat").age is Age.OLD


def test_link_down_makes_every_received_value_no_link_with_its_age_and_time():
    tr, mono, utc = _tracker()
    tr.expect("control", periodic=False)
    tr.set_link_up(True)
    tr.note("telemetry", 1)
    tr.note("control", "you have control")
    t_utc = utc.t
    _advance(mono, utc, 40.0)
    assert tr.freshness("control").age is Age.LIVE  # aperiodic: never old by silence
    tr.set_link_up(False)
    for name in ("telemetry", "control"):
        f = tr.freshness(name)
        assert f.age is Age.NO_LINK and f.stale
        hms = datetime.fromtimestamp(t_utc).strftime("%H:%M:%S")
        assert f.text() == f"last known {hms}, 40 s ago"
    assert tr.freshness("never").age is Age.NONE


def test_given_period_wins_over_the_arrivals():
    tr, mono, utc = _tracker(min_old_s=0.0)
    tr.expect("pose", period_s=1.0)
    tr.set_link_up(True)
    tr.note("pose")
    _advance(mono, utc, 0.01)
    tr.note("pose")
    assert tr.old_after_s("pose") == pytest.approx(3.0)
    with pytest.raises(ValueError):
        tr.expect("bad", period_s=0.0)


def test_age_texts():
    assert age_text(0.4) == "0 s ago"
    assert age_text(59.9) == "59 s ago"
    assert age_text(125) == "2 min ago"
    assert age_text(3600 + 300) == "1 h 5 min ago"
    assert last_known_text(0.0, 40).endswith(", 40 s ago")


def test_a_value_received_after_the_link_went_down_is_judged_by_its_age():
    tr, mono, utc = _tracker(min_old_s=1.0)
    tr.set_link_up(True)
    tr.note("telemetry", 1)
    _advance(mono, utc, 0.1)
    tr.set_link_up(False)
    assert tr.freshness("telemetry").age is Age.NO_LINK
    _advance(mono, utc, 0.1)
    tr.note("telemetry", 2)  # whatever the link state says, this one is new
    assert tr.freshness("telemetry").age is Age.LIVE
    _advance(mono, utc, 5.0)
    assert tr.freshness("telemetry").age is Age.OLD
