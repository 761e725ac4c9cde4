"""The desk's OPC UA server seen by a real OPC UA client (asyncua's Client, in this
process, over loopback): browse, values with units, timestamps and quality, a
subscription, users and roles, methods through the command gateway, security.

The desk pipeline is fed a synthetic stream on the test's thread, as
tests/e2e/test_desk_parity.py does; the server runs on its own thread and loop.
"""

from __future__ import annotations

import asyncio
import shutil
import sqlite3
from contextlib import asynccontextmanager, contextmanager
from dataclasses import dataclass

import pytest
from asyncua import Client, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from cryptography.x509.oid import ExtendedKeyUsageOID

from app.comm import protocol as P
from app.config import OpcuaSettings
from app.core.desk.channels import TELEMETRY_CHANNELS
from app.core.desk.pipeline import DeskPipeline
from app.core.freshness import FreshnessTracker
from app.core.meter_service import MeterRecord
from app.core.records import Archive
from app.interop.opcua.server import OpcUaDeskServer
from app.interop.opcua.space import NS_URI, eu_information
from app.interop.opcua.users import UserStore

pytestmark = pytest.mark.slow(30)

T0 = 1_800_000_000.0
PW = {"viewer": "viewer-pass", "op": "operator-pass", "boss": "supervisor-pass"}


class Sender:
    """The link the gateway hands commands to: records them."""

    def __init__(self) -> None:
        self.sent: list[str] = []

    def send_command(self, name, args=None):
        self.sent.append(name)
        return len(self.sent)

    def estop(self):
        self.sent.append("estop")
        return len(self.sent)

    def drive(self, *a):
        pass

    def stop(self):
        pass

    def reset_estop(self):
        return 0


@dataclass
class Lease:
    holder: str | None = "this desk"
    mine: bool = True


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    return tmp_path_factory.mktemp("pki")  # the desk's certificate, made once


@pytest.fixture(scope="module")
def users(tmp_path_factory):
    store = UserStore(tmp_path_factory.mktemp("users") / "users.json")
    store.add("viewer", "viewer", PW["viewer"])
    store.add("op", "operator", PW["op"])
    store.add("boss", "supervisor", PW["boss"])
    return store


def make_desk(users, pki, archive=None, **settings):
    """A desk pipeline and a server of its own, started, listening to it."""
    sender = Sender()
    pipe = DeskPipeline(sender=sender, archive=archive)
    s = OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0", **settings)
    server = OpcUaDeskServer(s, users=users, pki_dir=pki, tick_s=0.05,
                             freshness=FreshnessTracker(min_old_s=0.3))
    server.attach(pipe)
    server.start()
    return pipe, server, sender


@contextmanager
def shared_server(users, pki, **settings):
    """A server for the tests of this module that run on the same settings (a start
    costs about a second): started as the desk starts it, from a pipeline (its alarms'
    conditions made then); each test attaches a fresh pipeline of its own
    (:func:`attached`). What earlier tests sent stays served, so a test looks for
    values of its own, events after it subscribed, and counts as differences; a test
    that judges quality has a server of its own (:func:`own_desk`)."""
    pipe, server, _ = make_desk(users, pki, **settings)
    try:
        yield server
    finally:
        server.stop()
        pipe.close()


@contextmanager
def attached(server, archive=None):
    """A fresh desk pipeline (its own sender, alarm monitor, gateway and archive)
    attached to the running ``server``, detached at the end."""
    sender = Sender()
    pipe = DeskPipeline(sender=sender, archive=archive)
    server.attach(pipe)  # the server is told the new pipeline's link state: disconnected
    try:
        yield pipe, server, sender
    finally:
        server.detach()
        if not getattr(pipe, "closed_by_test", False):
            pipe.close()


@pytest.fixture(scope="module")
def main_server(users, pki):
    """None security allowed, anonymous not."""
    with shared_server(users, pki, allow_none_security=True) as server:
        yield server


@pytest.fixture
def desk(main_server, tmp_path):
    with attached(main_server, Archive(tmp_path / "archive.sqlite3")) as d:
        yield d


@pytest.fixture
def own_desk(users, pki, tmp_path):
    """A desk with a server of its own (None security allowed), for tests that look at
    state an earlier test would leave in a shared server (a condition's, the
    telemetry's interval its freshness rules learnt)."""
    archive = Archive(tmp_path / "archive.sqlite3")
    pipe, server, sender = make_desk(users, pki, archive, allow_none_security=True)
    yield pipe, server, sender
    server.stop()
    if not getattr(pipe, "closed_by_test", False):
        pipe.close()


