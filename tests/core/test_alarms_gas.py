"""Several set-points per channel and the gas detector model (A1, A2 latching,
over-range, sensor fault, bump tests and calibrations overdue)."""

from __future__ import annotations

import pytest

from app.core.alarms import AlarmMonitor, AlarmState, Priority, load_alarm_config
from app.core.alarms.config import gas_rule, parse_alarm_config
from app.core.alarms.service import DAY, ServiceLog, ServiceRecord, service_alarms
from app.core.alarms.setpoints import GasRule, SetPoint

GAS = "gas_lel_pct"
T0 = 1_800_000_000.0


def gas_monitor() -> AlarmMonitor:
    """The shipped rules: A1 = [limit.gas_lel_pct] high 10, A2 20 latching,
    over-range 100 latching, fault below -5 or stuck."""
    cfg, problems = load_alarm_config()
    assert problems == []
    return AlarmMonitor.from_config(cfg)


def keys(trs) -> list[tuple[str, AlarmState]]:
    return [(tr.alarm.key, tr.to_state) for tr in trs]


# ---------------------------------------------------------------- set-points
def test_rising_setpoint_raises_above_and_clears_only_below_its_deadband():
    m = AlarmMonitor([], setpoints=[SetPoint("p", "hh", 8.0, deadband=0.5,
                                             priority=Priority.HIGH)])
    assert m.update("p", 8.0, 0) == []  # at the set-point: not above
    assert keys(m.update("p", 8.1, 1)) == [("p.hh", AlarmState.UNACK)]
    assert m.update("p", 7.6, 2) == []  # inside the deadband: still in alarm
    assert m.is_active("p.hh")
    assert keys(m.update("p", 7.5, 3)) == [("p.hh", AlarmState.RTN_UNACK)]
    assert m.get("p.hh").priority is Priority.HIGH and m.get("p.hh").limit == 8.0


def test_falling_setpoint_mirrors_it_and_each_setpoint_has_its_own_priority():
    m = AlarmMonitor([], setpoints=[SetPoint("v", "l", 22.0, "falling", 0.3),
                                    SetPoint("v", "ll", 21.0, "falling", 0.2,
                                             Priority.EMERGENCY)])
    assert keys(m.update("v", 21.9, 0)) == [("v.l", AlarmState.UNACK)]
    assert keys(m.update("v", 20.9, 1)) == [("v.ll", AlarmState.UNACK)]
    assert m.get("v.ll").priority is Priority.EMERGENCY
    assert m.get("v.ll").text == "v ll 20.9 below limit 21"
    assert m.update("v", 21.1, 2) == []  # ll clears at 21.2 or above
    assert keys(m.update("v", 21.2, 3)) == [("v.ll", AlarmState.RTN_UNACK)]
    assert m.update("v", 22.2, 4) == []  # l clears at 22.3
    assert keys(m.update("v", 22.3, 5)) == [("v.l", AlarmState.RTN_UNACK)]


def test_setpoint_on_delay():
    m = AlarmMonitor([], setpoints=[SetPoint("p", "h", 5.0, on_delay_s=3.0)])
    assert m.update("p", 6.0, 0) == []
    assert m.tick(2.0) == []
    assert keys(m.tick(3.0)) == [("p.h", AlarmState.UNACK)]


@pytest.mark.parametrize("bad, words", [
    (dict(direction="up"), "direction must be 'rising' or 'falling'"),
    (dict(deadband=-1.0), "deadband must be >= 0"),
    (dict(name="high"), "reserved"),
    (dict(stage="A3"), "stage must be one of"),
])
def test_bad_setpoints_are_refused_with_a_clear_message(bad, words):
    kw = dict(channel="p", name="x", value=1.0) | bad
    with pytest.raises(ValueError, match=words):
        SetPoint(**kw)


