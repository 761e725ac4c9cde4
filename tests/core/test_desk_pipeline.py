"""The desk pipeline without Qt: one ingest path, every channel to the alarms, the one
link decision, commands journaled with their outcome, replay view-only, newest frame."""

from __future__ import annotations

import dataclasses
import threading

import numpy as np
import pytest

from app.comm import protocol as P
from app.core.alarms import AlarmState, LimitRule, default_alarm_config
from app.core.desk import DeskPipeline
from app.core.desk.gateway import NOT_DELIVERED, REFUSED, SENT
from app.core.desk.replay_rows import ReplayFeed
from app.core.records import Archive
from app.core.replay import Window
from app.core.video import DecodedFrame, LatestFrame

T0 = 1_800_000_000.0


class Sender:
    def __init__(self, fail: bool = False) -> None:
        self.calls: list[tuple] = []
        self.fail = fail
        self.seq = 0

    def send_command(self, name, args=None):
        if self.fail:
            raise OSError("socket gone")
        self.seq += 1
        self.calls.append((name, args))
        return self.seq

    def drive(self, lin, ang):
        self.calls.append(("drive", lin, ang))

    def stop(self):
        self.calls.append(("stop",))

    def estop(self):
        return self.send_command("estop")

    def reset_estop(self):
        return self.send_command("reset_estop")


def tel(t, **kw):
    m = P.Telemetry(**{"gas_lel_pct": 1.0, "temp_c": 22.0, "humidity_pct": 40.0,
                       "battery_v": 24.5, "obstacle_front_m": 3.0, **kw})
    m.received_s = t
    return m


def test_a_rule_on_any_telemetry_channel_alarms():
    rule = LimitRule("wheel_left_mps", high=1.0, unit="m/s")
    cfg = dataclasses.replace(default_alarm_config(),
                              limits=[*default_alarm_config().limits, rule])
    p = DeskPipeline(alarm_config=cfg)
    assert p.ingest("telemetry", tel(T0, wheel_left_mps=0.2))
    assert not p.monitor.is_active("wheel_left_mps.high")
    p.ingest("telemetry", tel(T0 + 0.1, wheel_left_mps=1.5))
    assert p.monitor.state("wheel_left_mps.high") is AlarmState.UNACK
    # a rule added while running alarms from the next sample on
    p.apply_alarm_config(dataclasses.replace(
        cfg, limits=[*cfg.limits, LimitRule("yaw_rate_rps", high=0.5)]))
    p.ingest("telemetry", tel(T0 + 0.2, yaw_rate_rps=0.9))
    assert p.monitor.is_active("yaw_rate_rps.high")


def test_bad_messages_are_counted_and_announced_not_raised():
    p = DeskPipeline()
    seen = []
    p.listen("malformed", seen.append)
    assert not p.ingest("telemetry", "not telemetry")
    assert not p.ingest("frame", object())
    assert not p.ingest("link_state", 42)
    assert not p.ingest("no_such_kind", None)
    assert p.malformed == 4 and len(seen) == 4 and p.samples == 0
    assert p.ingest("telemetry", tel(T0))


def test_link_loss_is_decided_once_and_raised_and_restored():
    p = DeskPipeline()
    restored = []
    p.listen("link_restored", lambda: restored.append(True))
    for s in ("connecting", "connected", "lost"):
        p.ingest("link_state", s)
    assert p.monitor.is_active("link.lost")
    p.ingest("link_state", "reconnecting")
    p.ingest("link_state", "connected")
    assert not p.monitor.is_active("link.lost") and restored == [True]
    assert p.restored_count == 1


def test_commands_are_journaled_with_their_outcome():
    sender = Sender()
    p = DeskPipeline(sender=sender)
    journal = []
    p.listen("command", journal.append)
    g = p.gateway
    assert g.send("start_patrol").outcome == NOT_DELIVERED  # the link is not up
    p.ingest("link_state", "connected")
    e = g.send("look_at", {"gauge": "PG-1"})
    assert (e.outcome, e.seq) == (SENT, 2)
    g.drive(0.3, 0.0)
    g.drive(0.3, 0.0)  # the same set-point again: sent, not journaled again
    g.stop()
    assert [x.name for x in journal] == ["start_patrol", "look_at", "drive", "drive"]
    assert sender.calls.count(("drive", 0.3, 0.0)) == 2
    sender.fail = True
    assert g.send("resume_patrol").outcome == NOT_DELIVERED and g.errors == 1


