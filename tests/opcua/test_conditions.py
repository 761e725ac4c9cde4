"""Alarms & Conditions seen by asyncua's Client: each desk alarm is a condition
instance (NonExclusiveLevelAlarmType / OffNormalAlarmType) with its state variables in
the address space, ConditionRefresh gives a late client the standing alarms, and the
client's Acknowledge and AddComment are on record with who and where from."""

from __future__ import annotations

import asyncio
import json

import pytest
from asyncua import ua
from test_server import (  # noqa: F401 - fixtures and helpers of the server tests
    Events,
    archived,
    client,
    node,
    own_desk,
    pki,
    telemetry,
    until,
    users,
)

from app.interop.opcua.alarms import ACKNOWLEDGE, ADD_COMMENT

pytestmark = pytest.mark.slow(36)

T0 = 1_800_000_000.0
KEY = "gas_lel_pct.high"


@pytest.fixture
def desk(own_desk):  # noqa: F811
    """A server for each test: each looks at the gas alarm's condition, whose state (its
    comment, acknowledged, shelved, out of service) an earlier test would leave in a
    server they shared."""
    return own_desk


async def drained(server, coro):
    """Await ``coro`` while the desk's thread drains the control room's calls."""
    async def drain():
        while True:
            server.drain()
            await asyncio.sleep(0.01)
    d = asyncio.create_task(drain())
    try:
        return await coro
    finally:
        d.cancel()


async def var(c, idx, key, *path):
    n = c.get_node(ua.NodeId(f"Alarms.{key}", idx))
    return await (await n.get_child([f"0:{p}" for p in path])).read_value()


def test_condition_instances_with_state_variables(desk):  # noqa: F811
    pipe, server, _ = desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))
    pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=15.0))  # gas A1: a limit alarm
    pipe.ingest("link_state", "lost")  # link lost: an off-normal alarm

    async def run():
        async with client(server, "viewer") as (c, idx):
            # every alarm the rules can raise is a condition from the start, normal
            fault = "gas_lel_pct.fault"
            fc = c.get_node(ua.NodeId(f"Alarms.{fault}", idx))
            assert (await fc.read_type_definition()) == ua.NodeId(
                ua.ObjectIds.OffNormalAlarmType)
            assert await var(c, idx, fault, "Retain") is False
            assert await var(c, idx, fault, "ActiveState", "Id") is False
            assert await var(c, idx, fault, "AckedState", "Id") is True
            cond = c.get_node(ua.NodeId(f"Alarms.{KEY}", idx))
            await until(lambda: _exists(cond))
            assert (await cond.read_type_definition()) == ua.NodeId(
                ua.ObjectIds.NonExclusiveLevelAlarmType)
            await until(lambda: _eq(var(c, idx, KEY, "AckedState", "Id"), False))
            assert (await var(c, idx, KEY, "ActiveState")).Text == "Active"
            assert await var(c, idx, KEY, "ActiveState", "Id") is True
            assert await var(c, idx, KEY, "EnabledState", "Id") is True
            assert await var(c, idx, KEY, "Retain") is True
            assert await var(c, idx, KEY, "Severity") == 750
            assert await var(c, idx, KEY, "HighLimit") == 10.0
            assert "Gas" in (await var(c, idx, KEY, "Message")).Text
            # the channel's variable has the condition (HasCondition)
            gas = node(c, idx, "Environment.gas_lel_pct")
            refs = await gas.get_referenced_nodes(refs=ua.ObjectIds.HasCondition)
            assert cond.nodeid in [r.nodeid for r in refs]
            methods = {(await m.read_browse_name()).Name for m in await cond.get_methods()}
            assert {"Acknowledge", "AddComment"} <= methods
            lost = [k for k in [a.key for a in pipe.monitor.listed()] if k.startswith("link")]
            assert lost, "the desk raised no link alarm"
            lc = c.get_node(ua.NodeId(f"Alarms.{lost[0]}", idx))
            await until(lambda: _exists(lc))
            assert (await lc.read_type_definition()) == ua.NodeId(
                ua.ObjectIds.OffNormalAlarmType)
    asyncio.run(run())
    assert server.stats()["write_errors"] == 0  # every state variable took its field


