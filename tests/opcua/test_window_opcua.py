"""The window serves OPC UA from its own desk pipeline: the control room's method runs
on the GUI thread through the service's timer, and anonymous / None security on is said
in red in the status bar."""

from __future__ import annotations

import asyncio
import threading

import pytest
from asyncua import Client, ua
from PySide6.QtWidgets import QLabel
from ui.fakes import FakeLink  # tests/ui/fakes.py (tests/ is on the path)

from app.comm.link import ControlState
from app.config import DeskConfig, OpcuaSettings
from app.interop.opcua.space import NS_URI
from app.interop.opcua.users import UserStore
from app.ui.app import _serve_opcua, build_window

pytestmark = [pytest.mark.gui, pytest.mark.slow(13)]


def test_window_serves_its_pipeline_and_says_anonymous_is_on(qtbot, tmp_path):
    users = tmp_path / "users.json"
    UserStore(users).add("op", "operator", "operator-pass")
    cfg = DeskConfig(data_dir=str(tmp_path), opcua=OpcuaSettings(
        endpoint="opc.tcp://127.0.0.1:0", users_file=str(users), allow_anonymous=True,
        allow_none_security=True))
    link = FakeLink()
    win = build_window(link)
    qtbot.addWidget(win)
    svc = _serve_opcua(cfg, win)
    try:
        notes = [w.text() for w in win.statusBar().findChildren(QLabel)]
        assert any("ANONYMOUS ACCESS ON" in n and "SECURITY NONE ON" in n for n in notes)
        link.state_changed.emit("connected")
        link.control_changed.emit(ControlState(holder="this desk", mine=True))
        result: dict = {}

        async def control_room():
            c = Client(svc.server.url, timeout=10)
            c.set_user("op")
            c.set_password("operator-pass")
            async with c:
                idx = await c.get_namespace_index(NS_URI)
                lease = c.get_node(ua.NodeId("Robot.DeskHoldsLease", idx))
                for _ in range(250):
                    dv = await lease.read_data_value(raise_on_bad_status=False)
                    if dv.Value.Value is True:
                        break
                    await asyncio.sleep(0.02)
                result["link"] = await c.get_node(ua.NodeId("Robot.LinkState", idx)).read_value()
                result["out"] = await c.get_node(ua.NodeId("Control", idx)).call_method(
                    ua.NodeId("Control.PausePatrol", idx))

        def run():
            try:
                asyncio.run(control_room())
            except Exception as e:  # noqa: BLE001 - reported by the assertion below
                result["error"] = repr(e)

        th = threading.Thread(target=run, daemon=True)
        th.start()
        qtbot.waitUntil(lambda: "out" in result or "error" in result, timeout=15000)
        th.join(5)
        assert result.get("error") is None
        assert result["link"] == "connected" and result["out"].startswith("sent")
        assert ("command", "pause_patrol", {}) in link.calls
        assert win.desk.gateway.entries[-1].user == "opcua:op"
    finally:
        svc.stop()
        win.desk.close()


def test_comment_from_the_control_room_in_the_windows_alarm_panel(qtbot, tmp_path):
    users = tmp_path / "users.json"
    UserStore(users).add("op", "operator", "operator-pass")
    cfg = DeskConfig(data_dir=str(tmp_path), opcua=OpcuaSettings(
        endpoint="opc.tcp://127.0.0.1:0", users_file=str(users), allow_none_security=True))
    link = FakeLink()
    win = build_window(link)
    qtbot.addWidget(win)
    svc = _serve_opcua(cfg, win)
    key = "gas_lel_pct.high"
    result: dict = {}
    raised = threading.Event()

    async def control_room():
        c = Client(svc.server.url, timeout=10)
        c.set_user("op")
        c.set_password("operator-pass")
        q: asyncio.Queue = asyncio.Queue()

        class Handler:
            def event_notification(self, ev):
                q.put_nowait(ev)

        async with c:
            idx = await c.get_namespace_index(NS_URI)
            sub = await c.create_subscription(50, Handler())
            await sub.subscribe_events(c.nodes.server, ua.ObjectIds.AlarmConditionType)
            raised.set()
            while (ev := await asyncio.wait_for(q.get(), 10)).ConditionName != key:
                pass
            await c.get_node(ua.NodeId(f"Alarms.{key}", idx)).call_method(
                ua.NodeId(ua.ObjectIds.ConditionType_AddComment),
                ua.Variant(ev.EventId, ua.VariantType.ByteString),
                ua.LocalizedText("gas team on the way"))
            result["done"] = True

    def run():
        try:
            asyncio.run(control_room())
        except Exception as e:  # noqa: BLE001 - reported by the assertion below
            result["error"] = repr(e)

    th = threading.Thread(target=run, daemon=True)
    try:
        th.start()
        assert raised.wait(15)
        link.set_state("connected")
        link.send_telemetry(gas_lel_pct=2.0)
        link.send_telemetry(gas_lel_pct=15.0)  # the gas alarm: a condition event
        panel = win.alarm_panel
        qtbot.waitUntil(lambda: "error" in result or any(
            r["key"] == key and r["Comment"] == "opcua:op: gas team on the way"
            for r in panel.rows()), timeout=20000)
        th.join(10)
        assert result.get("error") is None and result.get("done")
        assert any("comment by opcua:op: gas team on the way" in line
                   for line in panel.log_lines())
    finally:
        svc.stop()
        win.desk.close()
