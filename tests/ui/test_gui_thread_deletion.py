"""Qt objects die on the GUI thread: the garbage collector is kept to it (app/gui_gc),
and a model deleted while its pool job runs waits for the job before the carrier the
job emits on goes. Each scenario runs in a process of its own: the old behaviour
deletes objects off the GUI thread or raises in the pool's thread, and can crash."""

from __future__ import annotations

import gc
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# Objects owned by Python and caught in a reference cycle (as a desk session, a model
# or a plot item a closed window left behind) are dropped on the GUI thread while a
# writer thread allocates, as the archive writer does; prints how many were destroyed
# off the GUI thread and how many in all.
_CYCLES = r"""
import gc, sys, threading, time
from PySide6.QtCore import QObject, Qt
from PySide6.QtWidgets import QApplication

mode = sys.argv[1]
if mode == "desk":
    from app.ui.app import start_app
    app = start_app("en")
elif mode == "headless":
    from app.headless import start_headless_app
    app = start_headless_app()
else:
    app = QApplication([])
main = threading.main_thread()
where = {"gui": 0, "other": 0}
writer_collections = []


def died(*_):
    where["gui" if threading.current_thread() is main else "other"] += 1


class Held(QObject):
    def __init__(self):
        super().__init__()
        self.me = self  # a reference cycle: only the collector frees it
        self.destroyed.connect(died, Qt.ConnectionType.DirectConnection)  # where it dies


def on_gc(phase, info):
    if phase == "stop" and threading.current_thread() is not main:
        writer_collections.append(1)


gc.callbacks.append(on_gc)
stop = False
made = [0]  # rows the writer made


def writer():  # rows kept until a batch is written, as the archive writer keeps them
    rows = []
    while not stop:
        rows.append({"t": len(rows), "v": [0.0]})
        made[0] += 1
        if len(rows) > 20000:
            rows = []


t = threading.Thread(target=writer, daemon=True)
t.start()
ROUNDS = 20
for _ in range(ROUNDS):
    Held()
    start = made[0]
    end = time.monotonic() + 5.0
    while made[0] < start + 5000 and time.monotonic() < end:  # past the thresholds
        time.sleep(0.002)  # the GUI thread allocates nothing meanwhile
    app.processEvents()
end = time.monotonic() + 10.0
while where["gui"] + where["other"] < ROUNDS and time.monotonic() < end:
    app.processEvents()
    time.sleep(0.01)
stop = True
t.join()
print(where["other"], where["gui"] + where["other"], len(writer_collections) > 0)
"""


def _run(script: str, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen", "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-X", "faulthandler", "-c", script, *args],
                          capture_output=True, text=True, timeout=180, env=env, cwd=ROOT)


def test_without_the_desk_s_collector_a_writer_thread_deletes_qt_objects():
    """The hazard the desk guards against, shown: the writer's collections delete them."""
    out = _run(_CYCLES, "bare")
    assert out.returncode == 0, out.stderr[-3000:]
    off_gui, total, writer_collected = out.stdout.split()
    assert writer_collected == "True"
    assert int(off_gui) > 0


@pytest.mark.parametrize("desk", ["desk", "headless"])
def test_the_desk_s_qt_objects_in_cycles_die_on_the_gui_thread_only(desk):
    out = _run(_CYCLES, desk)
    assert out.returncode == 0, out.stderr[-3000:]
    off_gui, total, writer_collected = out.stdout.split()
    assert int(off_gui) == 0
    assert int(total) == 20  # the GUI thread's timer collected every one


def test_the_collector_collects_what_is_due_on_the_gui_thread(qapp):
    from app.gui_gc import collect_on_gui_thread

    collector = collect_on_gui_thread(qapp)
    assert collect_on_gui_thread(qapp) is collector  # one per application
    assert not gc.isenabled()

    class Node:
        pass

    for _ in range(collector.thresholds[0] + 10):  # past the youngest's threshold
        n = Node()
        n.me = n
    del n
    assert collector.collect_due() >= 1
    assert collector.collect_due() == 0  # nothing due right after