async def _exists(n):
    try:
        await n.read_browse_name()
        return True
    except ua.UaStatusCodeError:
        return False


async def _eq(coro, want):
    try:
        return (await coro) == want
    except ua.UaStatusCodeError:
        return False


def test_condition_refresh_gives_a_late_client_the_standing_alarms(desk):  # noqa: F811
    pipe, server, _ = desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))
    pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=15.0))
    pipe.ingest("telemetry", telemetry(T0 + 0.2, gas=21.0))  # A2 too (latching)

    async def run():
        async with client(server, "viewer") as (c, idx):
            await until(lambda: _eq(var(c, idx, "gas_lel_pct.a2", "Retain"), True))
            h = Events()  # a client that connects after the alarms were raised
            sub = await c.create_subscription(50, h)
            await sub.subscribe_events(c.nodes.server, [ua.ObjectIds.AlarmConditionType,
                                                        ua.ObjectIds.RefreshStartEventType,
                                                        ua.ObjectIds.RefreshEndEventType])
            await c.get_node(ua.NodeId(ua.ObjectIds.ConditionType)).call_method(
                ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh),
                ua.Variant(sub.subscription_id, ua.VariantType.UInt32))
            got = []
            while True:
                ev = await asyncio.wait_for(h.q.get(), 5)
                got.append(ev)
                if ev.EventType == ua.NodeId(ua.ObjectIds.RefreshEndEventType):
                    break
            assert got[0].EventType == ua.NodeId(ua.ObjectIds.RefreshStartEventType)
            names = {e.ConditionName for e in got[1:-1]}
            assert {KEY, "gas_lel_pct.a2"} <= names
            assert all(e.Retain for e in got[1:-1])
    asyncio.run(run())


def test_acknowledge_and_comment_from_the_client_on_record(desk):  # noqa: F811
    pipe, server, _ = desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))

    async def run():
        async with client(server, "op") as (c, idx):
            h = Events()
            sub = await c.create_subscription(50, h)
            await sub.subscribe_events(c.nodes.server, ua.ObjectIds.AlarmConditionType)
            pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=15.0))
            ev = await h.next(lambda e: e.ConditionName == KEY)
            cond = c.get_node(ua.NodeId(f"Alarms.{KEY}", idx))
            eid = ua.Variant(ev.EventId, ua.VariantType.ByteString)
            # AddComment through the condition's own method node
            add = await cond.get_child("0:AddComment")
            await drained(server, cond.call_method(add, eid, ua.LocalizedText("gas team sent")))
            ev2 = await h.next(lambda e: e.ConditionName == KEY and e.Comment.Text)
            assert ev2.Comment.Text == "gas team sent" and ev2.ClientUserId == "opcua:op"
            assert ev2.AckedState.Text == "Unacknowledged"  # a comment is not an ack
            assert (await var(c, idx, KEY, "Comment")).Text == "gas team sent"
            with pytest.raises(ua.uaerrors.BadEventIdUnknown):
                await cond.call_method(ADD_COMMENT, ua.Variant(b"x", ua.VariantType.ByteString),
                                       ua.LocalizedText("?"))
            # Acknowledge with a comment, through the type's method
            await drained(server, cond.call_method(
                ACKNOWLEDGE, ua.Variant(ev2.EventId, ua.VariantType.ByteString),
                ua.LocalizedText("acknowledged from the DCS")))
            acked = await h.next(lambda e: e.ConditionName == KEY
                                 and e.AckedState.Text == "Acknowledged")
            assert acked.Comment.Text == "acknowledged from the DCS"
            assert await var(c, idx, KEY, "AckedState", "Id") is True
    asyncio.run(run())
    a = pipe.monitor.get(KEY)
    assert a.acknowledged and a.acked_by == "opcua:op"
    # the comment is the desk's too (its alarm panel shows it), with who
    assert (a.comment, a.comment_by) == ("gas team sent", "opcua:op")
    path = pipe.record.archive.path
    rows = archived(pipe, f"SELECT to_state, user, reason, origin FROM alarm_transition "
                          f"WHERE alarm = '{KEY}' ORDER BY t, id")
    assert rows[0][:2] == ("UNACK", None)
    to, user, reason, origin = rows[-1]
    assert (to, user, reason) == ("ACKED", "opcua:op", "acknowledged from the DCS")
    assert origin.startswith("opc.tcp 127.0.0.1:")  # the client's address
    import sqlite3
    con = sqlite3.connect(path)
    try:
        comments = [json.loads(d) for (d,) in con.execute(
            "SELECT data FROM event WHERE kind = 'alarm_comment'")]
    finally:
        con.close()
    assert len(comments) == 1
    cm = comments[0]
    assert (cm["alarm"], cm["user"], cm["comment"]) == (KEY, "opcua:op", "gas team sent")
    assert cm["origin"].startswith("opc.tcp 127.0.0.1:")