# ---------------------------------------------------------------- the gas model
def test_gas_stages_in_order():
    m = gas_monitor()
    m.update(GAS, 5.0, T0)
    assert m.stage(GAS) == "normal"
    m.update(GAS, 12.0, T0 + 1)
    assert m.stage(GAS) == "A1" and m.is_active(f"{GAS}.high")
    m.update(GAS, 21.0, T0 + 2)
    assert m.stage(GAS) == "A2" and m.get(f"{GAS}.a2").priority is Priority.EMERGENCY
    m.update(GAS, 101.0, T0 + 3)
    assert m.stage(GAS) == "over-range"
    assert m.stage("temp_c") is None  # no gas rule: no stage


def test_a2_latches_until_reset_and_reset_is_refused_while_still_high():
    m = gas_monitor()
    a2 = f"{GAS}.a2"
    m.update(GAS, 25.0, T0)
    assert m.is_active(a2) and m.latched(a2)
    m.update(GAS, 3.0, T0 + 10)  # gas gone: A2 stays, latched
    assert m.is_active(a2) and m.stage(GAS) == "A2"
    # an acknowledgement is not a reset
    assert keys(m.acknowledge(a2, T0 + 11, "ana")) == [(a2, AlarmState.ACKED)]
    assert m.is_active(a2) and m.latched(a2)
    # back above: refused, with the value and the edge in the reason
    m.update(GAS, 19.5, T0 + 12)  # above 20 - 1 deadband
    trs, why = m.reset(a2, T0 + 13, "ana")
    assert trs == [] and "reset refused" in why and "19.5" in why and "below 19" in why
    assert m.is_active(a2)
    m.update(GAS, 18.9, T0 + 14)
    trs, why = m.reset(a2, T0 + 15, "ana")
    assert why == "" and keys(trs) == [(a2, AlarmState.NORMAL)]  # acked before: normal
    assert not m.latched(a2) and m.stage(GAS) == "A1"  # 18.9 is still above A1
    assert m.reset(a2, T0 + 16)[1] == f"{a2} is not latched"
    assert m.reset("temp_c.high", T0 + 16)[1] == "temp_c.high has no latching set-point"


def test_a2_reset_before_acknowledgement_leaves_it_to_acknowledge():
    m = gas_monitor()
    a2 = f"{GAS}.a2"
    m.update(GAS, 25.0, T0)
    m.update(GAS, 0.0, T0 + 5)
    trs, why = m.reset(a2, T0 + 6, "ana")
    assert why == "" and keys(trs) == [(a2, AlarmState.RTN_UNACK)]
    assert keys(m.acknowledge(a2, T0 + 7, "ana")) == [(a2, AlarmState.NORMAL)]


def test_over_range_latches():
    m = gas_monitor()
    over = f"{GAS}.over_range"
    m.update(GAS, 120.0, T0)
    assert m.is_active(over) and m.stage(GAS) == "over-range"
    m.update(GAS, 0.0, T0 + 30)  # a poisoned sensor reading zero is not trusted
    assert m.is_active(over) and m.stage(GAS) == "over-range"
    assert m.reset(over, T0 + 31)[1] == ""
    assert not m.is_active(over)


def test_sensor_fault_below_zero_beyond_the_band():
    m = gas_monitor()
    fault = f"{GAS}.fault"
    m.update(GAS, -4.9, T0)
    assert not m.is_active(fault) and m.stage(GAS) == "normal"
    [tr] = m.update(GAS, -6.0, T0 + 1)
    assert tr.alarm.key == fault and tr.to_state is AlarmState.UNACK
    assert "below -5 %LEL" in tr.alarm.text and tr.alarm.priority is Priority.HIGH
    assert m.stage(GAS) == "fault"
    assert keys(m.update(GAS, 0.0, T0 + 2)) == [(fault, AlarmState.RTN_UNACK)]


def _stuck_monitor(stuck_s=60.0) -> AlarmMonitor:
    return AlarmMonitor([], gas=[GasRule(GAS, stuck_band=0.01, stuck_s=stuck_s)])


def test_sensor_fault_stuck_while_other_channels_move():
    m = _stuck_monitor()
    fault = f"{GAS}.fault"
    for i in range(61):
        m.update_many({"temp_c": 20.0 + 0.1 * (i % 3), GAS: 1.0 + 0.004 * (i % 2)}, T0 + i)
        assert m.is_active(fault) == (i >= 60), i
    assert "stuck for more than 60 s" in m.get(fault).text
    assert m.stage(GAS) == "fault"
    m.update(GAS, 1.5, T0 + 62)  # it moved: the fault clears
    assert not m.is_active(fault)


