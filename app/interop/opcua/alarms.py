"""The desk's alarms as OPC UA Alarms & Conditions (Part 9), one condition per desk
alarm, and the control room's acknowledgement as the desk's acknowledgement.

Each transition of a desk alarm (app/core/alarms: raised, cleared, acknowledged,
shelved, ...) is a condition event from the Server object: ``LimitAlarmType`` for a
high / low limit on a channel, ``OffNormalAlarmType`` for everything else (MCU flags,
link lost, e-stop, meters, archive). Its fields: ``ConditionName`` the alarm's key,
``SourceName`` its source, ``Message`` the desk's text, ``Severity`` from the priority
(LOW 250, MEDIUM 500, HIGH 750, EMERGENCY 1000), ``ActiveState``/``AckedState`` with
their ``Id``, ``Retain`` while the alarm is listed, ``ClientUserId`` who acted, and the
``ConditionId`` (the event's NodeId field) ``Alarms.<key>``, an object in the address
space.

``Acknowledge`` (ns=0 i=9111, AcknowledgeableConditionType) called on a condition with
the EventId of its latest event: refused unless the caller's role may acknowledge,
``BadEventIdUnknown`` for an EventId the condition never had; otherwise the desk's
monitor acknowledges the alarm on the desk's thread with the user ``opcua:<name>``
(the archive keeps it with the transition), and the comment goes into the desk's log.
"""

from __future__ import annotations

import logging
from collections import deque
from datetime import UTC, datetime
from typing import Any

from asyncua import Node, ua

from app.core.alarms import Priority

__all__ = ["ConditionEvents", "SEVERITY"]

log = logging.getLogger(__name__)

SEVERITY = {Priority.LOW: 250, Priority.MEDIUM: 500, Priority.HIGH: 750,
            Priority.EMERGENCY: 1000}
ACKNOWLEDGE = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)


class ConditionEvents:
    """Condition nodes and events on ``space`` (a DeskSpace); ``ack(key, user, comment)``
    is awaited for a client's acknowledgement and returns the desk's answer."""

    def __init__(self, space: Any) -> None:
        self.space = space
        self._folder: Any = None
        self._gens: dict[int, Any] = {}
        self._keys: dict[ua.NodeId, str] = {}
        self._event_ids: dict[str, deque[bytes]] = {}
        self.sent = 0

    async def build(self, root: Any, acknowledge: Any) -> None:
        s, idx = self.space.server, self.space.idx
        self._folder = await root.add_object(ua.NodeId("Alarms", idx),
                                             ua.QualifiedName("Alarms", idx))
        for t in (ua.ObjectIds.LimitAlarmType, ua.ObjectIds.OffNormalAlarmType):
            self._gens[t] = await s.get_event_generator(t)
        s.link_method(Node(s.iserver.isession, ACKNOWLEDGE), acknowledge)

    def key_of(self, condition: ua.NodeId) -> str | None:
        return self._keys.get(condition)

    def knows_event(self, key: str, event_id: Any) -> bool:
        return bytes(event_id or b"") in self._event_ids.get(key, ())

    async def _condition(self, key: str) -> ua.NodeId:
        nid = ua.NodeId(f"Alarms.{key}", self.space.idx)
        if nid not in self._keys:
            self._keys[nid] = key
            await self._folder.add_object(nid, ua.QualifiedName(key, self.space.idx))
        return nid

    async def transition(self, tr: Any) -> None:
        a = tr.alarm
        nid = await self._condition(a.key)
        limit = a.condition in ("high", "low") and a.channel is not None
        gen = self._gens[ua.ObjectIds.LimitAlarmType if limit
                         else ua.ObjectIds.OffNormalAlarmType]
        ev = gen.event
        source = self.space.items.get(f"Environment.{a.channel}") if a.channel else None
        ev.SourceNode = source.node.nodeid if source is not None else nid
        ev.SourceName = a.source
        ev.NodeId = nid  # the ConditionId
        ev.ConditionName = a.key
        ev.Severity = ev.LastSeverity = SEVERITY.get(a.priority, 500)
        ev.Retain = bool(a.listed)
        ev.ClientUserId = tr.user or ""
        ev.Comment = ua.LocalizedText(tr.reason or "")
        for name, on, yes, no in (("ActiveState", a.active, "Active", "Inactive"),
                                  ("AckedState", a.acknowledged, "Acknowledged",
                                   "Unacknowledged"),
                                  ("EnabledState", True, "Enabled", "Disabled"),
                                  ("ConfirmedState", True, "Confirmed", "Unconfirmed")):
            setattr(ev, name, ua.LocalizedText(yes if on else no))
            setattr(ev, f"{name}/Id", bool(on))
        if limit:
            for f in ("HighLimit", "LowLimit"):
                if hasattr(ev, f):
                    setattr(ev, f, float(a.limit) if (f == "HighLimit") == (
                        a.condition == "high") and a.limit is not None else None)
        text = a.cleared_text if tr.cleared else a.text
        await gen.trigger(time_attr=datetime.fromtimestamp(tr.t, UTC), message=text)
        eid = ev.EventId.Value if isinstance(ev.EventId, ua.Variant) else ev.EventId
        # the condition's latest events may be acknowledged (older ones are forgotten)
        self._event_ids.setdefault(a.key, deque(maxlen=64)).append(bytes(eid))
        self.sent += 1
