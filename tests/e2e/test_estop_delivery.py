"""The e-stop against a real robot process (issue 12, A.1): acknowledged by the
robot when it is there, NOT DELIVERED (an alarm) when it is gone."""

import re

import pytest

from app.comm.link import LinkSettings, RobotLink
from app.core import estop

pytestmark = [pytest.mark.e2e, pytest.mark.gui]


def test_estop_is_acknowledged_by_the_robot_then_not_delivered_once_it_is_gone(qtbot,
                                                                                sim_robot):
    from app.ui.main_window import MainWindow

    link = RobotLink(LinkSettings(reconnect_every_s=5.0, lost_after_s=1.5))
    win = MainWindow(link)
    qtbot.addWidget(win)
    win.show()
    try:
        link.connect_to(sim_robot.host, sim_robot.port)
        qtbot.waitUntil(lambda: win.link_model.state == "connected", timeout=15000)
        win.control_panel.request_estop()
        qtbot.waitUntil(lambda: "acknowledged by the robot" in
                        win.control_panel.estop_status_text(), timeout=10000)
        assert re.fullmatch(r"E-stop sent \d\d:\d\d:\d\d, acknowledged by the robot at "
                            r"\d\d:\d\d:\d\d", win.control_panel.estop_status_text())
        # the robot holds its e-stop: the banner says so
        qtbot.waitUntil(lambda: "E-STOP ENGAGED" in win.banner_text(), timeout=10000)
        sim_robot.kill()
        qtbot.waitUntil(lambda: win.link_model.state in ("lost", "reconnecting"),
                        timeout=10000)
        win.control_panel.request_estop()
        assert win.control_panel.estop_status_text() == (
            "E-STOP NOT DELIVERED — link down: use the robot's own stop")
        assert win.telemetry_model.monitor.is_active(estop.ALARM_ID)
    finally:
        link.shutdown()
