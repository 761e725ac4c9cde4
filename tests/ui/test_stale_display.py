"""Values that are no longer current show their age, in the stale look, on a
fake link: telemetry that merely went quiet with the link up, and a lost link."""

import pytest

from app.comm import protocol as P
from app.comm.link import ControlState

pytestmark = pytest.mark.gui


def test_quiet_telemetry_with_the_link_up_shows_its_age(qtbot, window, link):
    link.set_state("connected")
    for _ in range(5):
        link.send_telemetry(mode=int(P.RobotMode.PATROL))
    tiles = [*window.data_panel.tiles.values(), window.control_panel.battery_tile]
    assert not any(t.is_stale() for t in tiles)
    # no update for a few periods (at least 2 s) while the link stays up
    qtbot.waitUntil(lambda: all(t.is_stale() for t in tiles), timeout=6000)
    assert all(t.stale_text().startswith("last known ") for t in tiles)
    assert "last known" in window.control_panel.mode_text()
    assert window.link_status_text() == "link connected"
    assert "no link" not in window.status_texts()["control"]
    link.send_telemetry()
    assert not any(t.is_stale() for t in tiles)
    assert window.control_panel.mode_text() == "mode TELEOP"


def test_lost_link_greys_what_came_before_and_says_no_link(qtbot, window, link):
    link.set_state("connected")
    link.send_telemetry(gas_lel_pct=12.5)  # a standing gas alarm
    link.control_changed.emit(ControlState("me", True, None, ""))
    gas = window.data_panel.tiles["gas_lel_pct"]
    assert gas.alarm_level() == "high" and gas.shown_alarm_level() == "high"
    assert "you have control" in window.control_panel.lease_text()
    link.set_state("lost")
    assert gas.is_stale() and gas.stale_text().startswith("last known ")
    assert gas.shown_alarm_level() == ""  # the alarm stands in the list, the tile is grey
    assert window.telemetry_model.monitor.channel_priority("gas_lel_pct") is not None
    assert "no link" in window.control_panel.lease_text()
    assert window.status_texts()["control"].startswith("control: no link")
    link.set_state("connected")
    link.send_telemetry(gas_lel_pct=12.5)
    assert not gas.is_stale() and gas.shown_alarm_level() == "high"
    assert "you have control" in window.control_panel.lease_text()


def test_the_header_patrol_line_shows_its_age_once_the_link_is_lost(qtbot, window, link):
    from app.widgets import is_stale

    line = window.patrol_label
    link.set_state("connected")
    link.patrol_status_received.emit(P.PatrolStatus(state="paused", route="north",
                                                    reason="operator"))
    qtbot.waitUntil(lambda: "paused by operator" in window.patrol_text(), timeout=2000)
    assert not is_stale(line) and line.property("abnormal") == "true"
    link.set_state("lost")
    qtbot.waitUntil(lambda: "last known " in window.patrol_text(), timeout=2000)
    assert window.patrol_text().startswith("Patrol: paused by operator")
    assert is_stale(line) and line.property("abnormal") == "false"  # no attention colour
    link.set_state("connected")
    link.patrol_status_received.emit(P.PatrolStatus(state="driving", route="north",
                                                    progress=0.5))
    qtbot.waitUntil(lambda: window.patrol_text() == "Patrol: DRIVING · route north · 50 %",
                    timeout=2000)
    assert not is_stale(line)


def test_stale_pose_in_the_status_bar_is_short_enough_to_read(qtbot, window, link):
    """The pose at the left of the status bar once stale: a short form with its age
    ("pose 12.3, -4.5 · 7 s ago") that fits its field; the full text in the tooltip."""
    import re

    from app.widgets import is_stale

    label = window.pose_label
    link.set_state("connected")
    link.pose_received.emit(P.Pose(12.34, -4.56, 1.5708))
    qtbot.waitUntil(lambda: label.text() == "x 12.34 m  y -4.56 m  θ 90°", timeout=2000)
    link.set_state("lost")
    qtbot.waitUntil(lambda: "ago" in label.text(), timeout=3000)
    assert re.fullmatch(r"pose 12\.3, -4\.6 · \d+ s ago", label.text()), label.text()
    assert is_stale(label)
    # shown whole: the field is as wide as the text (nothing cut off at the right)
    window.statusBar().layout().activate()
    qtbot.waitUntil(lambda: label.width() >= label.fontMetrics().horizontalAdvance(
        label.text()), timeout=2000)
    tip = label.toolTip()
    assert "x 12.34 m  y -4.56 m  θ 90°" in tip
    assert re.search(r"last known \d\d:\d\d:\d\d, \d+ s ago", tip), tip
    # an older pose still fits: minutes
    assert label.minimumWidth() >= label.fontMetrics().horizontalAdvance(
        "pose -888.8, -888.8 · 59 min ago")


def test_status_attention_look_is_re_polished_only_when_it_changes(qtbot, window):
    """The status bar's labels get their link figures every second: the attention
    look is set (and the label re-polished) only when it changes."""
    label = window.dropped_label
    polished = []
    style = label.style()
    real = style.polish

    def counting(*args):
        polished.append(args)
        return real(*args)

    style.polish = counting
    try:
        first = window._set_abnormal(label, True)
        n = len(polished)
        again = window._set_abnormal(label, True)
        assert n >= 1 and (first, again) == (True, False) and len(polished) == n
        assert window._set_abnormal(label, False) and label.property("abnormal") == "false"
    finally:
        del style.polish
