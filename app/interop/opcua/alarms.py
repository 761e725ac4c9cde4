"""The desk's alarms as OPC UA Alarms & Conditions (Part 9): one condition instance per
desk alarm, its state in the address space and in its events, and the control room's
Acknowledge and AddComment as the desk's.

Each desk alarm (app/core/alarms) becomes, on its first transition (or when the server
starts, for the alarms already listed), an object ``Alarms.<key>`` instantiated from
its type with asyncua's ``instantiate`` (every mandatory component of the type: the
state variables ``EnabledState``, ``ActiveState``, ``AckedState`` with their ``Id``,
``Retain``, ``Comment``, ``ClientUserId``, ``Severity``, ``LastSeverity``, ``Message``,
``Time``, ``EventId``, ``Quality``, ``BranchId``, ``InputNode``, the methods
``Acknowledge``, ``AddComment``, ``Enable``, ``Disable``):

* ``NonExclusiveLevelAlarmType`` (a LimitAlarmType) for a high / low limit or a
  set-point on a channel, with its ``HighLimit`` or ``LowLimit`` and, in its events,
  ``HighState`` / ``LowState``; the channel's variable ``HasCondition`` it;
* ``OffNormalAlarmType`` for everything else (MCU flags, link lost, e-stop, meters,
  archive, sensor fault, bump tests).

Each condition also has its ``ShelvingState`` (ShelvedStateMachineType, Part 9
§5.8.10): ``CurrentState`` Unshelved / TimedShelved / OneShotShelved and
``UnshelveTime`` (ms left), in the address space and in the events, and its methods
``TimedShelve``, ``OneShotShelve``, ``Unshelve``, which the server maps onto the desk's
shelving (app/interop/opcua/alarm_methods.py, app/interop/opcua/desk_calls.py).

``Severity`` from the priority (LOW 250, MEDIUM 500, HIGH 750, EMERGENCY 1000);
``ConditionClassId`` Process for a channel's alarms, Maintenance for bump tests and
calibrations, System for the rest. Each condition has its own event generator
(asyncua's ``EventGenerator``), so the event asyncua keeps for ``ConditionRefresh``
(while ``Retain`` is true) is that condition's latest state: a SCADA that connects late
calls ``ConditionRefresh`` and gets every listed alarm between RefreshStart and
RefreshEnd events (asyncua's ``bind_condition_methods``).

After each event the condition's variables are written with the event's fields, so a
client that browses or reads the condition sees the same state as the last event.
"""

from __future__ import annotations

import asyncio
import logging
from collections import deque
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from asyncua import Node, ua
from asyncua.common.instantiate_util import instantiate
from asyncua.server.event_generator import EventGenerator

from app.core.alarms import AlarmState, Priority

__all__ = ["ConditionEvents", "SEVERITY", "ACKNOWLEDGE", "ADD_COMMENT", "LIMIT_TYPE",
           "OFF_NORMAL_TYPE"]

log = logging.getLogger(__name__)

SEVERITY = {Priority.LOW: 250, Priority.MEDIUM: 500, Priority.HIGH: 750,
            Priority.EMERGENCY: 1000}
ACKNOWLEDGE = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)
ADD_COMMENT = ua.NodeId(ua.ObjectIds.ConditionType_AddComment)
SHELVE_METHODS = {"TimedShelve": ua.ObjectIds.ShelvedStateMachineType_TimedShelve,
                  "OneShotShelve": ua.ObjectIds.ShelvedStateMachineType_OneShotShelve,
                  "Unshelve": ua.ObjectIds.ShelvedStateMachineType_Unshelve}
SERVICE_METHODS = {"Enable": ua.ObjectIds.ConditionType_Enable,
                   "Disable": ua.ObjectIds.ConditionType_Disable}
_SHELVED = {"Unshelved": ua.ObjectIds.ShelvedStateMachineType_Unshelved,
            "TimedShelved": ua.ObjectIds.ShelvedStateMachineType_TimedShelved,
            "OneShotShelved": ua.ObjectIds.ShelvedStateMachineType_OneShotShelved}
LIMIT_TYPE = ua.ObjectIds.NonExclusiveLevelAlarmType
OFF_NORMAL_TYPE = ua.ObjectIds.OffNormalAlarmType
# asyncua records a field whose data type is a subtype of a built-in one (UtcTime,
# Duration) by that type's NodeId, which it cannot encode: name the built-in type
_BUILTIN = {ua.ObjectIds.UtcTime: ua.VariantType.DateTime,
            ua.ObjectIds.Duration: ua.VariantType.Double}
