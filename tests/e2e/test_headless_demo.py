"""`station-patrol --demo --headless` records what it receives and summarises it."""

import json
import os
import subprocess
import sys

import pytest

from app.core.records import Archive

pytestmark = [pytest.mark.e2e, pytest.mark.slow(37)]


# wall seconds the run may take: its 20 s, and a compile where the suite's kernels are
# missing (the suite compiles them before its first test, tests/conftest.py)
FIRST_RUN_S = 580


@pytest.fixture(scope="module")
def first_run(tmp_path_factory):
    """The README's headless demo, run once for the module on a machine that
    has never run it (its own data folder and station key): 20 s with --patrol
    at the headless demo's default time scale. The tests below check
    independent things of this one run. Its kernels are the ones the suite
    compiled before its first test; a first compile's load on the robot's
    threads is played in tests/sim/test_slow_start.py."""
    base = tmp_path_factory.mktemp("first-headless-demo")
    out, data = base / "run", base / "data"
    env = dict(os.environ, STATION_PATROL_KEY_FILE=str(base / "station.key"))
    proc = subprocess.run(
        [sys.executable, "-m", "app.cli", "--demo", "--headless", "--duration", "20",
         "--patrol", "--out", str(out), "--data-dir", str(data)],
        capture_output=True, text=True, timeout=FIRST_RUN_S, env=env)
    return proc, out, data


@pytest.mark.timeout(FIRST_RUN_S + 20)
def test_headless_demo_writes_summary(first_run):
    proc, out, data = first_run
    assert proc.returncode == 0, proc.stdout + proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["counts"]["telemetry"] >= 20
    assert summary["counts"]["video"] >= 10
    assert summary["counts"]["pose"] >= 10
    last = summary["last_telemetry"]
    assert 0 <= last["gas_lel_pct"] < 100 and 18 < last["battery_v"] < 30
    rows = (out / "telemetry.csv").read_text().strip().splitlines()
    assert len(rows) - 1 == summary["counts"]["telemetry"]
    assert (out / "last_frame.jpg").stat().st_size > 1000
    # --patrol: the robot was asked to patrol, accepted, and its progress is on record
    events = [json.loads(line) for line in (out / "events.jsonl").read_text().splitlines()]
    assert any(e["kind"] == "command_ack" and e["ok"] for e in events)
    states = {e["state"] for e in events if e["kind"] == "patrol_status"}
    assert states & {"planning", "driving", "avoiding"}, states
    assert (out / "map.png").read_bytes().startswith(b"\x89PNG")
    # the archive holds the same: every telemetry message, the command and its ack
    archive = Archive(data / "archive.sqlite3")
    try:
        assert archive.telemetry_count() == summary["counts"]["telemetry"]
        assert summary["archive"]["written"]["telemetry"] == summary["counts"]["telemetry"]
        assert summary["archive"]["pending"] == 0 and summary["archive"]["dropped"] == {}
        cmds = [c for c in archive.commands(0, 4e9) if c["command"] == "start_patrol"]
        assert len(cmds) == 1 and cmds[0]["user"] and cmds[0]["acked"] is not None
        kinds = {e["kind"] for e in archive.events(0, 4e9)}
        assert {"link_state", "robot_event", "patrol_status"} <= kinds
        assert len(archive.poses(0, 4e9)) == summary["counts"]["pose"]
        assert archive.latest_map().startswith(b"\x89PNG")
        # every row belongs to this desk run: one session, named with its robot
        sessions = archive.sessions()
        assert len(sessions) == 1, sessions
        [session] = sessions
        assert session["robot"].startswith("127.0.0.1:") and session["desk"]
        assert session["ended_t"] is not None
        view = archive.session_view(session["id"])
        assert view.telemetry_count() == summary["counts"]["telemetry"]
        assert len(view.poses(0, 4e9)) == summary["counts"]["pose"]
    finally:
        archive.close()