def test_estop_delivery_comes_from_the_gateway():
    sender = Sender()
    p = DeskPipeline(sender=sender)
    reports = []
    p.listen("estop", reports.append)
    p.gateway.estop()  # link down
    assert reports[-1].status == "not_delivered"
    assert p.monitor.is_active("desk.estop_not_delivered")
    p.ingest("link_state", "connected")
    seq = p.gateway.estop().seq
    p.ingest("ack", P.CommandAck(seq, True, ""))
    assert reports[-1].status == "acknowledged"
    assert not p.monitor.is_active("desk.estop_not_delivered")


def test_a_replay_pipeline_records_nothing_and_sends_nothing(tmp_path):
    sender = Sender()
    p = DeskPipeline(sender=sender, replay=True)
    assert p.record is None
    p.ingest("link_state", "replay")
    p.ingest("telemetry", tel(T0, gas_lel_pct=30.0))
    assert p.monitor.is_active("gas_lel_pct.high")  # the replayed data still alarms
    for entry in (p.gateway.send("start_patrol"), p.gateway.estop(),
                  p.gateway.drive(0.5, 0.0)):
        assert entry.outcome == REFUSED and entry.why == "replay is view-only"
    assert sender.calls == []
    assert p.gateway.estop_delivery.sent == 0


def test_replay_rows_become_the_live_messages(tmp_path):
    a = Archive(tmp_path / "a.sqlite3")
    rec = DeskPipeline(archive=a, clock=lambda: T0 + 5.0)
    for i in range(5):
        m = tel(T0 + i, gas_lel_pct=1.0 + i, tel_seq=i + 1)
        m.seq = i + 1
        rec.ingest("telemetry", m)
    rec.ingest("pose", P.Pose(1.0, 2.0, 0.5))
    rec.close()
    a = Archive(tmp_path / "a.sqlite3")
    try:
        items = ReplayFeed(a).window(Window(T0 - 1, T0 + 10, inclusive=True))
    finally:
        a.close()
    kinds = [k for _t, k, _m in items]
    assert kinds.count("telemetry") == 5 and kinds.count("pose") == 1
    tels = [m for _t, k, m in items if k == "telemetry"]
    assert [m.gas_lel_pct for m in tels] == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert [m.received_s for m in tels] == [T0 + i for i in range(5)]
    assert isinstance(tels[0].tel_seq, int) and tels[-1].seq == 5
    play = DeskPipeline(replay=True)
    assert all(play.ingest(k, m) for _t, k, m in items)
    assert play.samples == 5 and play.latest["gas_lel_pct"] == 5.0


def test_frames_keep_the_robots_jpeg_and_the_newest_wins():
    box = LatestFrame()
    frames = [DecodedFrame(i, i, np.zeros((4, 4, 3), np.uint8), 1.0, 4, 4, jpeg=b"J%d" % i)
              for i in range(5)]
    assert box.put(frames[0])  # empty: wake the reader
    assert not box.put(frames[1]) and not box.put(frames[2])
    assert box.take() is frames[2] and box.dropped == 2
    assert box.take() is None
    # from another thread, as the link's worker does
    th = threading.Thread(target=lambda: [box.put(f) for f in frames])
    th.start()
    th.join()
    assert box.take().jpeg == b"J4" and box.dropped == 6


