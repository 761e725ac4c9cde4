"""What a patrol report says, gathered from the archive (no Qt).

:func:`gather` reads one time range of an archive (anything with the read API
of ``app.core.records.Archive``) into a :class:`ReportData`, a plain object the
writers in :mod:`app.report.render` lay out. :func:`alarm_handling` folds the
stored alarm transitions into one line per alarm occurrence: when it was raised,
acknowledged (by whom), cleared, shelved or taken out of service.

An out-of-band reading of a calibrated inspection point has the point's reference frame
archived beside it (a snapshot with reason ``meter_reference`` and the meter as its
``ref``, at the reading's time); the report shows the two side by side.  The archive's
tables are unchanged, so older archives read as before.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.core.meter_service import OUT_OF_BAND, REFERENCE_SNAPSHOT_REASON

__all__ = [
    "ENVIRONMENT_CHANNELS", "AlarmLine", "ChannelStats", "MapInfo", "ReportData",
    "Reading", "alarm_handling", "driven_distance", "gather", "path_length",
]

# the environment channels whose min/max/mean a report lists first
ENVIRONMENT_CHANNELS = ("gas_lel_pct", "temp_c", "humidity_pct", "battery_v",
                        "obstacle_front_m")
UNITS = {"gas_lel_pct": "%LEL", "temp_c": "°C", "humidity_pct": "%RH", "battery_v": "V",
         "obstacle_front_m": "m", "obstacle_left_m": "m", "obstacle_right_m": "m",
         "wheel_left_mps": "m/s", "wheel_right_mps": "m/s", "yaw_rate_rps": "rad/s",
         "cmd_linear_mps": "m/s", "cmd_angular_rps": "rad/s"}
PLOT_POINTS = 600
ROUTE_POINTS = 20_000


@dataclass
class MapInfo:
    """The station map as the robot sent it (ROS map_server convention)."""

    png: bytes
    resolution_m: float = 0.1
    origin_x_m: float = 0.0
    origin_y_m: float = 0.0
    width: int = 0
    height: int = 0


@dataclass
class Reading:
    t: float
    point: str
    value: float | None
    unit: str
    confidence: float | None
    state: str
    error: str | None = None
    snapshot_jpeg: bytes | None = None
    reference_jpeg: bytes | None = None  # the calibrated point's reference frame


@dataclass
class AlarmLine:
    """One occurrence of an alarm, from raise to return to normal."""

    alarm: str
    priority: str
    text: str
    source: str = ""
    raised_t: float | None = None
    value: float | None = None
    limit: float | None = None
    unit: str = ""
    acked_t: float | None = None
    acked_by: str | None = None
    cleared_t: float | None = None
    shelved: list[tuple[float, str | None, str | None]] = field(default_factory=list)
    out_of_service: list[tuple[float, str | None, str | None]] = field(default_factory=list)
    final_state: str = ""

    @property
    def handling(self) -> str:
        parts = []
        if self.acked_t is not None:
            parts.append("acknowledged" + (f" by {self.acked_by}" if self.acked_by else ""))
        for _t, user, reason in self.shelved:
            parts.append("shelved" + (f" by {user}" if user else "")
                         + (f" ({reason})" if reason else ""))
        for _t, user, reason in self.out_of_service:
            parts.append("out of service" + (f" by {user}" if user else "")
                         + (f" ({reason})" if reason else ""))
        if self.cleared_t is None:
            parts.append("still standing at the end of the range")
        return "; ".join(parts) if parts else "not acknowledged"


@dataclass
class ChannelStats:
    channel: str
    unit: str
    n: int
    vmin: float
    vmax: float
    mean: float


@dataclass
class ReportData:
    t0: float
    t1: float
    generated_t: float = field(default_factory=time.time)
    source: str = ""
    map: MapInfo | None = None
    poses: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    points: list[dict[str, Any]] = field(default_factory=list)  # name, x, y
    readings: list[Reading] = field(default_factory=list)
    alarms: list[AlarmLine] = field(default_factory=list)
    stats: list[ChannelStats] = field(default_factory=list)
    # channel -> (t, mean, vmin, vmax) arrays, down-sampled for plotting
    plots: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = \
        field(default_factory=dict)
    n_events: int = 0
    n_commands: int = 0
    commands: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # what could not be gathered
    driven_m: float | None = None  # from every pose; None: from ``poses``
    wall: Any = None  # a wall climber's inspection: app.core.desk.wall.WallModel, or None

    @property
    def distance_m(self) -> float:
        if self.driven_m is not None:
            return self.driven_m
        return path_length(self.poses)


def path_length(poses: np.ndarray) -> float:
    """Length of the polyline through the poses' (x, y), in metres."""
    p = np.asarray(poses, float).reshape(-1, 4)
    if len(p) < 2:
        return 0.0
    d = np.diff(p[:, 1:3], axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())


