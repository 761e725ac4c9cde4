"""Replay of a recorded patrol: the clock is driven by hand (no wall clock)."""

from __future__ import annotations

import gc
import time
import weakref

import numpy as np
import pytest

from app.core.records import Archive
from app.report.sample import write_sample
from app.ui.replay import ReplayLink, attach_replay
from app.ui.replay_bar import ReplayBar


@pytest.fixture
def recorded(tmp_path):
    a = Archive(tmp_path / "archive.sqlite3")
    run = write_sample(a, time.time() - 120.0)
    assert a.flush()
    yield a, run
    a.close()


class Collect:
    def __init__(self, link: ReplayLink) -> None:
        self.telemetry: list = []
        self.poses: list = []
        self.frames: list = []
        self.maps: list = []
        self.events: list = []
        self.rewound: list = []
        link.telemetry_received.connect(self.telemetry.append)
        link.pose_received.connect(self.poses.append)
        link.frame_decoded.connect(self.frames.append)
        link.map_received.connect(self.maps.append)
        link.event_received.connect(self.events.append)
        link.rewound.connect(self.rewound.append)

    def times(self) -> list[float]:
        return [m.received_s for m in self.telemetry]


@pytest.fixture
def link(qtbot, recorded):
    archive, run = recorded
    lk = ReplayLink(archive, run.t0, run.t1)
    yield lk
    lk.shutdown()


def test_replay_emits_the_recorded_telemetry_in_order_once(link, recorded):
    _, run = recorded
    got = Collect(link)
    link.start()
    link.play()
    for _ in range(100):
        link.step(0.5)
        if not link.playing:
            break
    assert not link.playing and link.position == run.t1  # stopped at the end
    assert got.times() == pytest.approx(run.telemetry_t)  # each once, in order
    assert [m.gas_lel_pct for m in got.telemetry] == pytest.approx(run.gas)
    assert [m.seq for m in got.telemetry] == list(range(len(run.telemetry_t)))
    assert got.telemetry[0].mode == 2 and isinstance(got.telemetry[0].mode, int)
    # the same panels' other feeds: poses, snapshots as frames, the map, events
    assert len(got.poses) == len(run.telemetry_t)
    assert len(got.frames) == 4  # three meter readings, one alarm
    assert got.frames[0].image.shape == (96, 128, 3)
    assert len(got.maps) == 1 and got.maps[0].width == 300 and got.maps[0].resolution_m == 0.1
    texts = [e.text for e in got.events]
    assert "patrol started" in texts and "patrol finished" in texts
    assert any("Gas high: UNACK → ACKED by ann" in t for t in texts)


def test_pause_stops_and_play_resumes(link, recorded):
    _, run = recorded
    got = Collect(link)
    link.start()
    link.play()
    link.step(2.0)
    n, pos = len(got.telemetry), link.position
    link.pause()
    assert link.step(5.0) == 0
    assert len(got.telemetry) == n and link.position == pos
    link.play()
    link.step(1.0)
    assert link.position == pytest.approx(pos + 1.0)
    assert len(got.telemetry) == n + 10  # 10 Hz for one more second


def test_speed_scales_recorded_time_and_is_clamped(link, recorded):
    _, run = recorded
    got = Collect(link)
    link.start()
    assert link.set_speed(5.0) == 5.0
    link.play()
    link.step(1.0)  # one wall second at 5x
    assert link.position == pytest.approx(run.t0 + 5.0)
    assert max(got.times()) <= run.t0 + 5.0 + 1e-9
    assert len(got.telemetry) == 51  # t0 .. t0 + 5.0 at 10 Hz
    assert link.set_speed(40.0) == 10.0
    assert link.set_speed(0.1) == 0.5


def test_seek_rewinds_the_views_and_shows_the_state_there(link, recorded):
    _, run = recorded
    got = Collect(link)
    link.start()
    link.play()
    link.step(25.0)
    target = run.t0 + 10.0
    got.telemetry.clear()
    got.frames.clear()
    assert link.seek(target) == pytest.approx(target)
    assert got.rewound[-1] == pytest.approx(target)
    # primed with the telemetry up to the target, and the last snapshot before it
    assert max(got.times()) == pytest.approx(target)
    assert got.frames and got.frames[-1].capture_ts_us <= target * 1e6
    got.telemetry.clear()
    link.step(1.0)
    t = got.times()
    assert t[0] > target and t[-1] == pytest.approx(target + 1.0) and len(t) == 10
    assert link.seek(run.t1 + 100) == run.t1  # clamped


