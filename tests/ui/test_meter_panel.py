"""The desk's meter reading: fused readings in the table, overlay, alarms, refusals,
dropping frames while busy, the operator's read button and the calibration dialog."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from PySide6.QtCore import Qt

from app.comm import protocol as P
from app.core.meter import load_profile
from app.widgets import OverlayLine
from sim_robot.gauge_render import render_dial, render_view, stock_spec

from .fakes import Frame

pytestmark = pytest.mark.gui


def _frame(value: float, seed: int, spec_name: str = "paper_0_4mpa", fid: int = 1,
           dial: bool = True) -> Frame:
    rng = np.random.default_rng(seed)
    if dial:
        bgr, _ = render_view(stock_spec(spec_name), value, fill=0.6, tilt_deg=8.0,
                             tilt_axis_deg=30.0, roll_deg=4.0, noise_sigma=2.0, rng=rng,
                             background="clutter", jpeg_quality=85)
    else:  # a frame without any gauge in it: the pipe rack
        bgr = np.full((480, 640, 3), 110, np.uint8)
        cv2.line(bgr, (0, 200), (640, 260), (60, 60, 60), 40)
        bgr = cv2.add(bgr, rng.integers(0, 8, bgr.shape, dtype=np.uint8))
    rgb = np.ascontiguousarray(bgr[:, :, ::-1])
    return Frame(fid, P.now_us(), rgb, 20.0, 640, 480)


@pytest.fixture
def meters(window):
    m = window.meter_model
    m.service.settle_s = 0.0
    yield m
    m.wait_idle()


def _event(link, code, gauge, point="P-7"):
    link.event_received.emit(P.Event("info", code, "", {"point": point, "gauge": gauge}))


def _feed_until_recorded(qtbot, link, m, value, n_max=12, **kw):
    n0 = len(m.records())
    for i in range(n_max):
        if len(m.records()) > n0:
            break
        link.frame_decoded.emit(_frame(value, seed=i, fid=i, **kw))
        qtbot.waitUntil(lambda: not m.busy, timeout=10000)
    assert len(m.records()) > n0, "no record after feeding frames"
    return m.records()[-1]


def test_patrol_inspection_is_fused_into_the_table_with_an_overlay(qtbot, window, link, meters):
    overlays = []
    meters.overlays_changed.connect(overlays.append)
    _event(link, "inspection_started", "PG-102", "P-7")
    assert meters.current_gauge() == "PG-102"
    rec = _feed_until_recorded(qtbot, link, meters, 2.2)
    assert rec.value is not None and abs(rec.value - 2.2) <= 0.01 * 4.0
    assert rec.state == "normal" and rec.confidence >= 0.5 and rec.n_total == 7
    row = window.meter_panel.row_texts("PG-102")
    assert row["Point"] == "P-7" and row["State"] == "normal" and row["Unit"] == "MPa"
    assert abs(float(row["Value"]) - 2.2) < 0.04 and row["Normal band"] == "0.5 … 3"
    # the dial ellipse and the pointer were drawn on the video while reading, then cleared
    shown = [o for o in overlays if o]
    assert shown and sum(isinstance(x, OverlayLine) for x in shown[-1]) >= 30
    assert overlays[-1] == [] and window.video_panel.view._overlays == []
    _event(link, "inspection_done", "PG-102")  # already recorded: nothing more
    assert len(meters.records()) == 1


def test_out_of_band_reading_raises_an_alarm(qtbot, window, link, meters):
    raised = []
    window.telemetry_model.alarm_raised.connect(raised.append)
    _event(link, "inspection_started", "PG-102")
    rec = _feed_until_recorded(qtbot, link, meters, 3.5)
    assert rec.state == "out of band"
    assert raised and raised[0].source == "meter.PG-102" and raised[0].condition == "high"
    assert "Meter PG-102" in window.banner_text()
    assert window.meter_panel.row_texts("PG-102")["State"] == "out of band"


def test_no_dial_gives_no_reading_with_a_reason(qtbot, window, link, meters):
    _event(link, "inspection_started", "PG-101")
    rec = _feed_until_recorded(qtbot, link, meters, 0.0, dial=False)
    assert rec.value is None and rec.state == "no reading" and rec.reason
    row = window.meter_panel.row_texts("PG-101")
    assert row["State"] == "no reading" and row["Value"] == "—" and row["Note"]
    assert not window.telemetry_model.active_alarms()


def test_inspection_done_early_records_what_there_is(qtbot, window, link, meters):
    _event(link, "inspection_started", "PG-102")
    for i in range(3):
        link.frame_decoded.emit(_frame(1.0, seed=i, fid=i))
        qtbot.waitUntil(lambda: not meters.busy, timeout=10000)
    _event(link, "inspection_done", "PG-102")
    rec = meters.records()[-1]
    assert rec.n_total == 3 and rec.value is not None and abs(rec.value - 1.0) < 0.04


def test_frames_arriving_while_busy_are_dropped_not_queued(qtbot, window, link, meters):
    _event(link, "inspection_started", "PG-102")
    frames = [_frame(2.0, seed=i, fid=i) for i in range(3)]
    for i in range(40):  # much faster than a frame can be read
        link.frame_decoded.emit(frames[i % 3])
    assert meters.busy
    assert meters.frames_dropped >= 38  # one frame is being read; the rest were dropped
    assert meters.pool.activeThreadCount() <= 1
    qtbot.waitUntil(lambda: not meters.busy, timeout=10000)
    assert meters.frames_read == 1


def test_operator_reads_a_meter_with_look_at(qtbot, window, link, meters):
    panel = window.meter_panel
    panel.gauge_combo.setCurrentText("PG-101")
    qtbot.mouseClick(panel.read_button, Qt.MouseButton.LeftButton)
    assert ("command", "look_at", {"gauge": "PG-101"}) in link.calls
    assert not panel.read_button.isEnabled()
    rec = _feed_until_recorded(qtbot, link, meters, 0.9, spec_name="pressure_0_1p6mpa")
    assert rec.source == "operator" and abs(rec.value - 0.9) <= 0.016
    assert link.calls[-1] == ("command", "look_at", {"gauge": None})
    assert panel.read_button.isEnabled()


def test_unknown_gauge_event_is_logged_not_read(qtbot, window, link, meters):
    _event(link, "inspection_started", "XX-999")
    assert meters.current_gauge() is None
    assert "XX-999" in window.alarm_panel.log.toPlainText()


def test_calibration_dialog_writes_a_profile_from_three_clicks(qtbot, tmp_path):
    from app.ui.calibration_dialog import CalibrationDialog

    spec = stock_spec("pressure_0_10bar")  # 240 deg scale
    size = 300
    rgb = np.ascontiguousarray(render_dial(spec, 4.0, size)[:, :, ::-1])
    dlg = CalibrationDialog(rgb, save_dir=tmp_path)
    qtbot.addWidget(dlg)
    dlg.resize(900, 500)
    dlg.show()
    qtbot.waitExposed(dlg)
    c = size / 2
    r = spec.tick_outer * size - 3

    def tick(angle):
        a = math.radians(angle)
        return c + r * math.sin(a), c - r * math.cos(a)

    assert not dlg.save_button.isEnabled()
    for x, y in ((c, c), tick(spec.min_angle_deg), tick(spec.max_angle_deg)):
        qtbot.mouseClick(dlg.view, Qt.MouseButton.LeftButton,
                         pos=dlg.view.image_to_widget(x, y).toPoint())
    assert len(dlg.points) == 3 and dlg.save_button.isEnabled()
    dlg.name_edit.setText("test_0_10bar")
    dlg.unit_edit.setText("bar")
    dlg.min_spin.setValue(0.0)
    dlg.max_spin.setValue(10.0)
    dlg.band_check.setChecked(True)
    dlg.normal_min_spin.setValue(2.0)
    dlg.normal_max_spin.setValue(8.0)
    with qtbot.waitSignal(dlg.profile_saved, timeout=2000) as sig:
        qtbot.mouseClick(dlg.save_button, Qt.MouseButton.LeftButton)
    path = tmp_path / "test_0_10bar.json"
    assert sig.args[0] == str(path) and path.exists()
    prof = load_profile(path)
    assert abs(prof.min_angle_deg - spec.min_angle_deg) < 1.5
    assert abs(prof.max_angle_deg - spec.max_angle_deg) < 1.5
    assert prof.normal_min == 2.0 and prof.normal_max == 8.0 and prof.unit == "bar"


def test_calibration_dialog_undo_and_refusal(qtbot, tmp_path):
    from app.ui.calibration_dialog import CalibrationDialog

    dlg = CalibrationDialog(np.zeros((200, 200, 3), np.uint8), save_dir=tmp_path)
    qtbot.addWidget(dlg)
    dlg.add_point(100, 100)
    dlg.add_point(50, 150)
    dlg.undo_point()
    assert dlg.next_step() == "minimum tick"
    assert dlg.save() is None and "click the minimum tick" in dlg.error_label.text()


# ---------------------------------------------------------------- the Qt-free service


def test_service_station_table_profiles_and_rules(tmp_path):
    from app.core.meter_service import MeterService, load_station_gauges

    gauges = load_station_gauges()
    assert gauges["PG-102"].type == "paper_0_4mpa" and gauges["PG-201"].unit == "bar"
    svc = MeterService(gauges, settle_s=0.0)
    rule = svc.alarm_rule("PG-101")
    assert rule.channel == "meter.PG-101" and (rule.low, rule.high) == (0.2, 1.2)
    assert abs(rule.deadband - 0.016) < 1e-9
    with pytest.raises(ValueError, match="no gauge"):
        svc.profile("XX-1")
    bad = tmp_path / "station.json"
    bad.write_text('{"gauges": [{"id": "A"}]}', encoding="utf-8")
    with pytest.raises(ValueError, match="malformed"):
        load_station_gauges(bad)
    with pytest.raises(ValueError, match="station configuration"):
        load_station_gauges(tmp_path / "missing.json")


def test_service_session_without_frames_records_no_reading():
    from app.core.meter_service import MeterService

    svc = MeterService(settle_s=0.0)
    svc.start("CG-301", "P-9")
    assert svc.wants_frame()
    rec = svc.finish()
    assert rec.state == "no reading" and "no frames" in rec.reason and rec.point == "P-9"
    assert not svc.wants_frame() and svc.latest["CG-301"] is rec



def test_an_inspection_without_a_meter_is_not_malformed(qtbot, window, link, meters):
    """Tank walls and valves are inspected too; their events carry no gauge."""
    bad = []
    meters.malformed.connect(bad.append)
    _event(link, "inspection_started", None, point="T-102 east wall")
    _event(link, "inspection_done", None, point="T-102 east wall")
    assert bad == [] and meters.current_gauge() is None
    assert window.malformed_total == 0