_CLASSES = {"process": (ua.ObjectIds.ProcessConditionClassType, "Process"),
            "maintenance": (ua.ObjectIds.MaintenanceConditionClassType, "Maintenance"),
            "system": (ua.ObjectIds.SystemConditionClassType, "System")}


def condition_class(alarm: Any) -> str:
    key = str(alarm.key)
    if ".bump" in key or ".calibration" in key or key.startswith("service."):
        return "maintenance"
    return "process" if alarm.channel else "system"


def _is_limit(alarm: Any) -> bool:
    return (alarm.channel is not None and alarm.limit is not None
            and alarm.condition in ("high", "low"))


@dataclass
class _Condition:
    key: str
    node: Node
    gen: EventGenerator
    limit: bool
    fields: dict[str, ua.NodeId]
    event_ids: deque = field(default_factory=lambda: deque(maxlen=64))
    severity: int = 0
    comment: str = ""
    comment_t: datetime | None = None
    one_shot: bool = False  # shelved by OneShotShelve (until the alarm clears)


class ConditionEvents:
    """Condition instances and their events on ``space`` (a DeskSpace)."""

    def __init__(self, space: Any) -> None:
        self.space = space
        self._folder: Any = None
        self._conds: dict[str, _Condition] = {}
        self._keys: dict[ua.NodeId, str] = {}
        self._generates: set[int] = set()
        self._methods: dict[str, Any] = {}
        self.sent = 0
        self.write_errors = 0

    async def build(self, root: Any, acknowledge: Any, add_comment: Any,
                    shelving: dict[str, Any] | None = None) -> None:
        """``shelving``: the handlers of TimedShelve, OneShotShelve and Unshelve (called
        with the ShelvingState object's NodeId, see :meth:`key_of`), and of Enable and
        Disable (called with the condition's)."""
        s, idx = self.space.server, self.space.idx
        self._folder = await root.add_object(ua.NodeId("Alarms", idx),
                                             ua.QualifiedName("Alarms", idx))
        self._methods = {"Acknowledge": acknowledge, "AddComment": add_comment,
                         **(shelving or {})}
        # the type's methods (a client calls them with ObjectId = the condition, or its
        # ShelvingState for the shelving ones)
        s.link_method(Node(s.iserver.isession, ACKNOWLEDGE), acknowledge)
        s.link_method(Node(s.iserver.isession, ADD_COMMENT), add_comment)
        for name, fn in (shelving or {}).items():
            type_method = SHELVE_METHODS.get(name) or SERVICE_METHODS[name]
            s.link_method(Node(s.iserver.isession, ua.NodeId(type_method)), fn)

    def key_of(self, condition: ua.NodeId) -> str | None:
        """The desk alarm of a condition's NodeId (or of its ShelvingState's)."""
        return self._keys.get(condition)

    def set_one_shot(self, key: str, on: bool) -> None:
        c = self._conds.get(key)
        if c is not None:
            c.one_shot = on

    def knows_event(self, key: str, event_id: Any) -> bool:
        c = self._conds.get(key)
        return c is not None and bytes(event_id or b"") in c.event_ids

    def node_of(self, key: str) -> Node | None:
        c = self._conds.get(key)
        return c.node if c is not None else None

    # ------------------------------------------------------------ instances
    async def prepare(self, alarms: Any) -> int:
        """Make the conditions of ``alarms`` (pairs: a desk alarm, its text in the
        desk's language) now (the server's start): making one costs
        some 20 ms of the loop's CPU (70 ms before browsing was cached, see
        browse_cache.py), better spent before serving. One made while serving (a
        condition no rule names: link lost, e-stop, a meter) is made in steps."""
        n = 0
        for a, text in alarms:
            if a.key not in self._conds:
                c = await self._condition(a)
                raised = a.raised_t == a.raised_t  # NaN: never raised
                when = datetime.fromtimestamp(a.raised_t, UTC) if raised else None
                self._fill(c, a, when, a.acked_by, a.reason, text)
                await self._write(c)  # its state, browsable; no event (nothing happened)
                n += 1
        return n

    async def _condition(self, a: Any) -> _Condition:
        c = self._conds.get(a.key)
        if c is not None:
            return c
        s, idx = self.space.server, self.space.idx
        limit = _is_limit(a)
        type_id = LIMIT_TYPE if limit else OFF_NORMAL_TYPE
        nid = ua.NodeId(f"Alarms.{a.key}", idx)
        nodes = await instantiate(self._folder, Node(s.iserver.isession, ua.NodeId(type_id)),
                                  nodeid=nid, bname=ua.QualifiedName(a.key, idx),
                                  dname=ua.LocalizedText(a.key), idx=idx,
                                  instantiate_optional=False)
        node = nodes[0]
        await asyncio.sleep(0)  # made in steps: the loop serves its clients in between
        if limit:  # the limit this alarm has (LimitAlarmType's optional HighLimit/LowLimit)
            name = "HighLimit" if a.condition == "high" else "LowLimit"
            await node.add_property(ua.NodeId(f"Alarms.{a.key}.{name}", idx),
                                    ua.QualifiedName(name, 0), float(a.limit))
        item = self.space.items.get(f"Environment.{a.channel}") if a.channel else None
        source = item.node.nodeid if item is not None else nid
        if item is not None:
            await item.node.add_reference(nid, ua.ObjectIds.HasCondition)
        shelving = (await instantiate(
            node, Node(s.iserver.isession, ua.NodeId(ua.ObjectIds.ShelvedStateMachineType)),
            nodeid=ua.NodeId(f"Alarms.{a.key}.ShelvingState", idx),
            bname=ua.QualifiedName("ShelvingState", 0), dname=ua.LocalizedText("ShelvingState"),
            idx=idx, instantiate_optional=False))[0]
        await asyncio.sleep(0)
        for m in await node.get_methods() + await shelving.get_methods():
            fn = self._methods.get((await m.read_browse_name()).Name)
            if fn is not None:
                s.link_method(m, fn)
        await asyncio.sleep(0)
        gen = EventGenerator(s.iserver.isession)
        await gen.init(type_id, emitting_node=ua.ObjectIds.Server,
                       add_generates_event=type_id not in self._generates)
        self._generates.add(type_id)
        ev = gen.event
        for name, dt in list(ev.data_types.items()):
            if isinstance(dt, ua.NodeId) and dt.Identifier in _BUILTIN and dt.NamespaceIndex == 0:
                ev.data_types[name] = _BUILTIN[dt.Identifier]
        ev.SourceNode, ev.SourceName = source, a.source
        ev.NodeId = nid  # the ConditionId
        ev.ConditionName = a.key
        cls_id, cls_name = _CLASSES[condition_class(a)]
        ev.ConditionClassId = ua.NodeId(cls_id)
        ev.ConditionClassName = ua.LocalizedText(cls_name)
        ev.BranchId = ua.NodeId()
        ev.InputNode = item.node.nodeid if item is not None else ua.NodeId()
        if hasattr(ev, "NormalState"):
            ev.NormalState = ua.NodeId()
        ev.Quality = ua.StatusCode(ua.StatusCodes.Good)
        # the optional ShelvingState's fields (the generator knows the type's own only)
        ev.add_property("ShelvingState/CurrentState", ua.LocalizedText("Unshelved"),
                        ua.VariantType.LocalizedText)
        ev.add_property("ShelvingState/CurrentState/Id", ua.NodeId(_SHELVED["Unshelved"]),
                        ua.VariantType.NodeId)
        ev.add_property("ShelvingState/UnshelveTime", 0.0, ua.VariantType.Double)
        await asyncio.sleep(0)
        c = _Condition(a.key, node, gen, limit, await self._fields(node))
        self._conds[a.key] = c
        self._keys[nid] = a.key
        self._keys[shelving.nodeid] = a.key
        return c

    @staticmethod
    async def _fields(node: Node, prefix: str = "", depth: int = 3) -> dict[str, ua.NodeId]:
        """The condition's variables by event field name ("AckedState/Id",
        "ShelvingState/CurrentState/Id"), one browse per node."""
        out: dict[str, ua.NodeId] = {}
        for ref in await node.get_children_descriptions(
                nodeclassmask=ua.NodeClass.Variable | ua.NodeClass.Object):
            name = f"{prefix}{ref.BrowseName.Name}"
            nid = ua.NodeId(ref.NodeId.Identifier, ref.NodeId.NamespaceIndex)
            if ref.NodeClass == ua.NodeClass.Variable:
                out[name] = nid
            if depth > 1:
                out.update(await ConditionEvents._fields(Node(node.session, nid),
                                                         f"{name}/", depth - 1))
        return out

    # ------------------------------------------------------------ events
    async def transition(self, tr: Any, message: str) -> None:
        """A desk alarm's transition: the condition's new state, as an event with
        ``message`` (the alarm's text or its return to normal, in the desk's
        language: the desk sends it)."""
        await self.publish(tr.alarm, tr.t, tr.user, tr.reason, message)

    async def publish(self, a: Any, t: float, user: str | None, comment: str | None,
                      message: str) -> None:
        c = await self._condition(a)
        when = datetime.fromtimestamp(t, UTC)
        self._fill(c, a, when, user, comment, message)
        ev = c.gen.event
        await c.gen.trigger(time_attr=when, message=message)
        eid = ev.EventId.Value if isinstance(ev.EventId, ua.Variant) else ev.EventId
        c.event_ids.append(bytes(eid))  # its latest events may be acknowledged
        self.sent += 1
        await self._write(c)

    def _fill(self, c: _Condition, a: Any, when: datetime | None, user: str | None,
              comment: str | None, message: str) -> None:
        """The condition's event fields from the desk alarm ``a``."""
        ev = c.gen.event
        sev = SEVERITY.get(a.priority, 500)
        ev.LastSeverity = c.severity or sev
        ev.Severity = c.severity = sev
        ev.Retain = bool(a.listed)
        ev.ClientUserId = user or ""
        if comment:
            c.comment, c.comment_t = comment, when
        ev.Comment = ua.LocalizedText(c.comment)
        setattr(ev, "Comment/SourceTimestamp", c.comment_t)
        enabled = a.state is not AlarmState.OUT_OF_SERVICE
        for name, on, yes, no in (("EnabledState", enabled, "Enabled", "Disabled"),
                                  ("ActiveState", a.active, "Active", "Inactive"),
                                  ("AckedState", a.acknowledged, "Acknowledged",
                                   "Unacknowledged"),
                                  ("ConfirmedState", True, "Confirmed", "Unconfirmed")):
            self._two_state(ev, name, bool(on), yes, no, when)
        shelved = a.state is AlarmState.SHELVED
        ev.SuppressedOrShelved = shelved
        c.one_shot = c.one_shot and shelved
        state = ("OneShotShelved" if c.one_shot else "TimedShelved") if shelved else "Unshelved"
        setattr(ev, "ShelvingState/CurrentState/Id", ua.NodeId(_SHELVED[state]))
        setattr(ev, "ShelvingState/CurrentState", ua.LocalizedText(state))
        left_s = (a.shelved_until - when.timestamp()) if shelved and a.shelved_until \
            and when is not None else 0.0
        # whole ms (``when`` is rounded to the microsecond)
        setattr(ev, "ShelvingState/UnshelveTime", float(round(max(0.0, left_s) * 1000.0)))
        if c.limit:
            high = a.condition == "high"
            ev.HighLimit = float(a.limit) if high else None
            ev.LowLimit = None if high else float(a.limit)
            self._two_state(ev, "HighState", high and a.active, "High", "", when)
            self._two_state(ev, "LowState", not high and a.active, "Low", "", when)
        if not ev.Message:
            ev.Message = ua.LocalizedText(message)

    async def comment(self, key: str, text: str, user: str, t: float) -> None:
        """A comment on a condition (AddComment): a new event with it, same state."""
        c = self._conds[key]
        ev = c.gen.event
        c.comment, c.comment_t = text, datetime.fromtimestamp(t, UTC)
        ev.Comment = ua.LocalizedText(text)
        setattr(ev, "Comment/SourceTimestamp", c.comment_t)
        ev.ClientUserId = user
        await c.gen.trigger(time_attr=c.comment_t)
        eid = ev.EventId.Value if isinstance(ev.EventId, ua.Variant) else ev.EventId
        c.event_ids.append(bytes(eid))
        self.sent += 1
        await self._write(c)

    @staticmethod
    def _two_state(ev: Any, name: str, on: bool, yes: str, no: str,
                   when: datetime | None) -> None:
        if not hasattr(ev, name):
            return
        if getattr(ev, f"{name}/Id", None) != on:
            setattr(ev, f"{name}/TransitionTime", when)
        setattr(ev, name, ua.LocalizedText(yes if on else no))
        setattr(ev, f"{name}/Id", on)

    async def _write(self, c: _Condition) -> None:
        """The condition's variables take the event's fields."""
        ev, s = c.gen.event, self.space.server
        for name, nid in c.fields.items():
            if name not in ev.data_types:
                continue
            v = getattr(ev, name)
            if v is None:
                continue
            var = v if isinstance(v, ua.Variant) else ua.Variant(v, ev.data_types[name])
            try:
                await s.write_attribute_value(nid, ua.DataValue(var))
            except Exception:  # noqa: BLE001 - one odd field must not stop the alarms
                self.write_errors += 1
                log.debug("OPC UA: %s of %s not written", name, c.key, exc_info=True)
