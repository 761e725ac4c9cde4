"""The desk while another desk holds the robot's control lease."""

from app.comm.link import ControlState
from app.ui.control_panel import ControlPanel
from app.ui.models import control_text, refusals_text


def test_view_only_disables_driving_and_offers_to_request_control(qtbot):
    cp = ControlPanel()
    qtbot.addWidget(cp)
    drives, stops, asks = [], [], []
    cp.drive_requested.connect(lambda *a: drives.append(a))
    cp.stop_requested.connect(lambda: stops.append(1))
    cp.control_requested.connect(lambda: asks.append(1))
    cp._button_pressed("forward")
    assert drives  # driving works while nobody else has control
    cp.set_view_only(True, control_text("desk-a", False))
    assert stops  # the held drive is released
    assert cp.lease_text() == "view only — desk-a has control"
    assert not cp.button("forward").isEnabled() and not cp.speed_slider.isEnabled()
    assert cp.button("stop").isEnabled() and cp.button("estop").isEnabled()
    n = len(drives)
    cp._button_pressed("left")
    assert len(drives) == n
    assert not cp.request_button.isHidden()
    cp.request_button.click()
    assert asks == [1]
    cp.set_view_only(False, control_text("me", True))
    assert cp.button("forward").isEnabled() and cp.request_button.isHidden()
    cp._button_pressed("forward")
    assert len(drives) == n + 1


def test_control_state_and_texts():
    assert ControlState("desk-a", False).view_only
    assert not ControlState("me", True).view_only and not ControlState().view_only
    assert control_text(None, False) == "control is free"
    assert control_text("me", True, "desk-b") == "you have control — desk-b asks for it"
    text, tip = refusals_text({"by_reason": {"bad_header": 2}, "telemetry_lost": 1,
                               "robot_rejections": {"bad_mac": 3, "conn_limit": 1}})
    assert text == "refused 6 · tel lost 1"
    assert "bad_mac 3" in tip and "bad_header 2" in tip


def test_window_shows_refusals_and_the_lease(qtbot, window, link):
    from app.comm.link import LinkStats

    link.stats_changed.emit(LinkStats(state="connected",
                                      by_reason={"bad_header": 2, "garbage_bytes": 90},
                                      robot_rejections={"bad_mac": 4}, telemetry_lost=1))
    st = window.status_texts()
    assert st["refused"] == "refused 6 · tel lost 1"  # frames; garbage bytes in the tooltip
    assert "bad_mac 4" in window.refused_label.toolTip()
    assert any("desk decoder refused: bad_header 2" in line
               for line in window.alarm_panel.log_lines())
    link.control_changed.emit(ControlState("desk-a", False, None, ""))
    assert window.status_texts()["control"] == "view only — desk-a has control"
    assert not window.control_panel.button("forward").isEnabled()
    link.control_changed.emit(ControlState("me", True, None, ""))
    assert window.control_panel.button("forward").isEnabled()