def test_replay_is_view_only(link):
    refused = []
    link.command_refused.connect(refused.append)
    assert link.send_command("start_patrol", {}) == -1
    link.drive(0.3, 0.0)
    link.estop()
    assert refused == ["start_patrol", "drive", "estop"] and link.refused == 3


def test_main_window_replays_through_the_live_panels(qtbot, recorded):
    from app.ui.main_window import MainWindow

    archive, run = recorded
    link = ReplayLink(archive, run.t0, run.t1)
    win = MainWindow(link)
    qtbot.addWidget(win)
    attach_replay(win, link)
    bar = ReplayBar(link, win)
    win.addToolBar(bar)
    win.show()
    link.start()
    link.play()
    link.step(14.0)  # through the gas plume (samples 120-160) and two readings
    tm = win.telemetry_model
    assert tm.samples == 141
    t, y = tm.window("gas_lel_pct", 3600.0)
    assert np.allclose(y, run.gas[:141]) and t[-1] == pytest.approx(run.t0 + 14.0)
    assert win.video_model.frames == 3  # snapshots at 5 s, 12.1 s (the alarm) and 13 s
    assert win.map_model.maps_received == 1
    # the live alarm rules see the replayed plume; ann's recorded acknowledgement
    # (at 13 s) is repeated on the window's monitor
    mon = tm.monitor
    assert mon.is_active("gas_lel_pct.high")
    assert mon.state("gas_lel_pct.high").name == "ACKED"
    assert mon.get("gas_lel_pct.high").acked_by == "ann"
    assert mon.get("gas_lel_pct.high").acked_t == pytest.approx(run.alarm_t["acked"])
    cp = win.control_panel
    assert cp.estop_button.isHidden() and cp.drive_box.isHidden()
    # the banner says it is a replay, where and how fast (not only the title bar)
    assert win.banner_text().startswith("REPLAY ") and "×1" in win.banner_text()
    # the replayed alarm list is shown, not handled: acknowledging does nothing
    assert not win.alarm_panel.ack_all_button.isEnabled()
    assert win.alarm_panel.acknowledge_visible() == []
    win.control_panel.request_estop()  # e.g. the Esc key: nothing is sent or claimed
    win._on_estop()  # even if the intent got through, the window sends nothing
    assert link.refused == 0 and ("estop",) not in getattr(link, "calls", [])
    assert win.statusBar().currentMessage() == "replay is view-only: no e-stop sent"
    assert not any("sent" in line and "E-stop" in line for line in win.alarm_panel.log_lines())
    # the strip's time window ends at the replay position, not at the wall clock
    win.data_panel.strip.refresh()
    (x0, x1), _ = win.data_panel.strip.plot_item("gas_lel_pct").viewRange()
    assert x1 == pytest.approx(link.position)
    # seeking back clears the plots instead of mixing old and new samples
    link.seek(run.t0 + 2.0)
    t, _ = tm.window("gas_lel_pct", 3600.0)
    assert t[-1] == pytest.approx(run.t0 + 2.0) and np.all(np.diff(t) > 0)
    # transport bar: speed box, play key, slider
    bar.faster_action.trigger()
    assert link.clock.speed == 2.0
    bar.play_action.trigger()
    assert not link.playing
    bar._on_slider(500)
    assert link.position == pytest.approx(run.t0 + 0.5 * (run.t1 - run.t0))
    assert "UTC" in bar.time_label.text()
    link.shutdown()


