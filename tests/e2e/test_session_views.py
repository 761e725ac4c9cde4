"""Two desk sessions in one archive at the same time, with two robots far apart:
the report, replay and history each read one session and say which; only asked
for "all" do they mix (and say so)."""

from __future__ import annotations

import re
import time
from datetime import UTC, datetime

import numpy as np
import pytest

from app.core.records import Archive
from app.core.records.paths import default_archive_path
from app.core.records.queries import choose_session
from app.report.cli import main as report_main
from app.report.data import driven_distance
from app.report.sample import write_sample

pytestmark = [pytest.mark.gui, pytest.mark.slow(12)]


@pytest.fixture
def two_sessions(tmp_path):
    """Session A: the sample patrol (an ellipse near x 15 m); session B, written at
    the same time by another desk: a robot pacing 40 m away."""
    path = default_archive_path(tmp_path)
    a, b = Archive(path), Archive(path)
    sa = a.begin_session("desk-a", "10.0.0.5:7000")
    sb = b.begin_session("desk-b", "10.0.0.9:7000")
    t0 = time.time() - 200.0
    run = write_sample(a, t0)
    for k in range(300):  # 30 s at 10 Hz, interleaved with A's rows
        t = t0 + 0.05 + k / 10
        b.add_telemetry(t, {"gas_lel_pct": 50.0, "temp_c": 30.0, "humidity_pct": 20.0,
                            "battery_v": 23.0}, seq=k)
        b.add_pose(t, 60.0 + (k % 2) * 0.5, 40.0, 0.0)
    a.close()
    b.close()
    return tmp_path, sa, sb, run


def test_report_reads_one_session_and_names_it(qapp, two_sessions, tmp_path, capsys):
    data_dir, sa, sb, run = two_sessions
    frm, to = _iso(run.t0 - 1), _iso(run.t1 + 2)
    archive = Archive(default_archive_path(data_dir))
    try:
        only_a = driven_distance(archive.session_view(sa), run.t0 - 1, run.t1 + 2)
        mixed = driven_distance(archive, run.t0 - 1, run.t1 + 2)
    finally:
        archive.close()
    assert 25.0 < only_a < 40.0  # the ellipse
    assert mixed > 20 * only_a  # poses jumping 45 m between the robots, 600 times
    out = tmp_path / "a.html"
    args = ["--from", frm, "--to", to, "--data-dir", str(data_dir), "--out", str(out)]
    assert report_main([*args, "--session", str(sa)]) == 0
    said = capsys.readouterr().out
    assert f"session {sa} — robot 10.0.0.5:7000, desk desk-a" in said
    m = re.search(r"([\d.]+) m driven", said)
    assert m and float(m.group(1)) == pytest.approx(only_a, abs=0.1)
    html = out.read_text(encoding="utf-8")
    assert f"session {sa}" in html and "desk-a" in html and "desk-b" not in html
    # the default: the latest session with data in the range (B wrote last)
    assert report_main(args) == 0
    assert f"session {sb} — robot 10.0.0.9:7000" in capsys.readouterr().out
    # asked for all: mixed, and said so
    assert report_main([*args, "--session", "all"]) == 0
    assert "all sessions mixed" in capsys.readouterr().out
    assert report_main([*args, "--session", "99"]) == 2
    assert "no session 99" in capsys.readouterr().err


def _iso(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="seconds")


def test_replay_and_history_read_one_session_and_say_which(qtbot, two_sessions):
    from PySide6.QtWidgets import QMainWindow

    from app.ui.history_window import install_review_menu
    from app.ui.main_window import MainWindow
    from app.ui.replay import ReplayLink

    data_dir, sa, sb, run = two_sessions
    archive = Archive(default_archive_path(data_dir))
    try:
        rows, which = choose_session(archive, sa)
        link = ReplayLink(rows)
        assert (link.clock.t0, link.clock.t1) == pytest.approx(rows.time_range())
        got = []
        link.telemetry_received.connect(got.append)
        link.start()
        link.play()
        link.step(60.0)  # a minute of wall time at 1x: the whole 30 s session
        assert len(got) == len(run.telemetry_t) == 300
        assert max(m.gas_lel_pct for m in got) < 50.0  # none of session B's rows
        assert np.all(np.asarray(rows.poses(0, 4e9))[:, 1] < 30)
        assert which.startswith(f"session {sa}")
        link.shutdown()
    finally:
        archive.close()
    win = QMainWindow()
    win.data_dir = str(data_dir)
    qtbot.addWidget(win)
    review = install_review_menu(win, replay_window=MainWindow)
    try:
        h = review.open_history()
        assert f"history of session {sb}" in h.windowTitle()
        qtbot.waitUntil(lambda: not h.model.busy and bool(h.model.series), timeout=10000)
        assert _battery_max(h) == 23.0  # session B's robot only
        assert h.model.archive.telemetry_count() == 300
        assert h.session_box.currentData() == sb
        h.session_box.setCurrentIndex(h.session_box.findData(sa))  # the operator picks A
        assert f"history of session {sa}" in h.windowTitle()
        assert h.model.archive.scope_session == sa
        qtbot.waitUntil(lambda: not h.model.busy and _battery_max(h) > 24.0, timeout=10000)
        assert np.all(np.asarray(h.model.archive.poses(0, 4e9))[:, 1] < 30)
        h.session_box.setCurrentIndex(h.session_box.findData("all"))
        assert "all sessions mixed" in h.windowTitle()
        assert h.model.archive.telemetry_count() == 600
        r = review.open_replay()
        assert f"replay of session {sb}" in r.windowTitle()
        assert r.link.archive.scope_session == sb
    finally:
        for w in review.history_windows + review.replay_windows:
            w.close()
        review.close_archive()


def _battery_max(history_window) -> float:
    got = [s for s in history_window.model.series if s.channel == "battery_v"]
    return float(np.nanmax(got[0].vmax)) if got and len(got[0].vmax) else float("nan")
