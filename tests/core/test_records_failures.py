"""Archive failure paths: held in memory, retried, reported; and retention pruning."""

import csv
import sqlite3
import threading
import time

import pytest
from waits import wait_until

from app.core.records import Archive

T0 = 1_700_000_000.0


class StatusLog:
    def __init__(self):
        self.items: list[tuple[bool, str]] = []
        self.failed = threading.Event()
        self.recovered = threading.Event()

    def __call__(self, ok: bool, msg: str) -> None:
        self.items.append((ok, msg))
        (self.recovered if ok else self.failed).set()


@pytest.fixture
def status():
    return StatusLog()


def _feed(a, start, n):
    for i in range(start, start + n):
        a.add_telemetry(T0 + i * 0.1, {"gas_lel_pct": float(i)}, seq=i)
        if i % 10 == 0:
            a.add_event(T0 + i * 0.1, "patrol_status", {"i": i, "pad": "x" * 500})


def _check_all_there(a, n):
    assert a.telemetry_seqs().tolist() == list(range(n))
    assert [e["data"]["i"] for e in a.events(T0, T0 + n)] == list(range(0, n, 10))


def test_disk_full_holds_rows_and_writes_them_after_recovery(tmp_path, status):
    a = Archive(tmp_path / "a.sqlite3", batch_interval_s=0.05, on_status=status)
    _feed(a, 0, 50)
    assert a.flush()
    pages = a.call_in_writer(lambda con: con.execute("PRAGMA page_count").fetchone()[0])
    # the file may not grow any more: SQLite answers "database or disk is full"
    a.call_in_writer(lambda con: con.execute(f"PRAGMA max_page_count={pages}"))
    _feed(a, 50, 400)
    assert status.failed.wait(10)
    assert "full" in status.items[0][1] and not status.items[0][0]
    assert not a.flush(timeout=0.3)  # held, not on disk yet
    st = a.stats()
    assert st["failing"] and st["held"] > 0 and st["failures"] >= 1 and not st["dropped"]
    _feed(a, 450, 50)  # the desk keeps adding while the disk is full
    a.call_in_writer(lambda con: con.execute("PRAGMA max_page_count=1073741823"))
    assert status.recovered.wait(15)
    assert a.flush(timeout=10)
    _check_all_there(a, 500)
    assert a.stats()["dropped"] == {} and not a.stats()["failing"]
    assert [ok for ok, _ in status.items] == [False, True]
    a.close()


def test_read_only_database_holds_rows_until_writable_again(tmp_path, status):
    a = Archive(tmp_path / "a.sqlite3", batch_interval_s=0.05, on_status=status)
    a.call_in_writer(lambda con: con.execute("PRAGMA query_only=1"))  # refuses every write
    _feed(a, 0, 100)
    assert status.failed.wait(10)
    assert "readonly" in status.items[0][1]
    assert a.telemetry_seqs().tolist() == []
    a.call_in_writer(lambda con: con.execute("PRAGMA query_only=0"))
    assert status.recovered.wait(15) and a.flush(timeout=10)
    _check_all_there(a, 100)
    a.close()


def test_locked_database_is_retried_without_blocking_the_caller(tmp_path, status):
    path = tmp_path / "a.sqlite3"
    a = Archive(path, batch_interval_s=0.05, on_status=status, busy_timeout_ms=50)
    other = sqlite3.connect(path, isolation_level=None)
    other.execute("BEGIN EXCLUSIVE")  # another program holds the file
    t = time.monotonic()
    _feed(a, 0, 200)
    adding_s = time.monotonic() - t
    assert status.failed.wait(10)
    assert "locked" in status.items[0][1]
    assert a.stats()["held"] > 0
    other.execute("ROLLBACK")
    other.close()
    assert status.recovered.wait(15) and a.flush(timeout=10)
    _check_all_there(a, 200)
    assert adding_s < 5.0  # generous: the adds only enqueue, they never wait for the lock
    a.close()


def test_memory_bound_drops_oldest_bulk_rows_first_and_says_so(tmp_path, status):
    a = Archive(tmp_path / "a.sqlite3", batch_interval_s=0.05, on_status=status,
                max_held_rows=100)
    a.call_in_writer(lambda con: con.execute("PRAGMA query_only=1"))
    _feed(a, 0, 150)  # 150 telemetry rows + 15 events = 165 > 100
    wait_until(lambda: a.stats()["dropped"].get("telemetry", 0) == 65, 10, 0.02)
    assert any("dropped" in m and "65" in m for ok, m in status.items if not ok)
    a.call_in_writer(lambda con: con.execute("PRAGMA query_only=0"))
    assert status.recovered.wait(15) and a.flush(timeout=10)
    # the oldest telemetry went; every event (precious) and the newest telemetry stayed
    assert a.telemetry_seqs().tolist() == list(range(65, 150))
    assert len(a.events(T0, T0 + 100)) == 15
    st = a.stats()
    assert st["dropped"] == {"telemetry": 65} and st["pending"] == 0
    a.close()


