"""The alarm panel, header, sound and dialogs over a real AlarmMonitor."""

import pytest
from PySide6.QtCore import Qt

from app.core.alarms import (
    FLOOD_ID,
    AlarmMonitor,
    AlarmState,
    LimitRule,
    Priority,
    default_alarm_config,
)
from app.ui.alarm_banner import AlarmBanner, banner_text
from app.ui.alarm_dialogs import AlarmSettingsDialog, OutOfServiceDialog, ShelveDialog
from app.ui.alarm_panel import AlarmPanel
from app.ui.alarm_sound import AlarmSound, tone_wav

pytestmark = pytest.mark.gui

T0 = 1_800_000_000.0


@pytest.fixture
def setup(qtbot):
    mon = AlarmMonitor([LimitRule("temp_c", high=45.0, deadband=1.0, unit="°C",
                                  label="Temperature"),
                        LimitRule("gas_lel_pct", high=10.0, unit="%LEL", label="Gas",
                                  priority=Priority.HIGH)])
    now = [T0]
    panel = AlarmPanel(mon, user="ana", clock=lambda: now[0])
    banner = AlarmBanner(mon)
    mon.add_listener(panel.on_transition)
    mon.add_listener(lambda _tr: banner.refresh())
    qtbot.addWidget(panel)
    qtbot.addWidget(banner)
    panel.show()
    seen = []
    mon.add_listener(seen.append)
    return mon, panel, banner, seen, now


def test_acknowledge_from_the_panel_reaches_the_listener(qtbot, setup):
    mon, panel, banner, seen, now = setup
    mon.update("temp_c", 50.0, T0)
    [row] = panel.rows()
    assert row["State"] == "ACTIVE, unacknowledged" and row["Priority"] == "■ MEDIUM"
    assert banner.text().startswith("■ MEDIUM: Temperature 50.0 °C above limit 45 °C")
    assert banner.level() == "medium"
    assert not panel.ack_button.isEnabled()  # nothing selected
    panel.select_row(0)
    assert panel.ack_button.isEnabled()
    now[0] = T0 + 5
    qtbot.keyClick(panel.table, Qt.Key.Key_K, Qt.KeyboardModifier.ControlModifier)
    tr = seen[-1]
    assert (tr.from_state, tr.to_state, tr.user, tr.t) == (
        AlarmState.UNACK, AlarmState.ACKED, "ana", T0 + 5)
    assert tr.as_record()["to_state"] == "ACKED" and tr.as_record()["user"] == "ana"
    assert panel.rows()[0]["State"] == "ACTIVE, acknowledged"
    assert banner.text().startswith("No unacknowledged alarms (1 standing")
    assert banner.level() == ""
    assert any("acknowledged by ana" in line for line in panel.log_lines())