def driven_distance(archive: Any, t0: float, t1: float, chunk_s: float = 3600.0) -> float:
    """Distance driven over ``[t0, t1]`` from every stored pose, read an hour at
    a time so a long range never holds all its poses at once."""
    total, last = 0.0, None
    a = t0
    while a <= t1:
        b = min(t1, a + chunk_s)
        p = np.asarray(archive.poses(a, b), float).reshape(-1, 4)
        if last is not None and len(p) and p[0, 0] == last[0]:
            p = p[1:]  # a pose exactly on the chunk boundary was already counted
        if len(p):
            if last is not None:
                p = np.vstack([last, p])
            total += path_length(p)
            last = p[-1]
        if b >= t1:
            break
        a = b
    return total


def _f(v: Any) -> float | None:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def alarm_handling(records: Iterable[Mapping[str, Any]]) -> list[AlarmLine]:
    """One :class:`AlarmLine` per alarm occurrence, in the order they were raised.

    An occurrence opens when an alarm leaves NORMAL for an active state and
    closes when it returns to NORMAL; acknowledgement, shelving and out of
    service in between are noted on it. Transitions of an alarm whose raise lies
    before the range open a line with ``raised_t`` None."""
    lines: list[AlarmLine] = []
    open_: dict[str, AlarmLine] = {}
    for r in sorted(records, key=lambda r: float(r.get("t", 0.0))):
        aid = str(r.get("alarm", "?"))
        t = float(r.get("t", 0.0))
        frm = str(r.get("from_state", "")).upper()
        to = str(r.get("to_state", "")).upper()
        line = open_.get(aid)
        if line is None:
            line = AlarmLine(alarm=aid, priority=str(r.get("priority", "")),
                             text=str(r.get("text", "") or aid), source=str(r.get("source", "")),
                             unit=str(r.get("unit", "") or ""))
            if frm == "NORMAL" and to in ("UNACK", "ACKED"):
                line.raised_t = t
                line.value, line.limit = _f(r.get("value")), _f(r.get("limit"))
            open_[aid] = line
            lines.append(line)
        user, reason = r.get("user"), r.get("reason")
        if to == "ACKED" or (frm in ("UNACK", "RTN_UNACK") and to == "NORMAL"
                             and user is not None):
            if line.acked_t is None:
                line.acked_t, line.acked_by = t, user
        if to == "SHELVED":
            line.shelved.append((t, user, reason))
        if to == "OUT_OF_SERVICE":
            line.out_of_service.append((t, user, reason))
        if to == "RTN_UNACK" or (to == "NORMAL" and frm in ("ACKED", "UNACK")
                                 and user is None):
            if line.cleared_t is None:
                line.cleared_t = t
        line.final_state = to
        if to == "NORMAL":
            if line.cleared_t is None:
                line.cleared_t = t
            del open_[aid]
    return lines


def _get(obj: Any, name: str, default: Any = None) -> Any:
    if isinstance(obj, Mapping):
        return obj.get(name, default)
    return getattr(obj, name, default)


def gather(archive: Any, t0: float, t1: float, *, source: str = "",
           plot_points: int = PLOT_POINTS) -> ReportData:
    """Read everything a report shows for ``[t0, t1]`` from ``archive``."""
    data = ReportData(float(t0), float(t1), source=source)
    # --- environment channels: exact statistics (the archive's channel_stats),
    # plots down-sampled to min/max buckets
    channels = set(archive.channels())
    for ch in (c for c in ENVIRONMENT_CHANNELS if c in channels):
        st = None
        s = archive.channel_stats(ch, t0, t1)
        if s is not None and s["n"]:
            st = ChannelStats(ch, UNITS.get(ch, ""), int(s["n"]), float(s["min"]),
                              float(s["max"]), float(s["mean"]))
        if st is None:
            continue
        ser = archive.series(ch, t0, t1, max_points=plot_points)
        data.stats.append(st)
        data.plots[ch] = (np.asarray(ser.t, float), np.asarray(ser.mean, float),
                          np.asarray(ser.vmin, float), np.asarray(ser.vmax, float))
    # --- route: at most ROUTE_POINTS poses, evenly spread
    # --- route
    data.poses = np.asarray(archive.poses(t0, t1, max_points=ROUTE_POINTS),
                            float).reshape(-1, 4)
    data.driven_m = driven_distance(archive, t0, t1)
    data.map = _map_info(archive, t1)
    # --- meter readings with their snapshots
    for r in archive.meter_readings(t0, t1, fused_only=True):
        data.readings.append(Reading(
            t=float(_get(r, "t")), point=str(_get(r, "point", "")),
            value=_f(_get(r, "value")), unit=str(_get(r, "unit", "") or ""),
            confidence=_f(_get(r, "confidence")), state=str(_get(r, "state", "") or ""),
            error=_get(r, "error"), snapshot_jpeg=_snapshot_of(archive, r),
            reference_jpeg=_reference_of(archive, r)))
    # --- alarms and their handling
    data.alarms = alarm_handling(archive.alarm_transitions(t0, t1))
    # --- events: patrol points, counts
    events = list(archive.events(t0, t1))
    data.n_events = len(events)
    data.points = _inspection_points(events) or _visited_places(archive, data.readings,
                                                                        events)
    data.commands = [dict(c) if isinstance(c, Mapping) else dict(vars(c))
                     for c in archive.commands(t0, t1)]
    data.n_commands = len(data.commands)
    data.wall = _wall_inspection(events, data.notes)
    return data


