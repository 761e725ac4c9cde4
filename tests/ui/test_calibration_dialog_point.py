"""The calibration dialog stores a route point's calibration (no robot): the point is
offered from the active route, its values come from the gauge type's profile, and a
refusal leaves the route as it was."""

from __future__ import annotations

import json

import numpy as np
import pytest

from app.core.meter import load_profile
from app.core.meter_service import MeterService
from app.core.route import load_route
from app.ui.calibration_dialog import CalibrationDialog

pytestmark = pytest.mark.gui

ROUTE = {"name": "r", "points": [
    {"name": "north PG", "kind": "meter", "x_m": 30.0, "y_m": 28.4, "gauge": "PG-101"},
    {"name": "wall", "kind": "tank_wall", "x_m": 19.0, "y_m": 29.9, "gauge": None},
    {"name": "PG-102", "kind": "meter", "x_m": 53.8, "y_m": 35.0, "gauge": "PG-102"}]}


@pytest.fixture
def service(tmp_path):
    route = tmp_path / "r.json"
    route.write_text(json.dumps(ROUTE), encoding="utf-8")
    svc = MeterService()
    assert svc.set_route(route) is None
    return svc


def _frame():
    img = np.full((480, 640, 3), 200, np.uint8)
    img[200:280, 300:340] = 30
    return img


def test_dialog_stores_the_chosen_point_with_the_route(qtbot, service):
    dlg = CalibrationDialog(_frame(), service=service, point="north PG")
    qtbot.addWidget(dlg)
    # meter points only, the robot's point chosen; values from the gauge type's profile
    items = [dlg.target_combo.itemData(i) for i in range(dlg.target_combo.count())]
    assert items == [None, ("north PG", "PG-101"), ("PG-102", "PG-102")]
    assert dlg.target_point() == ("north PG", "PG-101")
    base = service.profile("PG-101")
    assert dlg.name_edit.text() == base.name and not dlg.name_edit.isEnabled()
    assert (dlg.min_spin.value(), dlg.max_spin.value()) == (base.min_value, base.max_value)
    assert not dlg.save_button.isEnabled()
    assert dlg.save() is None and "click the centre" in dlg.error_label.text()
    dlg.set_points((320, 240), (220, 320), (400, 340))
    with qtbot.waitSignal(dlg.point_calibrated) as sig:
        dlg.save_button.click()
    assert sig.args[0] == "north PG"
    route = load_route(service.route_path)
    assert route.points[0].profile == "r.points/north_PG.json"
    prof = load_profile(sig.args[1])
    assert prof.calibration.center == (320.0, 240.0)
    assert prof.calibration.image_path.name == "north_PG.png"
    assert route.points[2].profile is None


def test_dialog_refusal_keeps_the_route(qtbot, service):
    before = service.route_path.read_bytes()
    dlg = CalibrationDialog(_frame(), service=service)
    qtbot.addWidget(dlg)
    assert dlg.target_point() is None and dlg.name_edit.isEnabled()  # a new gauge type
    assert dlg.choose_point("PG-102") and not dlg.choose_point("wall")
    dlg.set_points((320, 240), (321, 241), (400, 340))  # the min mark on the pivot
    assert dlg.save() is None
    assert "from the center" in dlg.error_label.text()
    assert service.route_path.read_bytes() == before
    # back to a new gauge profile: the fields are the operator's again
    assert dlg.choose_point(None) and dlg.name_edit.isEnabled()
