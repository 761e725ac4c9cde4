"""app/gui_jobs: a job runs on its owner's own pool and its outcome comes back queued
on the GUI thread; an owner deleted while the job runs waits for it and gets nothing."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import threading
from pathlib import Path

from PySide6.QtCore import QObject

from app.gui_jobs import GuiJobs

ROOT = Path(__file__).resolve().parents[2]


def test_the_result_comes_back_queued_on_the_gui_thread(qtbot):
    owner = QObject()
    jobs = GuiJobs(owner)
    ran_on, got = [], []
    jobs.start(lambda: ran_on.append(threading.current_thread()) or 42,
               lambda r: got.append((r, threading.current_thread())))
    assert jobs.wait(10000)
    assert ran_on and ran_on[0] is not threading.main_thread()
    assert got == []  # queued: nothing until the event loop runs
    assert jobs.busy
    qtbot.waitUntil(lambda: got != [], timeout=5000)
    assert got == [(42, threading.main_thread())]
    assert not jobs.busy



def test_a_failed_job_reports_its_exception_or_is_logged(qtbot, caplog):
    owner = QObject()
    jobs = GuiJobs(owner)

    def broken():
        raise OSError("disk gone")

    failures, results = [], []
    jobs.start(broken, results.append, failures.append)
    qtbot.waitUntil(lambda: failures != [], timeout=5000)
    assert results == [] and isinstance(failures[0], OSError)
    with caplog.at_level(logging.ERROR, logger="app.gui_jobs"):
        jobs.start(broken, results.append)
        qtbot.waitUntil(lambda: not jobs.busy, timeout=5000)
    assert "disk gone" in caplog.text
    assert results == []


# Owners deleted while their job runs, a hundred times, both ways an owner goes: a
# Python-owned one with its last reference, a child with its parent (deleteLater).
_OWNER_DELETED = r"""
import threading
from PySide6.QtCore import QCoreApplication, QEvent, QObject
from PySide6.QtWidgets import QApplication
app = QApplication([])
from app.gui_jobs import GuiJobs

started = threading.Event()
released = threading.Event()
delivered = []
finished = [0]
held = [0]


def slow():
    started.set()
    # still running when its owner goes: released by the owner's `destroyed`, which
    # Qt emits before it deletes the owner's children (the pool among them)
    if released.wait(10):
        held[0] += 1
    finished[0] += 1
    return object()


for i in range(100):
    parent = QObject()
    owner = QObject(parent) if i % 2 else QObject()
    owner.destroyed.connect(released.set)
    started.clear()
    released.clear()
    GuiJobs(owner).start(slow, delivered.append, delivered.append)
    assert started.wait(10)
    if i % 2:
        parent.deleteLater()
        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
    else:
        del owner  # its last reference: deleted here, on the GUI thread
    app.processEvents()
# every job has ended (each pool waited for its own): whatever they posted is queued
QCoreApplication.sendPostedEvents()
app.processEvents()
print(finished[0], held[0], len(delivered))
"""


def test_an_owner_deleted_during_its_job_waits_for_it_and_gets_nothing():
    """The pool (made first) waits for the job while the carrier it emits on is still
    there; the carrier then goes with the queued result: no crash, no emit on a
    deleted object from the pool's thread, no callback into an owner that is gone."""
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen", "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-X", "faulthandler", "-c", _OWNER_DELETED],
                         capture_output=True, text=True, timeout=180, env=env, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.split() == ["100", "100", "0"]  # every job ran to its end, still
    # running when its owner went; none delivered
    assert "Traceback" not in out.stderr and "RuntimeError" not in out.stderr, \
        out.stderr[-3000:]
