"""Session recorder: everything the desk receives, written to a folder (no Qt).

Files in the output folder:

- ``telemetry.csv``  one row per telemetry message (received time in UTC ISO 8601)
- ``poses.csv``      the robot's pose estimates
- ``scans.csv``      lidar scans: time, angle_min, increment, then the ranges
- ``frames.csv``     every camera frame: id, capture time, latency
- ``map.png``        the robot's occupancy map, when it sends one
- ``events.jsonl``   robot events, link state changes, command acks, alarms
- ``last_frame.jpg`` the most recent camera frame
- ``summary.json``   counts, last values, alarms, link figures (written at close,
  and refreshed every few seconds so a killed run still leaves one)

Rows are flushed as they are written, so a crash loses nothing already received.
"""

from __future__ import annotations

import csv
import json
import logging
import os
import time
from collections import deque
from dataclasses import asdict, fields
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from app.comm import protocol as P

log = logging.getLogger(__name__)

TELEMETRY_FIELDS = [f.name for f in fields(P.Telemetry)]
POSE_FIELDS = [f.name for f in fields(P.Pose)]


def iso_utc(t_s: float | None = None) -> str:
    t = time.time() if t_s is None else t_s
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="milliseconds")


def _rounded(d: dict[str, Any], digits: int = 4) -> dict[str, Any]:
    """float32 fields printed as 1.2400000095 help nobody."""
    return {k: round(v, digits) if isinstance(v, float) else v for k, v in d.items()}


