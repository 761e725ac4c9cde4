"""The MCAP export read back with the ``mcap`` reader: every channel's schema, message
count and time range against the archive's rows, for an archive written by the real
headless desk pipeline from a deterministic stream (tests/e2e/test_desk_parity.py)."""

from __future__ import annotations

import json
import sqlite3

import cv2
import numpy as np
import pytest
from e2e.test_desk_parity import OBSTACLE_RULE, Clock, stream  # tests/ is on the path
from mcap.reader import make_reader
from ui.fakes import FakeLink

from app.comm import protocol as P
from app.core.alarms import default_alarm_config
from app.core.meter_service import MeterService
from app.core.records import Archive
from app.core.records.mcap_export import ExportError, export_mcap
from app.core.records.queries import choose_session
from app.export_cli import main as export_main
from app.headless import build_headless_desk
from app.session import LINK_SIGNALS


def _map_png() -> bytes:
    img = np.full((20, 30), 255, np.uint8)
    img[0, :] = 0  # a wall along the top row
    img[5:8, 20:] = 205
    ok, buf = cv2.imencode(".png", img)
    assert ok
    return buf.tobytes()


def record(path) -> None:
    """The parity stream, plus a map and two global paths, through the headless desk."""
    import dataclasses

    clock = Clock()
    link = FakeLink()
    archive = Archive(path)
    cfg = dataclasses.replace(default_alarm_config(),
                              limits=[*default_alarm_config().limits, OBSTACLE_RULE])
    from app.core.recorder import SessionRecorder

    desk = build_headless_desk(link, SessionRecorder(path.parent / "out"), archive,
                               alarm_config=cfg, clock=clock.wall, mono=clock.mono,
                               meter_service=MeterService(clock=clock.mono,
                                                          utc_clock=clock.wall))
    extra = []
    t_first = stream()[0][0]
    extra.append((t_first + 0.5, "map", P.MapImage(0.1, -1.0, -2.0, 30, 20, _map_png())))
    pts = np.array([[0, 0], [1, 0], [1, 1]], np.float32)
    extra.append((t_first + 0.6, "path", P.Path(P.Path.GLOBAL, pts)))
    extra.append((t_first + 4.0, "path", P.Path(P.Path.GLOBAL, pts[::-1].copy())))
    for i in range(20):  # lidar at 5 Hz for 4 s: the archive keeps one a second
        extra.append((t_first + 0.3 + 0.2 * i, "scan", SCAN))
    for t, what, msg in sorted(stream() + extra, key=lambda x: x[0]):
        clock.t = t
        if what == "tick":
            desk.tick()
        elif what == "command":
            desk.gateway.send(*msg)
        else:
            getattr(link, LINK_SIGNALS[what]).emit(msg)
    desk.close()


_RANGES = np.linspace(0.5, 11.0, 360).astype(np.float32)
_RANGES[10] = np.inf  # no return
SCAN = P.LidarScan(0, -np.pi, 2 * np.pi / 360, 12.0, _RANGES)

# topic -> (schema, the rows of the archive it carries)
EXPECTED = {
    "/telemetry": ("station_patrol.Telemetry", "SELECT t FROM telemetry"),
    "/pose": ("foxglove.PoseInFrame", "SELECT t FROM pose"),
    "/tf": ("foxglove.FrameTransform", "SELECT t FROM pose"),
    "/scan": ("foxglove.LaserScan", "SELECT t FROM scan"),
    "/map": ("foxglove.Grid", "SELECT t FROM map"),
    "/path/global": ("foxglove.PosesInFrame", "SELECT t FROM path"),
    "/path/teb": ("foxglove.PosesInFrame", "SELECT t FROM event WHERE kind = 'fws_teb'"),
    "/meter": ("station_patrol.MeterReading", "SELECT t FROM meter_reading WHERE fused=1"),
    "/snapshot/meter": ("foxglove.CompressedImage",
                        "SELECT t FROM snapshot WHERE reason != 'alarm'"),
    "/snapshot/alarm": ("foxglove.CompressedImage",
                        "SELECT t FROM snapshot WHERE reason = 'alarm'"),
    "/events": ("foxglove.Log", "SELECT t FROM event"),
    "/alarms": ("foxglove.Log", "SELECT t FROM alarm_transition"),
    "/commands": ("foxglove.Log", "SELECT t FROM command"),
}


