"""Alarm rules: deadband and delays against chattering input, rate of rise,
stale data, the MCU's flags, the flood guard."""

import math
import random

import pytest

from app.core.alarms import (
    FLOOD_ID,
    AlarmMonitor,
    AlarmState,
    Debounce,
    FlagRule,
    FloodGuard,
    LimitRule,
    Priority,
    RateRule,
    RateTracker,
    StaleRule,
    slope_per_min,
)


def test_debounce_on_and_off_delays():
    d = Debounce(on_delay_s=2.0, off_delay_s=1.0)
    assert d.feed(True, 0.0) is None and d.pending
    assert d.feed(True, 1.9) is None
    assert d.feed(True, 2.0) is True
    assert d.feed(False, 3.0) is None
    assert d.feed(True, 3.5) is None and not d.pending  # back before the off-delay
    assert d.feed(False, 4.0) is None
    assert d.poll(5.0) is False  # time passing alone completes the change


def noisy(center, amp, n, seed=3):
    rnd = random.Random(seed)
    return [center + rnd.uniform(-amp, amp) for _ in range(n)]


def test_noise_at_the_limit_chatters_without_deadband_but_not_with_it():
    vals = noisy(45.0, 0.4, 400)
    bare = AlarmMonitor([LimitRule("temp_c", high=45.0)])
    raised_bare = sum(tr.raised for i, v in enumerate(vals)
                      for tr in bare.update("temp_c", v, i * 0.1))
    held = AlarmMonitor([LimitRule("temp_c", high=45.0, deadband=1.0)])
    raised_held = sum(tr.raised for i, v in enumerate(vals)
                      for tr in held.update("temp_c", v, i * 0.1))
    assert raised_bare > 20  # chattering
    assert raised_held == 1  # raised once, held inside the deadband


def test_on_delay_ignores_short_spikes():
    m = AlarmMonitor([LimitRule("temp_c", high=45.0, on_delay_s=3.0)])
    # one-sample spikes above the limit every other second: never 3 s in a row
    for i in range(60):
        v = 50.0 if i % 2 == 0 else 40.0
        assert m.update("temp_c", v, float(i)) == []
    # a real excursion: raised once it has lasted 3 s
    assert m.update("temp_c", 50.0, 100.0) == []
    assert m.update("temp_c", 50.0, 102.0) == []
    [tr] = m.update("temp_c", 50.0, 103.0)
    assert tr.raised and tr.t == 103.0


def test_on_delay_completes_on_tick_without_new_samples():
    m = AlarmMonitor([LimitRule("temp_c", high=45.0, on_delay_s=3.0)])
    m.update("temp_c", 50.0, 0.0)
    assert m.tick(2.9) == []
    [tr] = m.tick(3.0)
    assert tr.raised and tr.alarm.last_value == 50.0


def test_off_delay_holds_a_flickering_return():
    m = AlarmMonitor([LimitRule("gas_lel_pct", high=10.0, deadband=0.5, off_delay_s=5.0)])
    m.update("gas_lel_pct", 12.0, 0.0)
    m.acknowledge("gas_lel_pct.high", 0.5)
    # drops below the deadband for short moments only
    for i in range(1, 40):
        v = 9.0 if i % 3 else 11.0
        assert m.update("gas_lel_pct", v, float(i)) == []
    assert m.is_active("gas_lel_pct.high")
    for i in range(40, 45):
        assert m.update("gas_lel_pct", 9.0, float(i)) == []
    [tr] = m.update("gas_lel_pct", 9.0, 45.0)
    assert tr.to_state is AlarmState.NORMAL


def test_low_limit_with_deadband():
    m = AlarmMonitor([LimitRule("battery_v", low=22.0, deadband=0.3)])
    [tr] = m.update("battery_v", 21.8, 1.0)
    assert tr.alarm.condition == "low" and tr.alarm.limit == 22.0
    assert m.update("battery_v", 22.2, 2.0) == []
    [tr] = m.update("battery_v", 22.31, 3.0)
    assert tr.cleared


