"""Every archive row belongs to a session (a desk run with one robot); a session
view reads only its own rows, even when two desks wrote at the same time."""

import sqlite3

import numpy as np

from app.core.records import Archive
from app.core.records.queries import describe_session
from app.core.records.schema import APP_ID, SCHEMA


def _write(a: Archive, t0: float, x: float, gas: float, n: int = 5) -> None:
    for i in range(n):
        t = t0 + i
        a.add_telemetry(t, {"gas_lel_pct": gas, "temp_c": 20.0})
        a.add_pose(t, x + i, 0.0, 0.0)
        a.add_event(t, "link_state", {"state": "connected"})


def test_two_desks_writing_at_once_are_told_apart(tmp_path):
    path = tmp_path / "archive.sqlite3"
    a, b = Archive(path), Archive(path)
    try:
        sa = a.begin_session("desk-a", "10.0.0.5:7000")
        sb = b.begin_session("desk-b")
        b.set_session_robot("10.0.0.9:7000")
        t0 = 1_800_000_000.0
        _write(a, t0, 0.0, 1.0)
        _write(b, t0 + 0.5, 100.0, 7.0)  # interleaved in time, far away
        assert a.flush() and b.flush()
        sessions = {s["id"]: s for s in a.sessions()}
        assert sessions[sa]["desk"] == "desk-a" and sessions[sa]["robot"] == "10.0.0.5:7000"
        assert sessions[sb]["robot"] == "10.0.0.9:7000"
        assert sessions[sa]["telemetry"] == sessions[sb]["telemetry"] == 5
        assert a.telemetry_count() == 10  # the archive as a whole: both
        va, vb = a.session_view(sa), a.session_view(sb)
        assert va.telemetry_count() == 5 and vb.telemetry_count() == 5
        assert np.all(va.poses(0, 4e9)[:, 1] < 10) and np.all(vb.poses(0, 4e9)[:, 1] >= 100)
        _t, _seq, v = vb.telemetry_values(["gas_lel_pct"], 0, 4e9)
        assert set(v[:, 0]) == {7.0}
        s = vb.series("gas_lel_pct", t0 - 3600, t0 + 3600, max_points=10)  # long: no roll-ups
        assert len(s.t) and set(np.round(s.mean, 6)) == {7.0}
        assert vb.channel_stats("gas_lel_pct", t0 - 10, t0 + 10)["max"] == 7.0
        assert len(va.events(0, 4e9)) == 5
        assert va.time_range() == (t0, t0 + 4)
        assert a.latest_session() == sb
        assert "desk desk-b" in vb.describe() and f"session {sb}" in vb.describe()
    finally:
        a.close()
        b.close()
    c = Archive(path)
    try:
        ended = {s["id"]: s["ended_t"] for s in c.sessions()}
        assert ended[sa] is not None and ended[sb] is not None
    finally:
        c.close()


def test_a_schema_1_archive_keeps_its_rows_as_session_0(tmp_path):
    path = tmp_path / "old.sqlite3"
    con = sqlite3.connect(path)  # as schema 1 wrote it: no session columns
    con.executescript(SCHEMA)
    con.executemany("INSERT INTO meta VALUES (?, ?)",
                    [("app", APP_ID), ("schema_version", "1")])
    con.executemany("INSERT INTO pose(t, x, y, theta) VALUES (?,?,?,?)",
                    [(1_700_000_000.0 + i, float(i), 0.0, 0.0) for i in range(3)])
    con.execute("INSERT INTO event(t, kind, data) VALUES (1700000000.0, 'link_state', '{}')")
    con.commit()
    assert "session" not in {r[1] for r in con.execute("PRAGMA table_info(pose)")}
    con.close()
    b = Archive(path)
    try:
        sid = b.begin_session("desk-new")
        _write(b, 1_800_000_000.0, 50.0, 3.0)
        assert b.flush()
        old, new = b.session_view(0), b.session_view(sid)
        assert len(old.poses(0, 4e9)) == 3 and len(old.events(0, 4e9)) == 1
        assert len(new.poses(0, 4e9)) == 5 and new.poses(0, 4e9)[0, 1] == 50.0
        assert b.session_info(sid)["desk"] == "desk-new"
        assert "before sessions" in describe_session({"id": 0})
    finally:
        b.close()
    con = sqlite3.connect(path)
    assert dict(con.execute("SELECT key, value FROM meta"))["schema_version"] == "2"
    con.close()
