"""The demo's robot child ends with the desk however the desk ends (issue 12, C):
killed outright (SIGKILL), the desk cannot stop it, yet the robot goes."""

import os
import re
import signal
import subprocess
import sys
import threading

import pytest
from waits import wait_until

pytestmark = pytest.mark.e2e

LINE = re.compile(r"simulated robot listening on \S+:\d+ \(pid (\d+)\)")


def _gone(pid: int) -> bool:
    """The process has ended (a zombie waiting for its new parent to reap it counts)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except FileNotFoundError:
        return True
    except OSError:
        pass
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def _env(tmp_path) -> dict:
    return {**os.environ, "STATION_PATROL_KEY_FILE": str(tmp_path / "station.key"),
            "STATION_PATROL_DATA_DIR": str(tmp_path / "data"), "QT_QPA_PLATFORM": "offscreen"}


def _read_lines(proc, lines: list[str]) -> None:
    for line in proc.stdout:
        lines.append(line)


def _listening_robot(tmp_path):
    """A robot started as the desk starts it (its standard input a pipe from here),
    once it listens: (process, its output lines so far, the thread reading them)."""
    robot = subprocess.Popen(
        [sys.executable, "-m", "sim_robot", "--listen", "127.0.0.1:0", "--no-video",
         "--key-file", str(tmp_path / "station.key"), "--exit-with-parent"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env=_env(tmp_path))
    lines: list[str] = []
    reader = threading.Thread(target=_read_lines, args=(robot, lines), daemon=True)
    reader.start()
    try:
        wait_until(lambda: any("listening on" in s for s in lines), 60,
                   what=lambda: "the robot's listening line in:\n" + "".join(lines))
    except BaseException:
        robot.kill()
        raise
    return robot, lines, reader


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="SIGKILL is POSIX")
def test_robot_child_is_gone_soon_after_the_desk_is_killed(tmp_path):
    desk = subprocess.Popen(
        [sys.executable, "-m", "app.cli", "--demo", "--headless", "--duration", "300",
         "--out", str(tmp_path / "out")], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL, text=True, env=_env(tmp_path))
    lines: list[str] = []
    threading.Thread(target=_read_lines, args=(desk, lines), daemon=True).start()
    robot = None
    try:
        m = wait_until(lambda: next((LINE.search(s) for s in lines if LINE.search(s)), None),
                       60, what=lambda: "the desk's robot line in:\n" + "".join(lines))
        robot = int(m.group(1))
        assert not _gone(robot)
        os.kill(desk.pid, signal.SIGKILL)  # no handler, no finally: the desk just vanishes
        desk.wait(10)
        wait_until(lambda: _gone(robot), 10, what=f"robot pid {robot} ending")
    finally:
        if desk.poll() is None:
            desk.kill()
        if robot is not None and not _gone(robot):
            os.kill(robot, signal.SIGKILL)  # do not leave an orphan behind a failed test


def test_robot_ends_when_its_standard_input_closes(tmp_path):
    """The pipe watch alone (the mechanism that works on every OS)."""
    robot, lines, _ = _listening_robot(tmp_path)
    try:
        robot.stdin.close()  # as when the desk ends: the write end goes away
        assert robot.wait(15) == 0
        assert any("has ended: shutting down" in s for s in lines)
    finally:
        if robot.poll() is None:
            robot.kill()


def test_robot_stopped_while_its_pipe_watch_waits_exits_cleanly(tmp_path):
    """The desk's orderly stop (SIGTERM) while the pipe watch is blocked reading the
    still-open standard input: the robot exits with 0. The watch read the buffered
    stream, whose lock it held as the interpreter ended, and the robot aborted
    ("Fatal Python error: _enter_buffered_busy")."""
    robot, lines, reader = _listening_robot(tmp_path)
    try:
        robot.terminate()
        code = robot.wait(15)
        reader.join(5)
        out = "".join(lines)
        assert code == 0, out
        assert "Fatal Python error" not in out and "stopped:" in out
    finally:
        if robot.poll() is None:
            robot.kill()
        robot.stdin.close()
