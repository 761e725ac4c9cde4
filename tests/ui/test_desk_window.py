"""The desk window against a fake link: data in, intents out."""

import pytest
from PySide6.QtCore import QEvent, Qt
from PySide6.QtGui import QKeyEvent
from PySide6.QtWidgets import QApplication

from app.comm import protocol as P

from .fakes import Stats, make_frame

pytestmark = pytest.mark.gui


def test_title_and_panels(window, link):
    assert window.windowTitle() == "Station Patrol"
    assert window.link_status_text() == "link connected"  # the fixture's link is up
    link.set_state("disconnected")
    assert window.link_status_text() == "link disconnected"
    assert window.banner_text() == "No active alarms"


def test_plots_receive_data_when_telemetry_arrives(qtbot, window, link):
    for i in range(5):
        link.send_telemetry(temp_c=20.0 + i)
    assert len(window.telemetry_model.series("temp_c")) == 5
    curve = window.data_panel.strip.curve("temp_c")

    def plotted():
        x, y = curve.getData()
        return x is not None and len(x) == 5

    qtbot.waitUntil(plotted, timeout=3000)
    assert list(curve.getData()[1]) == [20.0, 21.0, 22.0, 23.0, 24.0]
    assert window.data_panel.tiles["temp_c"].value_text() == "24.0"
    assert window.data_panel.strip.limit_lines("temp_c") == {"high 45 °C": 45.0}


def test_plot_window_selection(window):
    window.window_actions[1].trigger()
    assert window.data_panel.window_minutes() == 1
    window.data_panel.window_box.setCurrentIndex(2)
    assert window.data_panel.window_minutes() == 60


def test_limit_breach_raises_row_and_colours_tile_with_hysteresis(qtbot, window, link):
    tile = window.data_panel.tiles["gas_lel_pct"]
    t0 = 1_800_000_000.0
    link.send_telemetry(t0, gas_lel_pct=2.0)
    assert window.alarm_panel.rows() == [] and tile.alarm_level() == ""
    with qtbot.waitSignal(window.telemetry_model.alarm_raised, timeout=1000):
        link.send_telemetry(t0 + 1, gas_lel_pct=12.5)
    [row] = window.alarm_panel.rows()
    assert row["Source"] == "gas_lel_pct" and row["Alarm"] == "Gas high"
    assert row["State"] == "ACTIVE, unacknowledged" and row["Priority"] == "▲ HIGH"
    assert row["Value"] == "12.50 %LEL" and row["Limit"] == "10 %LEL"
    assert tile.alarm_level() == "high"
    assert window.banner_text().startswith("▲ HIGH: Gas 12.5 %LEL above limit 10 %LEL")
    assert window.banner.property("alarm") == "high"
    # back under the limit but within the deadband: still standing
    link.send_telemetry(t0 + 2, gas_lel_pct=9.8)
    assert window.alarm_panel.rows()[0]["State"].startswith("ACTIVE")
    assert tile.alarm_level() == "high"
    # below the deadband for the off-delay: returns to normal, still unacknowledged
    off = window.telemetry_model.monitor.rule("gas_lel_pct").off_delay_s
    link.send_telemetry(t0 + 3, gas_lel_pct=9.0)
    with qtbot.waitSignal(window.telemetry_model.alarm_cleared, timeout=1000):
        link.send_telemetry(t0 + 3 + off, gas_lel_pct=9.0)
    [row] = window.alarm_panel.rows()
    assert row["State"] == "CLEARED, unacknowledged"
    assert tile.alarm_level() == ""
    assert "(returned to normal)" in window.banner_text()
    assert window.alarm_panel.active_count() == 0
    # acknowledged: gone from the list and from the header
    window.alarm_panel.select_alarm("gas_lel_pct.high")
    window.alarm_panel.ack_action.trigger()
    assert window.alarm_panel.rows() == []
    assert window.banner_text() == "No active alarms" and window.banner.property("alarm") == ""
    assert any("Gas" in line for line in window.alarm_panel.log_lines())


def test_mcu_flag_alarm_and_mode(qtbot, window, link):
    link.send_telemetry(alarm_flags=int(P.AlarmFlag.OBSTACLE_NEAR), mode=int(P.RobotMode.PATROL))
    [row] = window.alarm_panel.rows()
    assert row["key"] == "flag.OBSTACLE_NEAR" and row["Source"] == "robot"
    assert window.control_panel.mode_text() == "mode PATROL"
    link.send_telemetry(alarm_flags=0, mode=int(P.RobotMode.ESTOP), battery_v=21.5)
    assert window.alarm_panel.active_count() == 1  # battery low
    assert window.control_panel.mode_text() == "mode ESTOP"
    assert window.control_panel.mode_lamp.color() is not None
    # the battery figure shows the newest sample of an event-loop pass (app/ui/frame_batch)
    qtbot.waitUntil(lambda: window.control_panel.battery_tile.alarm_level() == "medium",
                    timeout=2000)


