"""The desk tells the operator only what is true (issue 12, A.1, A.4, A.5):
an e-stop is "sent … acknowledged" only once the robot's ack arrives, and NOT
DELIVERED (an alarm) otherwise; a latched e-stop stays in the banner after its
alarm is acknowledged; a paused patrol is shown on every tab and F7 resumes it."""

import re

import pytest
from PySide6.QtCore import Qt

from app.comm import protocol as P
from app.core import estop
from app.core.alarms import AlarmState, Priority

HMS = r"\d\d:\d\d:\d\d"


def _estop_alarm(window):
    mon = window.telemetry_model.monitor
    return mon.get(estop.ALARM_ID) if mon.is_active(estop.ALARM_ID) else None


def test_estop_with_the_link_down_is_not_delivered_and_raises_an_alarm(qtbot, window, link):
    link.set_state("disconnected")
    qtbot.keyClick(window, Qt.Key.Key_Escape)
    text = window.control_panel.estop_status_text()
    assert text == "E-STOP NOT DELIVERED — link down: use the robot's own stop"
    alarm = _estop_alarm(window)
    assert alarm is not None and alarm.priority >= Priority.HIGH
    assert "E-STOP NOT DELIVERED" in window.banner_text()
    assert window.banner.level() in ("emergency", "high")
    assert "sent" not in window.statusBar().currentMessage()
    assert not any("EMERGENCY STOP sent" in line for line in window.alarm_panel.log_lines())


def test_estop_is_reported_acknowledged_only_when_the_ack_arrives(qtbot, window, link):
    link.set_state("connected")
    window.control_panel.request_estop()
    assert link.calls[-1] == ("estop",)
    seq = link._seq  # the fake link numbers its e-stops like the real one
    waiting = window.control_panel.estop_status_text()
    assert re.fullmatch(f"E-stop sent {HMS} — waiting for the robot's acknowledgement", waiting)
    assert "acknowledged by" not in waiting and _estop_alarm(window) is None
    link.ack_received.emit(P.CommandAck(seq + 100, True, ""))  # another command's ack
    assert window.control_panel.estop_status_text() == waiting
    link.ack_received.emit(P.CommandAck(seq, True, ""))
    done = window.control_panel.estop_status_text()
    assert re.fullmatch(f"E-stop sent {HMS}, acknowledged by the robot at {HMS}", done)
    assert done in window.statusBar().currentMessage()
    assert _estop_alarm(window) is None


def test_estop_without_an_ack_is_not_delivered(qtbot, window, link):
    window.estop_delivery.ack_timeout_s = 0.3
    link.set_state("connected")
    window.control_panel.request_estop()
    qtbot.waitUntil(lambda: _estop_alarm(window) is not None, timeout=5000)
    assert window.control_panel.estop_status_text().startswith("E-STOP NOT DELIVERED — no "
                                                               "acknowledgement")
    # a late ack still counts: the alarm returns to normal (it stays until acknowledged)
    link.ack_received.emit(P.CommandAck(link._seq, True, ""))
    assert "acknowledged by the robot" in window.control_panel.estop_status_text()
    state = window.telemetry_model.monitor.state(estop.ALARM_ID)
    assert state in (AlarmState.RTN_UNACK, AlarmState.NORMAL)


def test_estop_refused_or_cut_off_is_not_delivered(qtbot, window, link):
    link.set_state("connected")
    window.control_panel.request_estop()
    link.set_state("lost")
    assert window.control_panel.estop_status_text() == (
        "E-STOP NOT DELIVERED — link lost before the robot acknowledged: use the robot's own stop")
    assert _estop_alarm(window) is not None
    link.set_state("connected")
    window.control_panel.request_estop()
    link.ack_received.emit(P.CommandAck(link._seq, False, "bad_mac"))
    assert window.control_panel.estop_status_text().startswith(
        "E-STOP NOT DELIVERED — refused by the robot (bad_mac)")


def test_latched_estop_stays_in_the_banner_after_its_alarm_is_acknowledged(qtbot, window, link):
    estopped = dict(mode=int(P.RobotMode.ESTOP), alarm_flags=int(P.AlarmFlag.ESTOP))
    link.send_telemetry(**estopped)
    assert "E-STOP ENGAGED" in window.banner_text()
    assert window.alarm_panel.acknowledge_visible()  # the operator acknowledges everything
    link.send_telemetry(**estopped)
    window.banner.refresh()
    assert window.telemetry_model.monitor.most_severe_unacknowledged() is None
    # still engaged: still shown, in its colour, not calm grey
    assert "E-STOP ENGAGED" in window.banner_text()
    assert window.banner.level() == "emergency"
    link.send_telemetry(mode=int(P.RobotMode.FAILSAFE), alarm_flags=int(P.AlarmFlag.FAILSAFE_STOP))
    assert "FAIL-SAFE STOP" in window.banner_text() and "E-STOP" not in window.banner_text()
    link.send_telemetry(mode=int(P.RobotMode.TELEOP), alarm_flags=0)
    assert "E-STOP" not in window.banner_text() and "FAIL-SAFE" not in window.banner_text()


def test_a_robot_estop_clears_the_not_delivered_alarm(qtbot, window, link):
    link.set_state("disconnected")
    window.control_panel.request_estop()  # link down: not delivered
    assert _estop_alarm(window) is not None
    link.send_telemetry(mode=int(P.RobotMode.ESTOP), alarm_flags=int(P.AlarmFlag.ESTOP))
    assert _estop_alarm(window) is None or \
        window.telemetry_model.monitor.state(estop.ALARM_ID) is AlarmState.RTN_UNACK


def _paused(reason="operator took over (drive)"):
    return P.PatrolStatus(state="paused", route="default", index=2, points=[],
                          reason=reason, progress=0.4)


@pytest.mark.parametrize("tab", ["video_panel", "meter_panel", "map_panel"])
def test_a_paused_patrol_is_shown_on_every_tab_and_f7_resumes_it(qtbot, window, link, tab):
    window.views.setCurrentWidget(getattr(window, tab))
    link.patrol_status_received.emit(_paused())
    window.map_model.flush()
    assert window.patrol_label.isVisible()
    assert "paused by operator — F7 resumes" in window.patrol_text()
    assert "operator took over (drive)" in window.patrol_text()
    link.calls.clear()
    qtbot.keyClick(window, Qt.Key.Key_F7)
    assert link.calls == [("command", "resume_patrol", {})]


def test_f7_does_nothing_without_a_paused_patrol(qtbot, window, link):
    link.patrol_status_received.emit(P.PatrolStatus(state="driving", route="default",
                                                    progress=0.5))
    window.map_model.flush()
    assert window.patrol_text().startswith("Patrol: DRIVING")
    link.calls.clear()
    qtbot.keyClick(window, Qt.Key.Key_F7)
    assert link.calls == []
    assert "no paused patrol" in window.statusBar().currentMessage()
