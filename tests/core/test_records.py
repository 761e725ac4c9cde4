"""The archive: every table round-trips, long ranges are down-sampled with min/max kept."""

import csv
import sqlite3

import numpy as np
import pytest

from app.core.records import Archive, ArchiveError, bin_series, default_data_dir
from app.core.records.paths import ENV_VAR

T0 = 1_700_000_000.0


@pytest.fixture
def archive(tmp_path):
    a = Archive(tmp_path / "archive.sqlite3", batch_interval_s=0.05)
    yield a
    a.close()


def test_every_table_round_trips(archive):
    archive.add_telemetry(T0, {"gas_lel_pct": 1.5, "temp_c": 21.0}, seq=7)
    archive.add_telemetry(T0 + 0.1, {"gas_lel_pct": 2.5, "battery_v": 24.1}, seq=8)
    archive.add_pose(T0 + 0.2, 1.0, 2.0, 0.5)
    archive.add_event(T0 + 0.3, "link_state", {"state": "connected"})
    archive.add_command(T0 + 0.4, "ana", "start_patrol", {"route": "default"}, seq=41)
    archive.add_command(T0 + 0.45, "ana", "estop", {}, seq=42)
    archive.ack_command(41, True, "", T0 + 0.5)
    archive.ack_command(42, False, "lease held by another desk", T0 + 0.55)
    archive.ack_command(99, True, "", T0 + 0.56)  # never sent: kept as an event
    archive.add_meter_reading(T0 + 1, "P3", 1.25, "MPa", 0.93, fused=True, state="normal",
                              snapshot_jpeg=b"\xff\xd8jpeg\xff\xd9")
    archive.add_meter_reading(T0 + 0.9, "P3", 1.2, "MPa", 0.6, fused=False, state="normal")
    archive.add_meter_reading(T0 + 1.1, "P4", None, "bar", None, fused=True,
                              state="no reading", error="no needle found")
    rec = {"t": T0 + 2, "alarm": "gas_lel_pct.high", "source": "gas_lel_pct",
           "priority": "HIGH", "from_state": "NORMAL", "to_state": "UNACK", "value": 12.5,
           "limit": 10.0, "unit": "%LEL", "text": "Gas high", "user": None, "reason": None}
    archive.add_alarm_transition(rec)
    archive.add_snapshot(T0 + 2, b"\xff\xd8alarm", "alarm", ref="gas_lel_pct.high")
    archive.add_map(T0 + 3, b"\x89PNG-old")
    archive.add_map(T0 + 4, b"\x89PNG-new")
    archive.add_path(T0 + 5, "global", [[0, 0], [1.5, 2.5], [3, 4]])
    assert archive.flush()

    assert archive.channels() == ["battery_v", "gas_lel_pct", "temp_c"]
    assert archive.time_range() == (T0, T0 + 5)
    s = archive.series("gas_lel_pct", T0 - 1, T0 + 1)
    assert s.t.tolist() == [T0, T0 + 0.1] and s.mean.tolist() == [1.5, 2.5]
    assert archive.series("temp_c", T0 - 1, T0 + 1).mean.tolist() == [21.0]
    assert len(archive.series("nonexistent", T0, T0 + 1)) == 0
    assert archive.telemetry_seqs().tolist() == [7, 8]
    assert archive.poses(T0, T0 + 1).tolist() == [[T0 + 0.2, 1.0, 2.0, 0.5]]
    ev = archive.events(T0, T0 + 1)
    assert [e["kind"] for e in ev] == ["link_state", "command_ack_unmatched"]
    assert ev[0]["data"] == {"state": "connected"}
    assert archive.events(T0, T0 + 1, kinds=["link_state"])[0]["t"] == T0 + 0.3
    cmds = archive.commands(T0, T0 + 1)
    assert [(c["command"], c["user"], c["seq"], c["acked"]) for c in cmds] == \
        [("start_patrol", "ana", 41, True), ("estop", "ana", 42, False)]
    assert cmds[0]["args"] == {"route": "default"}
    assert cmds[1]["ack_reason"] == "lease held by another desk"
    fused = archive.meter_readings(T0, T0 + 2)
    assert [(m["point"], m["value"], m["state"]) for m in fused] == \
        [("P3", 1.25, "normal"), ("P4", None, "no reading")]
    assert fused[1]["error"] == "no needle found"
    everything = archive.meter_readings(T0, T0 + 2, fused_only=False)
    assert [m["fused"] for m in everything] == [False, True, True]
    assert everything[0]["confidence"] == 0.6
    assert archive.snapshot(fused[0]["snapshot_id"]) == b"\xff\xd8jpeg\xff\xd9"
    tr = archive.alarm_transitions(T0, T0 + 3)
    assert len(tr) == 1
    assert {k: tr[0][k] for k in rec} == rec
    snaps = archive.snapshots(T0, T0 + 3)
    assert [(s["reason"], s["ref"]) for s in snaps] == [("meter", "P3"), ("alarm",
                                                                            "gas_lel_pct.high")]
    assert archive.snapshot(snaps[1]["id"]) == b"\xff\xd8alarm"
    assert archive.latest_map() == b"\x89PNG-new"
    assert archive.latest_map(T0 + 3.5) == b"\x89PNG-old"
    assert archive.latest_map(T0) is None
    (p,) = archive.paths(T0, T0 + 10)
    assert p["kind"] == "global" and p["points"].tolist() == [[0, 0], [1.5, 2.5], [3, 4]]
    st = archive.stats()
    assert st["written"]["telemetry"] == 2 and st["pending"] == 0 and st["failures"] == 0
    assert archive.integrity_check() == "ok"