def test_forward_button_drives_and_release_stops(qtbot, window, link):
    button = window.control_panel.button("forward")
    qtbot.mousePress(button, Qt.MouseButton.LeftButton)
    assert link.calls[-1][0] == "drive" and link.calls[-1][1] > 0 and link.calls[-1][2] == 0
    qtbot.mouseRelease(button, Qt.MouseButton.LeftButton)
    assert link.calls[-1] == ("stop",)
    qtbot.mousePress(window.control_panel.button("left"), Qt.MouseButton.LeftButton)
    assert link.calls[-1][0] == "drive" and link.calls[-1][1] == 0 and link.calls[-1][2] > 0
    qtbot.mouseRelease(window.control_panel.button("left"), Qt.MouseButton.LeftButton)
    assert link.calls[-1] == ("stop",)


def test_arrow_key_drives_and_release_stops_ignoring_autorepeat(qtbot, window, link):
    qtbot.keyPress(window, Qt.Key.Key_Up)
    assert link.calls[-1][0] == "drive" and link.calls[-1][1] > 0
    n = len(link.calls)
    # the keyboard's auto-repeat while the key is held changes nothing
    for etype in (QEvent.Type.KeyRelease, QEvent.Type.KeyPress) * 3:
        QApplication.sendEvent(window, QKeyEvent(etype, Qt.Key.Key_Up,
                                                 Qt.KeyboardModifier.NoModifier, "", True))
    assert len(link.calls) == n
    qtbot.keyPress(window, Qt.Key.Key_D)  # and turn right
    assert link.calls[-1][0] == "drive" and link.calls[-1][2] < 0
    qtbot.keyRelease(window, Qt.Key.Key_D)
    assert link.calls[-1][0] == "drive" and link.calls[-1][2] == 0
    qtbot.keyRelease(window, Qt.Key.Key_Up)
    assert link.calls[-1] == ("stop",)
    # space stops whatever is held
    qtbot.keyPress(window, Qt.Key.Key_S)
    assert link.calls[-1][0] == "drive" and link.calls[-1][1] < 0
    qtbot.keyPress(window, Qt.Key.Key_Space)
    assert link.calls[-1] == ("stop",)


def test_speed_setting_scales_drive(qtbot, window, link):
    cp = window.control_panel
    cp.set_speed_mps(0.8)
    qtbot.keyPress(window, Qt.Key.Key_W)
    assert link.calls[-1][1] == pytest.approx(0.8)
    qtbot.keyClick(window, Qt.Key.Key_Minus)  # slower while driving: re-sent
    assert link.calls[-1][1] == pytest.approx(0.75)
    qtbot.keyRelease(window, Qt.Key.Key_W)
    assert link.calls[-1] == ("stop",)


def test_estop_button_and_keys(qtbot, window, link):
    qtbot.mouseClick(window.control_panel.button("estop"), Qt.MouseButton.LeftButton)
    assert link.calls[-1] == ("estop",)
    link.calls.clear()
    qtbot.keyClick(window, Qt.Key.Key_Escape)
    assert link.calls == [("estop",)]
    qtbot.keyClick(window, Qt.Key.Key_F1)
    assert link.calls[-1] == ("estop",)
    qtbot.keyClick(window, Qt.Key.Key_R, Qt.KeyboardModifier.ControlModifier
                   | Qt.KeyboardModifier.ShiftModifier)
    assert link.calls[-1] == ("reset_estop",)
    qtbot.mouseClick(window.control_panel.button("reset_estop"), Qt.MouseButton.LeftButton)
    assert link.calls[-1] == ("reset_estop",)


def test_status_bar_shows_lost_and_restored(qtbot, window, link):
    link.set_state("connecting")
    link.set_state("connected")
    assert window.link_status_text() == "link connected"
    assert window.link_lamp.color() is None  # normal: no colour
    link.stats_changed.emit(Stats())
    st = window.status_texts()
    assert st["rtt"] == "RTT 12 ms" and st["dropped"] == "dropped 3"
    assert st["rate"] == "42.0 msg/s"
    link.set_state("lost")
    assert window.link_status_text() == "link lost"
    assert window.link_lamp.color() is not None
    link.set_state("reconnecting")
    assert "reconnecting" in window.link_status_text()
    link.set_state("connected")
    assert window.statusBar().currentMessage() == "Link restored"
    assert any("link restored" in line for line in window.alarm_panel.log_lines())


