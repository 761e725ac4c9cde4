"""A short synthetic patrol written into an archive (no Qt).

``write_sample(archive, t0)`` records ``duration_s`` of telemetry at ``rate_hz``,
poses round a loop, a map, three meter readings with snapshots, one gas alarm (with a snapshot)
that is raised, acknowledged by ``ann`` and clears, one shelved alarm, events
and a command. The values are deterministic, so a test can check what a
history view, a replay or a report shows against what was written.

    python -m app.report.sample --data-dir DIR     write one into DIR's archive
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

__all__ = ["SampleRun", "write_sample"]

# in the patrol status message's shape (protocol.PatrolStatus.points)
POINTS = [{"name": "PG-101", "kind": "meter", "x_m": 12.0, "y_m": 4.0},
          {"name": "PG-102", "kind": "meter", "x_m": 20.0, "y_m": 10.0},
          {"name": "PG-103", "kind": "meter", "x_m": 8.0, "y_m": 14.0}]


@dataclass
class SampleRun:
    t0: float
    t1: float
    telemetry_t: list[float] = field(default_factory=list)
    gas: list[float] = field(default_factory=list)
    readings: list[dict[str, Any]] = field(default_factory=list)
    alarm_t: dict[str, float] = field(default_factory=dict)


def gas_at(k: int) -> float:
    """Gas (%LEL) of sample ``k``: a slow wave, with a plume above 10 %LEL
    between samples 120 and 160."""
    g = 2.0 + 1.0 * math.sin(k / 15.0)
    if 120 <= k < 160:
        g += 10.0
    return round(g, 4)


def _map_png(w: int = 300, h: int = 200) -> bytes:
    img = np.full((h, w), 255, np.uint8)
    img[:3, :] = img[-3:, :] = 0
    img[:, :3] = img[:, -3:] = 0
    img[60:90, 100:160] = 0  # a tank
    ok, buf = cv2.imencode(".png", img)
    assert ok
    return buf.tobytes()


def _jpeg(shade: int) -> bytes:
    img = np.full((96, 128, 3), shade, np.uint8)
    cv2.circle(img, (64, 48), 30, (240, 240, 240), 2)
    ok, buf = cv2.imencode(".jpg", img)
    assert ok
    return buf.tobytes()


def write_sample(archive: Any, t0: float, *, duration_s: float = 30.0,
                 rate_hz: float = 10.0) -> SampleRun:
    n = int(duration_s * rate_hz)
    run = SampleRun(t0, t0 + (n - 1) / rate_hz)
    archive.add_map(t0, _map_png())
    archive.add_event(t0, "map", {"resolution_m": 0.1, "origin_x_m": 0.0, "origin_y_m": 0.0,
                                  "width": 300, "height": 200})
    archive.add_event(t0, "link", {"state": "connected", "level": "info",
                                   "text": "link connected"})
    archive.add_event(t0 + 0.5, "patrol", {"state": "running", "route": "default",
                                           "points": POINTS, "text": "patrol started"})
    archive.add_command(t0 + 0.2, "ann", "start_patrol", {}, seq=7, acked=None)
    archive.ack_command(7, True, "", t0 + 0.3)
    for k in range(n):
        t = t0 + k / rate_hz
        g = gas_at(k)
        values = {"gas_lel_pct": g, "temp_c": round(20.0 + 0.01 * k, 4),
                  "humidity_pct": 55.0, "battery_v": round(25.0 - 0.001 * k, 4),
                  "obstacle_front_m": 3.0, "mode": 2.0}  # PATROL
        archive.add_telemetry(t, values, seq=k)
        run.telemetry_t.append(t)
        run.gas.append(g)
        a = 2 * math.pi * k / n
        archive.add_pose(t, 15.0 + 6.0 * math.cos(a), 9.0 + 5.0 * math.sin(a), a + math.pi / 2)
    # meter readings with snapshots
    for i, (p, v, state) in enumerate(((POINTS[0], 0.42, "normal"),
                                       (POINTS[1], 0.91, "high"),
                                       (POINTS[2], 0.37, "normal"))):
        t = t0 + 5.0 + 8.0 * i
        archive.add_meter_reading(t, p["name"], v, "MPa", 0.93 - 0.01 * i, fused=True,
                                  state=state, snapshot_jpeg=_jpeg(60 + 40 * i))
        run.readings.append({"t": t, "point": p["name"], "value": v, "state": state})
    # the gas alarm: raised at sample 121, acknowledged by ann, clears at 160
    base = {"alarm": "gas_lel_pct.high", "source": "gas_lel_pct", "priority": "HIGH",
            "limit": 10.0, "unit": "%LEL", "text": "Gas high", "reason": None}
    t_raise, t_ack, t_clear = (t0 + 121 / rate_hz, t0 + 130 / rate_hz, t0 + 160 / rate_hz)
    for t, frm, to, user, v in ((t_raise, "NORMAL", "UNACK", None, gas_at(121)),
                                (t_ack, "UNACK", "ACKED", "ann", gas_at(130)),
                                (t_clear, "ACKED", "NORMAL", None, gas_at(160))):
        archive.add_alarm_transition({**base, "t": t, "from_state": frm, "to_state": to,
                                      "user": user, "value": v})
    archive.add_snapshot(t_raise, _jpeg(200), "alarm", ref="gas_lel_pct.high")
    run.alarm_t = {"raised": t_raise, "acked": t_ack, "cleared": t_clear}
    # a humidity alarm shelved by bob
    hb = {"alarm": "humidity_pct.high", "source": "humidity_pct", "priority": "LOW",
          "limit": 90.0, "unit": "%RH", "text": "Humidity high", "value": None}
    archive.add_alarm_transition({**hb, "t": t0 + 20.0, "from_state": "NORMAL",
                                  "to_state": "UNACK", "user": None, "reason": None})
    archive.add_alarm_transition({**hb, "t": t0 + 21.0, "from_state": "UNACK",
                                  "to_state": "SHELVED", "user": "bob",
                                  "reason": "sensor maintenance"})
    archive.add_event(run.t1, "patrol", {"state": "done", "text": "patrol finished"})
    return run


def main(argv: list[str] | None = None) -> int:
    from app.core.records import Archive
    from app.core.records.paths import default_archive_path

    p = argparse.ArgumentParser(prog="python -m app.report.sample", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data-dir", help="data folder (default: the desk's)")
    p.add_argument("--duration", type=float, default=30.0, help="seconds of patrol")
    args = p.parse_args(argv)
    path = default_archive_path(args.data_dir)
    archive = Archive(path)
    t0 = time.time() - args.duration - 1.0
    run = write_sample(archive, t0, duration_s=args.duration)
    archive.close()
    print(f"{path}: {len(run.telemetry_t)} telemetry rows from {run.t0:.1f} to {run.t1:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
