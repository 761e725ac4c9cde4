"""The desk reads a meter from a real sim_robot: look_at, fused reading, compared with the
robot's logged ground truth (which the desk itself never sees)."""

from __future__ import annotations

import json

import pytest

from app.comm.link import LinkSettings, RobotLink
from app.sim_process import SimRobotProcess

pytestmark = [pytest.mark.e2e, pytest.mark.gui]


@pytest.fixture
def robot_at_pg102(tmp_path):
    truth = tmp_path / "truth.jsonl"
    sim = SimRobotProcess(seed=1, extra=["--start-at", "PG-102", "--log-truth", str(truth)])
    sim.start()
    yield sim, truth
    sim.stop()


def test_desk_reads_pg102_within_2pct_fs(qtbot, robot_at_pg102):
    from app.ui.main_window import MainWindow

    sim, truth = robot_at_pg102
    link = RobotLink(LinkSettings(reconnect_every_s=0.3))
    win = MainWindow(link)
    qtbot.addWidget(win)
    win.show()
    try:
        link.connect_to(sim.host, sim.port)
        qtbot.waitUntil(lambda: link.state == "connected", timeout=15000)
        with qtbot.waitSignal(link.frame_decoded, timeout=10000):
            pass
        model = win.meter_model
        panel = win.meter_panel
        panel.gauge_combo.setCurrentText("PG-102")
        panel.read_button.click()
        qtbot.waitUntil(lambda: panel.row_texts("PG-102") is not None, timeout=30000)
        rec = model.records()[-1]
        assert rec.gauge_id == "PG-102" and rec.source == "operator"
        assert rec.value is not None, rec.reason
        assert rec.confidence >= 0.5
        # the truth log (0.5 s period) around the time of the reading
        qtbot.waitUntil(lambda: _truth_after(truth, rec.t) is not None, timeout=5000)
        values = [v for t_us, v in _truth_rows(truth) if abs(t_us / 1e6 - rec.t) < 5.0]
        assert values
        lo, hi = min(values), max(values)
        assert lo - 0.02 * 4.0 <= rec.value <= hi + 0.02 * 4.0, (rec.value, lo, hi)
        assert model.frames_read >= 7
        model.wait_idle()
    finally:
        link.shutdown()


def _truth_rows(path):
    rows = []
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return rows
    for line in text.splitlines():
        try:
            r = json.loads(line)
        except json.JSONDecodeError:
            continue  # a line being written
        rows.append((r["utc_us"], r["gauges"]["PG-102"]))
    return rows


def _truth_after(path, t):
    rows = [r for r in _truth_rows(path) if r[0] / 1e6 > t]
    return rows[0] if rows else None
