"""Calibrating an inspection point in the desk, against a real sim_robot: the operator reads
PG-101, calibrates the route's point PG-101 on that frame through the meter panel's dialog
(points from its suggestion), the calibration is stored with the route, and the next visit
of the simulated patrol reads the point with the calibrated profile, within a few % FS of
the robot's logged ground truth (which the desk never sees)."""

from __future__ import annotations

import json

import pytest

from app.comm.link import LinkSettings, RobotLink
from app.core.meter import load_profile
from app.core.route import load_route
from app.sim_process import SimRobotProcess
from app.widgets import OverlayText

pytestmark = [pytest.mark.e2e, pytest.mark.gui]

FS_MPA = 1.6  # PG-101: 0 .. 1.6 MPa
ROUTE = {"name": "pg101 only", "points": [
    {"name": "PG-101", "kind": "meter", "x_m": 30.0, "y_m": 28.4, "gauge": "PG-101",
     "dwell_s": 4.0}]}


@pytest.fixture
def robot_at_pg101(tmp_path):
    truth = tmp_path / "truth.jsonl"
    sim = SimRobotProcess(seed=1, extra=["--start-at", "PG-101", "--log-truth", str(truth)])
    sim.start()
    yield sim, truth
    sim.stop()


def _truth(path, gauge: str) -> list[tuple[float, float]]:
    rows = []
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return rows
    for line in text.splitlines():
        try:
            r = json.loads(line)
        except json.JSONDecodeError:
            continue  # a line being written
        rows.append((r["utc_us"] / 1e6, r["gauges"][gauge]))
    return rows


def _near(rows, t: float, window_s: float = 5.0) -> list[float]:
    return [v for tt, v in rows if abs(tt - t) < window_s]


def test_point_calibrated_in_the_desk_reads_on_the_next_patrol_visit(qtbot, tmp_path,
                                                                    robot_at_pg101):
    from app.ui.main_window import MainWindow

    sim, truth = robot_at_pg101
    route_file = tmp_path / "routes" / "pg101.json"
    route_file.parent.mkdir()
    route_file.write_text(json.dumps(ROUTE), encoding="utf-8")
    link = RobotLink(LinkSettings(reconnect_every_s=0.3))
    win = MainWindow(link)
    qtbot.addWidget(win)
    win.show()
    model, panel, editor = win.meter_model, win.meter_panel, win.map_panel.editor
    overlays: list[list] = []
    model.overlays_changed.connect(overlays.append)
    try:
        assert editor.load(route_file)  # the route open in the editor is the active one
        assert model.service.route_path == route_file
        link.connect_to(sim.host, sim.port)
        qtbot.waitUntil(lambda: link.state == "connected", timeout=15000)
        with qtbot.waitSignal(link.frame_decoded, timeout=10000):
            pass

        # 1. the operator reads PG-101 (the gauge type's profile) ...
        panel.gauge_combo.setCurrentText("PG-101")
        panel.read_button.click()
        qtbot.waitUntil(lambda: any(r.source == "operator" for r in model.records()),
                        timeout=30000)
        first = model.records()[-1]
        assert first.value is not None, first.reason
        assert first.reference_image is None  # not calibrated yet
        assert model.last_read_frame is not None

        # 2. ... and calibrates the route's point on that frame through the dialog
        panel.calibrate_button.click()
        dlg = panel.dialog
        assert dlg is not None
        assert dlg.choose_point("PG-101")
        assert dlg.target_point() == ("PG-101", "PG-101")
        assert not dlg.name_edit.isEnabled()  # the values are the gauge type's
        with qtbot.waitSignal(dlg.points_suggested, timeout=10000) as suggested:
            dlg.suggest()
        assert suggested.args == [True], dlg.error_label.text()
        assert len(dlg.points) == 3 and dlg.save_button.isEnabled()
        with qtbot.waitSignal(dlg.point_calibrated, timeout=5000) as stored:
            dlg.save_button.click()
        point, profile_path = stored.args
        assert point == "PG-101"
        # stored with the route: the route names it, the profile carries the reference
        on_disk = load_route(route_file).points[0]
        assert on_disk.profile == "pg101.points/PG-101.json"
        assert str(route_file.parent / on_disk.profile) == profile_path
        prof = load_profile(profile_path)
        assert prof.calibration is not None and prof.calibration.image_path.is_file()
        assert editor.route.points[0].profile == on_disk.profile  # the editor has it too

        # 3. the next visit: the simulated patrol on this route (sent by the editor, with
        # the profile key the robot ignores)
        n_before = len(model.records())
        overlays.clear()
        editor.start_button.click()
        qtbot.waitUntil(lambda: any(r.source == "patrol" for r in
                                    model.records()[n_before:]), timeout=90000)
        rec = next(r for r in model.records()[n_before:] if r.source == "patrol")
        assert rec.point == "PG-101" and rec.gauge_id == "PG-101"
        assert rec.value is not None, rec.reason
        assert rec.method is not None and rec.method.startswith("calibrated"), rec.method
        assert rec.reference_image == str(prof.calibration.image_path)
        assert rec.confidence >= 0.5
        assert panel.row_texts("PG-101")["Note"] == "calibrated point"
        qtbot.waitUntil(lambda: any(tt > rec.t for tt, _ in _truth(truth, "PG-101")),
                        timeout=5000)
        values = _near(_truth(truth, "PG-101"), rec.t)
        assert values
        lo, hi = min(values), max(values)
        assert lo - 0.03 * FS_MPA <= rec.value <= hi + 0.03 * FS_MPA, (rec.value, lo, hi)
        # the video overlay showed the carried-over scale ends during that reading
        labels = {o.text for ovs in overlays for o in ovs if isinstance(o, OverlayText)}
        assert {"min", "max"} <= labels
        assert any("calibrated" in t for t in labels)
        model.wait_idle()
    finally:
        link.shutdown()