def test_shelving_from_the_client_is_the_desks_on_record(desk):  # noqa: F811
    """TimedShelve, Unshelve and OneShotShelve on a condition's ShelvingState are the
    desk's shelving, by the OPC UA user and from where; a one-shot shelving ends when
    the alarm clears."""
    from asyncua.ua.uaerrors import BadConditionAlreadyShelved, BadShelvingTimeOutOfRange

    from app.core.alarms import AlarmState

    pipe, server, _ = desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))
    shelving = {n: ua.NodeId(getattr(ua.ObjectIds, f"ShelvedStateMachineType_{n}"))
                for n in ("TimedShelve", "OneShotShelve", "Unshelve")}

    async def run():
        async with client(server, "op") as (c, idx):
            h = Events()
            sub = await c.create_subscription(50, h)
            await sub.subscribe_events(c.nodes.server, ua.ObjectIds.AlarmConditionType)
            pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=15.0))
            await h.next(lambda e: e.ConditionName == KEY)
            st = c.get_node(ua.NodeId(f"Alarms.{KEY}.ShelvingState", idx))
            state = await st.get_child("0:CurrentState")
            assert (await state.read_value()).Text == "Unshelved"

            def shelved(name):
                return lambda e: (e.ConditionName == KEY and getattr(
                    e, "ShelvingState/CurrentState").Text == name)
            await drained(server, st.call_method(
                shelving["TimedShelve"], ua.Variant(600_000.0, ua.VariantType.Double)))
            ev = await h.next(shelved("TimedShelved"))
            assert ev.SuppressedOrShelved is True
            assert 0 < getattr(ev, "ShelvingState/UnshelveTime") <= 600_000.0
            a = pipe.monitor.get(KEY)
            assert a.state is AlarmState.SHELVED
            assert a.shelved_until - a.raised_t == pytest.approx(600.0, abs=5.0)
            with pytest.raises(BadConditionAlreadyShelved):
                await drained(server, st.call_method(
                    shelving["TimedShelve"], ua.Variant(1000.0, ua.VariantType.Double)))
            # Unshelve through the instance's own method node
            await drained(server, st.call_method(await st.get_child("0:Unshelve")))
            await h.next(shelved("Unshelved"))
            assert pipe.monitor.get(KEY).state is AlarmState.UNACK
            with pytest.raises(BadShelvingTimeOutOfRange):  # beyond the desk's longest
                await drained(server, st.call_method(
                    shelving["TimedShelve"], ua.Variant(1e9, ua.VariantType.Double)))
            # one-shot: shelved until the alarm clears, then unshelved by the server
            await drained(server, st.call_method(shelving["OneShotShelve"]))
            await h.next(shelved("OneShotShelved"))
            assert (await state.read_value()).Text == "OneShotShelved"
            for k in range(1, 6):  # gas back to normal, past the off-delay
                pipe.ingest("telemetry", telemetry(T0 + 1 + k, gas=1.0))
            await drained(server, h.next(shelved("Unshelved")))
            assert pipe.monitor.get(KEY).state is AlarmState.NORMAL
    asyncio.run(run())
    rows = archived(pipe, f"SELECT to_state, user, origin, reason FROM alarm_transition "
                          f"WHERE alarm = '{KEY}' ORDER BY t, id")
    by_client = [r for r in rows if r[1] == "opcua:op"]
    assert [r[0] for r in by_client] == ["SHELVED", "UNACK", "SHELVED"]
    assert all(r[2].startswith("opc.tcp 127.0.0.1:") for r in by_client)
    assert "OPC UA" in by_client[0][3] and "one-shot" in by_client[2][3]
    assert rows[-1][:2] == ("NORMAL", None)  # the one-shot's end: the server's, no user


