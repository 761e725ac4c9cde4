"""A real robot process, the desk's RobotLink and session, and asyncua's Client
subscribed to a telemetry value: when the robot is killed the client is told the link
is lost, by Bad_NoCommunication (no value: OPC UA Part 4 §7.7.1) or, on a server set to
``link_lost_status = "uncertain"``, by Uncertain_NoCommunicationLastUsableValue with
the last value the robot sent."""

from __future__ import annotations

import asyncio
import threading

import pytest
from asyncua import Client, ua

from app.comm.link import LinkSettings, RobotLink
from app.config import OpcuaSettings
from app.interop.opcua.server import OpcUaDeskServer
from app.interop.opcua.space import NS_URI
from app.interop.opcua.users import UserStore
from app.session import DeskSession
from app.sim_process import SimRobotProcess

pytestmark = [pytest.mark.e2e, pytest.mark.gui]
KEY = "Environment.temp_c"


class Watcher:
    """asyncua clients on their own thread, subscribed to ``KEY`` on each server,
    keeping every DataValue notified (per server url)."""

    def __init__(self, urls: list[str]) -> None:
        self.urls = urls
        self.seen: dict[str, list[ua.DataValue]] = {u: [] for u in urls}
        self.error: BaseException | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as e:  # noqa: BLE001 - reported by the test
            self.error = e

    async def _main(self) -> None:
        clients = []
        for url in self.urls:
            c = Client(url, timeout=10)
            c.set_user("viewer")
            c.set_password("viewer-pass")
            await c.connect()
            clients.append(c)
            idx = await c.get_namespace_index(NS_URI)
            seen = self.seen[url]

            class Handler:
                def datachange_notification(self, node, val, data, _s=seen):
                    _s.append(data.monitored_item.Value)

            sub = await c.create_subscription(50, Handler())
            await sub.subscribe_data_change(c.get_node(ua.NodeId(KEY, idx)))
        while not self._stop.is_set():
            await asyncio.sleep(0.05)
        for c in clients:
            await c.disconnect()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(15)


def test_robot_killed_values_bad_or_last_usable(qtbot, tmp_path):
    users = UserStore(tmp_path / "users.json")
    users.add("viewer", "viewer", "viewer-pass")
    sim = SimRobotProcess(seed=2).start()
    link = RobotLink(LinkSettings(reconnect_every_s=0.5))
    session = DeskSession(link)
    servers = []
    for mode in ("bad", "uncertain"):
        s = OpcUaDeskServer(OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0",
                                          allow_none_security=True, link_lost_status=mode),
                            users=users, pki_dir=tmp_path / "pki")
        s.attach(session.pipeline)
        s.start()
        servers.append(s)
    watcher = Watcher([s.url for s in servers])
    bad, unc = (watcher.seen[s.url] for s in servers)
    try:
        link.connect_to(sim.host, sim.port)
        qtbot.waitUntil(lambda: link.state == "connected", timeout=20000)
        qtbot.waitUntil(lambda: any(d.StatusCode.is_good() and d.Value.Value is not None
                                    for d in bad)
                        and any(d.StatusCode.is_good() for d in unc), timeout=15000)
        sim.kill()
        qtbot.waitUntil(lambda: any(d.StatusCode.value == ua.StatusCodes.BadNoCommunication
                                    for d in bad), timeout=15000)
        qtbot.waitUntil(lambda: any(
            d.StatusCode.value == ua.StatusCodes.UncertainNoCommunicationLastUsableValue
            for d in unc), timeout=5000)
    finally:
        watcher.stop()
        for s in servers:
            s.stop()
        link.shutdown()
        session.close()
        sim.stop()
    assert watcher.error is None, watcher.error
    lost = next(d for d in bad if d.StatusCode.value == ua.StatusCodes.BadNoCommunication)
    assert lost.Value.Value is None  # a Bad code carries no value
    last = next(d for d in unc if d.StatusCode.value ==
                ua.StatusCodes.UncertainNoCommunicationLastUsableValue)
    # the last value the robot sent, with its source timestamp (when the desk got it)
    pipe = session.pipeline
    assert last.Value.Value == pytest.approx(pipe.latest["temp_c"])
    assert last.SourceTimestamp.timestamp() == pytest.approx(pipe.latest_t, abs=1e-3)
    assert session.pipeline.link_state != "connected"
