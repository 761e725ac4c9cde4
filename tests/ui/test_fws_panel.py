"""The 4WS robot's wheel display and TEB overlay, offscreen: hidden for other
robots, shown with the wheels' angles, speeds and mode once a 4WS robot reports
them, the TEB plan on the map, and both greyed with their age — never drawn as
live — once the link is lost."""

from __future__ import annotations

import numpy as np
from PySide6.QtGui import QColor

from app.comm.fws_protocol import TebPlan, WheelState
from app.core.freshness import Age, Freshness
from app.ui.fws_panel import FwsViewModel, WheelDisplay

PIVOT = WheelState(1000, 4, (-0.8761, 0.8761, 0.8761, -0.8761), (-0.47, 0.47, -0.47, 0.47))
ARC = WheelState(2000, 2, (0.3, 0.2, -0.3, -0.2), (0.55, 0.65, 0.55, 0.65))


def _plan():
    poses = np.array([[10, 5, 0], [10.5, 5.1, 0.2], [11, 5.3, 0.4], [11.4, 5.6, 0.6]],
                     np.float32)
    return TebPlan(False, poses, np.full(3, 0.3, np.float32))


def _grey_pixels(widget) -> int:
    img = widget.grab().toImage()
    n = 0
    for x in range(0, img.width(), 3):
        for y in range(0, img.height(), 3):
            c = QColor(img.pixel(x, y))
            n += c.blue() > 150 and c.red() < 80  # the live arrows' blue
    return n


def test_wheel_display_shows_the_wheels_and_greys_them_when_the_link_is_lost(window, link,
                                                                            qtbot):
    win = window
    disp = win.wheel_display
    assert not disp.isVisible()  # a skid-steer robot: nothing to show
    link.set_state("connected")
    link.fws_received.emit(PIVOT)
    qtbot.waitUntil(lambda: disp.isVisible() and disp.view.shown)
    assert disp.mode_text() == "mode: turn in place"
    fl = disp.view.wheels[0]
    assert fl.name == "front_left" and fl.x > 0 and fl.y > 0
    assert abs(fl.angle_deg + 50.2) < 0.1 and fl.speed_mps == -0.47
    assert disp.wheel_text(1) == "+50° · +0.47 m/s"
    assert not disp.view.stale and disp.stale_text() == ""

    link.fws_received.emit(ARC)
    qtbot.waitUntil(lambda: disp.mode_text() == "mode: counter-phase")
    assert [round(w.speed_mps, 2) for w in disp.view.wheels] == [0.55, 0.65, 0.55, 0.65]
    qtbot.waitUntil(lambda: _grey_pixels(disp) > 5)  # speed arrows drawn in colour

    link.fws_received.emit(_plan())
    view = win.map_panel.view
    qtbot.waitUntil(lambda: len(view.polyline("teb")) == 4)
    assert np.allclose(view.polyline("teb")[-1], [11.4, 5.6])
    assert len(view.polyline("teb_stale")) == 0

    link.set_state("lost")
    qtbot.waitUntil(lambda: disp.view.stale)
    assert disp.stale_text().startswith("last known ")
    assert disp.stale_text().endswith(" s ago")
    # the numbers stay readable, but nothing is drawn in the live colours
    assert disp.wheel_text(0) == "+17° · +0.55 m/s"
    qtbot.waitUntil(lambda: _grey_pixels(disp) == 0)
    qtbot.waitUntil(lambda: len(view.polyline("teb")) == 0)
    assert len(view.polyline("teb_stale")) == 4

    link.set_state("connected")
    link.fws_received.emit(ARC)
    qtbot.waitUntil(lambda: not disp.view.stale and disp.stale_text() == "")


def test_wheel_display_alone_old_data_and_no_data(qtbot):
    model = FwsViewModel()
    disp = WheelDisplay(model)
    qtbot.addWidget(disp)
    disp.resize(300, 240)
    disp.show()
    qtbot.waitExposed(disp)
    assert disp.mode_text() == "no wheel data" and not disp.view.shown
    model.pipeline.ingest("fws", ARC)
    qtbot.waitUntil(lambda: disp.view.shown and not disp.view.stale)
    # the robot went quiet with the link up: OLD is stale too
    disp.show_freshness(Freshness(Age.OLD, 75.0, 1.7e9))
    assert disp.view.stale and disp.stale_text().endswith("1 min ago")
    # a bad message is counted by the pipeline and changes nothing on show
    assert not model.pipeline.ingest("fws", "not a wheel state")
    assert model.pipeline.malformed == 1 and disp.view.wheels[0].speed_mps == 0.55
