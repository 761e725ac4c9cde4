"""A route made active on the desk has its calibrated points' reference frames measured on
the meter worker then, not on each point's first frame of the patrol."""

import json

import cv2
import numpy as np

import app.core.meter.calibrated as calibrated
from app.core.inspection_points import calibrate_point
from app.core.meter import load_profile
from app.core.meter_service import DEFAULT_GAUGE_DIR
from app.core.recorder import SessionRecorder
from app.session import DeskSession
from app.ui.meter_model import MeterModel
from sim_robot import gauge_render

from .fakes import FakeLink

BASE = load_profile(DEFAULT_GAUGE_DIR / "pressure_0_1p6mpa.json")
CLICKS = ((320.0, 240.0), (220.0, 320.0), (400.0, 340.0))
ROUTE = {"name": "north", "points": [
    {"name": "PG-101", "kind": "meter", "x_m": 30.0, "y_m": 28.4, "gauge": "PG-101",
     "dwell_s": 4.0}]}


def test_a_routes_references_are_measured_on_the_worker(qtbot, tmp_path, monkeypatch):
    route = tmp_path / "routes" / "north.json"
    route.parent.mkdir()
    route.write_text(json.dumps(ROUTE), encoding="utf-8")
    spec = gauge_render.stock_spec("pressure_0_1p6mpa")
    bgr, _ = gauge_render.render_view(spec, 0.9, rng=np.random.default_rng(3),
                                      frame_size=(640, 480), fill=0.6, offset_frac=(0, 0))
    calibrate_point(route, "PG-101", BASE, cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), *CLICKS)
    made = []
    real = calibrated.second_edge
    monkeypatch.setattr(calibrated, "second_edge",
                        lambda *a, **kw: made.append(1) or real(*a, **kw))
    desk = DeskSession(FakeLink(), SessionRecorder(tmp_path / "out"), tick_ms=50)
    calibrated._REFERENCES.clear()
    try:
        model = MeterModel(desk)
        model.set_route(route)
        qtbot.waitUntil(lambda: made == [1] and not desk.jobs.busy, timeout=10000)
        prof = model.service.profile_for("PG-101", "PG-101")
        calibrated._reference_geometry(prof.calibration, prof)
        assert made == [1]  # kept for the point's first frame
        assert model.service.profile_errors == 0
    finally:
        calibrated._REFERENCES.clear()
        desk.close()
