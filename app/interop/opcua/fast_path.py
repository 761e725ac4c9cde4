"""The server's per-value path made cheaper, with the same bytes and notifications.

With 50 subscribed items changing at 10 Hz (``bench/opcua_bench.py --vary all
--profile``) most of the server's CPU went, per written value, to three places in
asyncua that do more work than our values need:

1. ``MonitoredItemService.datachange_callback`` builds an empty
   ``MonitoredItemNotification()`` before it knows whether the value passes, and the
   empty one builds a default DataValue and a Null Variant (type guessed): some
   60 µs a value, thrown away. :func:`install` serves it as asyncua does, but makes
   the notification only for a value that passes, with its handle and value given.
   And a monitored item keeps a deep copy of each value (so that a writer changing
   its object later cannot change what was sent); the desk's DataValues are never
   changed once written (space.py's ``_Frozen``), so the copy is the value itself.
2. A DataValue is serialized by asyncua's generic dataclass serializer: a loop over
   its fields asking each for None, then a serializer per field looked up on each
   call. :func:`datavalue_to_binary` writes the same bytes (Part 6 §5.2.2.17: an
   encoding mask, then the fields present in order) directly, and converts each
   timestamp once (a flush writes fifty values with one server timestamp, and the
   values of one message share their source timestamp); so too a
   MonitoredItemNotification (its handle, its DataValue) and a scalar Variant.
3. ``ua.Variant(value, type)`` checks and guesses in ``__post_init__``;
   :func:`scalar_variant` makes the same object for a scalar of a known type. And a
   write goes through three layers that look the node up and check the value's type
   each time: :func:`value_writer` does what the last of them does, for one node.

:func:`install` changes asyncua's classes in the server's process only (the desk's
process imports it, never installs it). Tests compare the bytes with asyncua's own
serializer and the notifications with its own callback.
"""

from __future__ import annotations

import copy
import functools
import logging
import struct
from datetime import datetime
from typing import Any

from asyncua import ua
from asyncua.server import monitored_item_service as mis
from asyncua.ua import ua_binary

__all__ = ["datavalue_to_binary", "install", "notification_to_binary", "scalar_variant",
           "value_writer", "variant_to_binary"]

log = logging.getLogger(__name__)

_installed: dict[str, Any] = {}


def scalar_variant(value: Any, vtype: ua.VariantType) -> ua.Variant:
    """``ua.Variant(value, vtype)`` for a scalar (not a list, not None) of a type that
    matches ``vtype``: the fields ``__post_init__`` would set, set directly."""
    v = object.__new__(ua.Variant)
    v.Value, v.VariantType, v.Dimensions, v.is_array = value, vtype, None, False
    return v


# ------------------------------------------------------------ serializing a DataValue
_U8, _U16, _U32, _I64 = (struct.Struct(f).pack for f in ("<B", "<H", "<I", "<q"))
_stamps: dict[datetime, bytes] = {}


def _stamp(dt: datetime) -> bytes:
    """A DateTime's 8 bytes (Part 6 §5.2.2.5), kept for the few timestamps in use."""
    b = _stamps.get(dt)
    if b is None:
        if len(_stamps) > 256:
            _stamps.clear()
        b = _stamps[dt] = _I64(ua.datetime_to_win_epoch(dt))
    return b


_packers: dict[ua.VariantType, Any] = {}
# a numeric scalar's encoding byte and value in one struct (Part 6 §5.1.2: little-endian)
_NUMERIC = {getattr(ua.VariantType, name): struct.Struct("<B" + fmt).pack for name, fmt in (
    ("Boolean", "?"), ("SByte", "b"), ("Byte", "B"), ("Int16", "h"), ("UInt16", "H"),
    ("Int32", "i"), ("UInt32", "I"), ("Int64", "q"), ("UInt64", "Q"), ("Float", "f"),
    ("Double", "d"))}


def variant_to_binary(var: ua.Variant) -> bytes:
    """A Variant's encoding (Part 6 §5.2.2.16) as asyncua's ``variant_to_binary``; a
    numeric scalar packed with its encoding byte at once, another scalar with its
    type's packer looked up once (asyncua looks it up on each call)."""
    value = var.Value
    if var.is_array or var.Dimensions is not None or isinstance(value, (list, tuple)):
        return ua_binary.variant_to_binary(var)
    vtype = var.VariantType
    try:
        numeric = _NUMERIC.get(vtype)
        if numeric is not None:
            return numeric(vtype.value, value)
        pack = _packers.get(vtype)
        if pack is None:
            pack = _packers[vtype] = ua_binary.create_uatype_serializer(vtype)
        return _U8(vtype.value & 0b0011_1111) + pack(value)
    except (struct.error, TypeError, OverflowError):  # asyncua's message says why
        return ua_binary.variant_to_binary(var)