def _wall_inspection(events: Iterable[Any], notes: list[str]) -> Any:
    """The last wall-inspection record in the range (a wall climber's desk archives
    one on every change of state and every minute), as a WallModel."""
    from app.core.desk.wall import WALL_EVENT, model_from_record

    last = None
    for ev in events:
        if _get(ev, "kind") == WALL_EVENT:
            d = _get(ev, "data") or {}
            if isinstance(d, Mapping) and isinstance(d.get("wall"), Mapping):
                last = d["wall"]
    if last is None:
        return None
    try:
        return model_from_record(dict(last))
    except (KeyError, TypeError, ValueError) as e:
        notes.append(f"The wall inspection's record does not read: {e}")
        return None


def _snapshot_of(archive: Any, reading: Any) -> bytes | None:
    jpeg = _get(reading, "snapshot_jpeg")
    if jpeg:
        return bytes(jpeg)
    sid = _get(reading, "snapshot_id")
    if sid is None:
        return None
    try:
        return archive.snapshot(sid)
    except (KeyError, LookupError, ValueError):
        return None


def _reference_of(archive: Any, reading: Any, window_s: float = 1.0) -> bytes | None:
    """The reference frame archived with an out-of-band reading (nearest in time within
    ``window_s``), or None."""
    if str(_get(reading, "state", "") or "") != OUT_OF_BAND:
        return None
    t = float(_get(reading, "t"))
    point = str(_get(reading, "point", ""))
    try:
        snaps = [sn for sn in archive.snapshots(t - window_s, t + window_s)
                 if _get(sn, "reason") == REFERENCE_SNAPSHOT_REASON and _get(sn, "ref") == point]
        if not snaps:
            return None
        best = min(snaps, key=lambda sn: abs(float(_get(sn, "t")) - t))
        return archive.snapshot(_get(best, "id"))
    except (AttributeError, KeyError, LookupError, ValueError, TypeError):
        return None


def _map_info(archive: Any, t: float) -> MapInfo | None:
    """The last map received by ``t``, with its geometry from the ``map`` event
    recorded beside it (resolution and origin; the station default of 0.1 m
    at (0, 0) when none was recorded)."""
    png = archive.latest_map(t)
    if not png:
        return None
    info = MapInfo(png=bytes(png))
    for ev in archive.events(-math.inf, t, kinds=["map"]):
        d = _get(ev, "data") or {}
        if isinstance(d, Mapping):
            info.resolution_m = _f(d.get("resolution_m")) or info.resolution_m
            info.origin_x_m = _f(d.get("origin_x_m")) or 0.0
            info.origin_y_m = _f(d.get("origin_y_m")) or 0.0
            info.width = int(_f(d.get("width")) or 0)
            info.height = int(_f(d.get("height")) or 0)
    return info


def _visited_places(archive: Any, readings: list[Reading],
                    events: list[Any]) -> list[dict[str, Any]]:
    """Where the robot stood at each point it reached (``point_reached`` robot
    events) or read a meter at: its pose nearest in time, one mark per point.
    Used when the patrol's own point list was not recorded."""
    moments: list[tuple[float, str]] = []
    for ev in events:
        d = _get(ev, "data") or {}
        inner = d.get("data") if isinstance(d, Mapping) else None
        if isinstance(d, Mapping) and d.get("code") == "point_reached" \
                and isinstance(inner, Mapping) and inner.get("point"):
            moments.append((float(_get(ev, "t")), str(inner["point"])))
    moments += [(r.t, r.point) for r in readings if r.point]
    out: dict[str, dict[str, Any]] = {}
    for t, name in sorted(moments):
        if name in out:
            continue
        near = np.asarray(archive.poses(t - 5.0, t + 5.0), float).reshape(-1, 4)
        if len(near):
            i = int(np.argmin(np.abs(near[:, 0] - t)))
            out[name] = {"name": name, "x": float(near[i, 1]), "y": float(near[i, 2])}
    return list(out.values())


def _inspection_points(events: Iterable[Any]) -> list[dict[str, Any]]:
    """The patrol's inspection points from the last patrol status event that
    listed them (``data.points`` with ``name``, ``x``, ``y``)."""
    points: list[dict[str, Any]] = []
    for ev in events:
        d = _get(ev, "data") or {}
        pts = d.get("points") if isinstance(d, Mapping) else None
        if isinstance(pts, list) and pts:
            found = []
            for p in pts:
                if not isinstance(p, Mapping):
                    continue
                x, y = _f(p.get("x", p.get("x_m"))), _f(p.get("y", p.get("y_m")))
                if x is None or y is None:
                    continue
                found.append({"name": str(p.get("name", p.get("id", ""))), "x": x, "y": y})
            if found:
                points = found
    return points
