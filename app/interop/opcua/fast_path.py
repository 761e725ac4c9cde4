"""The server's per-value path made cheaper, with the same notifications and writes.

With 50 subscribed items changing at 10 Hz (``bench/opcua_bench.py --vary all
--profile``) most of the server's CPU went, per written value, to two places in
asyncua that do more work than our values need:

1. ``MonitoredItemService.datachange_callback`` builds an empty
   ``MonitoredItemNotification()`` before it knows whether the value passes, and the
   empty one builds a default DataValue and a Null Variant (type guessed): some
   60 µs a value, thrown away. :func:`install` serves it as asyncua does, but makes
   the notification only for a value that passes, with its handle and value given.
   And a monitored item keeps a deep copy of each value (so that a writer changing
   its object later cannot change what was sent); the desk's DataValues are never
   changed once written (space.py's ``_Frozen``), so the copy is the value itself.
2. ``ua.Variant(value, type)`` checks and guesses in ``__post_init__``;
   :func:`scalar_variant` makes the same object for a scalar of a known type. And a
   write goes through three layers that look the node up and check the value's type
   each time: :func:`value_writer` does what the last of them does, for one node.

3. asyncua's write awaits each data change callback, which awaits the subscription's
   enqueue, which awaits its queueing, which awaits a publish trigger that does
   nothing for a subscription publishing from its own loop: four coroutines a value.
   :func:`value_writer`'s write is a plain function that queues the notification as
   asyncua's ``_enqueue_event`` does (:func:`_notify`), and leaves an awaitable only
   for what it cannot serve so.

:func:`install` changes asyncua's classes in the server's process only (the desk's
process imports it, never installs it). Tests compare the notifications with asyncua's
own callback and the writes with its own write.

The binary encoding itself stays asyncua's: this module never writes OPC UA bytes.
"""

from __future__ import annotations

import copy
import logging
from typing import Any

from asyncua import ua
from asyncua.server import monitored_item_service as mis
from asyncua.server.internal_subscription import InternalSubscription as _Subscription

__all__ = ["install", "scalar_variant", "value_writer"]

log = logging.getLogger(__name__)

_installed: dict[str, Any] = {}


def scalar_variant(value: Any, vtype: ua.VariantType) -> ua.Variant:
    """``ua.Variant(value, vtype)`` for a scalar (not a list, not None) of a type that
    matches ``vtype``: the fields ``__post_init__`` would set, set directly."""
    v = object.__new__(ua.Variant)
    v.Value, v.VariantType, v.Dimensions, v.is_array = value, vtype, None, False
    return v


# ------------------------------------------------------------ a monitored item's value
def _keep(mvalue: Any, value: ua.DataValue) -> None:
    """MonitoredItemValues.set_current_datavalue: the copy of a value never changed is
    the value (``copy.deepcopy`` would return it too, by ``__deepcopy__``, slower)."""
    mvalue.old_dvalue = mvalue.current_dvalue
    mvalue.current_dvalue = value if getattr(type(value), "never_changed", False) \
        else copy.deepcopy(value)


async def _datachange_callback(self: Any, handle: int, value: ua.DataValue,
                               error: ua.StatusCode | None = None) -> None:
    # as asyncua's MonitoredItemService.datachange_callback (2.1), the notification
    # made only for a value that passes
    if error:
        await _installed["datachange_callback"](self, handle, value, error)
        return
    rest = _notify(self, handle, value)
    if rest is not None:
        await rest


