import math

import pytest

from app.comm import protocol as P
from app.ui.models import LinkModel, TelemetryModel, VideoModel, battery_percent, mode_name

from .fakes import Stats, make_frame

pytestmark = pytest.mark.gui


def tel(t, **kw):
    base = dict(gas_lel_pct=1.0, temp_c=25.0, humidity_pct=50.0, battery_v=24.5)
    base.update(kw)
    m = P.Telemetry(**base)
    m.received_s = t
    return m


def test_telemetry_fills_series_and_raises_alarms(qtbot):
    m = TelemetryModel(capacity=100)
    with qtbot.waitSignal(m.values_changed, timeout=1000):
        m.on_telemetry(tel(10.0))
    with qtbot.waitSignal(m.alarm_raised, timeout=1000) as blk:
        m.on_telemetry(tel(11.0, gas_lel_pct=12.0))
    assert blk.args[0].key == "gas_lel_pct.high"
    assert len(m.series("gas_lel_pct")) == 2
    t, y = m.window("gas_lel_pct", 60)
    assert t.tolist() == [10.0, 11.0] and y.tolist() == [1.0, 12.0]
    m.on_telemetry(tel(12.0, gas_lel_pct=9.8))  # inside the deadband
    assert m.most_severe().key == "gas_lel_pct.high"
    m.on_telemetry(tel(13.0, gas_lel_pct=9.0))  # below the deadband: the off-delay runs
    assert m.most_severe().key == "gas_lel_pct.high"
    off = m.monitor.rule("gas_lel_pct").off_delay_s
    with qtbot.waitSignal(m.alarm_cleared, timeout=1000):
        m.on_telemetry(tel(13.0 + off, gas_lel_pct=9.0))
    assert m.active_alarms() == []
    # not yet acknowledged: still listed (ISA-18.2 "returned to normal, unacknowledged")
    [a] = m.monitor.listed()
    assert a.state.value == "RTN_UNACK"


def test_every_transition_is_announced(qtbot):
    m = TelemetryModel(capacity=10)
    seen = []
    m.alarm_changed.connect(seen.append)
    m.on_telemetry(tel(1.0, temp_c=50.0))
    m.monitor.acknowledge("temp_c.high", 2.0, user="ana")
    m.monitor.shelve("temp_c.high", 3.0, 60.0, "maintenance")
    assert [(t.from_state.value, t.to_state.value) for t in seen] == [
        ("NORMAL", "UNACK"), ("UNACK", "ACKED"), ("ACKED", "SHELVED")]
    # the timer runs on the telemetry's time base: expiry comes with time passing
    m.on_telemetry(tel(64.0, temp_c=50.0))
    m.tick_alarms()
    assert seen[-1].to_state.value == "UNACK" and seen[-1].reason == "shelving expired"


def test_telemetry_flags_and_mode(qtbot):
    m = TelemetryModel(capacity=10)
    with qtbot.waitSignals([m.alarm_raised, m.mode_changed], timeout=1000):
        m.on_telemetry(tel(1.0, alarm_flags=int(P.AlarmFlag.ESTOP), mode=int(P.RobotMode.ESTOP)))
    assert m.most_severe().condition == "ESTOP"
    assert mode_name(m.mode) == "ESTOP" and mode_name(99) == "UNKNOWN(99)"


def test_malformed_telemetry_is_counted_not_raised(qtbot):
    m = TelemetryModel(capacity=10)
    with qtbot.waitSignal(m.malformed, timeout=1000):
        m.on_telemetry("not a telemetry message")
    m.on_telemetry(object())
    bad = tel(1.0)
    bad.temp_c = "hot"
    m.on_telemetry(bad)
    assert m.malformed_count == 3 and m.samples == 0
    m.on_telemetry(tel(2.0))
    assert m.samples == 1


def test_video_model_fps_latency_and_staleness(qtbot):
    now = [0.0]
    m = VideoModel(clock=lambda: now[0], stale_after_s=1.0)
    for i in range(11):
        now[0] = i * 0.1
        m.on_frame(make_frame(i, latency_ms=30.0 + i))
    assert m.fps == pytest.approx(10.0)
    assert m.latency_ms == 40.0 and not m.stale
    now[0] = 5.0
    with qtbot.waitSignal(m.stale_changed, timeout=1000) as blk:
        m.check_stale()
    assert blk.args == [True] and m.fps == 0.0
    bad = make_frame()
    bad.image = bad.image[:, :, 0]
    m.on_frame(bad)
    m.on_frame(None)
    assert m.malformed_count == 2 and m.frames == 11


def test_link_model_notices_restore(qtbot):
    m = LinkModel()
    m.on_state("connecting")
    m.on_state("connected")
    assert m.restored_count == 0
    m.on_state("lost")
    m.on_state("reconnecting")
    with qtbot.waitSignal(m.link_restored, timeout=1000):
        m.on_state("connected")
    m.on_state(42)
    assert m.malformed_count == 1 and m.state == "connected"
    with qtbot.waitSignal(m.stats_changed, timeout=1000) as blk:
        m.on_stats(Stats())
    assert blk.args[0]["rtt_ms"] == 12.5


def test_battery_percent():
    assert battery_percent(21.0) == 0.0
    assert battery_percent(30.0) == 100.0
    assert 40 < battery_percent(23.3) < 60
    assert math.isnan(battery_percent(float("nan")))