def test_rows_survive_reopening(tmp_path):
    a = Archive(tmp_path / "a.sqlite3")
    for i in range(30):
        a.add_telemetry(T0 + i, {"x": float(i)}, seq=i)
    a.close()
    b = Archive(tmp_path / "a.sqlite3")
    b.add_telemetry(T0 + 30, {"x": 30.0}, seq=30)
    assert b.flush()
    assert b.series("x", T0, T0 + 100).mean.tolist() == [float(i) for i in range(31)]
    b.close()


def test_long_range_is_down_sampled_from_rollups_keeping_min_and_max(archive):
    rng = np.random.default_rng(3)
    n = 3 * 3600 * 10  # three hours at 10 Hz (500 points of 21.6 s: the 10 s roll-up)
    t = T0 + np.arange(n) * 0.1
    v = rng.normal(20.0, 1.0, n)
    v[12345] = 99.0  # a one-sample spike
    v[54321] = -40.0  # and a dip
    for i in range(n):
        archive.add_telemetry(t[i], {"temp_c": v[i]})
    assert archive.flush(timeout=60)
    s = archive.series("temp_c", t[0], t[-1], max_points=500)
    assert s.source.startswith("rollup") and 250 <= len(s) <= 500
    assert s.vmax.max() == 99.0 and s.vmin.min() == -40.0
    assert np.all(s.vmin <= s.mean) and np.all(s.mean <= s.vmax)
    assert np.all(np.diff(s.t) > 0)
    # the bin holding the spike reports it; the overall mean is kept
    assert s.vmax[np.searchsorted(s.t, t[12345]) - 1: np.searchsorted(s.t, t[12345]) + 1] \
        .max() == 99.0
    assert abs(s.mean.mean() - v.mean()) < 0.05
    # a short range is raw, point for point
    short = archive.series("temp_c", t[100], t[199], max_points=2000)
    assert short.source == "raw" and np.allclose(short.mean, v[100:200])
    # a medium range of raw rows beyond max_points is binned from raw rows
    med = archive.series("temp_c", t[12000], t[13000], max_points=400)
    assert med.source == "raw" and len(med) == 400 and med.vmax.max() == 99.0
    # every bin's min/max agree with a brute-force computation
    edges = np.linspace(t[0], t[-1], 501)
    b = np.clip(np.searchsorted(edges, s.t, side="right") - 1, 0, 499)
    for k in (0, 77, 250, 499):
        i = np.flatnonzero(b == k)
        if len(i):
            inside = v[(t >= edges[k] - 60) & (t < edges[k + 1] + 60)]
            assert inside.min() <= s.vmin[i[0]] and s.vmax[i[0]] <= inside.max()


def test_bin_series_weights_by_count():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    n = np.array([1.0, 3.0, 1.0, 1.0])
    s = np.array([2.0, 3.0, 5.0, 7.0])
    tt, mean, lo, hi = bin_series(t, n, s, s / n - 1, s / n + 1, 0.0, 4.0, 2)
    assert mean.tolist() == [5.0 / 4.0, 6.0]
    assert lo.tolist() == [0.0, 4.0] and hi.tolist() == [3.0, 8.0]
    assert tt.tolist() == [3.0 / 4.0, 2.5]


