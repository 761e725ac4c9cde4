"""The headless desk drives the same alarm manager: telemetry, flags, link lost,
timers; every transition reaches the recorder and the archive."""

import pytest

from app.comm import protocol as P
from app.core.alarms import AlarmState
from app.core.recorder import SessionRecorder
from app.core.records import Archive
from app.session import DeskSession

from .fakes import FakeLink

T0 = 1_800_000_000.0


@pytest.fixture
def session(qtbot, tmp_path):
    link = FakeLink()
    archive = Archive(tmp_path / "a.sqlite")
    s = DeskSession(link, SessionRecorder(tmp_path / "out"), archive=archive, tick_ms=50)
    yield s, link, archive
    s.close()


def test_headless_alarms_are_recorded_and_archived(qtbot, session):
    s, link, archive = session
    link.send_telemetry(T0, gas_lel_pct=12.0,
                        alarm_flags=int(P.AlarmFlag.FAILSAFE_STOP))
    assert s.monitor.state("gas_lel_pct.high") is AlarmState.UNACK
    assert s.monitor.state("flag.FAILSAFE_STOP") is AlarmState.UNACK
    s.monitor.acknowledge("gas_lel_pct.high", T0 + 1, user="ana")
    link.state_changed.emit("connected")
    link.state_changed.emit("lost")
    assert s.monitor.state("link.lost") is AlarmState.UNACK
    assert archive.flush(5.0)
    rows = archive.alarm_transitions(T0 - 1, T0 + 3600 * 24 * 365 * 10)
    got = {(r["alarm"], r["to_state"]) for r in rows}
    assert {("gas_lel_pct.high", "UNACK"), ("gas_lel_pct.high", "ACKED"),
            ("flag.FAILSAFE_STOP", "UNACK"), ("link.lost", "UNACK")} <= got
    # the acknowledgement is not a return to normal: the alarm is still active
    assert "gas_lel_pct.high" in s.recorder.summary()["active_alarms"]


def test_headless_timer_runs_stale_data_on_the_telemetry_clock(qtbot, session):
    s, link, archive = session
    link.send_telemetry(T0)
    after = s.monitor.stale_rules[0].after_s
    s.pipeline._last_data_mono -= after + 1  # as if the robot had been silent that long
    qtbot.waitUntil(lambda: s.monitor.is_active(f"{s.monitor.stale_rules[0].channel}.stale"),
                    timeout=3000)
    link.send_telemetry(T0 + after + 2)
    assert not s.monitor.is_active(f"{s.monitor.stale_rules[0].channel}.stale")