def test_headless_desk_runs_on_when_the_archive_file_is_unusable(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    (data / "archive.sqlite3").write_text("a shopping list, not a database\n")
    proc = subprocess.run(
        [sys.executable, "-m", "app.cli", "--demo", "--headless", "--duration", "3",
         "--out", str(tmp_path / "run"), "--data-dir", str(data)], capture_output=True,
        text=True, timeout=90)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "archive disabled" in proc.stderr and "not a Station Patrol archive" in proc.stderr
    events = [json.loads(line) for line in
              (tmp_path / "run" / "events.jsonl").read_text().splitlines()]
    assert any(e["kind"] == "archive_status" and not e["ok"] for e in events)
    assert (data / "archive.sqlite3").read_text().startswith("a shopping list")


def test_bad_arguments_get_a_clear_message(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "app.cli", "--connect", "nowhere"],
                          capture_output=True, text=True, timeout=30)
    assert proc.returncode == 2
    assert "HOST:PORT" in proc.stderr
    proc = subprocess.run([sys.executable, "-m", "app.cli"], capture_output=True, text=True,
                          timeout=30)
    assert proc.returncode == 2 and "--demo" in proc.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text("nonsense = 1\n")
    proc = subprocess.run([sys.executable, "-m", "app.cli", "--demo", "--config", str(bad)],
                          capture_output=True, text=True, timeout=30)
    assert proc.returncode == 2 and "unknown setting 'nonsense'" in proc.stderr


@pytest.mark.timeout(FIRST_RUN_S + 20)
def test_headless_desk_reads_the_meters_the_patrol_inspects(first_run):
    """Without a window the meters are read too: fused readings with their
    confidence, raw per-frame readings and a snapshot go into the archive."""
    proc, out, data = first_run
    assert proc.returncode == 0, proc.stdout + proc.stderr
    archive = Archive(data / "archive.sqlite3")
    try:
        fused = archive.meter_readings(0, 4e9, fused_only=True)
        raw = [r for r in archive.meter_readings(0, 4e9, fused_only=False) if not r["fused"]]
        assert fused, "no meter was read during the patrol"
        assert len(raw) >= len(fused)
        read = [r for r in fused if r["value"] is not None]
        assert read and all(0.0 <= r["confidence"] <= 1.0 for r in read)
        assert all(r["unit"] for r in read)
        assert any(s["reason"] for s in archive.snapshots(0, 4e9))
    finally:
        archive.close()
    events = [json.loads(line) for line in (out / "events.jsonl").read_text().splitlines()]
    assert any(e["kind"] == "meter_reading" for e in events)


@pytest.mark.timeout(FIRST_RUN_S + 20)
def test_first_headless_demo_patrols_at_once_without_a_failsafe_stop(first_run):
    """The README's headless demo on a machine that has never run it: the robot
    prepares its planner before it accepts the desk, so no thread that feeds the
    MCU's link watchdog starves (no "Fail-safe stop" alarm) and the patrol drives
    at once; at the headless demo's time scale its 20 s reach and read at least
    one gauge."""
    proc, out, data = first_run
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "4x real time" in proc.stdout
    events = [json.loads(line) for line in (out / "events.jsonl").read_text().splitlines()]
    failsafe = [e for e in events
                if e.get("source") == "flag.FAILSAFE_STOP"
                or (e["kind"] == "robot_event" and "FAILSAFE" in e.get("text", ""))
                or e.get("code") == "failsafe_stop"]
    assert not failsafe, failsafe
    states = [e["state"] for e in events if e["kind"] == "patrol_status"]
    assert "driving" in states and "inspecting" in states, states
    read = [e for e in events if e["kind"] == "meter_reading" and e["value"] is not None]
    assert read, [e for e in events if e["kind"] == "meter_reading"]
    archive = Archive(data / "archive.sqlite3")
    try:
        assert [r for r in archive.meter_readings(0, 4e9, fused_only=True)
                if r["value"] is not None]
        alarms = {a["alarm"] for a in archive.alarm_transitions(0, 4e9)}
        assert "flag.FAILSAFE_STOP" not in alarms, alarms
    finally:
        archive.close()