class SessionRecorder:
    def __init__(self, out_dir: str | Path) -> None:
        self.out = Path(out_dir)
        self.out.mkdir(parents=True, exist_ok=True)
        self.started_s = time.time()
        self._t0 = time.monotonic()
        self.counts: dict[str, int] = {}
        self.last_telemetry: P.Telemetry | None = None
        self.last_pose: P.Pose | None = None
        self.alarms: deque[dict[str, Any]] = deque(maxlen=100)  # the latest, for the summary
        self._alarm_active: dict[str, bool] = {}
        self.link: dict[str, Any] = {}
        self.latencies_ms: list[float] = []
        self.errors = 0
        self.archive: dict[str, Any] | None = None  # the archive's figures, set at close
        self._tel_f = open(self.out / "telemetry.csv", "w", newline="", encoding="utf-8")
        self._tel = csv.writer(self._tel_f)
        self._tel.writerow(["received_utc", "seq", *TELEMETRY_FIELDS])
        self._pose_f = open(self.out / "poses.csv", "w", newline="", encoding="utf-8")
        self._pose = csv.writer(self._pose_f)
        self._pose.writerow(["received_utc", *POSE_FIELDS])
        self._ev_f = open(self.out / "events.jsonl", "w", encoding="utf-8")
        self._scan_f = open(self.out / "scans.csv", "w", newline="", encoding="utf-8")
        self._scan = csv.writer(self._scan_f)
        self._scan.writerow(["received_utc", "scan_ts_us", "angle_min_rad",
                             "angle_increment_rad", "range_max_m", "ranges_m..."])
        self._frames_f = open(self.out / "frames.csv", "w", newline="", encoding="utf-8")
        self._frames = csv.writer(self._frames_f)
        self._frames.writerow(["received_utc", "frame_id", "latency_ms"])
        self._last_summary = 0.0

    def count(self, kind: str) -> None:
        self.counts[kind] = self.counts.get(kind, 0) + 1

    def telemetry(self, t: P.Telemetry) -> None:
        self.count("telemetry")
        self.last_telemetry = t
        received = getattr(t, "received_s", time.time())
        self._tel.writerow([iso_utc(received), getattr(t, "seq", ""),
                            *(getattr(t, k) for k in TELEMETRY_FIELDS)])
        self._tel_f.flush()
        self._maybe_summary()

    def pose(self, p: P.Pose) -> None:
        self.count("pose")
        self.last_pose = p
        self._pose.writerow([iso_utc(), *(getattr(p, k) for k in POSE_FIELDS)])
        self._pose_f.flush()

    def scan(self, s: P.LidarScan) -> None:
        self.count("scan")
        self._scan.writerow([iso_utc(), s.scan_ts_us, round(s.angle_min_rad, 6),
                             round(s.angle_increment_rad, 8), s.range_max_m,
                             *(f"{r:.3f}" for r in s.ranges_m.tolist())])
        self._scan_f.flush()

    def map_png(self, png: bytes) -> None:
        """The robot's map as it sent it (a PNG)."""
        self.count("map")
        tmp = self.out / "map.tmp.png"
        tmp.write_bytes(png)
        os.replace(tmp, self.out / "map.png")

    def frame(self, frame_id: int, latency_ms: float, jpeg_or_rgb=None) -> None:
        self.count("video")
        self._frames.writerow([iso_utc(), frame_id, round(latency_ms, 2)])
        self._frames_f.flush()
        if len(self.latencies_ms) < 100_000:
            self.latencies_ms.append(latency_ms)
        if jpeg_or_rgb is not None and self.counts["video"] % 15 == 1:
            self._save_frame(jpeg_or_rgb)

    def _save_frame(self, img) -> None:
        """``img``: the robot's JPEG bytes (written as they came) or an RGB image."""
        try:
            tmp = self.out / "last_frame.tmp.jpg"
            if isinstance(img, (bytes, bytearray, memoryview)):
                tmp.write_bytes(bytes(img))
            else:
                import cv2

                cv2.imwrite(str(tmp), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
            os.replace(tmp, self.out / "last_frame.jpg")
        except Exception as e:  # a snapshot is a convenience; never stop recording
            self.errors += 1
            log.warning("could not save a snapshot: %s", e)

    def event(self, kind: str, **data: Any) -> None:
        self.count(kind)
        rec = {"time_utc": iso_utc(), "kind": kind, **data}
        self._ev_f.write(json.dumps(rec, default=str) + "\n")
        self._ev_f.flush()
        if kind in ("alarm_raised", "alarm_cleared"):
            self.alarms.append(rec)
            self._alarm_active[str(data.get("source", "?"))] = kind == "alarm_raised"

    def link_stats(self, stats: Any) -> None:
        self.link = asdict(stats) if hasattr(stats, "__dataclass_fields__") else dict(stats)

    def _maybe_summary(self) -> None:
        now = time.monotonic()
        if now - self._last_summary > 5.0:
            self._last_summary = now
            self.write_summary()

    def summary(self) -> dict[str, Any]:
        lat = sorted(self.latencies_ms)

        def pct(q: float) -> float | None:
            return round(lat[min(len(lat) - 1, int(q * len(lat)))], 2) if lat else None

        last = _rounded(asdict(self.last_telemetry)) if self.last_telemetry else None
        if last is not None:
            last["alarm_flags_names"] = [f.name for f in P.AlarmFlag
                                         if last["alarm_flags"] & f]
            last["mode_name"] = P.RobotMode(last["mode"]).name \
                if last["mode"] in P.RobotMode._value2member_map_ else str(last["mode"])
        return {
            "started_utc": iso_utc(self.started_s),
            "duration_s": round(time.monotonic() - self._t0, 2),
            "counts": dict(sorted(self.counts.items())),
            "last_telemetry": last,
            "last_pose": _rounded(asdict(self.last_pose)) if self.last_pose else None,
            "alarms": list(self.alarms),
            "active_alarms": self._active_alarms(),
            "video_latency_ms": {"median": pct(0.5), "p95": pct(0.95)},
            "link": self.link,
            "recorder_errors": self.errors,
            "archive": self.archive,
        }

    def _active_alarms(self) -> list[str]:
        return sorted(k for k, v in self._alarm_active.items() if v)

    def write_summary(self) -> Path:
        path = self.out / "summary.json"
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(self.summary(), indent=2, default=str), encoding="utf-8")
        os.replace(tmp, path)
        return path

    def close(self) -> Path:
        path = self.write_summary()
        for f in (self._tel_f, self._pose_f, self._ev_f, self._scan_f, self._frames_f):
            f.close()
        return path