def test_a_frozen_robot_is_not_a_stuck_gas_sensor():
    m = _stuck_monitor()
    for i in range(200):  # every channel frozen (the stale rule's matter)
        m.update_many({"temp_c": 20.0, GAS: 1.0}, T0 + i)
    assert not m.is_active(f"{GAS}.fault")
    m0 = _stuck_monitor(stuck_s=0.0)  # 0 turns the check off
    for i in range(200):
        m0.update_many({"temp_c": 20.0 + i, GAS: 1.0}, T0 + i)
    assert not m0.is_active(f"{GAS}.fault")


# ---------------------------------------------------------------- configuration
def test_old_alarm_files_load_unchanged(tmp_path):
    old = tmp_path / "site.toml"
    old.write_text("[limit.temp_c]\nhigh = 52.5\n[limit.gas_lel_pct]\nhigh = 12.0\n",
                   encoding="utf-8")
    cfg, problems = load_alarm_config(old)
    assert problems == []
    assert cfg.limit("temp_c").high == 52.5 and cfg.limit(GAS).high == 12.0
    # a file with only the old sections gives exactly the old rules
    bare, problems = parse_alarm_config({"limit": {"temp_c": {"high": 45.0}}}, "old.toml")
    assert problems == [] and bare.setpoints == [] and bare.gas == []
    m = AlarmMonitor.from_config(bare)
    assert keys(m.update("temp_c", 46.0, 0)) == [("temp_c.high", AlarmState.UNACK)]
    assert m.stage("temp_c") is None


def test_site_setpoints_and_gas_intervals_from_toml(tmp_path):
    f = tmp_path / "site.toml"
    f.write_text("[setpoint.gas_lel_pct.a2]\nvalue = 25.0\n"
                 "[setpoint.temp_c.hh]\nvalue = 60.0\ndeadband = 2.0\npriority = 'HIGH'\n"
                 "latching = true\n"
                 "[gas.gas_lel_pct]\nbump_test_days = 14\ncalibration_days = 90\n",
                 encoding="utf-8")
    cfg, problems = load_alarm_config(f)
    assert problems == []
    sp = {s.key: s for s in cfg.setpoints}
    assert sp[f"{GAS}.a2"].value == 25.0 and sp[f"{GAS}.a2"].latching  # rest kept
    assert sp["temp_c.hh"].latching and sp["temp_c.hh"].deadband == 2.0
    g = gas_rule(cfg, GAS)
    assert g.bump_test_days == 14 and g.calibration_days == 90 and g.gas == "CH4"
    again, problems = parse_alarm_config(__import__("tomllib").loads(
        __import__("app.core.alarms", fromlist=["x"]).dump_alarm_config(cfg)), "dump")
    assert problems == [] and again.setpoints == cfg.setpoints and again.gas == cfg.gas


