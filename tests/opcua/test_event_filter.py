"""A SCADA's event filter on a supertype of the desk's condition types, as UaExpert
and most SCADA clients write it: ``OfType(LimitAlarmType)`` or
``OfType(AlarmConditionType)`` in the where clause (Part 4 §7.7.3), with select
clauses that name fields by their whole browse path. asyncua's Client with a filter
of our own (its default one lists every subtype, which asyncua's server matched
already)."""

from __future__ import annotations

import asyncio

from asyncua import ua
from asyncua.common.events import get_filter_from_event_type
from test_server import (  # noqa: F401 - fixtures and helpers of the server tests
    Events,
    client,
    own_desk,
    pki,
    telemetry,
    users,
)

T0 = 1_800_000_000.0
KEY = "gas_lel_pct.high"


def _field(*path: str) -> ua.SimpleAttributeOperand:
    op = ua.SimpleAttributeOperand()
    op.TypeDefinitionId = ua.NodeId(ua.ObjectIds.BaseEventType)
    op.BrowsePath = [ua.QualifiedName(p, 0) for p in path]
    op.AttributeId = ua.AttributeIds.Value
    return op


def _element(operator: ua.FilterOperator, *operands: object) -> ua.ContentFilterElement:
    el = ua.ContentFilterElement()
    el.FilterOperator = operator
    el.FilterOperands = list(operands)
    return el


def _literal(value: object, vtype: ua.VariantType | None = None) -> ua.LiteralOperand:
    return ua.LiteralOperand(Value=ua.Variant(value, vtype) if vtype else ua.Variant(value))


async def _filter(c, type_id: int, active_only: bool = False) -> ua.EventFilter:
    """Select the type's fields; where: OfType(type) [and ActiveState/Id = true]."""
    f = await get_filter_from_event_type([c.get_node(ua.NodeId(type_id))],
                                         where_clause_generation=False)
    of_type = _element(ua.FilterOperator.OfType, _literal(ua.NodeId(type_id)))
    if active_only:
        active = _element(ua.FilterOperator.Equals, _field("ActiveState", "Id"),
                          _literal(True, ua.VariantType.Boolean))
        f.WhereClause.Elements = [
            _element(ua.FilterOperator.And, ua.ElementOperand(1), ua.ElementOperand(2)),
            of_type, active]
    else:
        f.WhereClause.Elements = [of_type]
    return f


def test_of_type_supertype_filters_get_the_desk_alarms(own_desk):  # noqa: F811
    # a server of its own: ConditionRefresh below would also give what another test
    # left standing in a shared one
    pipe, server, _ = own_desk
    pipe.ingest("link_state", "connected")
    pipe.ingest("telemetry", telemetry(T0, gas=2.0))

    async def run():
        async with client(server, "viewer") as (c, idx):
            limit, alarm, active = Events(), Events(), Events()
            subs = []
            for h, type_id, only in ((limit, ua.ObjectIds.LimitAlarmType, False),
                                     (alarm, ua.ObjectIds.AlarmConditionType, False),
                                     (active, ua.ObjectIds.AlarmConditionType, True)):
                sub = await c.create_subscription(50, h)
                await sub.subscribe_events(c.nodes.server,
                                           evfilter=await _filter(c, type_id, only))
                subs.append(sub)
            pipe.ingest("telemetry", telemetry(T0 + 0.1, gas=15.0))  # a limit alarm
            ev = await limit.next(lambda e: e.ConditionName == KEY)
            assert ev.EventType == ua.NodeId(ua.ObjectIds.NonExclusiveLevelAlarmType)
            assert ev.HighLimit == 10.0 and ev.Severity == 750
            assert ev.NodeId == ua.NodeId(f"Alarms.{KEY}", idx)  # the ConditionId
            assert (await alarm.next(lambda e: e.ConditionName == KEY)).Retain is True
            on = await active.next(lambda e: e.ConditionName == KEY)
            assert on.ActiveState.Text == "Active"
            pipe.ingest("link_state", "lost")  # an off-normal alarm, no LimitAlarm
            lost = await alarm.next(lambda e: e.ConditionName.startswith("link"))
            assert lost.EventType == ua.NodeId(ua.ObjectIds.OffNormalAlarmType)
            # gas back to normal: the condition goes inactive, which the active-only
            # filter is not told
            pipe.ingest("link_state", "connected")
            for k in range(1, 6):  # past the alarm's off-delay
                pipe.ingest("telemetry", telemetry(T0 + 1 + k, gas=1.0))
            await alarm.next(lambda e: e.ConditionName == KEY
                             and e.ActiveState.Text == "Inactive")
            # raised again: each subscription's events come in order, so what came
            # before this one is all it was told in between
            pipe.ingest("telemetry", telemetry(T0 + 10, gas=15.0))
            for h in (limit, active):
                between = []
                while True:
                    e = await asyncio.wait_for(h.q.get(), 5)
                    if e.ConditionName == KEY and e.ActiveState.Text == "Active":
                        break
                    between.append(e)
                if h is limit:  # the link's alarm is an OffNormalAlarm
                    assert all(e.EventType == ua.NodeId(
                        ua.ObjectIds.NonExclusiveLevelAlarmType) for e in between), \
                        [(e.ConditionName, e.EventType) for e in between]
                else:  # the link's alarm came active; nothing inactive came
                    assert all(e.ActiveState.Text == "Active" for e in between), \
                        [(e.ConditionName, e.ActiveState) for e in between]
            # ConditionRefresh: its Start and End events pass the LimitAlarm filter
            # (Part 9 §4.5), the standing gas alarm between them
            await c.get_node(ua.NodeId(ua.ObjectIds.ConditionType)).call_method(
                ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh),
                ua.Variant(subs[0].subscription_id, ua.VariantType.UInt32))
            start = ua.NodeId(ua.ObjectIds.RefreshStartEventType)
            await limit.next(lambda e: e.EventType == start)
            got = []
            while (e := await asyncio.wait_for(limit.q.get(), 5)).EventType != ua.NodeId(
                    ua.ObjectIds.RefreshEndEventType):
                got.append(e)
            assert KEY in {e.ConditionName for e in got}
    asyncio.run(run())