def datavalue_to_binary(dv: ua.DataValue) -> bytes:
    """A DataValue's binary encoding (Part 6 §5.2.2.17), as asyncua's serializer
    writes it: the mask of the fields present, then each present field in order."""
    mask, parts = 0, [b""]
    if dv.Value is not None:
        mask |= 0x01
        parts.append(variant_to_binary(dv.Value))
    if dv.StatusCode is not None:
        mask |= 0x02
        parts.append(_U32(dv.StatusCode.value))
    if dv.SourceTimestamp is not None:
        mask |= 0x04
        parts.append(_stamp(dv.SourceTimestamp))
    if dv.ServerTimestamp is not None:
        mask |= 0x08
        parts.append(_stamp(dv.ServerTimestamp))
    if dv.SourcePicoseconds is not None:
        mask |= 0x10
        parts.append(_U16(dv.SourcePicoseconds))
    if dv.ServerPicoseconds is not None:
        mask |= 0x20
        parts.append(_U16(dv.ServerPicoseconds))
    parts[0] = _U8(mask)
    return b"".join(parts)


def notification_to_binary(n: ua.MonitoredItemNotification) -> bytes:
    """A MonitoredItemNotification (Part 4 §7.25.2): its client handle, its value."""
    return _U32(n.ClientHandle) + datavalue_to_binary(n.Value)


_FAST = {ua.DataValue: datavalue_to_binary, ua.MonitoredItemNotification: notification_to_binary}


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
    mid = self._monitored_datachange[handle]
    mdata = self._monitored_items[mid]
    if mdata.mode == ua.MonitoringMode.Disabled:
        return
    _keep(mdata.mvalue, value)
    if mdata.filter:
        passes = self._is_data_changed(mdata.mvalue, mdata.filter.Trigger) and \
            self._is_deadband_exceeded(mdata.mvalue, mdata.filter)
    else:
        passes = self._is_data_changed(mdata.mvalue, ua.DataChangeTrigger.StatusValue)
    if passes:
        await self.isub.enqueue_datachange_event(
            mid, ua.MonitoredItemNotification(ClientHandle=mdata.client_handle, Value=value),
            mdata.queue_size)


def value_writer(server: Any, nodeid: ua.NodeId) -> Any:
    """An ``async write(dv)`` of the node's Value as asyncua's
    ``AddressSpace.write_attribute_value`` does it (the value kept, a value callback
    dropped, each data change callback called with it), without looking the node up,
    nor checking the value's type, on each write: for the desk's values, of their
    node's type by making (space.py), with a Bad code's value already null. None when
    the path is not installed or the node not as expected (its writes then go through
    asyncua's)."""
    if not _installed:
        return None
    node = getattr(getattr(server, "iserver", None), "aspace", None)
    node = getattr(node, "_nodes", {}).get(nodeid)
    av = None if node is None else node.attributes.get(ua.AttributeIds.Value)
    if av is None or getattr(av, "value_setter", True) is not None or \
            not isinstance(getattr(av, "datachange_callbacks", None), dict):
        return None

    async def write(dv: ua.DataValue) -> None:
        av.value = dv
        av.value_callback = None
        for handle, callback in tuple(av.datachange_callbacks.items()):
            try:
                await callback(handle, dv)
            except Exception:  # noqa: BLE001 - as asyncua: one subscriber's error is logged
                log.exception("OPC UA: data change callback %s of %s failed", handle, nodeid)

    return write


def install() -> bool:
    """Put the cheaper path in place in this process (once); False (and a warning: the
    server stays correct, only slower) when asyncua is not as expected."""
    if _installed:
        return True
    svc = getattr(mis, "MonitoredItemService", None)
    make = getattr(ua_binary, "create_dataclass_serializer", None)
    caches = [getattr(ua_binary, n, None) for n in
              ("create_dataclass_serializer", "create_type_serializer", "create_list_serializer")]
    if svc is None or make is None or not hasattr(svc, "datachange_callback") or \
            not hasattr(mis.MonitoredItemValues, "set_current_datavalue") or \
            not all(hasattr(c, "cache_clear") for c in caches):
        log.warning("OPC UA: asyncua's serializer or monitored items have changed; "
                    "the server's value path stays asyncua's")
        return False
    _installed["datachange_callback"] = svc.datachange_callback
    _installed["create_dataclass_serializer"] = make
    svc.datachange_callback = _datachange_callback

    @functools.cache
    def create_dataclass_serializer(dataclazz: type) -> Any:
        return _FAST.get(dataclazz) or make(dataclazz)

    ua_binary.create_dataclass_serializer = create_dataclass_serializer
    for c in caches:  # serializers made before hold asyncua's: made again on use
        c.cache_clear()
    return True