@pytest.fixture(scope="module")
def open_server(users, pki):
    """A site that allows anonymous clients (and the None security they come with)."""
    with shared_server(users, pki, allow_none_security=True, allow_anonymous=True) as server:
        yield server


@pytest.fixture
def open_desk(open_server):
    with attached(open_server) as d:
        yield d


@pytest.fixture(scope="module")
def secure_server(users, pki, tmp_path_factory):
    """Secure endpoints only; trusted client certificates in a folder of its own."""
    trusted = tmp_path_factory.mktemp("trusted")
    with shared_server(users, pki, trusted_dir=str(trusted)) as server:
        yield server, trusted


@pytest.fixture
def secure_desk(secure_server):
    server, trusted = secure_server
    with attached(server) as (pipe, _, _):
        yield pipe, server, trusted


def archived(pipe, sql: str) -> list[tuple]:
    """Close the desk (writing what is pending) and query its archive."""
    path = pipe.record.archive.path
    pipe.close()
    pipe.closed_by_test = True
    con = sqlite3.connect(path)
    try:
        return con.execute(sql).fetchall()
    finally:
        con.close()


def telemetry(t: float, gas: float = 3.5, **kw) -> P.Telemetry:
    m = P.Telemetry(gas_lel_pct=gas, temp_c=21.5, humidity_pct=40.0, battery_v=24.0, **kw)
    m.received_s = t
    return m


@asynccontextmanager
async def client(server, user="op", password=None):
    c = Client(server.url, timeout=10)
    if user is not None:
        c.set_user(user)
        c.set_password(PW.get(user, "") if password is None else password)
    async with c:
        idx = await c.get_namespace_index(NS_URI)
        yield c, idx


def node(c, idx, key):
    return c.get_node(ua.NodeId(key, idx))


async def until(pred, timeout=5.0):
    """Poll an async predicate (the server is on another thread)."""
    end = asyncio.get_running_loop().time() + timeout
    while True:
        v = await pred()
        if v:
            return v
        assert asyncio.get_running_loop().time() < end, "condition not met in time"
        await asyncio.sleep(0.02)


async def status_of(c, idx, key):
    return (await node(c, idx, key).read_data_value(raise_on_bad_status=False)).StatusCode


def test_browse_the_address_space(desk):
    pipe, server, _ = desk

    async def run():
        async with client(server, "viewer") as (c, idx):
            root = await c.nodes.objects.get_child(f"{idx}:StationPatrol")
            names = {(await n.read_browse_name()).Name for n in await root.get_children()}
            assert {"Robot", "Environment", "Meters", "Control"} <= names
            env = await root.get_child(f"{idx}:Environment")
            chans = {(await n.read_browse_name()).Name for n in await env.get_children()}
            assert chans == {ch.key for ch in TELEMETRY_CHANNELS}
            ctl = await root.get_child(f"{idx}:Control")
            methods = {(await n.read_browse_name()).Name for n in await ctl.get_methods()}
            assert methods == {"StartPatrol", "PausePatrol", "ResumePatrol", "ReturnToDock",
                               "EmergencyStop"}
    asyncio.run(run())


def test_values_with_units_timestamps_and_quality(own_desk):
    # a server of its own: a single telemetry is never old there (no interval learnt
    # yet); in a shared server an earlier test's arrivals would have taught one
    pipe, server, _ = own_desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=7.25, mode=int(P.RobotMode.PATROL)))
    pipe.ingest("pose", P.Pose(1.5, -2.0, 0.25))

    async def run():
        async with client(server, "viewer") as (c, idx):
            gas = node(c, idx, "Environment.gas_lel_pct")
            dv = await until(lambda: _value_is(gas, 7.25))
            assert dv.StatusCode.is_good()
            assert dv.SourceTimestamp.timestamp() == pytest.approx(T0, abs=1e-3)
            eu = await (await gas.get_child(f"{idx}:EngineeringUnits")).read_value()
            assert eu.DisplayName.Text == "%LEL" and eu.UnitId == eu_information("%").UnitId
            temp_eu = await (await node(c, idx, "Environment.temp_c").get_child(
                f"{idx}:EngineeringUnits")).read_value()
            assert temp_eu.UnitId == (ord("C") << 16) | (ord("E") << 8) | ord("L")  # CEL
            assert await node(c, idx, "Environment.temp_c").read_value() == 21.5
            assert await node(c, idx, "Robot.Mode").read_value() == "PATROL"
            assert await node(c, idx, "Robot.LinkState").read_value() == "connected"
            await until(lambda: _value_is(node(c, idx, "Robot.Pose.X"), 1.5))
            assert await node(c, idx, "Robot.Pose.Y").read_value() == -2.0
    asyncio.run(run())


