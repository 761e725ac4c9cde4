"""A session of the archive as an MCAP file with Foxglove's well-known schemas (no Qt).

The file is written by ``foxglove-sdk`` (``foxglove.open_mcap`` on a private
``foxglove.Context``, with the SDK's typed channels): its well-known messages are
protobuf-encoded with the schemas the SDK embeds, so Foxglove, Lichtblick and
PlotJuggler open the file as it is, and nothing of the format is written here. The
SDK's typed API was usable for every message we need, so the lower-level ``mcap``
writer is not used for writing (the tests read the file back with ``mcap``'s reader).

Topics (log time = the archive's time of the row):

====================  ============================  ==================================
topic                 schema                        from
====================  ============================  ==================================
/telemetry            station_patrol.Telemetry      ``telemetry``: one JSON message per
                      (JSON schema)                 received message, every channel a
                                                    field (PlotJuggler and Foxglove's
                                                    Plot panel plot ``/telemetry.gas_lel_pct``)
/pose                 foxglove.PoseInFrame          ``pose`` (frame ``map``)
/tf                   foxglove.FrameTransform       ``pose``: ``map`` -> ``base_link``
/scan                 foxglove.LaserScan            ``scan`` (frame ``base_link``; the
                                                    archive keeps one a second, u16 mm)
/map                  foxglove.Grid                 ``map`` PNG + its ``map`` event (int8
                                                    occupancy: 100 blocked, 0 free, -1 unknown)
/path/global          foxglove.PosesInFrame         ``path``
/path/teb             foxglove.PosesInFrame         ``event`` kind ``fws_teb`` (a 4WS
                                                    robot's TEB plan, compact record)
/meter                station_patrol.MeterReading   ``meter_reading`` (fused readings)
/snapshot/meter       foxglove.CompressedImage      ``snapshot`` reason meter/reference (JPEG)
/snapshot/alarm       foxglove.CompressedImage      ``snapshot`` reason alarm (JPEG)
/events               foxglove.Log                  ``event`` (name = kind, message = data)
/alarms               foxglove.Log                  ``alarm_transition``
/commands             foxglove.Log                  ``command``
====================  ============================  ==================================

Lidar scans are archived decimated (one a second, at most 720 beams:
app/core/records/scans.py); the live server (``app/core/interop``) sends every scan.
Messages of all topics are merged in time order (a streaming reader sees them as
they happened). Telemetry is read in batches of rows and decoded with numpy per
layout; the remaining per-row cost is the JSON text and the SDK's log call.
"""

from __future__ import annotations

import heapq
import json
import logging
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from app.core.records.scans import unpack_ranges

log = logging.getLogger(__name__)

BATCH_ROWS = 20_000
MAP_FRAME, ROBOT_FRAME = "map", "base_link"
TELEMETRY_SCHEMA = "station_patrol.Telemetry"
METER_SCHEMA = "station_patrol.MeterReading"


class ExportError(RuntimeError):
    """Nothing to export, or the file cannot be written (the message says which)."""


@dataclass
class TopicStats:
    schema: str
    count: int = 0
    t0: float = math.inf
    t1: float = -math.inf

    def add(self, t: float) -> None:
        """One more message at ``t`` (each topic's messages come in time order)."""
        if not self.count:
            self.t0 = t
        self.count += 1
        self.t1 = t


@dataclass
class ExportResult:
    path: Path
    topics: dict[str, TopicStats] = field(default_factory=dict)

    @property
    def messages(self) -> int:
        return sum(s.count for s in self.topics.values())


# ------------------------------------------------------------ message builders
_MESSAGES: Any = None


def _fg():
    """``foxglove.messages``, imported on first use (the desk starts without it)."""
    global _MESSAGES
    if _MESSAGES is None:
        import foxglove.messages as m

        _MESSAGES = m
    return _MESSAGES


def stamp(t: float):
    return _fg().Timestamp.from_epoch_secs(float(t))


def yaw_quaternion(theta: float):
    m = _fg()
    return m.Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2.0), w=math.cos(theta / 2.0))


def pose_in_frame(t: float, x: float, y: float, theta: float):
    m = _fg()
    return m.PoseInFrame(timestamp=stamp(t), frame_id=MAP_FRAME, pose=m.Pose(
        position=m.Vector3(x=float(x), y=float(y), z=0.0), orientation=yaw_quaternion(theta)))


def frame_transform(t: float, x: float, y: float, theta: float):
    m = _fg()
    return m.FrameTransform(timestamp=stamp(t), parent_frame_id=MAP_FRAME,
                            child_frame_id=ROBOT_FRAME,
                            translation=m.Vector3(x=float(x), y=float(y), z=0.0),
                            rotation=yaw_quaternion(theta))