def test_bad_setpoint_entries_are_named_and_the_default_kept(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("[setpoint.gas_lel_pct.a2]\nlatching = 'yes'\n"
                 "[setpoint.temp_c.hh]\ndeadband = 1.0\n"
                 "[setpoint.gas_lel_pct.over_range]\ndirection = 'sideways'\n"
                 "[gas.gas_lel_pct]\nbump_test_days = 0\n", encoding="utf-8")
    cfg, problems = load_alarm_config(f)
    text = "\n".join(problems)
    assert "bad.toml: [setpoint.gas_lel_pct.a2] latching: expected true or false" in text
    assert "[setpoint.temp_c.hh]: a set-point needs a value" in text
    assert "direction must be 'rising' or 'falling'" in text
    assert "bump_test_days must be > 0" in text
    assert len(problems) == 4
    sp = {s.key: s for s in cfg.setpoints}
    assert sp[f"{GAS}.a2"].latching and sp[f"{GAS}.over_range"].direction == "rising"
    assert gas_rule(cfg, GAS).bump_test_days == 30.0


# ---------------------------------------------------------------- service record
def _rule(**kw) -> GasRule:
    return GasRule(GAS, **kw)


def test_bump_test_overdue_raises_an_alarm(tmp_path):
    book = ServiceLog(tmp_path / "gas_service.json")
    now = T0 + 100 * DAY
    book.add(ServiceRecord(now - 31 * DAY, "bump", "CH4", "pass", "ana"))
    book.add(ServiceRecord(now - 10 * DAY, "calibration", "CH4", "pass", "ben"))
    by = {a.alarm_id: a for a in service_alarms(ServiceLog(book.path), [_rule()], now)}
    assert by["gas.CH4.bump_overdue"].active
    assert "bump test overdue" in by["gas.CH4.bump_overdue"].text
    assert not by["gas.CH4.calibration_overdue"].active
    # a site with 60-day bump tests: not yet due
    by = {a.alarm_id: a for a in service_alarms(book, [_rule(bump_test_days=60)], now)}
    assert not by["gas.CH4.bump_overdue"].active


def test_a_failed_or_missing_bump_test_is_an_alarm(tmp_path):
    book = ServiceLog(tmp_path / "s.json")
    [bump, _] = service_alarms(book, [_rule()], T0)
    assert bump.active and "no bump test on record" in bump.text
    book.add(ServiceRecord(T0 - DAY, "bump", "CH4", "pass", "ana"))
    book.add(ServiceRecord(T0, "bump", "CH4", "fail", "ana"))
    [bump, _] = service_alarms(book, [_rule()], T0)
    assert bump.active and "failed" in bump.text


def test_the_desk_raises_the_overdue_alarm_and_clears_it_once_recorded(tmp_path):
    from app.core.desk.pipeline import DeskPipeline

    path = tmp_path / "gas_service.json"
    book = ServiceLog(path)
    book.add(ServiceRecord(T0 - 40 * DAY, "bump", "CH4", "pass", "ana"))
    book.add(ServiceRecord(T0 - 40 * DAY, "calibration", "CH4", "pass", "ana"))
    mono = [0.0]
    p = DeskPipeline(gas_service=path, clock=lambda: T0, mono=lambda: mono[0])
    assert p.monitor.is_active("gas.CH4.bump_overdue")
    assert not p.monitor.is_active("gas.CH4.calibration_overdue")
    assert p.monitor.get("gas.CH4.bump_overdue").priority is Priority.LOW
    book.add(ServiceRecord(T0, "bump", "CH4", "pass", "ana"))
    mono[0] = 61.0
    p.tick()
    assert p.monitor.state("gas.CH4.bump_overdue") is AlarmState.RTN_UNACK
    assert DeskPipeline(clock=lambda: T0).monitor.get("gas.CH4.bump_overdue") is None


def test_bad_records_are_counted_and_an_unreadable_file_is_not_overwritten(tmp_path):
    f = tmp_path / "s.json"
    f.write_text('{"records": [{"t": 1, "kind": "bump", "gas": "CH4", "result": "ok", '
                 '"by": "x"}, {"t": 2, "kind": "bump", "gas": "CH4", "result": "pass", '
                 '"by": "x"}]}', encoding="utf-8")
    book = ServiceLog(f)
    assert book.skipped == 1 and len(book.records) == 1
    f.write_text("{not json", encoding="utf-8")
    broken = ServiceLog(f)
    assert "cannot be read" in broken.problem
    with pytest.raises(ValueError, match="fix or move it"):
        broken.add(ServiceRecord(3, "bump", "CH4", "pass", "x"))
    assert f.read_text(encoding="utf-8") == "{not json"


def test_applying_the_rules_again_keeps_a_latched_alarm_latched():
    m = gas_monitor()
    a2 = f"{GAS}.a2"
    m.update(GAS, 30.0, T0)
    cfg, _ = load_alarm_config()
    m.apply_config(cfg, T0 + 1)  # e.g. the settings dialog's OK
    m.update(GAS, 0.0, T0 + 2)
    assert m.is_active(a2) and m.latched(a2)
    assert m.reset(a2, T0 + 3)[1] == ""