def test_video_frames_shown_with_rate_and_latency(qtbot, window, link):
    for i in range(3):
        link.frame_decoded.emit(make_frame(i, latency_ms=55.0))
    vp = window.video_panel
    assert vp.view.image_size() == (64, 48)
    assert vp.latency_label.text() == "latency 55 ms"
    assert vp.fps_label.text().endswith("fps")
    assert vp.frame_label.text().startswith("frame 2")


def test_events_and_refused_acks_are_logged(window, link):
    link.event_received.emit(P.Event(level="warning", code="dock", text="docking failed"))
    link.ack_received.emit(P.CommandAck(7, False, "estop active"))
    link.ack_received.emit(P.CommandAck(8, True, ""))
    lines = window.alarm_panel.log_lines()
    assert any("dock: docking failed" in x for x in lines)
    assert any("command 7 refused: estop active" in x for x in lines)
    assert not any("command 8" in x for x in lines)


def test_window_survives_malformed_messages(qtbot, window, link):
    link.telemetry_received.emit("garbage")
    link.telemetry_received.emit(None)
    link.frame_decoded.emit(object())
    bad = make_frame()
    bad.image = "not an image"
    link.frame_decoded.emit(bad)
    link.event_received.emit(12)
    link.ack_received.emit({"ok": False})
    link.stats_changed.emit(Stats(frames_dropped="many"))
    link.state_changed.emit("connected")
    assert window.malformed_total == 7
    assert window.status_texts()["malformed"] == "malformed 7"
    link.send_telemetry(temp_c=30.0)  # still working
    qtbot.waitUntil(lambda: window.data_panel.tiles["temp_c"].value_text() == "30.0",
                    timeout=2000)


def test_failing_link_call_does_not_raise(qtbot, window, link):
    def broken(*_a):
        raise OSError("socket gone")

    link.estop = broken
    qtbot.mouseClick(window.control_panel.button("estop"), Qt.MouseButton.LeftButton)
    assert window.intent_errors == 1


def test_close_sends_stop(qtbot, window, link):
    window.close()
    assert link.calls[-1] == ("stop",)


def test_losing_focus_releases_held_keys(qtbot, window, link):
    qtbot.keyPress(window, Qt.Key.Key_Up)
    assert link.calls[-1][0] == "drive"
    QApplication.sendEvent(window, QEvent(QEvent.Type.WindowDeactivate))
    assert link.calls[-1] == ("stop",)
    assert window.control_panel.held() == set()


def test_keys_reach_the_panel_when_a_child_has_focus(qtbot, window, link):
    box = window.data_panel.window_box
    box.setFocus()
    qtbot.keyPress(box, Qt.Key.Key_Down)  # would change the combo box otherwise
    assert link.calls[-1][0] == "drive" and link.calls[-1][1] < 0
    qtbot.keyRelease(box, Qt.Key.Key_Down)
    assert link.calls[-1] == ("stop",)
    assert window.data_panel.window_minutes() == 10


def test_pose_shown_in_status_bar(qtbot, window, link):
    link.pose_received.emit(P.Pose(1.5, -2.0, 1.5708))
    qtbot.waitUntil(lambda: window.pose_label.text() == "x 1.50 m  y -2.00 m  θ 90°",
                    timeout=2000)
    link.pose_received.emit("nonsense")
    assert window.malformed_total == 1


def test_text_fields_keep_their_keys_but_estop_always_works(qtbot, window, link):
    from PySide6.QtWidgets import QLineEdit

    field = QLineEdit(window.centralWidget())
    field.show()
    field.setFocus()
    n = len(link.calls)
    qtbot.keyClicks(field, "wa -")
    assert field.text() == "wa -"
    assert len(link.calls) == n  # no drive, stop or speed change while typing
    qtbot.keyPress(field, Qt.Key.Key_Escape)
    assert link.calls[-1] == ("estop",)


def test_a_drive_key_held_before_typing_still_stops_on_release(qtbot, window, link):
    from PySide6.QtWidgets import QLineEdit

    qtbot.keyPress(window, Qt.Key.Key_Up)
    assert link.calls[-1][0] == "drive"
    field = QLineEdit(window.centralWidget())
    field.show()
    field.setFocus()
    qtbot.keyRelease(field, Qt.Key.Key_Up)
    assert link.calls[-1] == ("stop",)