async def _value_is(n, want):
    dv = await n.read_data_value(raise_on_bad_status=False)
    return dv if dv.Value.Value == want else None


def test_subscribed_client_sees_a_change(desk):
    pipe, server, _ = desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=1.0))

    class Handler:
        def __init__(self):
            self.q: asyncio.Queue = asyncio.Queue()

        def datachange_notification(self, n, val, data):
            self.q.put_nowait(val)

    async def run():
        async with client(server, "viewer") as (c, idx):
            gas = node(c, idx, "Environment.gas_lel_pct")
            # served before subscribing: the server's values are written every 50 ms
            # (tick_s), and a client connects to a running server faster than that
            await until(lambda: _value_is(gas, 1.0))
            h = Handler()
            sub = await c.create_subscription(50, h)
            await sub.subscribe_data_change(gas)
            assert await asyncio.wait_for(h.q.get(), 5) == 1.0  # the initial value
            pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=12.5))
            assert await asyncio.wait_for(h.q.get(), 5) == 12.5
    asyncio.run(run())


def test_quality_uncertain_when_stale_and_bad_when_link_lost(own_desk):
    # a server of its own: its freshness rules learn the telemetry's interval from the
    # arrivals (an earlier test's would count), and no pose was ever received
    pipe, server, _ = own_desk
    pipe.ingest("link_state", "connected")
    for i in range(5):
        pipe.ingest("telemetry", telemetry(T0 + 0.05 * i))

    async def run():
        async with client(server, "viewer") as (c, idx):
            key = "Environment.gas_lel_pct"
            await until(lambda: _value_is(node(c, idx, key), 3.5))
            # the telemetry stops with the link up: last usable value
            await until(lambda: _code_is(c, idx, key, ua.StatusCodes.UncertainLastUsableValue))
            pipe.ingest("telemetry", telemetry(T0 + 1.0))
            await until(lambda: _code_is(c, idx, key, ua.StatusCodes.Good))
            pipe.ingest("link_state", "lost")
            await until(lambda: _code_is(c, idx, key, ua.StatusCodes.BadNoCommunication))
            assert (await status_of(c, idx, "Robot.Pose.X")).value == \
                ua.StatusCodes.BadWaitingForInitialData  # never received
            assert (await status_of(c, idx, "Robot.LinkState")).is_good()
            assert await node(c, idx, "Robot.LinkState").read_value() == "lost"
    asyncio.run(run())


async def _code_is(c, idx, key, code):
    dv = await node(c, idx, key).read_data_value(raise_on_bad_status=False)
    return dv if dv.StatusCode.value == code else None


def test_meter_reading_with_confidence(desk):
    pipe, server, _ = desk
    rec = MeterRecord("PG-101", "P3", 0.42, "MPa", 0.2, 0.8, "normal", 0.87, None,
                      "2027-01-15T08:00:00Z", T0, 5, 6, "patrol")
    pipe._emit("meter_record", rec)  # as DeskMeters announces a fused reading

    async def run():
        async with client(server, "viewer") as (c, idx):
            await until(lambda: _value_is(node(c, idx, "Meters.PG-101.Value"), 0.42))
            assert await node(c, idx, "Meters.PG-101.Confidence").read_value() == 0.87
            assert await node(c, idx, "Meters.PG-101.State").read_value() == "normal"
            eu = await (await node(c, idx, "Meters.PG-101.Value").get_child(
                f"{idx}:EngineeringUnits")).read_value()
            assert eu.DisplayName.Text == "MPa"
    asyncio.run(run())


def test_wrong_password_and_anonymous_refused(desk):
    _, server, _ = desk
    refused = server.stats()["users_refused"]  # by earlier tests on this server

    async def run():
        with pytest.raises(ua.UaStatusCodeError):
            async with client(server, "op", password="not-the-password"):
                pass
        with pytest.raises(ua.UaStatusCodeError):
            async with client(server, user=None):
                pass
    asyncio.run(run())
    assert server.stats()["users_refused"] >= refused + 1


