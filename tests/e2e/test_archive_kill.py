"""SIGKILL the headless desk mid-run: the archive opens afterwards, passes SQLite's
integrity check, and at most the last second of telemetry is missing."""

import csv
import signal
import sqlite3
import subprocess
import sys
import time
from datetime import datetime

import pytest
from waits import wait_until

from app.core.records import Archive

pytestmark = pytest.mark.e2e


def _stored(path):
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=1.0)
        try:
            return con.execute("SELECT count(*) FROM telemetry").fetchone()[0]
        finally:
            con.close()
    except sqlite3.Error:
        return 0


def test_sigkill_mid_run_loses_at_most_the_last_second(tmp_path, sim_robot):
    data, out = tmp_path / "data", tmp_path / "out"
    path = data / "archive.sqlite3"
    log = open(tmp_path / "desk.log", "w")
    desk = subprocess.Popen(
        [sys.executable, "-m", "app.cli", "--connect", f"{sim_robot.host}:{sim_robot.port}",
         "--headless", "--duration", "120", "--out", str(out), "--data-dir", str(data)],
        stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        log_text = (tmp_path / "desk.log").read_text
        wait_until(lambda: _stored(path) >= 30 or desk.poll() is not None, 60, 0.1, log_text)
        first = _stored(path)
        assert first >= 30, log_text()
        wait_until(lambda: _stored(path) >= first + 20, 30, 0.1, log_text)  # rows keep flowing
        desk.send_signal(signal.SIGKILL)
        kill_t = time.time()
        desk.wait(10)
    finally:
        if desk.poll() is None:
            desk.kill()
            desk.wait(10)
        log.close()
    assert desk.returncode == -signal.SIGKILL

    a = Archive(path)  # the desk's next start opens the same file
    try:
        assert a.integrity_check() == "ok"
        newest = a.time_range()[1]
        stored = set(a.telemetry_seqs().tolist())
        assert newest >= kill_t - 1.0, f"newest row {kill_t - newest:.2f} s before the kill"
        # every row the desk had received more than a second before the kill is there
        # (the results folder's CSV is flushed row by row: it is the reference)
        rows = list(csv.DictReader((out / "telemetry.csv").open()))
        older = [int(r["seq"]) for r in rows
                 if datetime.fromisoformat(r["received_utc"]).timestamp() < kill_t - 1.0]
        assert len(older) >= first
        missing = [s for s in older if s not in stored]
        assert missing == []
        # and the file keeps working after the crash
        a.add_event(time.time(), "desk_restarted", {})
        assert a.flush()
    finally:
        a.close()
