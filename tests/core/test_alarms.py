import pytest

from app.core.alarms import AlarmMonitor, FlagRule, LimitRule, Priority


def test_high_limit_with_hysteresis():
    m = AlarmMonitor([LimitRule("temp_c", high=45.0, deadband=1.0, unit="°C")])
    assert m.update("temp_c", 44.9, 1.0) == []
    ch = m.update("temp_c", 45.5, 2.0)
    assert len(ch) == 1 and ch[0].raised
    a = ch[0].alarm
    assert (a.key, a.raised_t, a.value, a.limit) == ("temp_c.high", 2.0, 45.5, 45.0)
    # back under the limit but inside the deadband: still standing
    assert m.update("temp_c", 44.5, 3.0) == []
    assert m.is_active("temp_c.high")
    assert m.active()[0].last_value == 44.5
    # a second excursion does not raise twice
    assert m.update("temp_c", 46.0, 4.0) == []
    ch = m.update("temp_c", 44.0, 5.0)
    assert len(ch) == 1 and not ch[0].raised and ch[0].alarm.cleared_t == 5.0
    assert m.active() == []


def test_low_limit_battery_default():
    m = AlarmMonitor()
    assert m.update("battery_v", 24.0, 0.0) == []
    [c] = m.update("battery_v", 21.8, 1.0)
    assert c.raised and c.alarm.condition == "low" and c.alarm.limit == 22.0
    assert m.update("battery_v", 22.2, 2.0) == []  # below 22.0 + 0.3
    [c] = m.update("battery_v", 22.3, 3.0)
    assert not c.raised


def test_defaults_cover_the_channels():
    m = AlarmMonitor()
    assert m.rule("gas_lel_pct").high == 10.0
    assert m.rule("temp_c").high == 45.0
    assert m.rule("humidity_pct").high == 90.0
    assert m.rule("battery_v").low == 22.0
    [c] = m.update("gas_lel_pct", 12.0, 0.0)
    assert c.alarm.priority == Priority.HIGH
    assert "Gas 12.0 %LEL above limit 10 %LEL" == c.alarm.text


def test_unknown_channel_and_nan_are_ignored():
    m = AlarmMonitor()
    assert m.update("wheel_left_mps", 99.0, 0.0) == []
    assert m.update("temp_c", float("nan"), 0.0) == []
    assert m.ignored == 1


def test_flags_raise_and_clear():
    m = AlarmMonitor([], flags=[FlagRule(1, "GAS_HIGH", Priority.HIGH),
                                FlagRule(4, "HUMIDITY_HIGH", Priority.LOW)])
    ch = m.update_flags(0b101, 1.0)
    assert sorted(c.alarm.condition for c in ch) == ["GAS_HIGH", "HUMIDITY_HIGH"]
    assert all(c.raised for c in ch)
    assert m.update_flags(0b101, 2.0) == []
    [c] = m.update_flags(0b100, 3.0)
    assert not c.raised and c.alarm.condition == "GAS_HIGH"
    assert m.most_severe().condition == "HUMIDITY_HIGH"


def test_most_severe_orders_by_priority_then_age():
    m = AlarmMonitor()
    m.update("humidity_pct", 95.0, 1.0)
    m.update("temp_c", 50.0, 2.0)
    assert m.most_severe().source == "temp_c"
    m.update("gas_lel_pct", 20.0, 3.0)
    assert m.most_severe().source == "gas_lel_pct"
    assert [a.source for a in m.active()] == ["gas_lel_pct", "temp_c", "humidity_pct"]
    assert m.channel_priority("temp_c") == Priority.MEDIUM
    assert m.channel_priority("battery_v") is None
    assert len(m.clear_all(4.0)) == 3 and m.active() == []


def test_bad_rules_rejected():
    with pytest.raises(ValueError):
        LimitRule("x")
    with pytest.raises(ValueError):
        LimitRule("x", high=1.0, low=2.0)
    with pytest.raises(ValueError):
        LimitRule("x", high=1.0, deadband=-1)


def test_a_value_just_past_its_limit_does_not_read_as_the_limit():
    """A gauge at 1.25 MPa over a 1.2 MPa limit: one decimal would say "1.2 above
    limit 1.2"; the text gives the digits that tell them apart."""
    m = AlarmMonitor([LimitRule("meter.PG-302", high=1.2, unit="MPa", label="Meter PG-302"),
                      LimitRule("temp_c", low=5.0, unit="°C", label="Temperature")])
    [c] = m.update("meter.PG-302", 1.25, 0.0)
    assert c.alarm.text == "Meter PG-302 1.25 MPa above limit 1.2 MPa"
    [c] = m.update("meter.PG-302", 1.19, 1.0)
    assert c.alarm.cleared_text == "Meter PG-302 back to 1.19 MPa (limit 1.2 MPa)"
    [c] = m.update("temp_c", 4.96, 2.0)
    assert c.alarm.text == "Temperature 4.96 °C below limit 5 °C"
    m.update("temp_c", 3.04, 3.0)  # further below: one decimal tells them apart
    assert m.get("temp_c.low").text == "Temperature 3.0 °C below limit 5 °C"


def test_texts_for_the_operator():
    m = AlarmMonitor(flags=[FlagRule(8, "OBSTACLE_NEAR", Priority.LOW, "Obstacle near")])
    [c] = m.update("temp_c", 46.0, 0.0)
    assert c.alarm.text == "Temperature 46.0 °C above limit 45 °C"
    [c] = m.update("temp_c", 40.0, 1.0)
    assert c.alarm.cleared_text == "Temperature back to 40.0 °C (limit 45 °C)"
    [c] = m.update_flags(8, 2.0)
    assert c.alarm.text == "Obstacle near"