# A map big enough to decode on a pool thread; its model is deleted at once, while
# the job runs, a hundred times.
_MAP_MODEL_DELETED = r"""
import numpy as np
from PySide6.QtCore import QObject, QThreadPool
from PySide6.QtWidgets import QApplication
app = QApplication([])
from app.comm import protocol as P
from app.core.mapimage import encode_png
from app.ui.map_model import INLINE_DECODE_PX, MapModel

w, h = 1200, 900
assert w * h > INLINE_DECODE_PX
img = np.full((h, w), 255, np.uint8)
img[::7, ::5] = 0
msg = P.MapImage(0.05, 0, 0, w, h, encode_png(img))
for _ in range(100):
    owner = QObject()
    model = MapModel(owner)
    model.on_map(msg)
    del model, owner  # the window closed while the map decodes
    app.processEvents()
QThreadPool.globalInstance().waitForDone()
app.processEvents()
print("done")
"""


def test_a_map_model_deleted_while_its_map_decodes_waits_for_the_job():
    """Before: the job emitted on the deleted model's signal, from the pool's thread
    ("Signal source has been deleted"), racing the model's destruction."""
    out = _run(_MAP_MODEL_DELETED)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.strip() == "done"
    assert "Traceback" not in out.stderr, out.stderr[-3000:]


_HISTORY_DELETED = r"""
import threading, time
from PySide6.QtCore import QObject
from PySide6.QtWidgets import QApplication
app = QApplication([])
from app.ui.history_model import HistoryModel

started = threading.Event()
released = threading.Event()
held = [0]


class SlowArchive:
    def series(self, *a, **k):
        started.set()
        # a slow disk: the query still runs when the model goes (released by the
        # model's `destroyed`, which Qt emits before it deletes the model's children)
        if released.wait(10):
            held[0] += 1
        raise OSError("disk gone")


for _ in range(20):
    owner = QObject()
    model = HistoryModel(SlowArchive(), owner)
    model.set_channels(["gas"])
    model.destroyed.connect(released.set)
    started.clear()
    released.clear()
    model.load()
    assert started.wait(10)  # the query is running
    del model, owner  # the history window closed meanwhile
    app.processEvents()
print("done", held[0])
"""


def test_a_history_model_deleted_during_a_query_waits_for_it():
    """Before: the carrier the query reports on went first and the pool waited after,
    so the query emitted on a deleted object from the pool's thread."""
    out = _run(_HISTORY_DELETED)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.split() == ["done", "20"]  # each query still ran when its model went
    assert "already deleted" not in out.stderr and "RuntimeError" not in out.stderr, \
        out.stderr[-3000:]


def test_each_model_runs_its_jobs_on_a_gui_jobs_child_made_pool_first(qtbot, tmp_path):
    """Children are deleted in the order they were made: the pool (which waits for
    its job) must come before the carrier the job emits on; and a carrier without a
    parent died with its last Python reference, which a pool thread could hold. The
    desk session, the history model, the review menu, the calibration dialog and the
    map model each run their jobs on a GuiJobs child (app/gui_jobs) made that way."""
    import numpy as np
    from PySide6.QtWidgets import QMainWindow

    from app.gui_jobs import GuiJobs
    from app.session import DeskSession
    from app.ui.calibration_dialog import CalibrationDialog
    from app.ui.history_model import HistoryModel
    from app.ui.history_window import ReviewActions
    from app.ui.map_model import MapModel

    from .fakes import FakeLink

    win = QMainWindow()
    qtbot.addWidget(win)
    dialog = CalibrationDialog(np.zeros((48, 64, 3), np.uint8), save_dir=tmp_path)
    qtbot.addWidget(dialog)
    session = DeskSession(FakeLink())
    try:
        owners = [session, HistoryModel(None, win), ReviewActions(win), dialog,
                  MapModel(win)]
        for owner in owners:
            jobs = owner.findChildren(GuiJobs)
            assert len(jobs) == 1 and jobs[0].parent() is owner, type(owner).__name__
            kids = jobs[0].children()
            assert kids.index(jobs[0].pool) < kids.index(jobs[0]._carrier)
    finally:
        session.close()
