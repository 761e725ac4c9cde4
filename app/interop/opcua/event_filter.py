"""Event filters as OPC UA defines them, for the desk's condition events.

A SCADA that wants the desk's alarms subscribes to events on the Server object with a
where clause on the event type: ``OfType(LimitAlarmType)`` or
``OfType(AlarmConditionType)`` (Part 4 §7.7.3, Table 119: *TRUE if the target Node is
of type operand[0] or of a subtype of operand[0]*). asyncua's server evaluates
``OfType`` as equality with the event's own type, so such a client never receives a
``NonExclusiveLevelAlarmType`` or ``OffNormalAlarmType`` event. asyncua's own client
is not affected (it sends ``EventType InList [the type and every subtype]``).

:func:`install` puts :class:`SubtypeWhereClause` on every event monitored item of the
server when a client creates or modifies it (asyncua's server callbacks
``ItemSubscriptionCreated`` / ``ItemSubscriptionModified``, run before the reply goes
to the client, so no event is missed in between). It differs from asyncua's evaluator
in three points, each as Part 4 §7.7 says:

* ``OfType``: the event's type or any subtype of it (the HasSubtype chain in the
  server's address space, kept per type);
* a SimpleAttributeOperand's whole browse path names the field (``ActiveState/Id``,
  not ``ActiveState``);
* a field the event does not have is null (§7.7.4), not an error that drops the
  event;
* the events that bracket a ConditionRefresh (RefreshStartEventType,
  RefreshEndEventType) and RefreshRequiredEventType pass any filter: Part 9 §4.5,
  *to ensure a Client is always informed, the three special EventTypes ... ignore the
  Event content filtering associated with a Subscription*.
"""

from __future__ import annotations

import logging
from typing import Any

from asyncua import ua
from asyncua.common.callback import CallbackType
from asyncua.common.events import Event
from asyncua.server.monitored_item_service import WhereClauseEvaluator

__all__ = ["SubtypeWhereClause", "install", "supertypes"]

log = logging.getLogger(__name__)
_HAS_SUBTYPE = ua.NodeId(ua.ObjectIds.HasSubtype)
_ALWAYS = frozenset(ua.NodeId(t) for t in (ua.ObjectIds.RefreshStartEventType,
                                           ua.ObjectIds.RefreshEndEventType,
                                           ua.ObjectIds.RefreshRequiredEventType))


def supertypes(aspace: Any, type_id: ua.NodeId) -> frozenset[ua.NodeId]:
    """``type_id`` and every type above it (inverse HasSubtype references)."""
    seen: set[ua.NodeId] = set()
    todo = [type_id]
    while todo:
        nid = todo.pop()
        if nid in seen:
            continue
        seen.add(nid)
        data = aspace.get(nid)
        for ref in getattr(data, "references", ()) if data is not None else ():
            if ref.ReferenceTypeId == _HAS_SUBTYPE and not ref.IsForward:
                todo.append(ref.NodeId)
    return frozenset(seen)


class SubtypeWhereClause(WhereClauseEvaluator):
    """asyncua's where-clause evaluator with ``OfType`` matching subtypes."""

    def __init__(self, logger: Any, aspace: Any, whereclause: ua.ContentFilter,
                 types: dict[ua.NodeId, frozenset[ua.NodeId]] | None = None) -> None:
        super().__init__(logger, aspace, whereclause)
        # each event type's supertypes: the server's type tree does not change while it
        # runs, so one dict serves all its items
        self._types = types if types is not None else {}

    def eval(self, event: Any) -> bool:
        if getattr(event, "EventType", None) in _ALWAYS:
            return True
        return super().eval(event)

    def _is_of_type(self, event_type: Any, wanted: Any) -> bool:
        if not isinstance(event_type, ua.NodeId) or not isinstance(wanted, ua.NodeId):
            return False
        ups = self._types.get(event_type)
        if ups is None:
            ups = self._types[event_type] = supertypes(self._aspace, event_type)
        return wanted in ups

    def _eval_el(self, index: int, event: Any) -> Any:
        el = self.elements[index]
        if el.FilterOperator == ua.FilterOperator.OfType:
            return self._is_of_type(getattr(event, "EventType", None),
                                    self._eval_op(el.FilterOperands[0], event))
        return super()._eval_el(index, event)

    def _eval_op(self, op: Any, event: Any) -> Any:
        if isinstance(op, ua.SimpleAttributeOperand) and op.BrowsePath:
            return getattr(event, Event.browse_path_to_attribute_name(op.BrowsePath), None)
        return super()._eval_op(op, event)


def _event_items(iserver: Any, params: Any, results: Any) -> list[Any]:
    """The monitored items (asyncua's MonitoredItemData) of a create or modify request
    whose filter is an EventFilter. asyncua has no public accessor for them."""
    sub = iserver.subscription_service.subscriptions.get(params.SubscriptionId)
    if sub is None:
        return []
    items = sub.monitored_item_srv._monitored_items
    if isinstance(params, ua.CreateMonitoredItemsParameters):
        ids = [r.MonitoredItemId for r in results if r.StatusCode.is_good()]
    else:
        ids = [m.MonitoredItemId for m in params.ItemsToModify]
    return [m for m in (items.get(i) for i in ids)
            if m is not None and isinstance(m.filter, ua.EventFilter)]


def install(server: Any) -> None:
    """Evaluate the where clauses of ``server``'s event monitored items with
    :class:`SubtypeWhereClause` (also after a client modifies an item's filter, which
    asyncua keeps without evaluating it)."""
    iserver = server.iserver
    types: dict[ua.NodeId, frozenset[ua.NodeId]] = {}

    def on_item(event: Any, _dispatcher: Any) -> None:
        try:
            for m in _event_items(iserver, event.request_params, event.response_params):
                m.where_clause_evaluator = SubtypeWhereClause(
                    log, iserver.aspace, m.filter.WhereClause, types)
        except Exception:  # noqa: BLE001 - the item keeps asyncua's evaluator
            log.exception("OPC UA: event filter not set up for subtypes")

    server.subscribe_server_callback(CallbackType.ItemSubscriptionCreated, on_item)
    server.subscribe_server_callback(CallbackType.ItemSubscriptionModified, on_item)
