"""The desk session puts what it receives, what it sends and every alarm transition
into the archive; archive trouble becomes an alarm (a fake link, real archive)."""

import json
import time

import numpy as np
import pytest

from app.comm import protocol as P
from app.comm.link import LinkSignals
from app.core.alarms import AlarmMonitor
from app.core.recorder import SessionRecorder
from app.core.records import Archive
from app.session import DeskSession, open_archive

pytestmark = pytest.mark.gui


class Link(LinkSignals):
    def __init__(self):
        super().__init__()
        self.sent = []

    def send_command(self, name, args=None):
        self.sent.append((name, args))
        return 100 + len(self.sent)

    def estop(self):
        return self.send_command("estop")

    def drive(self, linear_mps, angular_rps):
        self.sent.append(("drive", (linear_mps, angular_rps)))

    def stop(self):
        self.sent.append(("drive", (0.0, 0.0)))


@pytest.fixture
def desk(tmp_path, qtbot):
    link = Link()
    archive = Archive(tmp_path / "a.sqlite3", batch_interval_s=0.05)
    rec = SessionRecorder(tmp_path / "out")
    session = DeskSession(link, rec, AlarmMonitor(), archive=archive, user="ana")
    yield link, session, archive
    session.close()


def _telemetry(t, gas=1.0, seq=0):
    m = P.Telemetry(gas_lel_pct=gas, temp_c=21.0, humidity_pct=40.0, battery_v=24.0)
    m.received_s = t
    m.seq = seq
    return m


def test_received_and_sent_go_into_the_archive(desk):
    link, session, archive = desk
    t0 = time.time()
    for i in range(20):
        link.telemetry_received.emit(_telemetry(t0 + i * 0.1, seq=i))
    link.pose_received.emit(P.Pose(1.0, 2.0, 0.3, 0.0, 0.0))
    link.state_changed.emit("connected")
    link.event_received.emit(P.Event(level="info", code="patrol_started", text="go"))
    link.patrol_status_received.emit(P.PatrolStatus(state="driving", route="default",
                                                    index=0))
    link.patrol_status_received.emit(P.PatrolStatus(state="driving", route="default",
                                                    index=0))  # unchanged: not again
    png = b"\x89PNG-map"
    link.map_received.emit(P.MapImage(resolution_m=0.05, origin_x_m=-3.0, width=8,
                                      height=6, png=png))
    link.map_received.emit(P.MapImage(png=png))  # the same map: stored once
    link.path_received.emit(P.Path(kind=P.Path.GLOBAL,
                                   points_xy=np.array([[0, 0], [1, 1]], np.float32)))
    # commands leave through the desk's gateway, which journals them
    seq = session.gateway.send("start_patrol", {"route": "default"}).seq
    session.gateway.estop()
    link.ack_received.emit(P.CommandAck(cmd_seq=seq, ok=True, reason=""))
    assert archive.flush()
    assert link.sent == [("start_patrol", {"route": "default"}), ("estop", None)]
    assert archive.telemetry_seqs().tolist() == list(range(20))
    assert "gas_lel_pct" in archive.channels() and "alarm_flags" in archive.channels()
    assert archive.series("temp_c", t0 - 1, t0 + 5).mean.tolist() == [21.0] * 20
    assert archive.poses(0, time.time() + 1)[0, 1:].tolist() == pytest.approx([1, 2, 0.3])
    kinds = [e["kind"] for e in archive.events(0, time.time() + 1)]
    assert kinds == ["link_state", "robot_event", "patrol_status", "map"]
    geometry = archive.events(0, time.time() + 1, kinds=["map"])[0]["data"]
    assert geometry == {"resolution_m": 0.05, "origin_x_m": -3.0, "origin_y_m": 0.0,
                        "width": 8, "height": 6}
    cmds = archive.commands(0, time.time() + 1)
    assert [(c["command"], c["user"], c["seq"], c["acked"]) for c in cmds] == \
        [("start_patrol", "ana", seq, True), ("estop", "ana", seq + 1, None)]
    assert archive.counts()["map"] == 1 and archive.latest_map() == png
    assert archive.paths(0, time.time() + 1)[0]["points"].tolist() == [[0, 0], [1, 1]]


