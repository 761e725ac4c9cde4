"""End the robot process together with the desk that started it.

A demo robot is a child of the desk. When the desk ends in an orderly way it
stops the robot; when it aborts, is killed (SIGKILL) or crashes, nothing would,
and the robot would live on as an orphan holding its port. So the desk hands
the robot the write end of a pipe as its standard input and never writes to
it: when the desk ends, however it ends, the operating system closes that end
and the robot reads end-of-file. This works on every OS.

On Linux the robot also asks the kernel for SIGTERM when its parent dies
(``prctl(PR_SET_PDEATHSIG)``), which also covers a robot whose standard input
is busy elsewhere. (The kernel sends it when the parent *thread* that started
the robot ends: start the robot from the desk's main thread.)
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os
import signal
import sys
import threading
from collections.abc import Callable
from typing import BinaryIO

log = logging.getLogger(__name__)

__all__ = ["exit_with_parent", "set_parent_death_signal", "watch_stream_end"]

PR_SET_PDEATHSIG = 1  # linux/prctl.h


def set_parent_death_signal(sig: int = signal.SIGTERM) -> bool:
    """Linux: ask for ``sig`` when the parent dies. False elsewhere or on failure."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0) != 0:
            log.warning("prctl(PR_SET_PDEATHSIG) failed: %s", os.strerror(ctypes.get_errno()))
            return False
    except (OSError, AttributeError) as e:
        log.warning("no parent-death signal: %s", e)
        return False
    return True


def watch_stream_end(stream: BinaryIO, on_end: Callable[[], None]) -> threading.Thread:
    """Call ``on_end`` (on a daemon thread) once ``stream`` reaches its end.

    The thread reads the stream's file descriptor itself (``os.read``), not the
    buffered stream: a daemon thread blocked in a buffered read holds the
    buffer's lock, and the interpreter, ending while it waits, aborted
    ("Fatal Python error: _enter_buffered_busy") instead of exiting with 0."""
    fd = stream.fileno()

    def run() -> None:
        try:
            while os.read(fd, 4096):
                pass  # the desk never writes; anything that comes is ignored
        except (OSError, ValueError) as e:
            log.debug("parent pipe: %s", e)
        log.info("the desk that started this robot has ended: shutting down")
        on_end()

    t = threading.Thread(target=run, name="parent-watch", daemon=True)
    t.start()
    return t


def exit_with_parent(on_end: Callable[[], None], parent_pid: int | None = None) -> None:
    """Both mechanisms: standard input's end calls ``on_end``; on Linux the parent's
    death also sends SIGTERM (whose handler the caller has installed). If the
    parent (``parent_pid``) is already gone, ``on_end`` is called at once."""
    set_parent_death_signal(signal.SIGTERM)
    if parent_pid is not None and os.getppid() != parent_pid:
        on_end()  # the parent died before the signal was asked for
        return
    watch_stream_end(sys.stdin.buffer, on_end)
