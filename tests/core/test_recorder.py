"""The session recorder keeps every row it was given, even when the run dies."""

import csv
import json

import numpy as np

from app.comm import protocol as P
from app.core.recorder import SessionRecorder


def test_rows_are_on_disk_before_close_and_summary_counts_them(tmp_path):
    rec = SessionRecorder(tmp_path)
    for i in range(25):
        t = P.Telemetry(mcu_time_ms=i, gas_lel_pct=1.0 + i, battery_v=24.0)
        t.received_s = 1_700_000_000.0 + i
        rec.telemetry(t)
    rec.pose(P.Pose(1.0, 2.0, 0.5, 0.1, 0.0))
    rec.event("alarm_raised", source="gas_lel_pct.high", priority="HIGH")
    # not closed yet: a crash now must not lose the rows (they are flushed)
    rows = list(csv.reader((tmp_path / "telemetry.csv").open()))
    assert len(rows) == 26 and rows[1][0].startswith("2023-11-14T22:13:20")
    assert rows[-1][rows[0].index("gas_lel_pct")] == "25.0"
    rec.close()
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["counts"]["telemetry"] == 25 and s["counts"]["pose"] == 1
    assert s["last_telemetry"]["gas_lel_pct"] == 25.0
    assert s["active_alarms"] == ["gas_lel_pct.high"]


def test_alarm_cleared_leaves_no_active_alarm(tmp_path):
    rec = SessionRecorder(tmp_path)
    rec.event("alarm_raised", source="temp_c.high")
    rec.event("alarm_cleared", source="temp_c.high")
    assert rec.summary()["active_alarms"] == []
    rec.close()


def test_latency_percentiles_and_a_bad_snapshot_is_counted_not_fatal(tmp_path):
    rec = SessionRecorder(tmp_path)
    rec.frame(0, 0.0, np.zeros((0, 0, 3), np.uint8))  # cannot be written as a JPEG
    for i in range(1, 100):
        rec.frame(i, float(i))
    s = rec.summary()
    assert s["video_latency_ms"]["median"] == 50.0
    assert s["video_latency_ms"]["p95"] == 95.0
    assert s["counts"]["video"] == 100
    assert s["recorder_errors"] == 1
    rec.close()


def test_scans_and_frames_are_recorded_row_by_row(tmp_path):
    rec = SessionRecorder(tmp_path)
    scan = P.LidarScan(5, -3.14, 0.0175, 12.0, np.array([1.0, 2.5, np.inf], np.float32))
    rec.scan(scan)
    rec.frame(7, 12.345)
    rec.map_png(b"\x89PNG fake")
    rows = list(csv.reader((tmp_path / "scans.csv").open()))
    assert rows[1][1] == "5" and rows[1][-3:] == ["1.000", "2.500", "inf"]
    frames = list(csv.reader((tmp_path / "frames.csv").open()))
    assert frames[1][1:] == ["7", "12.35"]
    assert (tmp_path / "map.png").read_bytes().startswith(b"\x89PNG")
    assert rec.summary()["counts"] == {"map": 1, "scan": 1, "video": 1}
    rec.close()


def test_alarm_history_in_memory_is_bounded_and_active_alarms_stay_right(tmp_path):
    rec = SessionRecorder(tmp_path)
    rec.event("alarm_raised", source="battery_v.low")  # raised long before the rest
    for i in range(1000):
        rec.event("alarm_raised" if i % 2 == 0 else "alarm_cleared", source="temp_c.high")
    s = rec.summary()
    assert len(rec.alarms) == 100 and len(s["alarms"]) == 100
    assert s["active_alarms"] == ["battery_v.low"]
    assert s["counts"]["alarm_raised"] == 501
    rec.close()