def test_replay_log_is_stamped_with_recorded_time_and_a_seek_shows_the_route(qtbot,
                                                                            recorded):
    from app.ui.alarm_panel import clock_text
    from app.ui.main_window import MainWindow

    archive, run = recorded  # recorded two minutes ago: wall and recorded stamps differ
    link = ReplayLink(archive, run.t0, run.t1)
    win = MainWindow(link)
    qtbot.addWidget(win)
    attach_replay(win, link)
    link.start()
    link.seek(run.t0 + 10.0)  # past "patrol started" (0.5 s): its route is restored
    assert win.map_model.patrol is not None
    assert [p["name"] for p in win.map_model.patrol["points"]] == ["PG-101", "PG-102",
                                                                   "PG-103"]
    assert win.patrol_text().startswith("Patrol: ")
    win.alarm_panel.log.clear()
    link.play()
    for _ in range(20):  # to the end: the gas alarm (12.1 s) and "patrol finished"
        link.step(2.0)
    lines = win.alarm_panel.log_lines()
    assert any("patrol finished" in line for line in lines)
    recorded_stamps = {clock_text(run.t0 + k) for k in range(int(run.t1 - run.t0) + 2)}
    assert lines and all(line.split()[0] in recorded_stamps for line in lines), lines
    link.shutdown()


def test_recorded_operator_actions_are_repeated_on_a_monitor():
    from app.core.alarms import AlarmMonitor, Priority
    from app.core.desk.replay_rows import mirror_handling

    mon = AlarmMonitor()
    mon.set_condition("link.lost", True, 100.0, source="link", priority=Priority.HIGH,
                      text="link lost")
    rec = {"alarm": "link.lost", "user": "bob"}
    assert mirror_handling(mon, {**rec, "t": 101.0, "from_state": "UNACK",
                                 "to_state": "SHELVED", "reason": "cable work"})
    assert mon.state("link.lost").name == "SHELVED" and mon.get("link.lost").reason == \
        "cable work"
    assert mirror_handling(mon, {**rec, "t": 102.0, "from_state": "SHELVED",
                                 "to_state": "UNACK"})
    assert mon.state("link.lost").name == "UNACK"
    assert mirror_handling(mon, {**rec, "t": 103.0, "from_state": "UNACK",
                                 "to_state": "ACKED"})
    assert mon.get("link.lost").acked_by == "bob"
    assert mirror_handling(mon, {**rec, "t": 104.0, "from_state": "ACKED",
                                 "to_state": "OUT_OF_SERVICE", "reason": "maintenance"})
    assert mon.state("link.lost").name == "OUT_OF_SERVICE"
    # an alarm the monitor does not hold, or a raise (the monitor's own business)
    assert not mirror_handling(mon, {"alarm": "nope.high", "t": 105.0,
                                     "from_state": "UNACK", "to_state": "ACKED"})
    assert not mirror_handling(mon, {"alarm": "x", "t": 105.0, "from_state": "NORMAL",
                                     "to_state": "UNACK"})


@pytest.mark.parametrize("extra, message", [
    ([], "no archive at"),
    (["--from", "whenever"], "is not a time"),
    (["--from", "-1h", "--to", "-2h"], "is not after"),
])
def test_replay_command_bad_input_exits_2(tmp_path, capsys, extra, message):
    from app.cli import main

    data = tmp_path / "data"
    if message != "no archive at":
        Archive(data / "archive.sqlite3").close()
    assert main(["--replay", "--data-dir", str(data), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_replay_command_without_a_display_says_so(tmp_path, capsys):
    from app.config import DeskConfig
    from app.ui.app import replay_main

    Archive(tmp_path / "archive.sqlite3").close()
    cfg = DeskConfig()
    cfg.data_dir = str(tmp_path)
    assert replay_main(cfg, None, None, display=False) == 2
    assert "needs a display" in capsys.readouterr().err


def test_a_replay_window_is_freed_while_its_link_lives_on(qtbot, link, recorded):
    """The link's slots (closures over the window) kept every replay window built on a
    link that outlived it, and the link itself, alive: connections the garbage
    collector cannot see. They hold the window weakly and go with it now."""
    from PySide6.QtCore import QCoreApplication, QEvent

    from app.ui.main_window import MainWindow

    _archive, run = recorded
    win = MainWindow(link)
    attach_replay(win, link)
    win.show()
    qtbot.waitExposed(win)
    link.start()
    window = weakref.ref(win)
    win.close()
    win.deleteLater()
    QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
    del win
    gc.collect()
    assert window() is None
    link.seek(run.t0 + 5.0)  # the link plays on with no window: nothing raised
    link.step(1.0)
    assert link.position == pytest.approx(run.t0 + 5.0, abs=1.5)
