"""The headless desk and the window run one desk pipeline: fed the same stream they
make the same alarm transitions and write the same archive rows.

The stream is synthetic and deterministic (both desks get the same injected wall and
monotonic clock): the link connects, telemetry in which a site rule on
``obstacle_front_m`` (not one of the four channels the headless desk used to watch)
and the default gas limit trip, a camera frame (its JPEG becomes the alarm snapshot as
it came), poses, robot and patrol events, a command and its ack, the link lost and
restored, and a meter inspection that ends without a reading.
"""

from __future__ import annotations

import dataclasses
import sqlite3

import cv2
import numpy as np
import pytest
from ui.fakes import FakeLink  # tests/ui/fakes.py (tests/ is on the path)

from app.comm import protocol as P
from app.core.alarms import LimitRule, Priority, default_alarm_config
from app.core.meter_service import MeterService
from app.core.recorder import SessionRecorder
from app.core.records import Archive
from app.core.video import DecodedFrame
from app.headless import build_headless_desk
from app.session import LINK_SIGNALS
from app.ui.app import build_window

pytestmark = pytest.mark.gui

T0 = 1_800_000_000.0
OBSTACLE_RULE = LimitRule("obstacle_front_m", low=0.5, deadband=0.1, unit="m",
                          label="Obstacle close ahead", priority=Priority.HIGH)


class Clock:
    """Wall and monotonic time, set by the stream."""

    def __init__(self) -> None:
        self.t = T0

    def wall(self) -> float:
        return self.t

    def mono(self) -> float:
        return self.t - T0 + 500.0


def _jpeg() -> bytes:
    img = np.zeros((120, 160, 3), np.uint8)
    img[:, :80] = (200, 40, 40)
    ok, buf = cv2.imencode(".jpg", img)
    assert ok
    return buf.tobytes()


def stream() -> list[tuple[float, str, object]]:
    """(time, kind, message): kinds are the pipeline's, plus 'tick' and 'command'."""
    out: list[tuple[float, str, object]] = [(T0, "link_state", "connecting"),
                                            (T0 + 0.01, "link_state", "connected"),
                                            (T0 + 0.02, "command", ("start_patrol", {})),
                                            (T0 + 0.05, "ack", P.CommandAck(1, True, ""))]
    jpeg = _jpeg()
    t = T0 + 0.1
    for i in range(80):
        t = T0 + 0.1 + i * 0.1 + (3.0 if i >= 50 else 0.0)  # 3 s without data at the loss
        if i == 10:
            img = cv2.cvtColor(cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR),
                               cv2.COLOR_BGR2RGB)
            out.append((t, "frame", DecodedFrame(7, int(t * 1e6), img, 40.0, 160, 120,
                                                 jpeg=jpeg)))
        if i == 12:
            out.append((t, "event", P.Event("info", "patrol_started", "go", {})))
            out.append((t, "patrol_status", P.PatrolStatus(state="driving", route="default",
                                                           index=0)))
        if i % 5 == 0:
            out.append((t, "pose", P.Pose(1.0 + 0.1 * i, 2.0, 0.1)))
        if i == 48:
            out.append((t, "link_state", "lost"))
            out.append((t + 1.5, "tick", None))
            out.append((t + 2.0, "link_state", "reconnecting"))
            out.append((t + 2.9, "link_state", "connected"))
        if i == 60:
            out.append((t, "event", P.Event("info", "inspection_started", "",
                                            {"point": "P-3", "gauge": "PG-102"})))
        if i == 66:
            out.append((t, "event", P.Event("info", "inspection_done", "",
                                            {"point": "P-3", "gauge": "PG-102"})))
        obstacle = 0.3 if 20 <= i < 30 else 3.0  # something close ahead for a second
        gas = 14.0 if 35 <= i < 40 else 2.0
        msg = P.Telemetry(gas_lel_pct=gas, temp_c=24.0, humidity_pct=45.0, battery_v=24.6,
                          obstacle_front_m=obstacle, obstacle_left_m=2.0,
                          obstacle_right_m=2.0, mode=int(P.RobotMode.PATROL),
                          tel_seq=i + 1)
        msg.received_s = t
        msg.seq = i + 1
        out.append((t, "telemetry", msg))
        if i % 20 == 19:
            out.append((t + 0.01, "tick", None))
    return out


