"""The alarm rule file: defaults, overrides, and clear messages for bad input."""

import tomllib

from app.core.alarms import (
    AlarmMonitor,
    Priority,
    default_alarm_config,
    dump_alarm_config,
    load_alarm_config,
    parse_alarm_config,
)


def test_defaults_load_cleanly():
    cfg, problems = load_alarm_config()
    assert problems == []
    gas = cfg.limit("gas_lel_pct")
    assert (gas.high, gas.deadband, gas.priority) == (10.0, 0.5, Priority.HIGH)
    assert cfg.limit("battery_v").low == 22.0
    assert [r.channel for r in cfg.rates] == ["gas_lel_pct"]
    assert {s.channel for s in cfg.stale} >= {"gas_lel_pct"}
    assert cfg.flags["FAILSAFE_STOP"][0] == Priority.HIGH
    assert {r.name for r in cfg.flag_rules()} >= {"FAILSAFE_STOP", "ESTOP", "BATTERY_LOW"}
    m = AlarmMonitor.from_config(cfg)
    assert m.rule("temp_c").high == 45.0 and m.flood.max_per_minute == cfg.flood_per_minute


def test_override_changes_only_what_it_names(tmp_path):
    f = tmp_path / "site.toml"
    f.write_text('[limit.temp_c]\nhigh = 50.0\non_delay_s = 2\n'
                 '[limit.wind_mps]\nhigh = 20.0\nunit = "m/s"\n'
                 '[flood]\nmax_per_minute = 20\n', encoding="utf-8")
    cfg, problems = load_alarm_config(f)
    assert problems == []
    t = cfg.limit("temp_c")
    assert (t.high, t.on_delay_s, t.deadband, t.label) == (50.0, 2.0, 1.0, "Temperature")
    assert cfg.limit("wind_mps").unit == "m/s"
    assert cfg.limit("gas_lel_pct").high == 10.0
    assert cfg.flood_per_minute == 20


def test_bad_entries_named_by_file_and_key_and_defaults_kept(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text('[limit.temp_c]\nhigh = "hot"\n'
                 '[limit.gas_lel_pct]\nhigh = 5.0\nlow = 8.0\n'
                 '[limit.humidity_pct]\ndeadbnd = 2\n'
                 '[limit.battery_v]\npriority = "urgent"\n'
                 '[rate.gas_lel_pct]\nrise_per_min = -1\n'
                 '[flag.NOT_A_FLAG]\npriority = "LOW"\n'
                 '[sirens]\nx = 1\n'
                 '[flood]\nmax_per_minute = 0\n', encoding="utf-8")
    cfg, problems = load_alarm_config(f)
    text = "\n".join(problems)
    assert "bad.toml: [limit.temp_c] high: expected a number, got 'hot'" in text
    assert "bad.toml: [limit.gas_lel_pct]: rule for 'gas_lel_pct': low 8.0 >= high 5.0" in text
    assert "bad.toml: [limit.humidity_pct] deadbnd: unknown setting" in text
    assert "bad.toml: [limit.battery_v] priority: unknown priority 'urgent'" in text
    assert "bad.toml: [rate.gas_lel_pct]: rate rule for 'gas_lel_pct': rise_per_min" in text
    assert "bad.toml: [flag.NOT_A_FLAG]: unknown flag" in text
    assert "bad.toml: unknown section [sirens]" in text
    assert "bad.toml: [flood] max_per_minute: must be >= 1, got 0" in text
    assert len(problems) == 8
    # each bad point kept its default
    d = default_alarm_config()
    for ch in ("temp_c", "gas_lel_pct", "humidity_pct", "battery_v"):
        assert cfg.limit(ch) == d.limit(ch)
    assert cfg.rates == d.rates and cfg.flood_per_minute == d.flood_per_minute


def test_unreadable_or_broken_file_keeps_the_defaults(tmp_path):
    cfg, problems = load_alarm_config(tmp_path / "missing.toml")
    assert len(problems) == 1 and "missing.toml: file not found" in problems[0]
    assert "default alarm rules are kept" in problems[0]
    assert cfg.limit("gas_lel_pct").high == 10.0
    f = tmp_path / "broken.toml"
    f.write_text("[limit.temp_c\nhigh = 3", encoding="utf-8")
    cfg, problems = load_alarm_config(f)
    assert "broken.toml: not valid TOML" in problems[0]
    assert cfg.limit("temp_c").high == 45.0
    f.write_bytes(b"\xff\xfe\x00bad")
    cfg, problems = load_alarm_config(f)
    assert "cannot be read" in problems[0] and cfg.limit("temp_c").high == 45.0


def test_dump_reads_back_to_the_same_rules():
    cfg = default_alarm_config()
    back, problems = parse_alarm_config(tomllib.loads(dump_alarm_config(cfg)), "round.toml")
    assert problems == []
    assert back.limits == cfg.limits and back.rates == cfg.rates and back.stale == cfg.stale
    assert back.flags == cfg.flags and back.conditions == cfg.conditions


def test_configured_condition_priority_wins():
    m = AlarmMonitor.from_config(default_alarm_config())
    [tr] = m.set_condition("link.lost", True, 1.0, source="link", priority=Priority.LOW,
                           text="lost")
    assert tr.alarm.priority == Priority.HIGH and tr.alarm.text == "Link to the robot lost"
    [tr] = m.set_condition("meter.P3.band", True, 1.0, source="meter:P3",
                           priority=Priority.MEDIUM, text="P3 out of band", value=1.7)
    assert tr.alarm.priority == Priority.MEDIUM and tr.alarm.text == "P3 out of band"
    assert tr.as_record()["source"] == "meter:P3" and tr.as_record()["value"] == 1.7


def test_new_rules_keep_standing_alarms_and_clear_orphans():
    import dataclasses

    from app.core.alarms import LimitRule

    cfg = default_alarm_config()
    m = AlarmMonitor.from_config(cfg)
    m.set_rule(LimitRule("meter.PG-1", high=1.0))  # added outside the configuration
    m.update_many({"temp_c": 50.0, "humidity_pct": 95.0, "meter.PG-1": 2.0}, 10.0)
    m.update_flags(1 << 5, 10.0)
    new = dataclasses.replace(cfg, limits=[r for r in cfg.limits if r.channel != "humidity_pct"],
                              flood_per_minute=3)
    seen = []
    m.add_listener(seen.append)
    trs = m.apply_config(new)
    assert [(t.alarm.key, t.to_state.value, t.t) for t in trs] == [
        ("humidity_pct.high", "RTN_UNACK", 10.0)]
    assert seen == trs
    assert m.is_active("temp_c.high") and m.is_active("meter.PG-1.high")
    assert m.is_active("flag.FAILSAFE_STOP") and m.rule("meter.PG-1") is not None
    assert m.flood.max_per_minute == 3
    off = m.rule("temp_c").off_delay_s  # still judged by its rule
    assert m.update("temp_c", 40.0, 20.0) == [] and m.update("temp_c", 40.0, 20.0 + off)[0].cleared
