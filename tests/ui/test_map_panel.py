"""The map tab: model, view, patrol intents and the route editor (fake link)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from PySide6.QtCore import Qt

from app.comm import protocol as P
from app.core.mapimage import BLOCKED, FREE, encode_png

from .fakes import FakeLink


@pytest.fixture
def link(qtbot):
    return FakeLink()  # it has the map, path, patrol and obstacle signals


@pytest.fixture
def panel(window):
    window.views.setCurrentWidget(window.map_panel)
    return window.map_panel


def _map_msg(w=80, h=60, res=0.1, ox=-2.0, oy=1.0) -> P.MapImage:
    img = np.full((h, w), FREE, np.uint8)
    img[0, :] = BLOCKED
    return P.MapImage.unpack(P.MapImage(res, ox, oy, w, h, encode_png(img)).pack())


def _commands(link, name):
    return [c[2] for c in link.calls if c[0] == "command" and c[1] == name]


def _send_map(qtbot, window, link, msg=None):
    with qtbot.waitSignal(window.map_model.changed, timeout=2000,
                          check_params_cb=lambda layers: "map" in layers):
        link.map_received.emit(msg or _map_msg())


def test_map_tab_shows_map_with_size_and_extent(qtbot, window, link, panel):
    assert window.views.tabText(window.views.indexOf(panel)) == "Map"
    _send_map(qtbot, window, link)
    assert panel.view.image_item.image.shape == (60, 80)
    assert panel.view.image_rect() == pytest.approx((-2.0, 1.0, 8.0, 6.0))
    # row 0 of the PNG (the wall) is drawn at the top: the flipped image's last row
    assert (panel.view.image_item.image[-1] == BLOCKED).all()
    x, y, w, h = panel.view.view_rect()  # fitted to the map
    assert x <= -2.0 and y <= 1.0 and x + w >= 6.0 and y + h >= 7.0


def test_bad_map_is_counted_not_fatal(qtbot, window, link, panel):
    bad = P.MapImage(0.1, 0, 0, 10, 10, b"\x89PNG not really")
    link.map_received.emit(bad)
    assert window.malformed_total == 1
    assert "Map not shown" in panel.hint.text()


def test_large_map_decodes_off_the_gui_thread(qtbot, window, link, panel):
    _send_map(qtbot, window, link, _map_msg(w=1200, h=900, res=0.05, ox=0, oy=0))
    assert panel.view.image_rect() == pytest.approx((0, 0, 60.0, 45.0))


def test_pose_moves_marker_and_scan_lands_in_map_frame(qtbot, window, link, panel):
    with qtbot.waitSignal(window.map_model.changed, timeout=2000):
        link.pose_received.emit(P.Pose(1.5, 2.0, math.pi / 2))
    assert panel.view.pose == pytest.approx((1.5, 2.0, math.pi / 2))
    link.pose_received.emit(P.Pose(3.0, 4.0, 0.0))
    qtbot.waitUntil(lambda: panel.view.pose == pytest.approx((3.0, 4.0, 0.0)), timeout=2000)
    scan = P.LidarScan(0, 0.0, math.pi / 2, 10.0, np.array([1.0, 2.0, np.inf], np.float32))
    link.scan_received.emit(scan)
    qtbot.waitUntil(lambda: panel.view.points_count() == 2, timeout=2000)
    xy = window.map_model.scan_xy
    assert xy[0] == pytest.approx([4.0, 4.0], abs=1e-5)
    assert xy[1] == pytest.approx([3.0, 6.0], abs=1e-5)


def test_paths_and_obstacles_drawn(qtbot, window, link, panel):
    g = np.array([[0, 0], [1, 0], [1, 2]], np.float32)
    loc = np.array([[0, 0], [0.5, 0.1]], np.float32)
    link.path_received.emit(P.Path(P.Path.GLOBAL, g))
    link.path_received.emit(P.Path(P.Path.LOCAL, loc))
    link.obstacles_received.emit(P.Obstacles(np.array([[2, 2, 0.5, 0, 0.3],
                                                       [4, 1, 0, -0.2, 0.4]], np.float32)))
    qtbot.waitUntil(lambda: panel.view.circles_count() == 2, timeout=2000)
    assert panel.view.polyline("global") == pytest.approx(g)
    assert panel.view.polyline("local") == pytest.approx(loc)
    # a path of the wrong shape is counted, the window keeps going
    link.path_received.emit(P.Path(0, np.zeros(3, np.float32)))
    assert window.malformed_total == 1


def test_click_in_goto_mode_sends_goto_once(qtbot, window, link, panel):
    _send_map(qtbot, window, link)
    view = panel.view
    # a click without the mode armed sends nothing
    pos = view.map_to_widget(1.0, 3.0).toPoint()
    with qtbot.waitSignal(view.clicked, timeout=2000):
        qtbot.mouseClick(view.plot.viewport(), Qt.MouseButton.LeftButton, pos=pos)
    assert _commands(link, "goto") == []
    panel.actions_["goto"].trigger()  # Ctrl+G
    assert panel.goto_mode()
    with qtbot.waitSignal(view.clicked, timeout=2000) as blocker:
        qtbot.mouseClick(view.plot.viewport(), Qt.MouseButton.LeftButton, pos=pos)
    x, y = blocker.args
    assert (x, y) == pytest.approx((1.0, 3.0), abs=0.05)  # one pixel of slack
    (args,) = _commands(link, "goto")
    assert args == pytest.approx({"x_m": x, "y_m": y}, abs=1e-3)
    assert not panel.goto_mode()  # one shot
    assert view.target == pytest.approx((x, y), abs=1e-3)


def test_patrol_buttons_and_status(qtbot, window, link, panel):
    st = P.PatrolStatus(state="driving", route="north", index=1, progress=0.4, points=[
        {"name": "A", "kind": "meter", "x_m": 1, "y_m": 2, "state": "done"},
        {"name": "B", "kind": "valve", "x_m": 3, "y_m": 2, "state": "current"},
        {"name": "C", "kind": "waypoint", "x_m": 3, "y_m": 5, "state": "skipped"}])
    link.patrol_status_received.emit(st)
    qtbot.waitUntil(lambda: panel.points_table.rowCount() == 3, timeout=2000)
    assert panel.state_label.text() == "Patrol: DRIVING"
    assert panel.progress.value() == 40
    assert panel.buttons["pause"].isEnabled() and not panel.buttons["start"].isEnabled()
    assert [m[3] for m in panel.view.markers] == ["done", "current", "skipped"]
    for key, name in (("pause", "pause_patrol"), ("abort", "abort_patrol"),
                      ("dock", "dock")):
        panel.actions_[key].trigger()
        assert _commands(link, name) == [{}]
    panel.points_table.selectRow(2)
    panel.goto_point_button.click()
    assert _commands(link, "goto") == [{"point": "C"}]
    link.patrol_status_received.emit(P.PatrolStatus(state="paused", route="north"))
    qtbot.waitUntil(lambda: panel.buttons["resume"].isEnabled(), timeout=2000)
    panel.actions_["resume"].trigger()
    assert _commands(link, "resume_patrol") == [{}]
    link.patrol_status_received.emit(P.PatrolStatus(state="failed", reason="blocked"))
    qtbot.waitUntil(lambda: panel.reason_label.text() == "blocked", timeout=2000)
    assert "c8102e" in panel.state_label.styleSheet()


def test_start_without_route_uses_robot_default(window, link, panel):
    panel.buttons["start"].click()
    assert _commands(link, "start_patrol") == [{}]


def test_route_editor_round_trip_and_start(qtbot, window, link, panel, tmp_path):
    ed = panel.editor
    _send_map(qtbot, window, link)
    ed.set_add_mode(True)
    assert not panel.goto_mode()
    view = panel.view
    for x, y in ((0.0, 2.0), (1.0, 3.0), (2.0, 4.0)):
        with qtbot.waitSignal(view.clicked, timeout=2000):
            qtbot.mouseClick(view.plot.viewport(), Qt.MouseButton.LeftButton,
                             pos=view.map_to_widget(x, y).toPoint())
    assert ed.route.names() == ["P1", "P2", "P3"]
    assert ed.route.points[1].x_m == pytest.approx(1.0, abs=0.05)
    assert _commands(link, "goto") == []  # add mode never moves the robot
    ed.set_add_mode(False)
    assert len(view.markers) == 3
    ed.remove_point(0)
    assert ed.route.names() == ["P2", "P3"]
    ed.move_point(1, -1)
    assert ed.route.names() == ["P3", "P2"]
    assert ed.rename_point(0, "Gauge hall")
    assert not ed.rename_point(1, "Gauge hall")  # duplicate refused with a message
    assert "already" in ed.message_text()
    ed.set_kind(0, "meter")
    panel.request_start()  # a meter point without a gauge: refused here, with a message
    assert _commands(link, "start_patrol") == []
    assert "needs a 'gauge'" in ed.message_text()
    ed.set_gauge(0, "PG-101")
    ed.set_dwell(0, 5.0)
    ed.set_route_name("east")
    f = tmp_path / "east.json"
    assert ed.save(f)
    saved = json.loads(f.read_text())
    assert saved["name"] == "east"
    assert saved["points"][0] == {"name": "Gauge hall", "kind": "meter",
                                  "x_m": pytest.approx(2.0, abs=0.05),
                                  "y_m": pytest.approx(4.0, abs=0.05),
                                  "gauge": "PG-101", "dwell_s": 5.0}
    ed.clear()
    assert ed.route.points == []
    assert ed.load(f)
    assert ed.route.names() == ["Gauge hall", "P2"]
    assert ed.table.rowCount() == 2 and ed.table.item(0, 1).text() == "Gauge hall"

    panel.actions_["start"].trigger()  # F5: the edited route
    ed.start_button.click()  # the editor's own button does the same
    starts = _commands(link, "start_patrol")
    assert len(starts) == 2 and starts[0] == starts[1] == {"route": saved}


@pytest.mark.parametrize("text, words", [
    ("{not json", "not valid JSON"),
    ('{"name": "x", "points": []}', "empty route"),
    ('{"name": "x", "points": [{"name": "A", "kind": "meter", "x_m": 1}]}', "'y_m'"),
])
def test_bad_route_file_gives_message(window, panel, tmp_path, text, words):
    ed = panel.editor
    ed.add_point(1.0, 1.0)
    f = tmp_path / "bad.json"
    f.write_text(text)
    assert not ed.load(f)
    assert "Could not open the route" in ed.message_text() and words in ed.message_text()
    assert ed.route.names() == ["P1"]  # the route being edited is kept


def test_unsaveable_route_gives_message(window, panel, tmp_path):
    ed = panel.editor
    assert not ed.save(tmp_path / "empty.json")
    assert "empty route" in ed.message_text()
    assert not (tmp_path / "empty.json").exists()


@pytest.mark.parametrize("heading_deg", [0.0, 90.0, -144.0, 34.0])
def test_pose_arrow_points_along_heading(qtbot, heading_deg):
    from app.widgets.map_view import MapView

    view = MapView()
    qtbot.addWidget(view)
    view.resize(300, 300)
    view.show()
    qtbot.waitExposed(view)
    view.set_image(np.full((100, 100), FREE, np.uint8), (0.0, 0.0, 10.0, 10.0))
    view.set_pose(5.0, 5.0, math.radians(heading_deg))
    img = view.plot.grab().toImage()
    c = view.map_to_widget(5.0, 5.0)
    ptr = np.array([[img.pixelColor(x, y).blue() - img.pixelColor(x, y).red()
                     for x in range(img.width())] for y in range(img.height())])
    ys, xs = np.nonzero(ptr > 40)  # the accent-blue arrow
    i = np.hypot(xs - c.x(), ys - c.y()).argmax()  # its tip
    tip_deg = math.degrees(math.atan2(-(ys[i] - c.y()), xs[i] - c.x()))
    assert abs((tip_deg - heading_deg + 180) % 360 - 180) < 8


def _quality_pose(x, y, th, cov=(0.04, 0.0, 0.01), status=P.Pose.STATUS_TRACKING):
    return P.Pose.unpack(P.Pose(x, y, th, 0.0, 0.0, cov[0], cov[1], cov[2], 1e-4, 0.9, 0.03,
                                status).pack())


def test_pose_quality_draws_the_uncertainty_ellipse_and_says_when_lost(qtbot, window, link,
                                                                       panel):
    link.pose_received.emit(_quality_pose(2.0, 3.0, 0.0))
    qtbot.waitUntil(lambda: len(panel.view.polyline("uncertainty")) > 0, timeout=2000)
    e = panel.view.polyline("uncertainty") - np.array([2.0, 3.0])
    # σx 0.2 m, σy 0.1 m: the 95 % ellipse spans 2.45 σ each way
    assert np.abs(e[:, 0]).max() == pytest.approx(0.2 * 2.4477, rel=0.01)
    assert np.abs(e[:, 1]).max() == pytest.approx(0.1 * 2.4477, rel=0.01)
    assert "tracking" in panel.loc_label.text() and "match 90 %" in panel.loc_label.text()
    link.pose_received.emit(_quality_pose(2.0, 3.0, 0.0, status=P.Pose.STATUS_LOST))
    qtbot.waitUntil(lambda: "LOST" in panel.loc_label.text(), timeout=2000)
    # an older robot's pose has no quality: no ellipse, and the line says so
    link.pose_received.emit(P.Pose(2.5, 3.0, 0.0))
    qtbot.waitUntil(lambda: len(panel.view.polyline("uncertainty")) == 0, timeout=2000)
    assert "no quality" in panel.loc_label.text()


def test_set_pose_drag_sends_set_pose_through_the_gateway_once(qtbot, window, link, panel):
    _send_map(qtbot, window, link)
    view = panel.view
    vp = view.plot.viewport()
    a = view.map_to_widget(1.0, 3.0).toPoint()
    b = view.map_to_widget(1.0, 5.0).toPoint()  # facing +y
    # not armed: a drag pans, nothing is sent
    qtbot.mousePress(vp, Qt.MouseButton.LeftButton, pos=a)
    qtbot.mouseRelease(vp, Qt.MouseButton.LeftButton, pos=b)
    assert _commands(link, "set_pose") == []
    panel.actions_["set_pose"].trigger()  # Ctrl+P
    assert panel.set_pose_mode() and view.drag_mode
    a = view.map_to_widget(1.0, 3.0).toPoint()
    b = view.map_to_widget(1.0, 5.0).toPoint()
    with qtbot.waitSignal(view.dragged, timeout=2000):
        qtbot.mousePress(vp, Qt.MouseButton.LeftButton, pos=a)
        qtbot.mouseRelease(vp, Qt.MouseButton.LeftButton, pos=b)
    (args,) = _commands(link, "set_pose")
    assert args["x_m"] == pytest.approx(1.0, abs=0.05)
    assert args["y_m"] == pytest.approx(3.0, abs=0.05)
    assert args["theta_rad"] == pytest.approx(math.pi / 2, abs=0.05)
    assert not panel.set_pose_mode() and not view.drag_mode  # one shot
    assert [e.name for e in window.gateway.entries if e.name == "set_pose"] == ["set_pose"]
    # a press and release on one spot gives no heading: nothing sent, a hint
    panel.actions_["set_pose"].trigger()
    qtbot.mousePress(vp, Qt.MouseButton.LeftButton, pos=a)
    qtbot.mouseRelease(vp, Qt.MouseButton.LeftButton, pos=a)
    assert len(_commands(link, "set_pose")) == 1
    assert "at least 20 cm" in panel.hint.text()


def test_mapping_buttons_send_their_commands_through_the_gateway(qtbot, window, link, panel):
    panel.mapping_buttons["start_mapping"].click()
    panel.map_name.setText("north-yard")
    panel.mapping_buttons["save_map"].click()
    panel.mapping_buttons["stop_mapping"].click()
    assert _commands(link, "start_mapping") == [{}]
    assert _commands(link, "save_map") == [{"name": "north-yard"}]
    assert _commands(link, "stop_mapping") == [{}]
    names = [e.name for e in window.gateway.entries]
    assert names[-3:] == ["start_mapping", "save_map", "stop_mapping"]


def test_hidden_map_tab_draws_nothing_until_shown_then_the_latest(qtbot, window, link):
    """With the camera tab in front the map is not redrawn for every pose and scan;
    the patrol's labels and table still follow, and showing the map tab draws the
    latest of each layer."""
    panel = window.map_panel
    window.views.setCurrentWidget(window.video_panel)
    assert not panel.isVisible()
    with qtbot.waitSignal(window.map_model.changed, timeout=2000):
        link.pose_received.emit(P.Pose(1.0, 1.0, 0.0))
    link.pose_received.emit(P.Pose(3.0, 4.0, 0.5))
    link.scan_received.emit(P.LidarScan(0, 0.0, math.pi / 2, 10.0,
                                        np.array([1.0, 2.0], np.float32)))
    link.patrol_status_received.emit(P.PatrolStatus(state="driving", route="north", points=[
        {"name": "A", "kind": "meter", "x_m": 1, "y_m": 2, "state": "current"}]))
    qtbot.waitUntil(lambda: panel.points_table.rowCount() == 1, timeout=2000)
    qtbot.waitUntil(lambda: {"pose", "scan", "patrol"} <= panel.held_layers(), timeout=2000)
    assert panel.state_label.text() == "Patrol: DRIVING"
    assert panel.view.pose is None and panel.view.points_count() == 0
    assert panel.view.markers == []

    window.views.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: panel.view.pose == pytest.approx((3.0, 4.0, 0.5)), timeout=2000)
    assert panel.view.points_count() == 2
    assert [m[2:] for m in panel.view.markers] == [("A", "current")]
    assert panel.held_layers() == frozenset()
    # shown, it follows each change again
    link.pose_received.emit(P.Pose(5.0, 6.0, 0.0))
    qtbot.waitUntil(lambda: panel.view.pose == pytest.approx((5.0, 6.0, 0.0)), timeout=2000)
