"""With no link nothing that sends a command looks sendable: the drive pad, speed,
Stop, reset, the patrol buttons and go-to are disabled (or refuse and say "no
link"); the EMERGENCY STOP stays pressable and reports NOT DELIVERED."""

import pytest
from PySide6.QtCore import Qt

from app.comm import protocol as P

pytestmark = pytest.mark.gui

SENDING = ("forward", "back", "left", "right", "stop", "speed", "reset_estop",
           "request_control")


@pytest.mark.parametrize("down", ["lost", "reconnecting", "disconnected"])
def test_control_panel_has_nothing_sendable_without_a_link(qtbot, window, link, down):
    cp = window.control_panel
    assert all(cp.controls_enabled()[k] for k in SENDING if k != "request_control")
    link.set_state(down)
    enabled = cp.controls_enabled()
    assert not any(enabled[k] for k in SENDING), enabled
    assert enabled["estop"] and cp.button("estop").isVisible()
    assert cp.no_link_label.isVisible() and "NO LINK" in cp.no_link_label.text()
    # a drive key does nothing
    n = len(link.calls)
    qtbot.keyPress(window, Qt.Key.Key_Up)
    qtbot.keyRelease(window, Qt.Key.Key_Up)
    assert not [c for c in link.calls[n:] if c[0] == "drive"]
    # the e-stop is still tried and says it did not arrive
    qtbot.mouseClick(cp.button("estop"), Qt.MouseButton.LeftButton)
    assert link.calls[-1] == ("estop",)
    assert cp.estop_status_text().startswith("E-STOP NOT DELIVERED")
    # the link returns: everything is sendable again, the line is gone
    link.set_state("connected")
    assert all(cp.controls_enabled()[k] for k in SENDING if k != "request_control")
    assert not cp.no_link_label.isVisible()


def test_a_drive_held_when_the_link_drops_is_released(qtbot, window, link):
    cp = window.control_panel
    qtbot.mousePress(cp.button("forward"), Qt.MouseButton.LeftButton)
    assert link.calls[-1][0] == "drive"
    link.set_state("lost")
    assert link.calls[-1] == ("stop",)  # nothing renews the drive once the link is back
    assert cp.held() == set()
    link.set_state("connected")
    assert link.calls[-1] == ("stop",)


def test_map_panel_patrol_commands_off_without_a_link(qtbot, window, link):
    mp = window.map_panel
    window.views.setCurrentWidget(mp)
    link.patrol_status_received.emit(P.PatrolStatus(state="paused", route="default",
                                                    index=1, points=[], reason="",
                                                    progress=0.2))
    qtbot.waitUntil(lambda: mp.buttons["resume"].isEnabled(), timeout=2000)
    link.set_state("lost")
    assert not any(b.isEnabled() for b in mp.buttons.values())
    assert not mp.goto_point_button.isEnabled()
    assert "No link" in mp.hint.text()
    n = len(link.calls)
    mp.request_start()  # e.g. the route editor's start: refused, and it says so
    mp.request_goto(1.0, 2.0)
    window.resume_patrol()  # F7 from any tab
    assert link.calls[n:] == []
    assert "No link to the robot: goto not sent" in mp.hint.text()
    assert "no link" in window.statusBar().currentMessage()
    link.set_state("connected")
    assert mp.buttons["resume"].isEnabled() and mp.buttons["abort"].isEnabled()
    assert not mp.buttons["start"].isEnabled()  # as the paused patrol allows
    assert "No link" not in mp.hint.text()
    mp.buttons["resume"].click()
    assert link.calls[-1] == ("command", "resume_patrol", {})