def test_slope_per_min():
    ts = [0.0, 10.0, 20.0, 30.0]
    assert slope_per_min(ts, [1.0, 2.0, 3.0, 4.0]) == pytest.approx(6.0)
    assert slope_per_min([1.0], [5.0]) == 0.0
    assert slope_per_min([1.0, 1.0], [5.0, 6.0]) == 0.0


def test_rate_of_rise_tracker_waits_for_half_a_window():
    rt = RateTracker(RateRule("gas_lel_pct", rise_per_min=5.0, window_s=20.0))
    assert rt.feed(0.0, 0.0) is None
    assert rt.feed(50.0, 1.0) is None  # a jump at start-up is no rate yet
    assert rt.feed(50.0, 2.0) is None and rt.rate == 0.0


def test_rate_of_rise_raises_on_a_leak_not_on_a_steady_high_value():
    m = AlarmMonitor([LimitRule("gas_lel_pct", high=50.0)],
                     rates=[RateRule("gas_lel_pct", rise_per_min=5.0, window_s=20.0,
                                     deadband=1.0, unit="%LEL", priority=Priority.HIGH)])
    rnd = random.Random(1)
    t = 0.0
    # steady at 8 %LEL with noise: no rate alarm
    for _ in range(300):
        t += 0.5
        assert m.update("gas_lel_pct", 8.0 + rnd.gauss(0, 0.2), t) == []
    # a leak: +12 %LEL per minute
    raised = []
    for i in range(120):
        t += 0.5
        raised += [tr for tr in m.update("gas_lel_pct", 8.0 + 0.1 * i, t) if tr.raised]
    [tr] = raised
    assert tr.alarm.key == "gas_lel_pct.rate" and tr.alarm.priority is Priority.HIGH
    assert tr.alarm.value > 5.0 and tr.alarm.limit == 5.0
    assert "rising" in tr.alarm.text
    # it levels off: the rate alarm clears once the window holds the plateau
    cleared = []
    for _ in range(80):
        t += 0.5
        cleared += [tr for tr in m.update("gas_lel_pct", 20.0, t) if tr.cleared]
    assert [c.alarm.key for c in cleared] == ["gas_lel_pct.rate"]


def test_stale_data_raises_on_tick_and_clears_on_the_next_sample():
    m = AlarmMonitor([], stale=[StaleRule("temp_c", after_s=10.0, label="Temperature")])
    assert m.tick(100.0) == []  # never seen: not judged (link lost covers that)
    m.update("temp_c", 20.0, 0.0)
    assert m.tick(10.0) == []
    [tr] = m.tick(10.5)
    assert tr.raised and tr.alarm.key == "temp_c.stale"
    assert tr.alarm.text == "Temperature stale: no data for more than 10 s"
    assert m.tick(20.0) == []
    [tr] = m.update("temp_c", 21.0, 21.0)
    assert tr.cleared and tr.to_state is AlarmState.RTN_UNACK


def test_nan_and_garbage_values_are_counted_not_raised():
    m = AlarmMonitor([LimitRule("temp_c", high=45.0)])
    assert m.update("temp_c", math.nan, 0.0) == []
    assert m.update("temp_c", "hot", 1.0) == []
    assert m.update("temp_c", None, 2.0) == []
    assert m.ignored == 3 and m.listed() == []


def test_flag_bits_are_robot_alarms():
    m = AlarmMonitor([], flags=[FlagRule(1 << 5, "FAILSAFE_STOP", Priority.HIGH,
                                         "Fail-safe stop"),
                                FlagRule(1 << 4, "BATTERY_LOW", Priority.MEDIUM)])
    trs = m.update_flags((1 << 5) | (1 << 4), 1.0)
    assert sorted(t.alarm.key for t in trs) == ["flag.BATTERY_LOW", "flag.FAILSAFE_STOP"]
    rec = next(t for t in trs if t.alarm.key == "flag.FAILSAFE_STOP").as_record()
    assert rec["source"] == "robot" and rec["text"] == "Fail-safe stop"
    assert m.update_flags((1 << 5) | (1 << 4), 2.0) == []
    [tr] = m.update_flags(1 << 4, 3.0)
    assert tr.alarm.key == "flag.FAILSAFE_STOP" and tr.cleared