def test_acknowledge_all_visible_respects_the_filter(qtbot, setup):
    mon, panel, banner, seen, now = setup
    mon.update("temp_c", 50.0, T0)
    mon.update("gas_lel_pct", 20.0, T0 + 1)
    assert banner.text().startswith("▲ HIGH: Gas") and "(+1 more unacknowledged)" in banner.text()
    assert [r["key"] for r in panel.rows()] == ["gas_lel_pct.high", "temp_c.high"]
    panel.set_filters(priority=Priority.HIGH)
    assert [r["key"] for r in panel.rows()] == ["gas_lel_pct.high"]
    qtbot.keyClick(panel.table, Qt.Key.Key_K,
                   Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert mon.state("gas_lel_pct.high") is AlarmState.ACKED
    assert mon.state("temp_c.high") is AlarmState.UNACK  # not visible: left alone
    panel.set_filters(source="temp_c")  # unnamed filters go back to "all"
    assert [r["key"] for r in panel.rows()] == ["temp_c.high"]
    panel.set_filters(priority=Priority.HIGH, source="temp_c")
    assert [r["key"] for r in panel.rows()] == []
    panel.set_filters(state="Unacknowledged")
    assert [r["key"] for r in panel.rows()] == ["temp_c.high"]
    panel.set_filters()
    assert len(panel.rows()) == 2


def test_shelve_with_dialog_then_expiry(qtbot, setup):
    mon, panel, banner, seen, now = setup
    mon.update("temp_c", 50.0, T0)
    panel.select_row(0)
    dlg = ShelveDialog(mon.get("temp_c.high"), mon.max_shelve_s)
    qtbot.addWidget(dlg)
    ok = dlg.buttons.button(dlg.buttons.StandardButton.Ok)
    assert not ok.isEnabled()  # a reason is required
    dlg.minutes.setValue(30)
    dlg.reason.setText("sensor being cleaned")
    assert ok.isEnabled()
    trs = panel.shelve_selected(dlg)
    assert trs[0].to_state is AlarmState.SHELVED and trs[0].reason == "sensor being cleaned"
    row = panel.rows()[0]
    assert row["State"].startswith("SHELVED until") and "sensor being cleaned" in row["State"]
    assert banner.text() == "No active alarms"
    mon.tick(T0 + 30 * 60)
    assert seen[-1].reason == "shelving expired" and panel.rows()[0]["State"].startswith("ACTIVE")


def test_bad_shelve_is_refused_with_a_message(qtbot, setup):
    mon, panel, banner, seen, now = setup
    mon.update("temp_c", 50.0, T0)
    assert panel.shelve("temp_c.high", 60.0, "") == []
    assert panel.shelve("temp_c.high", -5, "x") == []
    assert len(panel.errors) == 2 and "needs a reason" in panel.errors[0]
    assert mon.state("temp_c.high") is AlarmState.UNACK


def test_out_of_service_and_back(qtbot, setup):
    mon, panel, banner, seen, now = setup
    mon.update("temp_c", 50.0, T0)
    panel.select_row(0)
    dlg = OutOfServiceDialog(mon.get("temp_c.high"))
    qtbot.addWidget(dlg)
    dlg.reason.setText("probe replaced")
    panel.out_of_service_selected(dlg)
    assert mon.state("temp_c.high") is AlarmState.OUT_OF_SERVICE
    assert panel.rows()[0]["State"] == "OUT OF SERVICE (probe replaced)"
    panel.select_row(0)
    assert panel.in_service_button.isEnabled() and not panel.shelve_button.isEnabled()
    panel.in_service_selected()
    assert mon.state("temp_c.high") is AlarmState.UNACK


def test_flood_groups_by_source_and_says_so(qtbot, setup):
    mon, panel, banner, seen, now = setup
    for i in range(14):
        mon.set_condition(f"robot.f{i}", True, T0 + i, source="robot" if i % 2 else "link",
                          priority=Priority.LOW, text=f"fault {i}")
    now[0] = T0 + 14
    panel.refresh()
    assert panel.flood_label.isVisible() and "ALARM FLOOD" in panel.flood_label.text()
    assert panel.group_box.isChecked()
    rows = panel.rows()
    assert {r["Source"] for r in rows} == {"robot", "link", "alarms"}
    grp = next(r for r in rows if r["Source"] == "robot")
    assert grp["State"] == "GROUP" and grp["Alarm"] == "7 alarms (7 unacknowledged)"
    assert banner.text().startswith("ALARM FLOOD — ")
    # only the notice sounded (silently, offscreen), not fourteen alarms
    assert sum(panel.sound.requested.values()) == 10 + 1  # 10 before the flood, the notice
    # acknowledging a group row acknowledges its alarms
    r = next(i for i, row in enumerate(rows) if row["Source"] == "robot")
    panel.select_row(r)
    panel.acknowledge_selected()
    assert all(mon.state(f"robot.f{i}") is AlarmState.ACKED for i in range(1, 14, 2))
    assert mon.state(FLOOD_ID) is AlarmState.UNACK


def test_sound_is_silent_offscreen_and_mutable(qtbot, tmp_path):
    s = AlarmSound()
    assert s.silent  # offscreen
    assert s.play(Priority.HIGH) is False and s.requested[Priority.HIGH] == 1
    s.set_muted(True)
    assert s.muted and s.play(Priority.LOW) is False
    f = tone_wav(tmp_path / "t.wav", 1000.0, 2, 0.05)
    assert f.stat().st_size > 44


def test_banner_text_is_not_colour_only():
    assert banner_text(None, 0, 0, False) == "No active alarms"
    mon = AlarmMonitor([LimitRule("x", high=1.0, priority=Priority.EMERGENCY, label="X")])
    mon.update("x", 2.0, 1.0)
    text = banner_text(mon.most_severe_unacknowledged(), 1, 1, False)
    assert text.startswith("◆ EMERGENCY: X")


def test_settings_dialog_validates_and_applies(qtbot):
    cfg = default_alarm_config()
    dlg = AlarmSettingsDialog(cfg)
    qtbot.addWidget(dlg)
    ok = dlg.buttons.button(dlg.buttons.StandardButton.Ok)
    assert dlg.validate() == [] and ok.isEnabled()
    dlg.set_cell("temp_c", "High", "hot")
    assert not ok.isEnabled()
    assert "settings: [limit.temp_c] high: expected a number, got 'hot'" in dlg.problems.text()
    dlg.set_cell("temp_c", "High", "40")
    dlg.set_cell("temp_c", "Low", "41")
    assert "low 41.0 >= high 40.0" in dlg.problems.text() and dlg.config() is None
    dlg.set_cell("temp_c", "Low", "")
    dlg.set_cell("temp_c", "Priority", "EMERGENCY")
    dlg.set_cell("temp_c", "On delay s", "3")
    assert ok.isEnabled()
    new = dlg.config()
    t = new.limit("temp_c")
    assert (t.high, t.low, t.priority, t.on_delay_s) == (40.0, None, Priority.EMERGENCY, 3.0)
    assert new.rates == cfg.rates  # what the dialog does not show is kept


def test_settings_dialog_saves_a_file_that_loads_back(qtbot, tmp_path):
    from app.core.alarms import load_alarm_config

    dlg = AlarmSettingsDialog(default_alarm_config())
    qtbot.addWidget(dlg)
    dlg.set_cell("humidity_pct", "High", "85")
    dlg.save(tmp_path / "a.toml")
    back, problems = load_alarm_config(tmp_path / "a.toml")
    assert problems == [] and back.limit("humidity_pct").high == 85.0


def test_acknowledge_in_the_window_is_found_in_the_archive(qtbot, window, link, tmp_path):
    from app.core.records import Archive

    archive = Archive(tmp_path / "desk.sqlite")
    try:
        mon = window.telemetry_model.monitor
        mon.add_listener(lambda tr: archive.add_alarm_transition(tr.as_record()))
        with qtbot.waitSignal(window.telemetry_model.alarm_raised, timeout=1000):
            link.send_telemetry(T0, temp_c=50.0)
        panel = window.alarm_panel
        panel.user = "ana"
        assert panel.select_alarm("temp_c.high")
        panel._clock = lambda: T0 + 7
        window.alarm_panel.ack_action.trigger()
        assert archive.flush(5.0)
        got = [(r["alarm"], r["from_state"], r["to_state"], r["user"])
               for r in archive.alarm_transitions(T0 - 1, T0 + 10)]
        assert got == [("temp_c.high", "NORMAL", "UNACK", None),
                       ("temp_c.high", "UNACK", "ACKED", "ana")]
        [ack] = [r for r in archive.alarm_transitions(T0 + 5, T0 + 10)]
        assert ack["t"] == T0 + 7 and ack["priority"] == "MEDIUM" and ack["limit"] == 45.0
    finally:
        archive.close()


def test_selecting_an_alarm_shows_its_trend_with_limits(qtbot, window, link):
    for i in range(3):
        link.send_telemetry(T0 + i, battery_v=21.0 + 0.1 * i)
    panel = window.alarm_panel
    assert panel.select_alarm("battery_v.low")
    dp = window.data_panel
    assert dp.trend_channel == "battery_v"
    assert dp.strip.limit_lines(dp.TREND) == {"low 22 V": 22.0}
    t, y = dp._source(dp.TREND, 60.0)
    assert list(y) == pytest.approx([21.0, 21.1, 21.2])


def test_link_lost_is_an_alarm(qtbot, window, link):
    link.state_changed.emit("connected")
    link.state_changed.emit("lost")
    a = window.telemetry_model.monitor.get("link.lost")
    assert a is not None and a.state is AlarmState.UNACK and a.priority is Priority.HIGH
    assert window.banner_text().startswith("▲ HIGH: Link to the robot lost")
    link.state_changed.emit("connected")
    assert window.telemetry_model.monitor.state("link.lost") is AlarmState.RTN_UNACK


def test_settings_applied_in_the_window_move_the_limit_lines(qtbot, window):
    dlg = AlarmSettingsDialog(window.telemetry_model.alarm_config)
    qtbot.addWidget(dlg)
    dlg.set_cell("temp_c", "High", "40")
    assert window.open_alarm_settings(dlg)
    assert window.telemetry_model.monitor.rule("temp_c").high == 40.0
    assert window.data_panel.strip.limit_lines("temp_c") == {"high 40 °C": 40.0}


def test_window_keys_acknowledge_on_the_telemetry_clock(qtbot, window, link):
    link.send_telemetry(T0, temp_c=50.0, humidity_pct=95.0)
    panel = window.alarm_panel
    seen = []
    window.telemetry_model.alarm_changed.connect(seen.append)
    assert panel.select_alarm("temp_c.high")
    qtbot.keyClick(window, Qt.Key.Key_K, Qt.KeyboardModifier.ControlModifier)
    assert [(t.alarm.key, t.to_state) for t in seen] == [("temp_c.high", AlarmState.ACKED)]
    assert T0 <= seen[0].t < T0 + 60  # the telemetry's time base, not the test machine's
    qtbot.keyClick(window, Qt.Key.Key_K,
                   Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert window.telemetry_model.monitor.state("humidity_pct.high") is AlarmState.ACKED
    assert window.banner.level() == ""


def test_settings_dialog_edits_rate_stale_and_fault_rules(qtbot):
    dlg = AlarmSettingsDialog(default_alarm_config())
    qtbot.addWidget(dlg)
    dlg.set_cell("gas_lel_pct", "Rise per min", "3", section="rate")
    dlg.set_cell("temp_c", "After s", "30", section="stale")
    dlg.set_cell("FAILSAFE_STOP", "Priority", "EMERGENCY", section="flag")
    cfg = dlg.config()
    assert cfg.rates[0].rise_per_min == 3.0
    assert next(r for r in cfg.stale if r.channel == "temp_c").after_s == 30.0
    assert cfg.flags["FAILSAFE_STOP"][0] is Priority.EMERGENCY
    dlg.set_cell("gas_lel_pct", "Deadband", "4", section="rate")  # not below the rise
    assert dlg.config() is None and "[rate.gas_lel_pct]" in dlg.problems.text()
    dlg.set_cell("temp_c", "After s", "soon", section="stale")
    assert "[stale.temp_c] after_s: expected a number, got 'soon'" in dlg.problems.text()


def test_event_log_keeps_only_its_newest_lines(qtbot):
    """The event log is bounded (each laid-out line costs kilobytes): a desk left
    running keeps the newest EVENT_LOG_LINES lines, oldest dropped first."""
    from app.ui.alarm_panel import EVENT_LOG_LINES

    panel = AlarmPanel(AlarmMonitor(()), user="ana")
    qtbot.addWidget(panel)
    total = 2100  # more than the old bound (2000), so the old panel kept them all
    for i in range(total):
        panel.add_log("info", "desk", f"line {i}", T0 + i)
    lines = panel.log_lines()
    assert EVENT_LOG_LINES <= 1000
    assert len(lines) == EVENT_LOG_LINES
    assert lines[0].endswith(f"line {total - EVENT_LOG_LINES}")
    assert lines[-1].endswith(f"line {total - 1}")


def test_comment_from_another_thread_shown_with_who(qtbot, setup):
    """A control room's comment (the OPC UA server's, run off the GUI thread) is in
    the alarm's row and in the event log, with who made it; a new occurrence of the
    alarm starts without it."""
    import threading

    mon, panel, banner, seen, now = setup
    mon.update("gas_lel_pct", 15.0, T0)
    th = threading.Thread(target=mon.comment, args=("gas_lel_pct.high", T0 + 1,
                                                     "gas team sent"),
                          kwargs={"user": "opcua:op"})
    th.start()
    th.join(5)
    qtbot.waitUntil(lambda: panel.rows()[0]["Comment"] == "opcua:op: gas team sent",
                    timeout=5000)
    assert any("Gas: comment by opcua:op: gas team sent" in line
               for line in panel.log_lines())
    assert mon.comment("no.such.alarm", T0, "?") is None
    # acknowledged and cleared, then raised again: a new occurrence, no comment
    mon.acknowledge("gas_lel_pct.high", T0 + 2, user="ana")
    mon.update("gas_lel_pct", 1.0, T0 + 10)
    mon.update("gas_lel_pct", 1.0, T0 + 20)
    assert not any(r["key"] == "gas_lel_pct.high" for r in panel.rows())
    mon.update("gas_lel_pct", 15.0, T0 + 30)
    [row] = [r for r in panel.rows() if r["key"] == "gas_lel_pct.high"]
    assert row["Comment"] == "" and row["State"] == "ACTIVE, unacknowledged"
