"""The desk's log files: rotation by size and at midnight, bounded by count and age;
alarm transitions and operator commands land in the file."""

from __future__ import annotations

import logging
import os
import time

import pytest

from app.core.alarms import AlarmMonitor, LimitRule
from app.core.desk.gateway import CommandGateway
from app.logs import LOG_NAME, LogSettings, RotatingLogHandler, setup_logging


def _logger(handler: RotatingLogHandler, name: str) -> logging.Logger:
    lg = logging.getLogger(name)
    lg.propagate = False
    lg.setLevel(logging.INFO)
    lg.addHandler(handler)
    return lg


def test_size_rollover_is_bounded(tmp_path):
    h = RotatingLogHandler(tmp_path / LOG_NAME, max_bytes=2000, max_files=3)
    h.setFormatter(logging.Formatter("%(message)s"))
    lg = _logger(h, "test.logs.size")
    try:
        for i in range(400):
            lg.info("line %04d %s", i, "x" * 40)
    finally:
        lg.removeHandler(h)
        h.close()
    rolled = h.rolled_files()
    assert h.rollovers >= 5  # ~19 kB through a 2 kB file
    assert len(rolled) == 3  # only the newest max_files kept
    for f in [*rolled, tmp_path / LOG_NAME]:
        assert f.stat().st_size <= 2000
    # nothing lost within what is kept: the newest lines, in order, up to the last
    text = "".join(f.read_text() for f in [*rolled, tmp_path / LOG_NAME])
    nums = [int(ln.split()[1]) for ln in text.splitlines()]
    assert nums == list(range(nums[0], 400))


def test_midnight_rollover_and_age_pruning(tmp_path):
    now = [time.mktime((2026, 3, 1, 23, 59, 0, 0, 0, -1))]
    old = tmp_path / f"{LOG_NAME}.2026-02-01_00-00-00"
    old.write_text("a month ago\n")
    os.utime(old, (now[0] - 30 * 86400,) * 2)
    recent = tmp_path / f"{LOG_NAME}.2026-02-28_00-00-00"
    recent.write_text("yesterday\n")
    os.utime(recent, (now[0] - 86400,) * 2)
    h = RotatingLogHandler(tmp_path / LOG_NAME, keep_days=7, max_bytes=0,
                           clock=lambda: now[0])
    lg = _logger(h, "test.logs.midnight")
    try:
        assert not old.exists() and recent.exists()  # a week kept
        lg.info("before midnight")
        now[0] += 120  # 00:01 the next day
        lg.info("after midnight")
    finally:
        lg.removeHandler(h)
        h.close()
    assert h.rollovers == 1
    rolled = h.rolled_files()
    assert rolled[-1].name == f"{LOG_NAME}.2026-03-02_00-01-00"
    assert "before midnight" in rolled[-1].read_text()
    assert "after midnight" in (tmp_path / LOG_NAME).read_text()


@pytest.fixture
def desk_log(tmp_path):
    root = logging.getLogger()
    level, before = root.level, list(root.handlers)
    folder = setup_logging("INFO", LogSettings(dir=str(tmp_path / "log")), console=False)
    yield folder
    for h in list(root.handlers):
        if h not in before:
            root.removeHandler(h)
            h.close()
    root.setLevel(level)


class _Sender:
    def __init__(self):
        self.seq = 0

    def send_command(self, name, args=None):
        self.seq += 1
        return self.seq


def test_alarm_transitions_and_commands_are_logged(desk_log):
    assert desk_log is not None
    m = AlarmMonitor([LimitRule("temp_c", high=45.0, deadband=1.0, unit="°C")])
    m.update("temp_c", 50.0, 1.0)
    m.acknowledge("temp_c.high", 2.0, user="op1")
    gw = CommandGateway(_Sender())
    gw.on_link_state("connected")
    gw.send("start_patrol", {"route": "default"})
    gw.on_link_state("lost")
    gw.send("look_at", {"gauge": "PG-101"})
    for h in logging.getLogger().handlers:
        h.flush()
    text = (desk_log / LOG_NAME).read_text(encoding="utf-8")
    assert "alarm temp_c.high activate: NORMAL -> UNACK (MEDIUM, value 50.0)" in text
    assert "alarm temp_c.high ack: UNACK -> ACKED" in text and "by op1" in text
    assert "command start_patrol {'route': 'default'}: sent (seq 1)" in text
    assert "command look_at {'gauge': 'PG-101'}: not delivered (seq 2), link down" in text


def test_an_unwritable_log_folder_leaves_the_console(tmp_path, caplog):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    root = logging.getLogger()
    before = list(root.handlers)
    try:
        with caplog.at_level(logging.ERROR):
            assert setup_logging("INFO", LogSettings(dir=str(blocker / "log")),
                                 console=False) is None
        assert "logging to the console only" in caplog.text
    finally:
        for h in list(root.handlers):
            if h not in before:
                root.removeHandler(h)
                h.close()