def test_disable_and_enable_from_the_client_are_the_desks_out_of_service(desk):  # noqa: F811
    """Disable takes the desk's alarm out of service (a supervisor's act, on record with
    who and where from), Enable puts it back; a condition disabled already answers
    Bad_ConditionAlreadyDisabled, an operator may not."""
    from asyncua.ua.uaerrors import (
        BadConditionAlreadyDisabled,
        BadConditionAlreadyEnabled,
        BadUserAccessDenied,
    )

    from app.core.alarms import AlarmState

    pipe, server, _ = desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))
    disable = ua.NodeId(ua.ObjectIds.ConditionType_Disable)
    enable = ua.NodeId(ua.ObjectIds.ConditionType_Enable)

    async def run():
        async with client(server, "op") as (co, idxo), client(server, "boss") as (c, idx):
            h = Events()
            sub = await c.create_subscription(50, h)
            await sub.subscribe_events(c.nodes.server, ua.ObjectIds.AlarmConditionType)
            pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=15.0))
            await h.next(lambda e: e.ConditionName == KEY)
            cond = c.get_node(ua.NodeId(f"Alarms.{KEY}", idx))
            with pytest.raises(BadUserAccessDenied):
                await drained(server, co.get_node(ua.NodeId(f"Alarms.{KEY}", idxo))
                              .call_method(disable))
            with pytest.raises(BadConditionAlreadyEnabled):
                await drained(server, cond.call_method(enable))
            await drained(server, cond.call_method(disable))
            ev = await h.next(lambda e: e.ConditionName == KEY
                              and getattr(e, "EnabledState/Id") is False)
            assert ev.EnabledState.Text == "Disabled"
            assert pipe.monitor.get(KEY).state is AlarmState.OUT_OF_SERVICE
            await until(lambda: _eq(var(c, idx, KEY, "EnabledState", "Id"), False))
            with pytest.raises(BadConditionAlreadyDisabled):
                await drained(server, cond.call_method(disable))
            # back in service through the instance's own method: the standing gas alarm
            # annunciates again
            await drained(server, cond.call_method(await cond.get_child("0:Enable")))
            ev = await h.next(lambda e: e.ConditionName == KEY
                              and getattr(e, "EnabledState/Id") is True)
            assert pipe.monitor.get(KEY).state is AlarmState.UNACK
    asyncio.run(run())
    rows = archived(pipe, f"SELECT to_state, user, reason FROM alarm_transition "
                          f"WHERE alarm = '{KEY}' ORDER BY t, id")
    by_client = [r for r in rows if r[1] == "opcua:boss"]
    assert [r[0] for r in by_client] == ["OUT_OF_SERVICE", "UNACK"]
    assert "control room" in by_client[0][2] and "opc.tcp 127.0.0.1:" in by_client[0][2]