def run_desk(kind: str, tmp_path, qtbot) -> tuple[list[dict], dict[str, list[tuple]]]:
    """Feed the stream to a headless desk or a window; the alarm transitions and the
    archive's rows."""
    clock = Clock()
    link = FakeLink()
    archive = Archive(tmp_path / f"{kind}.sqlite3")
    cfg = dataclasses.replace(default_alarm_config(),
                              limits=[*default_alarm_config().limits, OBSTACLE_RULE])
    kw = dict(alarm_config=cfg, clock=clock.wall, mono=clock.mono,
              meter_service=MeterService(clock=clock.mono, utc_clock=clock.wall))
    recorder = SessionRecorder(tmp_path / f"{kind}-out")
    if kind == "headless":
        desk = build_headless_desk(link, recorder, archive, **kw)
        send = desk.gateway.send
    else:
        win = build_window(link, recorder, archive, **kw)
        qtbot.addWidget(win)
        desk = win.desk
        # the operator's intent, as the map panel emits it
        send = win.map_panel.command_requested.emit  # noqa: E731
    transitions: list[dict] = []
    desk.pipeline.listen("alarm", lambda tr: transitions.append(tr.as_record()))
    for t, what, msg in stream():  # one go: no timer runs between two messages
        clock.t = t
        if what == "tick":
            desk.tick()
        elif what == "command":
            send(*msg)
        else:
            getattr(link, LINK_SIGNALS[what]).emit(msg)
    if kind == "window":
        win.close()
    desk.close()  # writes what is pending, closes the archive
    return transitions, archive_rows(tmp_path / f"{kind}.sqlite3")


def archive_rows(path) -> dict[str, list[tuple]]:
    """Every row of every table but the session's and the file's own (whose times are the
    wall clock's: when the desk started and ended)."""
    con = sqlite3.connect(path)
    try:
        tables = [r[0] for r in con.execute(
            "SELECT name FROM sqlite_master WHERE type='table' AND name NOT LIKE 'sqlite_%'")]
        return {t: sorted((_rounded(r) for r in con.execute(f"SELECT * FROM {t}")), key=repr)
                for t in tables if t not in ("session", "meta")}
    finally:
        con.close()


def _rounded(row: tuple) -> tuple:
    """Floats to 12 significant digits: the per-second summaries add samples up per write
    batch, and where the writer thread cuts a batch changes the last bit of a sum."""
    return tuple(float(f"{v:.12g}") if isinstance(v, float) else v for v in row)


def test_headless_desk_and_window_make_the_same_alarms_and_archive(qtbot, tmp_path):
    tr_headless, rows_headless = run_desk("headless", tmp_path, qtbot)
    tr_window, rows_window = run_desk("window", tmp_path, qtbot)
    raised = [(r["alarm"], r["t"]) for r in tr_headless if r["to_state"] == "UNACK"]
    # the site rule on a channel beyond the four the headless desk used to watch
    assert ("obstacle_front_m.low", pytest.approx(T0 + 0.1 + 2.0)) in raised
    assert "gas_lel_pct.high" in [a for a, _t in raised]
    assert "link.lost" in [a for a, _t in raised]
    assert tr_window == tr_headless

    assert rows_window.keys() == rows_headless.keys()
    for table, rows in rows_headless.items():
        assert rows_window[table] == rows, f"the {table} rows differ"
    assert len(rows_headless["telemetry"]) == 80
    assert any(r for r in rows_headless["command"] if "start_patrol" in r)
    # the alarm snapshot is the robot's own JPEG, stored as it came (not re-encoded)
    snaps = [r for r in rows_headless["snapshot"] if "alarm" in r]
    assert snaps and all(_jpeg() in r for r in snaps)
    # the inspection without frames is on record as "no reading"
    assert [r for r in rows_headless["meter_reading"] if "no reading" in r]