@pytest.mark.parametrize("jpeg", [b"\xff\xd8 robot bytes", None])
def test_the_alarm_snapshot_is_the_frame_as_the_robot_sent_it(tmp_path, jpeg):
    a = Archive(tmp_path / "a.sqlite3")
    p = DeskPipeline(archive=a)
    img = np.full((48, 64, 3), 100, np.uint8)
    p.ingest("frame", DecodedFrame(1, 1, img, 5.0, 64, 48, jpeg=jpeg))
    p.ingest("telemetry", tel(T0, gas_lel_pct=15.0))  # A1 only: one alarm, one snapshot
    assert a.flush()
    [s] = a.snapshots(0, 4e9)
    stored = a.snapshot(s["id"])
    p.close()
    if jpeg is not None:
        assert stored == jpeg  # not decoded and encoded again
    else:
        assert stored.startswith(b"\xff\xd8")  # the writer made one from the RGB frame


def test_a_recorded_patrol_replays_with_its_route_after_a_seek(tmp_path):
    """The patrol status goes on record with its points, and a seek into the run
    restores the last status before the target (route drawn, state shown)."""
    pts = [{"name": "PG-101", "kind": "meter", "x_m": 12.0, "y_m": 4.0, "state": "done"},
           {"name": "PG-102", "kind": "meter", "x_m": 20.0, "y_m": 10.0, "state": "current"}]
    now = [T0]
    a = Archive(tmp_path / "a.sqlite3")
    rec = DeskPipeline(archive=a, clock=lambda: now[0])
    for i in range(20):
        now[0] = T0 + i
        rec.ingest("telemetry", tel(T0 + i))
        if i == 2:
            rec.ingest("patrol_status", P.PatrolStatus(state="driving", route="default",
                                                       index=1, points=pts, progress=0.5,
                                                       local_planner="apf"))
    rec.close()
    a = Archive(tmp_path / "a.sqlite3")
    try:
        feed = ReplayFeed(a)
        at = feed.state_at(T0 + 10.0)
        later = ReplayFeed(a).state_at(T0 + 1.0)  # before the patrol started
    finally:
        a.close()
    status = [m for _t, k, m in at if k == "patrol_status"]
    assert len(status) == 1
    st = status[0]
    assert (st.state, st.route, st.index, st.local_planner) == ("driving", "default", 1, "apf")
    assert [p["name"] for p in st.points] == ["PG-101", "PG-102"]
    assert [p["state"] for p in st.points] == ["done", "current"]
    assert not [m for _t, k, m in later if k == "patrol_status"]
    play = DeskPipeline(replay=True)
    assert all(play.ingest(k, m) for _t, k, m in at)


def test_a_patrol_status_recorded_without_points_keeps_the_last_route(tmp_path):
    a = Archive(tmp_path / "a.sqlite3")
    pts = [{"name": "PG-101", "kind": "meter", "x_m": 12.0, "y_m": 4.0}]
    a.add_event(T0, "patrol", {"state": "running", "route": "default", "points": pts})
    a.add_event(T0 + 5.0, "patrol", {"state": "done", "text": "patrol finished"})
    assert a.flush()
    try:
        items = ReplayFeed(a).window(Window(T0 - 1, T0 + 10, inclusive=True))
    finally:
        a.close()
    status = [m for _t, k, m in items if k == "patrol_status"]
    assert [s.state for s in status] == ["running", "done"]
    assert [p["name"] for p in status[1].points] == ["PG-101"]