def test_retention_exports_then_prunes_old_rows(tmp_path):
    day = 86400.0
    now = T0 + 40 * day
    a = Archive(tmp_path / "a.sqlite3", batch_interval_s=0.05)
    for d in range(40):
        for i in range(300):
            a.add_telemetry(T0 + d * day + i, {"temp_c": float(d)}, seq=d * 1000 + i)
        a.add_event(T0 + d * day, "patrol_status", {"day": d})
        a.add_pose(T0 + d * day, float(d), 0.0, 0.0)
        a.add_alarm_transition({"t": T0 + d * day, "alarm": "temp_c.high", "to_state": "UNACK"})
    assert a.flush(timeout=20)
    cutoff = now - 30 * day
    assert a.prune(cutoff, export_dir=tmp_path / "exported").wait(60)
    pruned = a.stats()["pruned"]
    assert pruned["telemetry"] == 10 * 300 and pruned["event"] == 10 and pruned["rollup"] > 0
    assert a.time_range()[0] >= cutoff
    assert [e["data"]["day"] for e in a.events(0, now)] == list(range(10, 40))
    assert len(a.alarm_transitions(0, now)) == 30 and len(a.poses(0, now)) == 30
    assert a.series("temp_c", T0, T0 + 10 * day - 600, max_points=100).t.size == 0
    kept = a.series("temp_c", T0, now, max_points=100)
    assert kept.vmin.min() == 10.0 and kept.vmax.max() == 39.0
    files = {p.name.split("-before-")[0]: p for p in (tmp_path / "exported").iterdir()}
    assert {"telemetry", "event", "pose", "alarm_transition"} <= set(files)
    rows = list(csv.reader(files["telemetry"].open()))
    assert len(rows) == 1 + 10 * 300 and rows[0][:3] == ["time_utc", "t", "seq"]
    assert {r[3] for r in rows[1:]} == {str(float(d)) for d in range(10)}
    assert a.integrity_check() == "ok"
    a.close()


def test_retention_days_prunes_on_open(tmp_path):
    a = Archive(tmp_path / "a.sqlite3")
    old = time.time() - 10 * 86400
    a.add_event(old, "old", {})
    a.add_event(time.time(), "new", {})
    a.close()
    b = Archive(tmp_path / "a.sqlite3", retention_days=5)
    wait_until(lambda: b.stats()["pruned"].get("event") == 1, 10, 0.02)
    assert [e["kind"] for e in b.events(0, time.time() + 1)] == ["new"]
    b.close()


def test_closed_archive_counts_late_rows(tmp_path):
    a = Archive(tmp_path / "a.sqlite3")
    a.close()
    a.add_event(T0, "late", {})
    assert a.stats()["dropped"] == {"event": 1}


def test_a_row_sqlite_refuses_is_dropped_and_counted_not_the_batch(tmp_path, status):
    import numpy as np

    a = Archive(tmp_path / "a.sqlite3", batch_interval_s=0.2, on_status=status)
    for i in range(10):
        a.add_telemetry(T0 + i, {"x": float(i)}, seq=2**70 if i == 4 else i)  # too big
        a.add_event(T0 + i, "e", {"i": i})
    a.add_telemetry(T0 + 20, {"new_channel": 1.0}, seq=2**70)  # refused with its new layout
    a.add_telemetry(T0 + 21, {"new_channel": 2.0}, seq=21)
    a.add_snapshot(T0, np.zeros((4, 4), np.float32), "alarm", ref="x")  # not an RGB image
    a.add_snapshot(T0, np.full((480, 640, 3), 50, np.uint8), "alarm", ref="y")
    assert a.flush()
    assert a.telemetry_seqs().tolist() == [0, 1, 2, 3, 5, 6, 7, 8, 9, 21]
    assert a.series("new_channel", T0, T0 + 30).mean.tolist() == [2.0]
    assert len(a.events(T0, T0 + 10)) == 10
    st = a.stats()
    assert st["dropped"] == {"bad_telemetry": 2, "bad_snapshot": 1}
    assert not st["failing"] and status.items == []  # the disk is fine: no failure alarm
    (snap,) = a.snapshots(T0, T0)
    assert snap["ref"] == "y" and snap["size"] < 20_000
    assert a.snapshot(snap["id"]).startswith(b"\xff\xd8")
    # the roll-ups hold only the rows written
    assert a.series("x", T0, T0 + 100000, max_points=1).vmax.tolist() == [9.0]
    a.close()