def test_alarm_transitions_and_a_snapshot_are_archived(desk):
    link, session, archive = desk
    t0 = time.time()
    img = np.zeros((480, 640, 3), np.uint8)
    img[:, :320] = 255
    link.frame_decoded.emit(type("F", (), dict(frame_id=1, latency_ms=5.0, image=img))())
    link.telemetry_received.emit(_telemetry(t0, gas=1.0))
    link.telemetry_received.emit(_telemetry(t0 + 0.1, gas=80.0))  # far above any limit
    assert archive.flush()
    tr = archive.alarm_transitions(0, time.time() + 1)
    raised = [r for r in tr if r["alarm"].startswith("gas_lel_pct") and
              r["to_state"] == "UNACK"]
    assert raised, tr
    assert raised[0]["value"] == pytest.approx(80.0)
    snaps = archive.snapshots(0, time.time() + 1)
    assert [s["reason"] for s in snaps] == ["alarm"] and snaps[0]["ref"] == raised[0]["alarm"]
    jpeg = archive.snapshot(snaps[0]["id"])
    assert jpeg.startswith(b"\xff\xd8") and len(jpeg) < 30_000  # small, 320 px wide


def test_archive_write_failure_and_recovery_raise_and_clear_an_alarm(desk, qtbot):
    link, session, archive = desk
    # every status, from the start: the failure may be told before a waitSignal would listen
    statuses: list[bool] = []
    session.archive_status.connect(lambda ok, *_: statuses.append(ok))
    archive.call_in_writer(lambda con: con.execute("PRAGMA query_only=1"))
    link.telemetry_received.emit(_telemetry(time.time()))
    qtbot.waitUntil(lambda: len(statuses) >= 1, timeout=10000)
    assert statuses[0] is False
    qtbot.waitUntil(lambda: session.monitor.is_active("archive.write"), timeout=5000)
    archive.call_in_writer(lambda con: con.execute("PRAGMA query_only=0"))
    qtbot.waitUntil(lambda: len(statuses) >= 2, timeout=15000)
    assert statuses[:2] == [False, True]
    qtbot.waitUntil(lambda: not session.monitor.is_active("archive.write"), timeout=5000)
    assert archive.flush()
    assert archive.telemetry_count() == 1
    lines = (session.recorder.out / "events.jsonl").read_text().splitlines()
    kinds = [json.loads(x)["kind"] for x in lines]
    assert kinds.count("archive_status") == 2


def test_an_unusable_archive_file_leaves_the_desk_running_with_an_alarm(tmp_path, qtbot):
    bad = tmp_path / "archive.sqlite3"
    bad.write_bytes(b"not a database at all" * 50)
    archive, error = open_archive(path=bad)
    assert archive is None and "not a Station Patrol archive" in error
    link = Link()
    session = DeskSession(link, SessionRecorder(tmp_path / "out"), AlarmMonitor(),
                          archive=None, archive_error=error)
    assert session.monitor.is_active("archive.open")
    link.telemetry_received.emit(_telemetry(time.time()))  # still records the folder
    assert session.recorder.counts["telemetry"] == 1
    session.close()
    assert bad.read_bytes().startswith(b"not a database")  # never overwritten


def test_meter_readings_fused_and_raw_with_a_snapshot(desk):
    from app.core.meter import Reading
    from app.core.meter_service import MeterRecord

    link, session, archive = desk
    p = session.pipeline
    p.meters.last_image = np.full((480, 640, 3), 90, np.uint8)
    p.record_meter_reading("PG-3", Reading(0.52, "MPa", 0.9))
    p.record_meter_reading("PG-3", Reading(None, "MPa", 0.1, error="needle not found"))
    t = time.time()
    p.record_meter_record(MeterRecord("PG-3", "P3", 0.52, "MPa", 0.0, 1.0, "normal", 0.88,
                                      None, "", t, 1, 2, "patrol"))
    assert archive.flush()
    raw = [m for m in archive.meter_readings(0, t + 5, fused_only=False) if not m["fused"]]
    assert [(m["value"], m["state"], m["error"]) for m in raw] == \
        [(0.52, "read", None), (None, "refused", "needle not found")]
    (fused,) = archive.meter_readings(0, t + 5)
    assert (fused["point"], fused["value"], fused["confidence"], fused["state"]) == \
        ("PG-3", 0.52, 0.88, "normal")
    jpeg = archive.snapshot(fused["snapshot_id"])
    assert jpeg.startswith(b"\xff\xd8") and len(jpeg) < 30_000