def _notify(svc: Any, handle: int, value: ua.DataValue) -> Any:
    """The body of :func:`_datachange_callback` without its awaits: the value checked
    and, when it passes, its notification queued in the subscription as asyncua's
    ``InternalSubscription._enqueue_event`` queues it. None when done; else the
    awaitable that is left (a subscription that is not asyncua's periodic one: its
    ``enqueue_datachange_event``, which may publish at once)."""
    mid = svc._monitored_datachange[handle]
    mdata = svc._monitored_items[mid]
    if mdata.mode == ua.MonitoringMode.Disabled:
        return None
    _keep(mdata.mvalue, value)
    if mdata.filter:
        passes = svc._is_data_changed(mdata.mvalue, mdata.filter.Trigger) and \
            svc._is_deadband_exceeded(mdata.mvalue, mdata.filter)
    else:
        passes = svc._is_data_changed(mdata.mvalue, ua.DataChangeTrigger.StatusValue)
    if not passes:
        return None
    note = ua.MonitoredItemNotification(ClientHandle=mdata.client_handle, Value=value)
    isub = svc.isub
    # a subscription publishing from its own loop (_task): asyncua's _trigger_publish
    # does nothing for it, so the queueing is all there is to do
    if type(isub) is not _Subscription or isub._task is None:
        return isub.enqueue_datachange_event(mid, note, mdata.queue_size)
    queue = isub._triggered_datachanges
    notes = queue.get(mid)
    if notes is None:
        queue[mid] = [note]
        return None
    if mdata.queue_size != 0 and len(notes) >= mdata.queue_size:
        notes.pop(0)
    notes.append(note)
    return None


def value_writer(server: Any, nodeid: ua.NodeId) -> Any:
    """A ``write(dv)`` of the node's Value as asyncua's
    ``AddressSpace.write_attribute_value`` does it (the value kept, a value callback
    dropped, each data change callback called with it), without looking the node up,
    nor checking the value's type, on each write: for the desk's values, of their
    node's type by making (space.py), with a Bad code's value already null. None when
    the path is not installed or the node not as expected (its writes then go through
    asyncua's).

    ``write`` is not a coroutine: a monitored item's callback is served in it
    (:func:`_notify`) without the four coroutines asyncua's path makes for each value;
    what cannot be (another callback, a subscription without its own publishing loop)
    is returned as one awaitable to await before the next write, None when nothing
    is left."""
    if not _installed:
        return None
    node = getattr(getattr(server, "iserver", None), "aspace", None)
    node = getattr(node, "_nodes", {}).get(nodeid)
    av = None if node is None else node.attributes.get(ua.AttributeIds.Value)
    if av is None or getattr(av, "value_setter", True) is not None or \
            not isinstance(getattr(av, "datachange_callbacks", None), dict):
        return None

    def write(dv: ua.DataValue) -> Any:
        av.value = dv
        av.value_callback = None
        rest: list[tuple[int, Any, Any]] | None = None
        for handle, callback in tuple(av.datachange_callbacks.items()):
            left = None
            if getattr(callback, "__func__", None) is _datachange_callback:
                try:  # a monitored item's: served here, without a coroutine
                    left = _notify(callback.__self__, handle, dv)
                except Exception:  # noqa: BLE001 - as asyncua: logged, the others go on
                    log.exception("OPC UA: data change callback %s of %s failed", handle,
                                  nodeid)
                    continue
                if left is None:
                    continue
            if rest is None:
                rest = []
            rest.append((handle, callback, left))
        return None if rest is None else _finish(rest, dv)

    async def _finish(rest: list[tuple[int, Any, Any]], dv: ua.DataValue) -> None:
        for handle, callback, left in rest:
            try:
                await (left if left is not None else callback(handle, dv))
            except Exception:  # noqa: BLE001 - as asyncua: one subscriber's error is logged
                log.exception("OPC UA: data change callback %s of %s failed", handle, nodeid)

    return write


def install() -> bool:
    """Put the cheaper path in place in this process (once); False (and a warning: the
    server stays correct, only slower) when asyncua is not as expected."""
    if _installed:
        return True
    svc = getattr(mis, "MonitoredItemService", None)
    if svc is None or not hasattr(svc, "datachange_callback") or \
            not hasattr(mis.MonitoredItemValues, "set_current_datavalue"):
        log.warning("OPC UA: asyncua's monitored items have changed; "
                    "the server's value path stays asyncua's")
        return False
    _installed["datachange_callback"] = svc.datachange_callback
    svc.datachange_callback = _datachange_callback
    return True
