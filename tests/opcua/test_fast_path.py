"""The server's cheaper value path (app/interop/opcua/fast_path.py) gives what asyncua's
own gives: the same Variants, the same notifications from a monitored item for a
sequence of values, and the same node value and data change callbacks from a write.
``install`` changes asyncua in this (the test) process too, as it does in the
server's; asyncua's own callback is kept by it and used here as the reference."""

from __future__ import annotations

import asyncio
import logging
from datetime import UTC, datetime, timedelta

import pytest
from asyncua import Server, ua
from asyncua.server.internal_subscription import InternalSubscription
from asyncua.server.monitored_item_service import MonitoredItemData, MonitoredItemService

from app.interop.opcua import aspace_cache, fast_path
from app.interop.opcua.space import NO_COMM, DeskSpace, _Frozen, _status

T0 = datetime(2027, 1, 2, 3, 4, 5, 678901, tzinfo=UTC)


@pytest.fixture(scope="module", autouse=True)
def installed():
    assert fast_path.install()
    assert fast_path.install()  # once only: a second install keeps the first's originals


def test_scalar_variant_is_asyncuas():
    for value, vt in ((1.5, ua.VariantType.Double), ("x", ua.VariantType.String),
                      (None, ua.VariantType.String), (3, ua.VariantType.Int32),
                      (False, ua.VariantType.Boolean)):
        mine, theirs = fast_path.scalar_variant(value, vt), ua.Variant(value, vt)
        assert (mine.Value, mine.VariantType, mine.Dimensions, mine.is_array) == \
            (theirs.Value, theirs.VariantType, theirs.Dimensions, theirs.is_array)


class _Sub:
    def __init__(self) -> None:
        self.got: list[tuple] = []

    async def enqueue_datachange_event(self, mid: int, ev: ua.MonitoredItemNotification,
                                       size: int) -> None:
        self.got.append((mid, ev.ClientHandle, ev.Value, size))

    async def trigger_statuschange(self, code: ua.StatusCode) -> None:
        self.got.append(("status", code))


def _service(flt: ua.DataChangeFilter | None) -> MonitoredItemService:
    svc = object.__new__(MonitoredItemService)
    svc.isub = _Sub()
    svc.logger = logging.getLogger("test")
    mdata = MonitoredItemData()
    mdata.client_handle, mdata.monitored_item_id, mdata.queue_size = 42, 7, 3
    mdata.mode, mdata.filter = ua.MonitoringMode.Reporting, flt
    svc._monitored_items = {7: mdata}
    svc._monitored_datachange = {99: 7}
    return svc


@pytest.mark.parametrize("flt", [None, ua.DataChangeFilter(
    Trigger=ua.DataChangeTrigger.StatusValueTimestamp),
    ua.DataChangeFilter(Trigger=ua.DataChangeTrigger.StatusValue,
                        DeadbandType=ua.DeadbandType.Absolute, DeadbandValue=0.5)])
def test_monitored_item_notifies_as_asyncua(flt):
    def dv(v: float, code: int = 0, t: datetime = T0) -> ua.DataValue:
        return _Frozen(fast_path.scalar_variant(v, ua.VariantType.Double),
                       StatusCode=_status(code), SourceTimestamp=t)
    seq = [dv(1.0), dv(1.0), dv(1.2), dv(2.0), dv(2.0, t=T0 + timedelta(seconds=1)),
           dv(2.0, NO_COMM), dv(2.0), ua.DataValue(ua.Variant(3.0)), dv(3.0)]

    async def run(callback) -> list[tuple]:
        svc = _service(flt)
        for value in seq:
            await callback(svc, 99, value)
        return svc.isub.got

    mine = asyncio.run(run(fast_path._datachange_callback))
    theirs = asyncio.run(run(fast_path._installed["datachange_callback"]))
    assert mine == theirs and len(mine) >= 3
    # a value never changed is kept as it is; any other is copied
    svc = _service(None)
    frozen, plain = dv(5.0), ua.DataValue(ua.Variant(6.0))
    asyncio.run(fast_path._datachange_callback(svc, 99, frozen))
    assert svc._monitored_items[7].mvalue.current_dvalue is frozen
    asyncio.run(fast_path._datachange_callback(svc, 99, plain))
    kept = svc._monitored_items[7].mvalue.current_dvalue
    assert kept == plain and kept is not plain


def test_value_writer_writes_as_asyncua():
    async def main():
        server, _ = await aspace_cache.initialised(Server)  # the run's cached standard nodes
        sp = DeskSpace(server, refresh_s=60.0)
        await sp.build()
        key = "Environment.gas_lel_pct"
        item = sp.items[key]
        assert item.put is not None  # installed: the space writes through it
        nodeid = item.node.nodeid
        seen: list[ua.DataValue] = []

        async def on_change(handle, value):
            seen.append(value)
        server.iserver.aspace.add_datachange_callback(nodeid, ua.AttributeIds.Value, on_change)
        sp.set(key, -6.5, T0.timestamp())
        assert await sp.flush() == 1
        dv = server.read_attribute_value(nodeid)
        assert dv.Value == ua.Variant(-6.5, ua.VariantType.Double) and dv.StatusCode.is_good()
        assert dv.SourceTimestamp == T0 and seen == [dv]
        sp.set_quality("telemetry", NO_COMM)  # Bad: the value is null, as asyncua has it
        await sp.flush()
        dv = server.read_attribute_value(nodeid)
        assert dv.StatusCode.value == NO_COMM and dv.Value.Value is None
        assert dv.Value.VariantType == ua.VariantType.Null and seen[-1] is dv
        # asyncua's own write of the same DataValue leaves the same node value
        await server.write_attribute_value(nodeid, dv)
        assert server.read_attribute_value(nodeid) == dv and len(seen) == 3
    asyncio.run(main())


def test_monitored_item_queues_in_a_subscription_as_asyncua():
    """In a subscription publishing from its own loop, the notifications are queued
    without asyncua's coroutines: the same queue (the oldest dropped past the monitored
    item's queue size) as asyncua's own callback leaves."""
    def dv(v: float, code: int = 0) -> ua.DataValue:
        return _Frozen(fast_path.scalar_variant(v, ua.VariantType.Double),
                       StatusCode=_status(code), SourceTimestamp=T0)
    seq = [dv(1.0), dv(1.0), dv(1.5), dv(2.0), dv(2.0, NO_COMM), dv(3.0), dv(4.0)]

    async def run(callback) -> dict:
        svc = _service(None)
        server, _ = await aspace_cache.initialised(Server)  # the run's cached standard nodes

        async def sent(*a):
            pass
        isub = InternalSubscription(ua.CreateSubscriptionResult(
            SubscriptionId=1, RevisedPublishingInterval=100.0, RevisedLifetimeCount=300,
            RevisedMaxKeepAliveCount=10), server.iserver.aspace, sent, ua.NodeId(1),
            request_callback=lambda sid: None)
        isub._task = object()  # as started: its loop publishes
        svc.isub = isub
        for value in seq:
            await callback(svc, 99, value)
        return isub._triggered_datachanges

    mine = asyncio.run(run(fast_path._datachange_callback))
    theirs = asyncio.run(run(fast_path._installed["datachange_callback"]))
    assert mine == theirs and len(mine[7]) == 3  # queue size 3: the oldest dropped
    assert [(n.ClientHandle, n.Value.Value.Value, n.Value.StatusCode.value)
            for n in mine[7]] == [(42, 2.0, NO_COMM), (42, 3.0, 0), (42, 4.0, 0)]