@pytest.fixture
def archive_file(tmp_path):
    path = tmp_path / "archive.sqlite3"
    record(path)
    return path


def read_back(path) -> dict[str, tuple[str, list[int], list[bytes]]]:
    out: dict[str, tuple[str, list[int], list[bytes]]] = {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            name = schema.name if schema else ""
            entry = out.setdefault(channel.topic, (name, [], []))
            entry[1].append(message.log_time)
            entry[2].append(message.data)
    return out


def test_every_channel_matches_the_archive(archive_file, tmp_path):
    out = tmp_path / "session.mcap"
    archive = Archive(archive_file)
    try:
        rows, _which = choose_session(archive, "latest")
        result = export_mcap(rows, out)
    finally:
        archive.close()
    got = read_back(out)
    con = sqlite3.connect(archive_file)
    try:
        for topic, (schema, sql) in EXPECTED.items():
            ts = sorted(r[0] for r in con.execute(sql))
            if not ts:
                assert topic not in got, topic
                continue
            assert topic in got, f"{topic} missing from the file"
            name, times, _data = got[topic]
            assert name == schema, topic
            assert len(times) == len(ts), topic
            assert min(times) == round(ts[0] * 1e9) and max(times) == round(ts[-1] * 1e9), topic
            assert result.topics[topic].count == len(ts)
        # the stream makes every kind at least once (a missing one would hide a topic)
        for topic in ("/telemetry", "/pose", "/scan", "/map", "/path/global", "/snapshot/alarm",
                      "/events", "/alarms", "/commands"):
            assert topic in got, topic
        assert set(got) <= set(EXPECTED)
        # telemetry values are the archive's, in receive order
        _name, _times, data = got["/telemetry"]
        first = json.loads(data[0])
        lay, blob = con.execute("SELECT layout, data FROM telemetry ORDER BY t, id LIMIT 1"
                                ).fetchone()
        names = json.loads(con.execute("SELECT channels FROM telemetry_layout WHERE id=?",
                                       (lay,)).fetchone()[0])
        vals = np.frombuffer(blob, np.float64)
        assert {k: first[k] for k in names} == dict(zip(names, vals.tolist(), strict=True))
        gas = [json.loads(d)["gas_lel_pct"] for d in data]
        assert max(gas) == 14.0 and min(gas) == 2.0
        # the stored JPEG bytes go out as they are
        jpeg = bytes(con.execute("SELECT jpeg FROM snapshot WHERE reason='alarm'").fetchone()[0])
        assert any(jpeg in d for d in got["/snapshot/alarm"][2])
    finally:
        con.close()


def test_time_range_and_empty_range(archive_file, tmp_path):
    con = sqlite3.connect(archive_file)
    t_lo, t_hi = con.execute("SELECT min(t), max(t) FROM telemetry").fetchone()
    con.close()
    archive = Archive(archive_file)
    try:
        rows, _ = choose_session(archive, "latest")
        mid = (t_lo + t_hi) / 2
        result = export_mcap(rows, tmp_path / "half.mcap", mid, t_hi)
        assert result.topics["/telemetry"].t0 >= mid
        full = export_mcap(rows, tmp_path / "full.mcap")
        assert 0 < result.topics["/telemetry"].count < full.topics["/telemetry"].count
        with pytest.raises(ExportError, match="nothing to export"):
            export_mcap(rows, tmp_path / "none.mcap", t_hi + 10, t_hi + 20)
    finally:
        archive.close()


def test_cli_progress_and_clear_errors(archive_file, tmp_path, capsys):
    out = tmp_path / "cli.mcap"
    assert export_main(["--mcap", str(out), "--archive", str(archive_file)]) == 0
    err = capsys.readouterr().err
    assert "100 %" in err and "session 1" in err
    assert "/telemetry" in read_back(out)
    assert export_main(["--mcap", str(out), "--archive", str(tmp_path / "nope.sqlite3")]) == 2
    assert "no archive at" in capsys.readouterr().err
    assert export_main(["--mcap", str(out), "--archive", str(archive_file),
                        "--session", "9"]) == 2
    assert "no session 9" in capsys.readouterr().err
    assert export_main(["--mcap", str(out), "--archive", str(archive_file),
                        "--from", "2000-01-01", "--to", "2000-01-02"]) == 2
    assert "nothing to export" in capsys.readouterr().err


def _decoder(schema):
    """A protobuf message class from an MCAP schema (a FileDescriptorSet), as Foxglove
    and Lichtblick build it."""
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for f in fds.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def test_protobuf_messages_decode_to_the_archives_values(archive_file, tmp_path):
    out = tmp_path / "decode.mcap"
    archive = Archive(archive_file)
    try:
        rows, _ = choose_session(archive, "latest")
        export_mcap(rows, out)
        poses = rows.poses(-np.inf, np.inf)
    finally:
        archive.close()
    decoded: dict[str, list] = {}
    with open(out, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            if schema.encoding == "protobuf":
                cls = _decoder(schema)
                decoded.setdefault(channel.topic, []).append(cls.FromString(message.data))
    got = np.array([[p.pose.position.x, p.pose.position.y,
                     2 * np.arctan2(p.pose.orientation.z, p.pose.orientation.w)]
                    for p in decoded["/pose"]])
    np.testing.assert_allclose(got, poses[:, 1:], atol=1e-9)
    tf = decoded["/tf"][0]
    assert (tf.parent_frame_id, tf.child_frame_id) == ("map", "base_link")
    grid = decoded["/map"][0]
    assert (grid.column_count, grid.cell_size.x, grid.pose.position.x,
            grid.pose.position.y) == (30, pytest.approx(0.1), -1.0, -2.0)
    occ = np.frombuffer(grid.data, np.int8).reshape(-1, grid.column_count)
    assert occ.shape == (20, 30)
    assert (occ[-1] == 100).all()  # the picture's top row is the grid's last row
    assert (occ[12:15, 20:] == -1).all() and occ[0, 0] == 0
    path = decoded["/path/global"][0]
    assert [(p.position.x, p.position.y) for p in path.poses] == [(0, 0), (1, 0), (1, 1)]
    assert any(lg.name == "gas_lel_pct" or "gas" in lg.name for lg in decoded["/alarms"])
    # lidar: decimated to one scan a second, the ranges to the millimetre, no return kept
    scans = decoded["/scan"]
    assert 4 <= len(scans) <= 5
    sc = scans[0]
    assert sc.frame_id == "base_link" and len(sc.ranges) == 360
    assert sc.start_angle == pytest.approx(-np.pi)
    assert sc.end_angle == pytest.approx(-np.pi + 359 * 2 * np.pi / 360)
    r = np.array(sc.ranges)
    assert np.isinf(r[10])
    fin = np.isfinite(_RANGES)
    np.testing.assert_allclose(r[fin], _RANGES[fin], atol=6e-4)


def test_robot_picks_that_robots_latest_session(archive_file, tmp_path, capsys):
    con = sqlite3.connect(archive_file)
    con.execute("UPDATE session SET robot='10.0.0.12:7000'")
    con.commit()
    con.close()
    out = tmp_path / "robot.mcap"
    assert export_main(["--mcap", str(out), "--archive", str(archive_file),
                        "--robot", "10.0.0.12"]) == 0
    assert "robot 10.0.0.12:7000" in capsys.readouterr().err
    assert export_main(["--mcap", str(out), "--archive", str(archive_file),
                        "--robot", "10.9.9.9"]) == 2
    assert "robots: 10.0.0.12:7000" in capsys.readouterr().err


def test_telemetry_json_is_valid_with_odd_values(tmp_path):
    """NaN and infinities become null; tiny, huge and negative values keep their value."""
    a = Archive(tmp_path / "odd.sqlite3")
    a.begin_session("desk", "robot")
    rows = [{"a": 1e-300, "b": -2.5e20}, {"a": float("nan"), "b": 3.0},
            {"a": float("inf"), "b": -0.0}]
    for i, r in enumerate(rows):
        a.add_telemetry(1_790_000_000.0 + i, r, seq=None if i == 1 else i)
    assert a.flush()
    try:
        view, _ = choose_session(a, "latest")
        export_mcap(view, tmp_path / "odd.mcap")
    finally:
        a.close()
    got = [json.loads(d) for d in read_back(tmp_path / "odd.mcap")["/telemetry"][2]]
    assert got == [{"a": 1e-300, "b": -2.5e20, "seq": 0}, {"a": None, "b": 3.0, "seq": None},
                   {"a": None, "b": -0.0, "seq": 2}]