def call(server, c, idx, method):
    """Call a Control method while the desk's thread drains the calls (as its timer does)."""
    async def drain():
        while True:
            server.drain()
            await asyncio.sleep(0.01)

    async def go():
        d = asyncio.create_task(drain())
        try:
            return await node(c, idx, "Control").call_method(
                ua.NodeId(f"Control.{method}", idx))
        finally:
            d.cancel()
    return go()


def test_methods_need_the_role_and_the_lease(desk):
    pipe, server, sender = desk
    refused = server.refused_calls  # by earlier tests on this server
    pipe.ingest("link_state", "connected")

    async def run():
        async with client(server, "viewer") as (c, idx):
            with pytest.raises(ua.uaerrors.BadUserAccessDenied):
                await call(server, c, idx, "StartPatrol")
            with pytest.raises(ua.uaerrors.BadUserAccessDenied):
                await call(server, c, idx, "EmergencyStop")
        async with client(server, "op") as (c, idx):
            with pytest.raises(ua.uaerrors.BadInvalidState):  # no lease yet
                await call(server, c, idx, "StartPatrol")
            pipe.ingest("control", Lease())
            await until(lambda: _value_is(node(c, idx, "Robot.DeskHoldsLease"), True))
            out = await call(server, c, idx, "StartPatrol")
            assert out.startswith("sent")
        async with client(server, "boss") as (c, idx):
            await call(server, c, idx, "EmergencyStop")
    asyncio.run(run())
    assert sender.sent == ["start_patrol", "estop"]
    journal = [(e.name, e.user) for e in pipe.gateway.entries]
    assert journal == [("start_patrol", "opcua:op"), ("estop", "opcua:boss")]
    assert server.refused_calls == refused + 3
    assert archived(pipe, "SELECT command, user FROM command ORDER BY t") == journal


@pytest.mark.parametrize(("mode", "gas"), [(ua.MessageSecurityMode.SignAndEncrypt, 4.0),
                                           (ua.MessageSecurityMode.Sign, 4.5)])
def test_secure_client_trusted_through_the_folder(secure_desk, pki, tmp_path, mode, gas):
    # one server for both modes: each mode's client has a certificate of its own
    # (unknown to the server at first) and reads a value of its own
    pipe, server, trusted = secure_desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=gas))
    key, cert = tmp_path / "client-key.pem", tmp_path / "client-cert.der"

    async def connect():
        c = Client(server.url, timeout=10)
        c.application_uri = "urn:test:scada"
        await c.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key),
                             mode=mode)
        c.set_user("viewer")
        c.set_password(PW["viewer"])
        async with c:
            idx = await c.get_namespace_index(NS_URI)
            return await node(c, idx, "Environment.gas_lel_pct").read_value()

    async def run():
        await setup_self_signed_certificate(key, cert, "urn:test:scada", "localhost",
                                            [ExtendedKeyUsageOID.CLIENT_AUTH],
                                            {"commonName": "test scada"})
        with pytest.raises(Exception):  # noqa: B017 - unknown client: refused
            await connect()
        rejected = list((pki / "rejected").glob("*.der"))
        assert len(rejected) == 1
        shutil.move(rejected[0], trusted / rejected[0].name)  # the administrator trusts it
        assert await connect() == gas

        plain = Client(server.url, timeout=10)  # no None endpoint unless the site allows it
        plain.set_user("viewer")
        plain.set_password(PW["viewer"])
        with pytest.raises(Exception):  # noqa: B017
            async with plain:
                pass
    asyncio.run(run())


def test_anonymous_viewer_when_the_site_allows_it(open_desk):
    pipe, server, sender = open_desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("control", Lease())
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))

    async def run():
        async with client(server, user=None) as (c, idx):
            await until(lambda: _value_is(node(c, idx, "Environment.gas_lel_pct"), 2.0))
            with pytest.raises(ua.uaerrors.BadUserAccessDenied):
                await call(server, c, idx, "StartPatrol")
    asyncio.run(run())
    assert sender.sent == []


class Events:
    def __init__(self):
        self.q: asyncio.Queue = asyncio.Queue()

    def event_notification(self, ev):
        self.q.put_nowait(ev)

    async def next(self, pred, timeout=5.0):
        while True:
            ev = await asyncio.wait_for(self.q.get(), timeout)
            if pred(ev):
                return ev