def test_poses_down_sampled_keep_ends(archive):
    for i in range(1000):
        archive.add_pose(T0 + i, float(i), 0.0, 0.0)
    assert archive.flush()
    p = archive.poses(T0, T0 + 1000, max_points=100)
    assert p.shape == (100, 4) and p[0, 1] == 0.0 and p[-1, 1] == 999.0


def test_export_csv_writes_the_raw_rows(archive, tmp_path):
    for i in range(20):
        archive.add_telemetry(T0 + i, {"a": float(i), "b": -float(i)}, seq=i)
    assert archive.flush()
    out = tmp_path / "x.csv"
    assert archive.export_csv(["b"], T0 + 5, T0 + 9, out) == 5
    rows = list(csv.reader(out.open()))
    assert rows[0] == ["time_utc", "t", "seq", "b"]
    assert [r[3] for r in rows[1:]] == ["-5.0", "-6.0", "-7.0", "-8.0", "-9.0"]
    assert rows[1][0].startswith("2023-11-14T22:13:25")


def test_a_non_number_is_counted_not_stored_and_not_fatal(archive):
    archive.add_telemetry(T0, {"a": "oops"})
    archive.add_telemetry(T0 + 1, {"a": 1.0})
    assert archive.flush()
    assert archive.stats()["dropped"] == {"bad_telemetry": 1}
    assert archive.series("a", T0 - 1, T0 + 2).mean.tolist() == [1.0]


def test_a_foreign_or_corrupt_file_gets_a_clear_message(tmp_path):
    junk = tmp_path / "junk.sqlite3"
    junk.write_bytes(b"this is a text file, not a database\n" * 100)
    with pytest.raises(ArchiveError, match="not a Station Patrol archive"):
        Archive(junk)
    assert junk.read_bytes().startswith(b"this is a text file")  # untouched
    other = tmp_path / "other.sqlite3"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE customers (name TEXT)")
    con.commit()
    con.close()
    with pytest.raises(ArchiveError, match="another program"):
        Archive(other)
    damaged = tmp_path / "damaged.sqlite3"
    a = Archive(damaged)
    for i in range(2000):
        a.add_event(T0 + i, "e", {"i": i, "pad": "x" * 200})
    a.close()
    raw = bytearray(damaged.read_bytes())
    raw[100:4096] = b"\xa5" * (4096 - 100)  # scribble over the schema page
    damaged.write_bytes(bytes(raw))
    with pytest.raises(ArchiveError, match="damaged|cannot be opened|another program"):
        Archive(damaged)
    folder = tmp_path / "dir.sqlite3"
    folder.mkdir()
    with pytest.raises(ArchiveError, match="is a folder"):
        Archive(folder)


def test_default_data_dir_follows_env_and_platform(monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, str(tmp_path / "here"))
    assert default_data_dir() == tmp_path / "here"
    monkeypatch.delenv(ENV_VAR)
    monkeypatch.setattr("sys.platform", "linux")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert default_data_dir() == tmp_path / "xdg" / "station-patrol"
    monkeypatch.delenv("XDG_DATA_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_data_dir() == tmp_path / "home" / ".local" / "share" / "station-patrol"
    monkeypatch.setattr("sys.platform", "darwin")
    assert default_data_dir() == tmp_path / "home" / "Library" / "Application Support" / \
        "Station Patrol"
    # platformdirs asks the Windows shell for the folder; off Windows, its
    # environment-variable way stands in for it
    import platformdirs.windows as win

    monkeypatch.setattr(win, "get_win_folder", win.get_win_folder_from_env_vars)
    monkeypatch.setattr("sys.platform", "win32")
    monkeypatch.setenv("LOCALAPPDATA", str(tmp_path / "local"))
    assert default_data_dir() == tmp_path / "local" / "Station Patrol"


def test_tests_never_write_to_the_home_folder():
    import os

    assert os.environ.get(ENV_VAR), "tests/conftest.py must point the data folder elsewhere"
    assert not str(default_data_dir()).startswith(os.path.expanduser("~/.local"))