def test_flood_guard_alone():
    g = FloodGuard(max_per_minute=3, window_s=60.0)
    assert [g.note(t) for t in (0, 1, 2)] == [False, False, False]
    assert g.note(3) is True and g.active and g.floods == 1
    assert g.note(4) is False  # said once
    assert g.check(30) is False
    assert g.check(64) is True and not g.active  # 1 left in the window (<= 3 // 2)
    with pytest.raises(ValueError):
        FloodGuard(0)


def test_flood_notice_once_and_grouping():
    m = AlarmMonitor([], flood_per_minute=5, flood_window_s=60.0)
    seen = []
    m.add_listener(seen.append)
    for i in range(12):
        m.set_condition(f"robot.fault{i}", True, float(i), source="robot" if i % 2 else "link",
                        priority=Priority.LOW, text=f"fault {i}")
    notices = [t for t in seen if t.alarm.key == FLOOD_ID]
    assert len(notices) == 1 and notices[0].raised and notices[0].t == 5.0
    assert "Alarm flood" in notices[0].alarm.text and m.flood_active
    # every alarm still reached the listeners (and so the archive)
    assert sum(1 for t in seen if t.raised and t.alarm.key != FLOOD_ID) == 12
    assert m.get("robot.fault11").in_flood and not m.get("robot.fault0").in_flood
    groups = m.groups()
    assert {g.source: g.count for g in groups} == {"robot": 6, "link": 6, "alarms": 1}
    assert all(g.unacked == g.count for g in groups)
    # the flood ends when the rate falls, and the notice returns to normal
    assert m.tick(30.0) == []
    [end] = m.tick(70.0)
    assert end.alarm.key == FLOOD_ID and end.cleared and not m.flood_active


def test_groups_of_a_filtered_list():
    """Grouping a filtered list counts and lists only the shown keys; a group keeps
    its whole source's priority and place, and a source with none shown is left out."""
    m = AlarmMonitor([])
    for i in range(6):
        m.set_condition(f"dev.f{i}", True, float(i), source="robot" if i % 2 else "link",
                        priority=Priority.LOW, text=f"fault {i}")
    m.set_condition("dev.f9", True, 9.0, source="robot", priority=Priority.HIGH, text="f9")
    m.set_condition("dev.c", True, 9.0, source="camera", priority=Priority.HIGH, text="c")
    m.acknowledge("dev.f3", 10.0)
    within = m.groups(within=["dev.f3", "dev.f5", "dev.f0"])
    assert [(g.source, g.count, g.unacked, g.keys) for g in within] == [
        ("robot", 2, 1, ("dev.f3", "dev.f5")), ("link", 1, 1, ("dev.f0",))]
    assert within[0].priority is Priority.HIGH and within[1].priority is Priority.LOW
    assert [g.source for g in m.groups()] == ["robot", "camera", "link"]
    assert m.groups(within=[]) == []


def test_rate_tracker_running_slope_matches_the_least_squares_slope():
    """The O(1) sliding slope equals the plain least-squares slope of the same
    window at every step, over hours of 10 Hz data with a moving window."""
    from app.core.alarms.rules import RateRule, RateTracker, slope_per_min

    rule = RateRule("gas_lel_pct", rise_per_min=5.0, window_s=30.0)
    tr = RateTracker(rule)
    rng = random.Random(4)
    t0 = 1.7e9
    window: list[tuple[float, float]] = []
    for i in range(40_000):  # > 1 h, so the reference moves
        t = t0 + i * 0.1
        v = 10 + 0.02 * i + rng.gauss(0, 0.3)
        tr.feed(v, t)
        window = [p for p in window if t - p[0] <= rule.window_s] + [(t, v)]
        if i % 997 == 0 and i > 400:
            want = slope_per_min([p[0] for p in window], [p[1] for p in window])
            assert tr.rate == pytest.approx(want, rel=1e-6, abs=1e-9)