def test_alarm_condition_event_and_acknowledge_from_the_client(desk):
    pipe, server, _ = desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))
    key = "gas_lel_pct.high"

    async def run():
        async with client(server, "viewer") as (cv, idxv), client(server, "op") as (c, idx):
            h = Events()
            sub = await c.create_subscription(50, h)
            await sub.subscribe_events(c.nodes.server, ua.ObjectIds.LimitAlarmType)
            pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=15.0))
            ev = await h.next(lambda e: e.ConditionName == key)
            assert ev.Severity == 750 and ev.Retain
            assert ev.ActiveState.Text == "Active" and ev.AckedState.Text == "Unacknowledged"
            assert "Gas" in ev.Message.Text
            cond = c.get_node(ua.NodeId(f"Alarms.{key}", idx))
            ack = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)
            comment = ua.LocalizedText("seen from the control room")
            with pytest.raises(ua.uaerrors.BadUserAccessDenied):  # a viewer may not
                await cv.get_node(ua.NodeId(f"Alarms.{key}", idxv)).call_method(
                    ack, ua.Variant(ev.EventId, ua.VariantType.ByteString), comment)
            with pytest.raises(ua.uaerrors.BadEventIdUnknown):
                await cond.call_method(ack, ua.Variant(b"nope", ua.VariantType.ByteString),
                                       comment)

            async def drain():
                while True:
                    server.drain()
                    await asyncio.sleep(0.01)
            d = asyncio.create_task(drain())
            try:
                await cond.call_method(ack, ua.Variant(ev.EventId, ua.VariantType.ByteString),
                                       comment)
            finally:
                d.cancel()
            acked = await h.next(lambda e: e.ConditionName == key
                                 and e.AckedState.Text == "Acknowledged")
            assert acked.ClientUserId == "opcua:op"
    asyncio.run(run())
    a = pipe.monitor.get(key)
    assert a.acknowledged and a.acked_by == "opcua:op"
    assert archived(pipe, f"SELECT to_state, user FROM alarm_transition WHERE alarm = '{key}' "
                          f"ORDER BY t") == [("UNACK", None), ("ACKED", "opcua:op")]


def test_attach_replaces_the_pipeline_and_detach_ends_its_feed(users, pki):
    """What the shared servers above rely on, seen on the desk's side (no process): a
    pipeline attached in place of another feeds the server alone, its link state first;
    once detached, nothing is fed, the lease is not taken as held and the control
    room's calls are refused."""
    class Pipe:  # the desk → server pipe: what was posted
        def __init__(self):
            self.msgs = []

        def post(self, msg):
            self.msgs.append(msg)

    server = OpcUaDeskServer(OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0"),
                             users=users, pki_dir=pki)
    server._send = posted = Pipe()
    first, second = DeskPipeline(sender=Sender()), DeskPipeline(sender=Sender())
    server.attach(first)
    first.ingest("link_state", "connected")
    first.ingest("control", Lease())
    assert server.lease_mine
    posted.msgs.clear()
    server.attach(second)
    assert [m[:2] for m in posted.msgs] == [("link_state", ("disconnected",)),
                                            ("identity", ("",))]
    assert not server.lease_mine  # the new pipeline has not told the lease
    first.ingest("telemetry", telemetry(T0, gas=9.0))
    second.ingest("telemetry", telemetry(T0, gas=1.5))
    fed = [m[1][0]["gas_lel_pct"] for m in posted.msgs if m[0] == "values"]
    assert fed == [1.5]
    second.ingest("link_state", "connected")
    second.ingest("control", Lease())
    call = ("call", 1, "command", {"command": "start_patrol", "user": "opcua:op"})
    server._handle([call])
    assert posted.msgs[-1][:3] == ("reply", 1, True) and second.gateway.sender.sent == \
        ["start_patrol"]
    posted.msgs.clear()
    server.detach()
    assert not server.lease_mine
    second.ingest("telemetry", telemetry(T0 + 1, gas=2.5))
    assert posted.msgs == []
    server._handle([call])
    assert posted.msgs[-1][:3] == ("reply", 1, False)
    assert "no desk pipeline attached" in posted.msgs[-1][3]
    assert second.gateway.sender.sent == ["start_patrol"] and first.gateway.sender.sent == []
    first.close()
    second.close()
