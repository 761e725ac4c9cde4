"""The desk window against a real sim_robot process over a real socket."""

import pytest

from app.comm.link import LinkSettings, RobotLink
from app.sim_process import SimRobotProcess

pytestmark = [pytest.mark.e2e, pytest.mark.gui]


@pytest.fixture
def desk(qtbot, sim_robot):
    from app.ui.main_window import MainWindow

    link = RobotLink(LinkSettings(reconnect_every_s=0.3))
    win = MainWindow(link)
    qtbot.addWidget(win)
    win.show()
    link.connect_to(sim_robot.host, sim_robot.port)
    qtbot.waitUntil(lambda: link.state == "connected", timeout=15000)
    yield win, link
    link.shutdown()


def test_plots_receive_telemetry_and_video(qtbot, desk):
    win, link = desk
    model = win.telemetry_model
    qtbot.waitUntil(lambda: len(model.series("gas_lel_pct")) >= 5, timeout=10000)
    t, y = model.series("temp_c").window(60)
    assert len(y) >= 5 and all(-40 < v < 80 for v in y)
    with qtbot.waitSignal(link.frame_decoded, timeout=10000) as blocker:
        pass
    frame = blocker.args[0]
    assert frame.image.shape == (480, 640, 3)
    assert frame.latency_ms >= 0


def test_forward_button_moves_the_robot(qtbot, desk):
    from PySide6.QtCore import Qt

    win, link = desk
    poses = []
    link.pose_received.connect(poses.append)
    qtbot.waitUntil(lambda: len(poses) >= 2, timeout=10000)
    x0, y0 = poses[-1].x_m, poses[-1].y_m
    button = win.control_panel.button("forward")
    qtbot.mousePress(button, Qt.MouseButton.LeftButton)

    def moved():
        p = poses[-1]
        return ((p.x_m - x0) ** 2 + (p.y_m - y0) ** 2) ** 0.5 > 0.15

    qtbot.waitUntil(moved, timeout=10000)
    qtbot.mouseRelease(button, Qt.MouseButton.LeftButton)
    # released: the robot comes to rest
    qtbot.waitUntil(lambda: abs(poses[-1].v_mps) < 0.02, timeout=10000)


def test_robot_gone_shows_lost_and_return_reconnects(qtbot, desk, sim_robot):
    win, link = desk
    port = sim_robot.port
    sim_robot.kill()
    qtbot.waitUntil(lambda: link.state in ("lost", "reconnecting"), timeout=4000)
    qtbot.waitUntil(lambda: "lost" in win.link_status_text().lower()
                    or "reconnect" in win.link_status_text().lower(), timeout=2000)
    again = SimRobotProcess(seed=1, port=port).start()
    try:
        qtbot.waitUntil(lambda: link.state == "connected", timeout=6000)
        qtbot.waitUntil(lambda: "connected" in win.link_status_text().lower(), timeout=2000)
    finally:
        again.stop()
