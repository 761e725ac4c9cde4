"""The event log: bounded in lines and in memory, follows the newest line unless the
operator has scrolled back, and reads like the text log it replaced."""

import gc

import pytest

from app.ui.event_log import EventLog
from bench.soak_probe import malloc_kb

pytestmark = [pytest.mark.gui, pytest.mark.slow(10)]

T0 = 1_800_000_000.0
LINE = "patrol point {i} reached: gauge P-3 read 1.23 MPa, within its limits"


def _heap_kb() -> int | None:
    gc.collect()
    k = malloc_kb()
    return k["malloc_kb:in_use"] + k["malloc_kb:mmapped"] if k else None


def test_fed_many_times_its_bound_it_keeps_the_newest_lines(qtbot):
    log = EventLog(max_lines=50)
    qtbot.addWidget(log)
    for i in range(5 * 50 + 3):
        log.add("info", "robot", f"line {i}", T0 + i)
    assert log.line_count() == 50 == log.model().rowCount()
    lines = log.lines()
    assert lines[0].endswith("line 203") and lines[-1].endswith("line 252")
    assert log.toPlainText().splitlines() == lines
    log.clear()
    assert log.lines() == [] and log.toPlainText() == ""


def test_it_follows_the_newest_line_unless_scrolled_back(qtbot):
    log = EventLog(max_lines=200)
    qtbot.addWidget(log)
    log.resize(400, 120)
    log.show()
    qtbot.waitExposed(log)
    for i in range(100):
        log.add("info", "desk", f"line {i}", T0 + i)
    bar = log.verticalScrollBar()
    qtbot.waitUntil(lambda: bar.maximum() > 0 and bar.value() == bar.maximum())
    bar.setValue(0)  # the operator reads back
    end = bar.maximum()
    log.add("alarm", "alarm", "gas high", T0 + 200)
    qtbot.waitUntil(lambda: bar.maximum() > end)  # the new row laid out
    assert bar.value() == 0
    bar.setValue(bar.maximum())  # and goes back to the end
    log.add("info", "desk", "newest", T0 + 201)
    qtbot.waitUntil(lambda: bar.value() == bar.maximum())
    assert log.lines()[-1].endswith("newest")


def test_a_full_log_holds_little_memory(qtbot):
    """500 lines in the old text-editor log held about 3.8 MB once laid out; a full
    list-view log holds a small fraction of that, and stays there as lines go on."""
    if _heap_kb() is None:
        pytest.skip("needs glibc's mallinfo2 to count the heap")
    log = EventLog(max_lines=500)
    qtbot.addWidget(log)
    log.resize(600, 200)
    log.show()
    qtbot.waitExposed(log)
    log.add("info", "robot", "first", T0)
    qtbot.wait(1)  # first paint (fonts, styles): a fixed cost, not per line
    before = _heap_kb()
    # painted after every fifth line, as a busy log is (a paint lays out the visible rows)
    for i in range(500):
        log.add("info", "robot", LINE.format(i=i), T0 + i)
        if i % 5 == 4:
            log.viewport().repaint()
    full = _heap_kb()
    for i in range(500, 2000):
        log.add("info", "robot", LINE.format(i=i), T0 + i)
        if i % 5 == 4:
            log.viewport().repaint()
    later = _heap_kb()
    assert log.line_count() == 500
    assert full - before < 1024, f"500 lines hold {full - before} KiB"
    assert later - full < 256, f"1500 lines past the bound grew {later - full} KiB"


def test_a_line_reads_in_full_in_its_tooltip(qtbot):
    """Rows do not wrap: a line wider than the pane shows whole in its tooltip."""
    from PySide6.QtCore import Qt

    log = EventLog()
    qtbot.addWidget(log)
    log.add("warning", "robot", "a long line " * 20, T0)
    index = log.model().index(0)
    assert log.model().data(index, Qt.ItemDataRole.ToolTipRole) == log.lines()[0]
    assert "a long line " * 20 in log.lines()[0]
