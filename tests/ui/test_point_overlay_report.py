"""A calibrated point in the video overlay and in the report: the overlay marks the carried
pivot, both scale ends and the needle; an out-of-band reading of a calibrated point is
archived with its reference frame, and the report shows the two side by side."""

from __future__ import annotations

import time

import cv2
import numpy as np
import pytest

from app.core.alarms import AlarmMonitor
from app.core.meter import Reading
from app.core.meter_service import MeterRecord
from app.core.recorder import SessionRecorder
from app.core.records import Archive
from app.report.data import gather
from app.report.render import render_html
from app.session import DeskSession
from app.ui.meter_model import ENDS_COLOR, PIVOT_COLOR, reading_overlays
from app.widgets import OverlayLine, OverlayText

from .fakes import FakeLink

pytestmark = pytest.mark.gui


def _calibrated_reading(value) -> Reading:
    return Reading(value, "MPa", 0.93 if value is not None else 0.1,
                   error=None if value is not None else "registration failed: 9 inliers",
                   dial_centre_xy=(320.0, 240.0),
                   scale_ends_xy=((220.0, 320.0), (400.0, 340.0)),
                   pointer_line_xy=((320.0, 240.0), (380.0, 130.0)),
                   method="calibrated-reference")


def test_overlay_marks_pivot_scale_ends_and_needle_without_an_ellipse():
    ovs = reading_overlays(_calibrated_reading(0.9), "PG-101")
    lines = [o for o in ovs if isinstance(o, OverlayLine)]
    texts = {o.text: o for o in ovs if isinstance(o, OverlayText)}
    # the pivot: a cross centred on it
    pivot = [o for o in lines if o.color == PIVOT_COLOR]
    assert len(pivot) == 2
    assert all(abs((o.x0 + o.x1) / 2 - 320) < 1e-9 and abs((o.y0 + o.y1) / 2 - 240) < 1e-9
               for o in pivot)
    # each scale end: a mark labelled min / max, and a spoke from the pivot
    assert texts["min"].color == texts["max"].color == ENDS_COLOR
    spokes = {(o.x1, o.y1) for o in lines if o.color == ENDS_COLOR and (o.x0, o.y0) ==
              (320.0, 240.0)}
    assert spokes == {(220.0, 320.0), (400.0, 340.0)}
    # the needle from the pivot to its tip, and a caption saying how it was read
    assert any((o.x0, o.y0, o.x1, o.y1) == (320.0, 240.0, 380.0, 130.0) for o in lines)
    caption = [t for t in texts if t.startswith("PG-101")]
    assert caption and "0.9" in caption[0] and "calibrated-reference" in caption[0]
    # a refusal still shows where the points were carried, with the reason
    bad = reading_overlays(_calibrated_reading(None), "PG-101")
    assert any("registration failed" in o.text for o in bad if isinstance(o, OverlayText))


def _record(t, value, state, reference) -> MeterRecord:
    return MeterRecord("PG-101", "PG-101", value, "MPa", 0.2, 1.2, state, 0.9, None, "", t,
                       7, 7, "patrol", "pressure_0_1p6mpa", "calibrated-reference",
                       reference)


def test_out_of_band_calibrated_reading_shows_reference_beside_snapshot(qtbot, tmp_path):
    ref_png = tmp_path / "PG-101.png"
    ref = np.zeros((480, 640, 3), np.uint8)
    ref[:, :, 2] = 200  # a red-ish reference (RGB), to tell it from the current frame
    cv2.imwrite(str(ref_png), cv2.cvtColor(ref, cv2.COLOR_RGB2BGR))
    archive = Archive(tmp_path / "a.sqlite3", batch_interval_s=0.05)
    session = DeskSession(FakeLink(), SessionRecorder(tmp_path / "out"), AlarmMonitor(),
                          archive=archive, user="ana")
    try:
        p = session.pipeline
        p.meters.last_image = np.full((480, 640, 3), 60, np.uint8)  # the current frame
        t = time.time() - 30.0
        p.record_meter_record(_record(t, 1.45, "out of band", str(ref_png)))
        p.record_meter_record(_record(t + 10, 0.9, "normal", str(ref_png)))
        p.record_meter_record(_record(t + 20, 1.5, "out of band", None))  # not calibrated
        p.record_meter_record(_record(t + 25, 1.5, "out of band",
                                      str(tmp_path / "gone.png")))  # reference lost
        assert archive.flush()
        refs = [s for s in archive.snapshots(t - 1, t + 30) if s["reason"] == "meter_reference"]
        assert [(s["t"], s["ref"]) for s in refs] == [(t, "PG-101")]
        data = gather(archive, t - 1, t + 30)
    finally:
        session.close()
    assert [r.state for r in data.readings] == ["out of band", "normal", "out of band",
                                               "out of band"]
    with_ref = [r.reference_jpeg is not None for r in data.readings]
    assert with_ref == [True, False, False, False]
    shown = cv2.imdecode(np.frombuffer(data.readings[0].reference_jpeg, np.uint8),
                         cv2.IMREAD_COLOR)
    assert shown[..., 2].mean() < 30 and shown[..., 0].mean() > 150  # BGR: the red frame
    html = render_html(data)
    assert html.count(">reference</td>") == 1 and html.count(">now</td>") == 1
    row = html[html.index(">reference</td>"):]
    row = row[:row.index("</table>")]
    assert row.count("<img ") == 2  # the reference and the current snapshot side by side
