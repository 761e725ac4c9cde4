"""The gas detector's stage on the desk: the gas tile's label, the alarm list's
reset of a latched alarm (refused while the gas is still high)."""

import pytest

from app.core.alarms import AlarmState
from app.ui.alarm_panel import AlarmPanel
from app.ui.data_panel import DataPanel
from app.ui.models import TelemetryModel

pytestmark = pytest.mark.gui

T0 = 1_800_000_000.0
GAS = "gas_lel_pct"


def test_the_gas_tile_names_the_stage_and_the_panel_resets_the_latch(qtbot):
    model = TelemetryModel(capacity=100, clock=lambda: T0)
    data = DataPanel(model)
    now = [T0]
    panel = AlarmPanel(model.monitor, user="ana", clock=lambda: now[0])
    model.monitor.add_listener(panel.on_transition)
    qtbot.addWidget(data)
    qtbot.addWidget(panel)
    tile = data.tiles[GAS]
    mon = model.monitor
    mon.update(GAS, 5.0, T0)
    assert tile.label_text() == "Gas"
    mon.update(GAS, 12.0, T0 + 1)
    qtbot.waitUntil(lambda: tile.label_text() == "Gas · A1")
    assert tile.alarm_level() != ""  # abnormal: coloured
    mon.update(GAS, 24.0, T0 + 2)
    qtbot.waitUntil(lambda: tile.label_text() == "Gas · A2")
    assert any(r["key"] == f"{GAS}.a2" for r in panel.rows())

    mon.update(GAS, 19.5, T0 + 3)  # below 20 but inside the deadband
    assert panel.select_alarm(f"{GAS}.a2")
    assert panel.reset_button.isEnabled()
    assert panel.reset_selected() == []
    assert "reset refused" in panel.errors[-1]
    assert mon.latched(f"{GAS}.a2")

    mon.update(GAS, 2.0, T0 + 10)
    mon.tick(T0 + 20)  # A1's off-delay
    assert tile.label_text() == "Gas · A2"  # latched: still A2 with no gas
    now[0] = T0 + 21
    trs = panel.reset_selected()
    assert [t.to_state for t in trs] == [AlarmState.RTN_UNACK]  # still to acknowledge
    qtbot.waitUntil(lambda: tile.label_text() == "Gas")
    assert tile.alarm_level() == ""  # normal: no colour
    assert not panel.reset_button.isEnabled()


def test_the_settings_dialog_keeps_the_setpoints_and_gas_rule(qtbot):
    from app.core.alarms import default_alarm_config
    from app.ui.alarm_dialogs import AlarmSettingsDialog

    dlg = AlarmSettingsDialog(default_alarm_config())
    qtbot.addWidget(dlg)
    assert dlg.validate() == []
    cfg = dlg.config()
    assert {s.key for s in cfg.setpoints} == {f"{GAS}.a2", f"{GAS}.over_range"}
    assert [g.channel for g in cfg.gas] == [GAS]