def test_desk_configuration_chooses_folder_retention_and_export(tmp_path, monkeypatch):
    from app.config import ConfigError, load_config
    from app.core.records.paths import ENV_VAR
    from app.session import open_desk_archive

    toml = tmp_path / "desk.toml"
    toml.write_text(f'data_dir = "{tmp_path / "here"}"\n[archive]\nretention_days = 7\n'
                    'export_before_prune = true\n')
    cfg = load_config(toml)
    archive, error = open_desk_archive(cfg)
    assert error is None
    assert archive.path == tmp_path / "here" / "archive.sqlite3"
    assert archive.retention_days == 7.0
    assert archive.export_dir == tmp_path / "here" / "exported"
    archive.close()
    # no data_dir: the environment's folder (the tests' temporary one)
    monkeypatch.setenv(ENV_VAR, str(tmp_path / "env"))
    cfg = load_config(None)
    archive, _ = open_desk_archive(cfg)
    assert archive.path == tmp_path / "env" / "archive.sqlite3" and archive.export_dir is None
    assert archive.retention_days == 30.0
    archive.close()
    toml.write_text("[archive]\nenabled = false\n")
    assert open_desk_archive(load_config(toml)) == (None, None)
    toml.write_text("[archive]\nretention_days = -1\n")
    with pytest.raises(ConfigError, match="retention_days"):
        load_config(toml)


def test_data_dir_option_overrides_the_configuration(tmp_path):
    from app.cli import apply_flags, build_parser
    from app.config import DeskConfig

    cfg = DeskConfig(data_dir="/from/the/toml")
    apply_flags(cfg, build_parser().parse_args(["--demo", "--data-dir", str(tmp_path)]))
    assert cfg.data_dir == str(tmp_path)


def test_link_figures_are_archived_once_a_minute_and_when_telemetry_is_lost(desk):
    from app.comm.link import LinkStats

    link, session, archive = desk
    link.stats_changed.emit(LinkStats(state="connected", rtt_ms=3.0))
    link.stats_changed.emit(LinkStats(state="connected", rtt_ms=4.0))  # within the minute
    link.stats_changed.emit(LinkStats(state="connected", rtt_ms=5.0, telemetry_lost=2))
    assert archive.flush()
    ev = archive.events(0, time.time() + 1, kinds=["link_stats"])
    assert [(e["data"]["rtt_ms"], e["data"]["telemetry_lost"]) for e in ev] == \
        [(3.0, 0), (5.0, 2)]
    assert session.recorder.link["rtt_ms"] == 5.0


def test_teleop_set_point_changes_go_on_record_not_every_renewal(desk):
    link, session, archive = desk
    g = session.gateway  # every intent leaves through it
    link.state_changed.emit("connected")
    for _ in range(5):  # a held key: the same set-point again and again
        g.drive(0.3, 0.0)
    g.drive(0.3, 0.5)
    g.stop()
    g.stop()
    g.drive(0.3, 0.0)
    g.estop()
    g.drive(0.3, 0.0)  # after the e-stop the same set-point is a new start
    link.state_changed.emit("lost")
    g.drive(0.0, 0.4)  # the link is down: journaled as not delivered
    assert archive.flush()
    cmds = [(c["command"], c["args"], c["user"]) for c in archive.commands(0, time.time() + 1)]
    drive = [a for c, a, _u in cmds if c == "drive"]
    assert drive == [{"linear_mps": 0.3, "angular_rps": 0.0},
                     {"linear_mps": 0.3, "angular_rps": 0.5},
                     {"linear_mps": 0.0, "angular_rps": 0.0},
                     {"linear_mps": 0.3, "angular_rps": 0.0},
                     {"linear_mps": 0.3, "angular_rps": 0.0},
                     {"linear_mps": 0.0, "angular_rps": 0.4,
                      "outcome": "not delivered: link down"}]
    assert [c for c, _a, _u in cmds].count("estop") == 1
    assert {u for _c, _a, u in cmds} == {"ana"}