def occupancy_grid(t: float, grey: np.ndarray, resolution_m: float, origin_x_m: float,
                   origin_y_m: float):
    """A grey map picture (0 blocked, 255 free, 205 unknown; row 0 on top) as a
    ``foxglove.Grid`` whose row 0 is the bottom row, at the map's origin."""
    m = _fg()
    occ = np.full(grey.shape, -1, np.int8)
    occ[grey <= 50] = 100
    occ[grey >= 250] = 0
    occ = np.ascontiguousarray(occ[::-1])
    h, w = occ.shape
    return m.Grid(timestamp=stamp(t), frame_id=MAP_FRAME,
                  pose=m.Pose(position=m.Vector3(x=origin_x_m, y=origin_y_m, z=0.0),
                              orientation=m.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
                  column_count=w, cell_size=m.Vector2(x=resolution_m, y=resolution_m),
                  row_stride=w, cell_stride=1,
                  fields=[m.PackedElementField(name="occupancy", offset=0,
                                               type=m.PackedElementFieldNumericType.Int8)],
                  data=occ.tobytes())


def laser_scan(t: float, ranges: Any, angle_min: float, angle_increment: float):
    m = _fg()
    r = [float(x) for x in np.asarray(ranges, np.float64)]
    return m.LaserScan(timestamp=stamp(t), frame_id=ROBOT_FRAME,
                       pose=m.Pose(position=m.Vector3(x=0.0, y=0.0, z=0.0),
                                   orientation=m.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
                       start_angle=float(angle_min),
                       end_angle=float(angle_min + angle_increment * max(len(r) - 1, 0)),
                       ranges=r)


def poses_in_frame(t: float, points: np.ndarray):
    m = _fg()
    q = m.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
    return m.PosesInFrame(timestamp=stamp(t), frame_id=MAP_FRAME, poses=[
        m.Pose(position=m.Vector3(x=float(x), y=float(y), z=0.0), orientation=q)
        for x, y in np.asarray(points, np.float64).reshape(-1, 2)])


def jpeg_image(t: float, jpeg: bytes, frame_id: str):
    return _fg().CompressedImage(timestamp=stamp(t), frame_id=frame_id, data=bytes(jpeg),
                                 format="jpeg")


def log_message(t: float, level: str, name: str, text: str):
    m = _fg()
    lv = {"debug": m.LogLevel.Debug, "info": m.LogLevel.Info, "warning": m.LogLevel.Warning,
          "error": m.LogLevel.Error, "fatal": m.LogLevel.Fatal}.get(level, m.LogLevel.Info)
    return m.Log(timestamp=stamp(t), level=lv, name=name, message=text)


_ALARM_LEVEL = {"LOW": "info", "MEDIUM": "warning", "HIGH": "error", "EMERGENCY": "fatal"}


def alarm_log(t: float, rec: dict):
    """An alarm transition as a Log line: the level from the priority while it is
    active, ``info`` when it returns to normal."""
    to = str(rec.get("to_state") or "")
    level = "info" if to.lower() in ("normal", "norm", "") else \
        _ALARM_LEVEL.get(str(rec.get("priority") or "").upper(), "warning")
    parts = [f"{rec.get('from_state')} -> {to}"]
    if rec.get("value") is not None:
        parts.append(f"value {rec['value']:g}{' ' + rec['unit'] if rec.get('unit') else ''}")
    if rec.get("limit_value") is not None:
        parts.append(f"limit {rec['limit_value']:g}")
    for k in ("text", "user", "reason", "origin"):
        if rec.get(k):
            parts.append(f"{k}: {rec[k]}")
    return log_message(t, level, str(rec.get("alarm")), "; ".join(parts))


def telemetry_schema(channels: list[str]) -> dict:
    props = {"seq": {"type": ["integer", "null"]}}
    props.update({c: {"type": ["number", "null"]} for c in channels})
    return {"title": TELEMETRY_SCHEMA, "type": "object", "properties": props}


METER_JSON_SCHEMA = {"title": METER_SCHEMA, "type": "object", "properties": {
    "point": {"type": "string"}, "value": {"type": ["number", "null"]},
    "unit": {"type": ["string", "null"]}, "confidence": {"type": ["number", "null"]},
    "state": {"type": ["string", "null"]}}}


def json_channel(topic: str, schema_name: str, schema: dict, context: Any):
    import foxglove

    return foxglove.Channel(topic, message_encoding="json", context=context,
                            schema=foxglove.Schema(name=schema_name, encoding="jsonschema",
                                                   data=json.dumps(schema).encode()))


# ------------------------------------------------------------ reading the archive
def _telemetry_rows(q: Any, t0: float, t1: float) -> Iterator[tuple[float, bytes]]:
    """(t, JSON text) of each telemetry row in [t0, t1], in time order, in batches."""
    con = q._reader()
    layouts = {lid: json.loads(ch) for lid, ch in
               con.execute("SELECT id, channels FROM telemetry_layout")}
    sw, sp = q._scope()
    cur = con.execute(f"SELECT t, seq, layout, data FROM telemetry WHERE t >= ? AND t <= ?"
                      f"{sw} ORDER BY t, id", (t0, t1, *sp))
    while True:
        rows = cur.fetchmany(BATCH_ROWS)
        if not rows:
            return
        n = len(rows)
        lay = np.fromiter((r[2] for r in rows), np.int64, n)
        text: list[bytes] = [b""] * n
        for lid in np.unique(lay):
            names = layouts.get(int(lid), [])
            sel = np.flatnonzero(lay == lid)
            block = np.frombuffer(b"".join(rows[i][3] for i in sel), np.float64
                                  ).reshape(len(sel), len(names))
            finite = np.isfinite(block).all(axis=1).tolist()
            values = block.tolist()
            # a finite float's repr is valid JSON: one C-level format per row
            template = "{" + "".join(f"{json.dumps(n)}:%r," for n in names) + '"seq":%s}'
            for k, i in enumerate(sel.tolist()):
                seq = rows[i][1]
                if finite[k]:
                    text[i] = (template % (*values[k], "null" if seq is None else int(seq))
                               ).encode()
                else:
                    d = {n: (v if math.isfinite(v) else None)
                         for n, v in zip(names, values[k], strict=True)}
                    d["seq"] = seq
                    text[i] = json.dumps(d).encode()
        for i, r in enumerate(rows):
            yield r[0], text[i]


def _tagged(k: int, rows: Iterator[tuple], row_is_pair: bool = False
            ) -> Iterator[tuple[float, int, int, Any]]:
    """(t, topic index, n, payload) for a time-ordered merge; the payload is the row
    itself, or its second item when rows are (t, message) pairs."""
    if row_is_pair:
        for i, (t, m) in enumerate(rows):
            yield t, k, i, m
    else:
        for i, r in enumerate(rows):
            yield r[0], k, i, r


def _pose_rows(q: Any, t0: float, t1: float) -> Iterator[tuple]:
    """(t, x, y, theta) of each pose in [t0, t1], in time order, in batches."""
    sw, sp = q._scope()
    cur = q._reader().execute(f"SELECT t, x, y, theta FROM pose WHERE t >= ? AND t <= ?{sw} "
                              "ORDER BY t, id", (t0, t1, *sp))
    while rows := cur.fetchmany(BATCH_ROWS):
        yield from rows


def _scan_rows(q: Any, t0: float, t1: float) -> Iterator[tuple]:
    """(t, angle_min, angle_increment, ranges blob) of each archived scan, in batches."""
    sw, sp = q._scope()
    cur = q._reader().execute(
        f"SELECT t, angle_min, angle_increment, ranges FROM scan WHERE t >= ? AND t <= ?{sw} "
        "ORDER BY t, id", (t0, t1, *sp))
    while rows := cur.fetchmany(BATCH_ROWS // 10):
        yield from rows


def archived_scan(t: float, angle_min: float, angle_increment: float, blob: bytes):
    return laser_scan(t, unpack_ranges(blob), angle_min, angle_increment)


def _rows(q: Any, sql: str, t0: float, t1: float) -> list[tuple]:
    sw, sp = q._scope()
    return q._reader().execute(sql.format(scope=sw), (t0, t1, *sp)).fetchall()


def _teb_rows(q: Any, t0: float, t1: float) -> list[tuple[float, np.ndarray]]:
    """(t, xy n × 2) of the archived TEB plans (``fws_teb`` events); a record that
    is not one is skipped."""
    out = []
    for t, data in _rows(q, "SELECT t, data FROM event WHERE kind = 'fws_teb' AND t >= ? "
                         "AND t <= ?{scope} ORDER BY t, id", t0, t1):
        try:
            xy = np.asarray(json.loads(data)["poses"], np.float64).reshape(-1, 3)[:, :2]
        except (KeyError, TypeError, ValueError):
            log.warning("MCAP export: an fws_teb record at %.3f is not a plan", t)
            continue
        out.append((float(t), xy))
    return out


def _map_messages(q: Any, t0: float, t1: float) -> list[tuple[float, Any]]:
    """Each stored map in the range (or the last before it) with its geometry event."""
    geo = [(t, json.loads(d)) for t, d in _rows(
        q, "SELECT t, data FROM event WHERE kind='map' AND t >= ? AND t <= ?{scope} "
        "ORDER BY t", -math.inf, t1)]
    maps = _rows(q, "SELECT t, png FROM map WHERE t >= ? AND t <= ?{scope} ORDER BY t",
                 -math.inf, t1)
    out = []
    for i, (t, png) in enumerate(maps):
        if t < t0 and i + 1 < len(maps) and maps[i + 1][0] <= t0:
            continue  # superseded before the range starts
        g = next((d for tg, d in reversed(geo) if tg <= t), None)
        img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_GRAYSCALE)
        if g is None or img is None:
            log.warning("map at %.3f skipped: %s", t,
                        "no geometry recorded" if g is None else "unreadable PNG")
            continue
        tt = max(t, t0)
        out.append((tt, occupancy_grid(tt, img, g["resolution_m"], g["origin_x_m"],
                                       g["origin_y_m"])))
    return out


def count_rows(q: Any, t0: float, t1: float) -> int:
    sw, sp = q._scope()
    con = q._reader()
    return sum(con.execute(f"SELECT count(*) FROM {tb} WHERE t >= ? AND t <= ?{sw}",
                           (t0, t1, *sp)).fetchone()[0]
               for tb in ("telemetry", "pose", "path", "meter_reading", "snapshot", "event",
                          "alarm_transition", "command", "scan"))


# ------------------------------------------------------------ the export
def export_mcap(q: Any, out: str | Path, t0: float = -math.inf, t1: float = math.inf, *,
                progress: Callable[[float], None] | None = None,
                progress_step: float = 0.05) -> ExportResult:
    """Write the rows of ``q`` (an archive or one session's view of it, as
    :func:`choose_session` gives) in [t0, t1] to ``out``. ``progress(fraction)`` is
    called every ``progress_step`` of the rows. Raises :class:`ExportError` when the
    range holds nothing or the file cannot be written."""
    import foxglove
    from foxglove import channels as fc

    if count_rows(q, t0, t1) == 0:
        raise ExportError("nothing to export: no rows in this session and time range")
    out = Path(out)
    if not out.parent.exists():
        raise ExportError(f"the folder {str(out.parent)!r} does not exist")
    ctx = foxglove.Context()
    result = ExportResult(out)
    chans: dict[str, Any] = {}

    order: list[str] = []

    def channel(topic: str, schema: str, make: Callable[[], Any]) -> int:
        """Open a topic; its index in ``order``."""
        chans[topic] = make()
        result.topics[topic] = TopicStats(schema)
        order.append(topic)
        return len(order) - 1

    telemetry_names = q.channels()
    k_tel = channel("/telemetry", TELEMETRY_SCHEMA, lambda: json_channel(
        "/telemetry", TELEMETRY_SCHEMA, telemetry_schema(telemetry_names), ctx))

    sw, sp = q._scope()
    total = q._reader().execute(f"SELECT count(*) FROM telemetry WHERE t >= ? AND t <= ?{sw}",
                                (t0, t1, *sp)).fetchone()[0]
    sources: list[Iterator[tuple[float, int, int, Any]]] = [
        _tagged(k_tel, _telemetry_rows(q, t0, t1), row_is_pair=True)]

    def add(topic: str, schema: str, make: Callable[[], Any],
            msgs: list[tuple[float, Any]]) -> None:
        if not msgs:
            return
        nonlocal total
        total += len(msgs)
        k = channel(topic, schema, make)
        sources.append(_tagged(k, iter(msgs), row_is_pair=True))

    builders: dict[int, Callable] = {}  # topic index -> message from a row, built late

    # poses come as often as telemetry: read them in batches, built as they are written
    n_poses = q._reader().execute(f"SELECT count(*) FROM pose WHERE t >= ? AND t <= ?{sw}",
                                  (t0, t1, *sp)).fetchone()[0]
    for topic, schema, make, build in (
            ("/pose", "foxglove.PoseInFrame", fc.PoseInFrameChannel, pose_in_frame),
            ("/tf", "foxglove.FrameTransform", fc.FrameTransformChannel, frame_transform)):
        if n_poses:
            total += n_poses
            k = channel(topic, schema, lambda make=make, topic=topic: make(topic, context=ctx))
            sources.append(_tagged(k, _pose_rows(q, t0, t1)))
            builders[k] = build
    n_scans = q._reader().execute(f"SELECT count(*) FROM scan WHERE t >= ? AND t <= ?{sw}",
                                  (t0, t1, *sp)).fetchone()[0]
    if n_scans:
        total += n_scans
        k = channel("/scan", "foxglove.LaserScan",
                    lambda: fc.LaserScanChannel("/scan", context=ctx))
        sources.append(_tagged(k, _scan_rows(q, t0, t1)))
        builders[k] = archived_scan
    add("/map", "foxglove.Grid", lambda: fc.GridChannel("/map", context=ctx),
        _map_messages(q, t0, t1))
    add("/path/global", "foxglove.PosesInFrame",
        lambda: fc.PosesInFrameChannel("/path/global", context=ctx),
        [(t, poses_in_frame(t, np.frombuffer(p, np.float32))) for t, p in _rows(
            q, "SELECT t, points FROM path WHERE t >= ? AND t <= ?{scope} ORDER BY t, id",
            t0, t1)])
    add("/path/teb", "foxglove.PosesInFrame",
        lambda: fc.PosesInFrameChannel("/path/teb", context=ctx),
        [(t, poses_in_frame(t, xy)) for t, xy in _teb_rows(q, t0, t1)])
    add("/meter", METER_SCHEMA,
        lambda: json_channel("/meter", METER_SCHEMA, METER_JSON_SCHEMA, ctx),
        [(t, json.dumps({"point": p, "value": v, "unit": u, "confidence": c,
                         "state": s}).encode())
         for t, p, v, u, c, s in _rows(
            q, "SELECT t, point, value, unit, confidence, state FROM meter_reading "
            "WHERE fused = 1 AND t >= ? AND t <= ?{scope} ORDER BY t, id", t0, t1)])
    snaps = _rows(q, "SELECT t, reason, ref, jpeg FROM snapshot WHERE t >= ? AND t <= ?"
                  "{scope} ORDER BY t, id", t0, t1)
    for topic, want in (("/snapshot/meter", False), ("/snapshot/alarm", True)):
        add(topic, "foxglove.CompressedImage",
            lambda topic=topic: fc.CompressedImageChannel(topic, context=ctx),
            [(t, jpeg_image(t, j, f"{reason}:{ref or ''}")) for t, reason, ref, j in snaps
             if (reason == "alarm") == want])
    add("/events", "foxglove.Log", lambda: fc.LogChannel("/events", context=ctx),
        [(t, log_message(t, "warning" if k == "link_state" and "lost" in d else "info", k, d))
         for t, k, d in _rows(q, "SELECT t, kind, data FROM event WHERE t >= ? AND t <= ?"
                              "{scope} ORDER BY t, id", t0, t1)])
    cols = ("t", "alarm", "source", "priority", "from_state", "to_state", "value",
            "limit_value", "unit", "text", "user", "reason", "origin")
    add("/alarms", "foxglove.Log", lambda: fc.LogChannel("/alarms", context=ctx),
        [(r[0], alarm_log(r[0], dict(zip(cols, r, strict=True)))) for r in _rows(
            q, f"SELECT {', '.join(cols)} FROM alarm_transition WHERE t >= ? AND t <= ?"
            "{scope} ORDER BY t, id", t0, t1)])
    add("/commands", "foxglove.Log", lambda: fc.LogChannel("/commands", context=ctx),
        [(t, log_message(t, "info" if a != 0 else "warning", str(u or ""),
                         f"{c} {args} -> " + {None: "no answer", 1: "accepted",
                                              0: f"refused: {why}"}[a]))
         for t, u, c, args, a, why in _rows(
            q, "SELECT t, user, command, args, acked, ack_reason FROM command "
            "WHERE t >= ? AND t <= ?{scope} ORDER BY t, id", t0, t1)])

    done, next_report = 0, progress_step
    try:
        writer = foxglove.open_mcap(out, allow_overwrite=True, context=ctx)
    except Exception as e:  # the SDK raises its own error type for I/O problems
        raise ExportError(f"cannot write {out}: {e}") from e
    try:
        logs = [chans[topic].log for topic in order]
        stats = [result.topics[topic] for topic in order]
        for t, k, _i, msg in heapq.merge(*sources):
            if k in builders:
                msg = builders[k](*msg)
            logs[k](msg, log_time=round(t * 1e9))
            stats[k].add(t)
            done += 1
            if progress is not None and done >= next_report * total:
                progress(done / total)
                next_report = (math.floor(done / total / progress_step) + 1) * progress_step
    finally:
        writer.close()
    return result