def test_the_4ws_wheels_are_archived_on_a_mode_change_and_while_moving(tmp_path):
    from app.comm.fws_protocol import MODES, WheelState
    from app.core.desk.fws import WHEEL_RECORD_S

    a = Archive(tmp_path / "a.sqlite3")
    now = [T0]
    p = DeskPipeline(archive=a, clock=lambda: now[0])
    still = WheelState(1000, MODES.index("stopped"), (0.0,) * 4, (0.0,) * 4)
    arc = WheelState(2000, MODES.index("front"), (0.2, 0.15, 0.0, 0.0), (0.55, 0.5, 0.55, 0.5))
    for k in range(40):  # 4 s standing, then 4 s driving, a state every 0.2 s
        now[0] = T0 + 0.2 * k
        assert p.ingest("fws", still if k < 20 else arc)
    p.close()
    a = Archive(tmp_path / "a.sqlite3")
    try:
        rows = a.events(T0 - 1, T0 + 10, kinds=["fws_wheels"])
    finally:
        a.close()
    # standing: one record; driving: one on the change, then one every WHEEL_RECORD_S
    assert [r["data"]["mode"] for r in rows] == ["stopped"] + ["front"] * int(
        1 + (19 * 0.2) // WHEEL_RECORD_S)
    assert rows[1]["t"] == pytest.approx(T0 + 4.0)
    assert rows[1]["data"]["angles_deg"] == [11.5, 8.6, 0.0, 0.0]
    assert rows[1]["data"]["speeds_mps"] == [0.55, 0.5, 0.55, 0.5]


def test_the_4ws_teb_plans_are_archived_compactly_replayed_and_exported(tmp_path):
    """TEB plans at 5 Hz: kept at once when the base starts turning in place, else
    at most once a second and only when the plan moved; at most 16 poses each;
    replay turns the records back into plans on the map; the MCAP export draws
    them on /path/teb."""
    from mcap.reader import make_reader

    from app.comm.fws_protocol import TebPlan
    from app.core.desk.fws import TEB_RECORD_POSES, TEB_RECORD_S
    from app.core.records.mcap_export import export_mcap
    from app.core.records.queries import choose_session

    a = Archive(tmp_path / "a.sqlite3")
    now = [T0]
    p = DeskPipeline(archive=a, clock=lambda: now[0])
    s = np.linspace(0.0, 3.0, 40)
    sent = []
    for k in range(24):  # 6 s at 4 Hz: driving 0.1 m further each plan, turning 3.0–3.75 s
        now[0] = T0 + 0.25 * k
        turning = 12 <= k < 16
        x0 = 0.1 * k if k < 12 else 1.2 + 0.1 * max(0, k - 15)
        poses = np.column_stack([x0 + s, 0.2 * s, np.full(40, 0.1)]).astype(np.float32)
        plan = TebPlan(turning, poses, np.full(39, 0.125, np.float32))
        sent.append((now[0], plan))
        assert p.ingest("fws", plan)
    p.close()
    a = Archive(tmp_path / "a.sqlite3")
    try:
        rows = a.events(T0 - 1, T0 + 10, kinds=["fws_teb"])
        items = ReplayFeed(a).window(Window(T0 - 1, T0 + 10, inclusive=True))
        session, _ = choose_session(a, "latest")
        export_mcap(session, tmp_path / "s.mcap")
    finally:
        a.close()
    assert TEB_RECORD_S == 1.0
    # the first; one a second while driving; at once into and out of the turn
    assert [r["t"] - T0 for r in rows] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    turning = [r["data"]["turning_in_place"] for r in rows]
    assert turning == [False, False, False, True, False, False]
    for r in rows:
        d = r["data"]
        assert 2 <= len(d["poses"]) <= TEB_RECORD_POSES
        assert len(d["dts_s"]) == len(d["poses"]) - 1
        assert sum(d["dts_s"]) == pytest.approx(39 * 0.125, abs=1e-3)  # the whole horizon
    # the record's poses are the plan's (kept poses, to the centimetre), ends included
    first = next(pl for t, pl in sent if t == rows[0]["t"])
    got = np.asarray(rows[0]["data"]["poses"])
    assert got[0] == pytest.approx(first.poses[0], abs=0.006)
    assert got[-1] == pytest.approx(first.poses[-1], abs=0.006)
    # replay: the plans come back for the map's overlay, at the recorded times
    plans = [(t, m) for t, k, m in items if k == "fws"]
    assert [t for t, _ in plans] == [r["t"] for r in rows]
    assert all(isinstance(m, TebPlan) for _, m in plans)
    assert [m.turning_in_place for _, m in plans] == turning
    rp = DeskPipeline(replay=True)
    rp.ingest("fws", plans[0][1])
    assert rp.fws.teb is plans[0][1]
    # the MCAP export: one /path/teb message per record, at its time
    with open(tmp_path / "s.mcap", "rb") as f:
        teb = [m.log_time for _s, c, m in make_reader(f).iter_messages() if c.topic == "/path/teb"]
    assert teb == [round(r["t"] * 1e9) for r in rows]
