"""Start a local sim_robot process and learn the port it listens on (no Qt)."""

from __future__ import annotations

import logging
import os
import re
import subprocess
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path

from app.comm import auth
from app.core.thread_priority import lower_this_thread

log = logging.getLogger(__name__)

_LISTEN = re.compile(r"listening on (\S+):(\d+)")


class SimRobotProcess:
    """``with SimRobotProcess(seed=1) as sim: sim.host, sim.port``.

    The robot's stdout and stderr are read on a thread and kept (last 200 lines)
    so a failure can say what the robot printed. The robot says it listens only
    once its navigation is ready; a first run compiles the planner first (tens of
    seconds, minutes on a slow or busy machine), hence the generous
    ``start_timeout_s``; ``on_wait(seconds)`` is called every ``wait_note_s`` while
    it waits, so a caller can show that the start goes on. A robot that exits
    before it listens is reported at once, with what it printed.

    The robot ends with this process however it ends (``stop``, an abort, SIGKILL,
    a crash): it runs in its own process group (a Ctrl+C in the terminal reaches
    the desk, which stops it in order), its standard input is a pipe from here
    that it watches for end-of-file, and on Linux it also asks for SIGTERM on its
    parent's death (sim_robot/parent_watch.py). Start it from the main thread.
    """

    def __init__(self, *, host: str = "127.0.0.1", port: int = 0, seed: int = 1,
                 time_scale: float = 1.0, extra: list[str] | None = None,
                 start_timeout_s: float = 600.0, key_file: str | None = None,
                 on_wait: Callable[[float], None] | None = None,
                 wait_note_s: float = 30.0) -> None:
        # the robot signs nothing but checks every command with the desk's station key:
        # hand it the same key file (created here on first use)
        key_path = Path(key_file).expanduser() if key_file else auth.default_key_path()
        auth.load_or_create_key(key_path)
        self.key_file = str(key_path)
        self.args = [sys.executable, "-m", "sim_robot", "--listen", f"{host}:{port}",
                     "--seed", str(seed), "--time-scale", str(time_scale),
                     "--key-file", self.key_file, "--exit-with-parent", *(extra or [])]
        self.start_timeout_s = start_timeout_s
        self.on_wait = on_wait
        self.wait_note_s = wait_note_s
        self.proc: subprocess.Popen | None = None
        self.host = host
        self.port = port
        self.output: deque[str] = deque(maxlen=200)
        self._ready = threading.Event()
        self._pumped = threading.Event()  # its output has ended

    def start(self) -> SimRobotProcess:
        log.info("starting %s", " ".join(self.args))
        group: dict = ({"start_new_session": True} if os.name == "posix" else
                       {"creationflags": getattr(subprocess, "CREATE_NEW_PROCESS_GROUP", 0)})
        env = {**os.environ, "SIM_ROBOT_PARENT_PID": str(os.getpid())}
        # stdin: a pipe this process never writes to; its end tells the robot we ended
        self.proc = subprocess.Popen(self.args, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, stdin=subprocess.PIPE,
                                     text=True, bufsize=1, env=env, **group)
        threading.Thread(target=self._pump, daemon=True, name="sim-robot-output").start()
        t0 = time.monotonic()
        next_note = self.wait_note_s
        while not self._ready.wait(min(0.5, self.wait_note_s)):
            waited = time.monotonic() - t0
            code = self.proc.poll()
            if code is not None:
                self._pumped.wait(2.0)  # its last lines
                if self._ready.is_set():
                    break
                tail = "\n".join(self.output)
                raise RuntimeError(f"sim_robot exited with code {code} before it listened; "
                                   f"it printed:\n{tail}")
            if waited > self.start_timeout_s:
                tail = "\n".join(self.output)
                self.stop()
                raise RuntimeError(f"sim_robot did not report a port within "
                                   f"{self.start_timeout_s:.0f} s; it printed:\n{tail}")
            if self.on_wait is not None and waited >= next_note:
                next_note += self.wait_note_s
                self.on_wait(waited)
        return self

    def _pump(self) -> None:
        assert self.proc is not None and self.proc.stdout is not None
        lower_this_thread()  # the robot's log lines can wait for the GUI thread
        for line in self.proc.stdout:
            line = line.rstrip("\n")
            self.output.append(line)
            m = _LISTEN.search(line)
            if m and not self._ready.is_set():
                self.host, self.port = m.group(1), int(m.group(2))
                self._ready.set()
        self._pumped.set()

    @property
    def pid(self) -> int | None:
        return None if self.proc is None else self.proc.pid

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def kill(self) -> None:
        """Vanish at once (SIGKILL), as a crashed robot would."""
        if self.alive():
            self.proc.kill()
            self.proc.wait(5)

    def stop(self, timeout_s: float = 5.0) -> int | None:
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.terminate()
            t0 = time.monotonic()
            try:
                self.proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                log.warning("sim_robot did not stop in %.1f s; killing it",
                            time.monotonic() - t0)
                self.proc.kill()
                self.proc.wait(5)
        if self.proc.stdin is not None and not self.proc.stdin.closed:
            self.proc.stdin.close()
        return self.proc.returncode

    def __enter__(self) -> SimRobotProcess:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
