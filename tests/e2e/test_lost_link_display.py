"""The robot process dies mid-patrol: every value the desk got from it shows its
age in the stale look ("last known 15:17:21, 40 s ago"), control says "no link",
and no tile takes an alarm colour — not even once the stale-data alarms stand."""

import re
from dataclasses import replace

import numpy as np
import pytest

from app.comm.link import LinkSettings, RobotLink
from app.ui import theme
from app.ui.alarm_banner import ALARM_EMERGENCY

pytestmark = [pytest.mark.e2e, pytest.mark.gui]

LAST_KNOWN = re.compile(r"last known \d\d:\d\d:\d\d, \d+ (s|min) ago")
POSE_AGE = re.compile(r"^pose -?\d+\.\d, -?\d+\.\d · \d+ (s|min) ago$")
ALARM_COLOURS = (theme.ALARM_HIGH, theme.ALARM_MEDIUM, theme.ALARM_LOW, ALARM_EMERGENCY)
# the shipped stale-data rules (gas and temperature after 10 s without a sample) at this
# shorter delay, as a site may set it: the test waits for them to stand, not for 10 s
STALE_AFTER_S = 3.0


def alarm_colour_share(widget) -> float:
    """The share of ``widget``'s rendered pixels that are (near) an alarm colour."""
    from PySide6.QtGui import QImage

    img = widget.grab().toImage().convertToFormat(QImage.Format.Format_RGB32)
    w, h = img.width(), img.height()
    buf = np.frombuffer(img.constBits(), np.uint8, count=img.sizeInBytes())
    bgr = buf.reshape(h, img.bytesPerLine() // 4, 4)[:, :w, :3].astype(int)
    rgb = bgr[..., ::-1]
    near = np.zeros((h, w), bool)
    for c in ALARM_COLOURS:
        ref = np.array([int(c[i:i + 2], 16) for i in (1, 3, 5)])
        near |= np.abs(rgb - ref).sum(axis=2) < 40
    return float(near.mean())


@pytest.fixture
def desk(qtbot, sim_robot):
    from PySide6.QtWidgets import QApplication

    from app.ui.main_window import MainWindow
    from app.ui.theme import apply_theme

    app = QApplication.instance()
    palette, sheet = app.palette(), app.styleSheet()
    apply_theme(app)  # the desk's look, as the real program has it
    from app.core.alarms.config import default_alarm_config

    alarms = default_alarm_config()
    assert {r.channel for r in alarms.stale} >= {"gas_lel_pct", "temp_c"}
    alarms.stale = [replace(r, after_s=STALE_AFTER_S) for r in alarms.stale]
    link = RobotLink(LinkSettings(reconnect_every_s=0.3))
    win = MainWindow(link, alarm_config=alarms)
    qtbot.addWidget(win)
    win.resize(1440, 900)
    win.show()
    link.connect_to(sim_robot.host, sim_robot.port)
    qtbot.waitUntil(lambda: link.state == "connected", timeout=15000)
    yield win, link
    link.shutdown()
    app.setStyleSheet(sheet)
    app.setPalette(palette)


def test_killed_robot_leaves_no_value_looking_live(qtbot, desk, sim_robot):
    win, link = desk
    cp, dp, mp = win.control_panel, win.data_panel, win.map_panel
    mp.request_start()  # the robot's default route
    qtbot.waitUntil(lambda: "DRIVING" in mp.patrol_text() or "PLANNING" in mp.patrol_text(),
                    timeout=20000)
    qtbot.waitUntil(lambda: "you have control" in cp.lease_text(), timeout=10000)
    qtbot.waitUntil(lambda: win.status_texts()["rtt"] != "RTT — ms", timeout=10000)
    qtbot.waitUntil(lambda: win.pose_label.text().startswith("x "), timeout=10000)
    tiles = [*dp.tiles.values(), cp.battery_tile]
    assert set(dp.tiles) == {"gas_lel_pct", "temp_c", "humidity_pct"}
    assert all(t.value() is not None and not t.is_stale() for t in tiles)
    assert "last known" not in cp.mode_text() + mp.patrol_text()
    assert not mp.view.pose_stale

    sim_robot.kill()
    qtbot.waitUntil(lambda: link.state in ("lost", "reconnecting"), timeout=6000)

    def every_display_says_its_age():
        return (all(LAST_KNOWN.search(t.stale_text()) for t in tiles)
                and LAST_KNOWN.search(cp.mode_text())
                and LAST_KNOWN.search(mp.patrol_text())
                and LAST_KNOWN.search(win.status_texts()["rtt"])
                and POSE_AGE.search(win.pose_label.text())
                and LAST_KNOWN.search(win.pose_label.toolTip())
                and "no link" in cp.lease_text()
                and "no link" in win.status_texts()["control"])

    qtbot.waitUntil(every_display_says_its_age, timeout=5000)
    assert "you have control" not in cp.lease_text()
    assert "DRIVING" in mp.patrol_text() or "PLANNING" in mp.patrol_text()  # the last word
    assert dp.tiles["humidity_pct"].is_stale()
    assert cp.mode_lamp.color() is None  # a hollow grey ring, not a colour
    assert mp.view.pose_stale  # the robot's arrow on the map: hollow, dashed
    for w in (win.pose_label, win.rtt_label, win.lease_status, mp.state_label):
        assert w.property("stale") == "true"

    # the stale-data alarms (gas and temperature, STALE_AFTER_S after their last
    # sample) come up; they are alarms in the list, but the tiles keep the stale look,
    # not an alarm colour
    monitor = win.telemetry_model.monitor
    qtbot.waitUntil(lambda: {"gas_lel_pct.stale", "temp_c.stale"}
                    <= {a.key for a in monitor.active()}, timeout=20000)
    for t in tiles:
        assert t.shown_alarm_level() == "", t
        assert alarm_colour_share(t) < 0.01, (t, alarm_colour_share(t))
        assert LAST_KNOWN.search(t.stale_text())
