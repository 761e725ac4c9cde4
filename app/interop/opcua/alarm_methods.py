"""The control room's calls on the desk's alarm conditions (Part 9), in the server's
process: the caller's role and the call are checked here, then the desk does it, on its
own thread, as its own action on its alarm monitor (app/interop/opcua/desk_calls.py),
by ``opcua:<user>`` and from where (the client's address and application URI), so the
archive has both:

* ``Acknowledge(EventId, Comment)``: the desk's acknowledgement, with the comment;
* ``AddComment(EventId, Comment)``: archived (event ``alarm_comment``) and kept with the
  alarm, which the alarm panel shows with who made it;
* ``ShelvingState.TimedShelve(ShelvingTime)`` (ms): the desk's shelving for that
  time, within the desk's longest (``max_shelve_s``, else
  Bad_ShelvingTimeOutOfRange);
* ``ShelvingState.OneShotShelve()``: Part 9 §5.8.10 shelves the alarm until it
  returns to normal; the desk's shelving is for the desk's longest time, and the desk
  unshelves it as soon as the alarm's condition clears;
* ``ShelvingState.Unshelve()``;
* ``Disable()`` / ``Enable()``: the desk's alarm out of service / back in service
  (``EnabledState`` follows the desk's OUT_OF_SERVICE state).

A shelving call on an alarm already shelved answers Bad_ConditionAlreadyShelved, an
unshelve of one that is not Bad_ConditionNotShelved. Roles: ``acknowledge``,
``shelve`` and ``disable`` in :data:`~app.interop.opcua.users.METHOD_ROLES`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from asyncua import ua

from app.interop.opcua.users import METHOD_ROLES
from app.interop.opcua.wire import DeskRefused

__all__ = ["AlarmMethods"]

log = logging.getLogger(__name__)


class AlarmMethods:
    """``server``: the ServerCore (its conditions, ``desk`` and ``refuse``);
    ``caller()``: the user of the request being served."""

    def __init__(self, server: Any, caller: Callable[[], Any]) -> None:
        self.srv = server
        self.caller = caller

    def shelving_handlers(self) -> dict[str, Any]:
        """The shelving methods' handlers, and Enable's and Disable's."""
        return {"TimedShelve": self.timed_shelve, "OneShotShelve": self.one_shot_shelve,
                "Unshelve": self.unshelve, "Enable": self.enable, "Disable": self.disable}

    # ------------------------------------------------------------ common
    def _who(self, user: Any) -> tuple[str, str]:
        """``("opcua:<name>", origin)``: the desk's name for an OPC UA user and where
        the session comes from (peer address and client application URI)."""
        if user is not None and not getattr(user, "origin", ""):
            peer = ""
            iserver = getattr(self.srv._server, "iserver", None)
            # asyncua keeps the sessions by token; the one whose user this is says its
            # peer (asyncua has no public accessor for it)
            for sess in list(getattr(iserver, "_external_sessions", {}).values()):
                if sess.user is user:
                    name = sess.name
                    peer = (f"{name[0]}:{name[1]}" if isinstance(name, tuple)
                            and len(name) >= 2 else str(name))
                    break
            user.origin = " ".join(x for x in (f"opc.tcp {peer}" if peer else "",
                                               getattr(user, "app_uri", "")) if x)
        return f"opcua:{getattr(user, 'name', None)}", getattr(user, "origin", "") or ""

    def _check(self, what: str, role_of: str, node: ua.NodeId, event_id: Any = None
               ) -> tuple[Any, str | None]:
        """(refusal or None, alarm key) for a call on ``node`` (a condition or its
        ShelvingState); ``event_id`` is checked when given."""
        user = self.caller()
        name, role = getattr(user, "name", None), getattr(user, "desk_role", None)
        conditions = self.srv.conditions
        key = conditions.key_of(node)
        if role not in METHOD_ROLES[role_of]:
            return self.srv.refuse(what, name, f"role {role or 'none'} may not",
                                    ua.StatusCodes.BadUserAccessDenied), key
        if key is None:
            return self.srv.refuse(what, name, f"no condition {node}",
                                    ua.StatusCodes.BadNodeIdUnknown), key
        if event_id is not None and not conditions.knows_event(
                key, getattr(event_id, "Value", event_id)):
            return self.srv.refuse(what, name, f"unknown EventId for {key}",
                                    ua.StatusCodes.BadEventIdUnknown), key
        return None, key

    def _request(self, what: str, role_of: str, node: ua.NodeId, event_id: Any = None
                 ) -> tuple[Any, str | None, str, str]:
        """(refusal or None, alarm key, who, origin) of the caller's request on
        ``node``: :meth:`_check`, then :meth:`_who` of an allowed caller."""
        refused, key = self._check(what, role_of, node, event_id)
        if refused is not None:
            return refused, key, "", ""
        return (None, key, *self._who(self.caller()))

    @staticmethod
    def _text(comment: Any) -> str:
        comment = getattr(comment, "Value", comment)
        return str(getattr(comment, "Text", None) or "")

    async def _desk(self, what: str, op: str, **kw: Any) -> tuple[Any, Any]:
        """(answer, None) of the desk's call ``op``, or (None, refusal)."""
        try:
            return await self.srv.desk(op, **kw), None
        except DeskRefused as e:
            return None, self.srv.refuse(what, getattr(self.caller(), "name", None), str(e),
                                         ua.StatusCodes.BadTimeout)

    # ------------------------------------------------------------ acknowledge, comment
    async def acknowledge(self, condition: ua.NodeId, event_id: Any, comment: Any) -> Any:
        """A client's Acknowledge on a condition: the desk's acknowledgement, by its user,
        with its comment and where it came from (all in the archive)."""
        refused, key, who, origin = self._request("acknowledge", "acknowledge", condition, event_id)
        if refused is not None:
            return refused
        text = self._text(comment)
        done, refused = await self._desk("acknowledge", "acknowledge", key=key, user=who,
                                         comment=text, origin=origin)
        if refused is not None:
            return refused
        if not done:
            return ua.StatusCode(ua.StatusCodes.BadConditionBranchAlreadyAcked)
        log.info("OPC UA: alarm %s acknowledged by %s from %s%s", key, who, origin or "?",
                 f" ({text})" if text else "")
        return []

    async def add_comment(self, condition: ua.NodeId, event_id: Any, comment: Any) -> Any:
        """A client's AddComment, on the desk's thread: archived (event
        ``alarm_comment``: alarm, user, origin, comment) and given to the alarm monitor
        (the alarm panel shows it, with who); then a condition event with the comment."""
        refused, key, who, origin = self._request("add comment", "acknowledge", condition, event_id)
        if refused is not None:
            return refused
        text = self._text(comment)
        t, refused = await self._desk("add comment", "comment", key=key, user=who,
                                      origin=origin, text=text)
        if refused is not None:
            return refused
        await self.srv.conditions.comment(key, text, who, t)
        log.info("OPC UA: comment on %s by %s from %s: %s", key, who, origin or "?", text)
        return []

    # ------------------------------------------------------------ shelving
    async def timed_shelve(self, shelving_state: ua.NodeId, shelving_time: Any) -> Any:
        ms = getattr(shelving_time, "Value", shelving_time)
        try:
            seconds = float(ms) / 1000.0
        except (TypeError, ValueError):
            return ua.StatusCode(ua.StatusCodes.BadShelvingTimeOutOfRange)
        return await self._shelve("timed shelve", shelving_state, seconds, one_shot=False)

    async def one_shot_shelve(self, shelving_state: ua.NodeId) -> Any:
        return await self._shelve("one-shot shelve", shelving_state, None, one_shot=True)

    async def _shelve(self, what: str, node: ua.NodeId, seconds: float | None,
                      one_shot: bool) -> Any:
        refused, key, who, origin = self._request(what, "shelve", node)
        if refused is not None:
            return refused
        # the condition's next event says which shelving it is
        self.srv.conditions.set_one_shot(key, one_shot)
        answer, refused = await self._desk(what, "shelve", key=key, seconds=seconds,
                                           one_shot=one_shot, user=who, origin=origin)
        outcome, detail = answer if refused is None else ("refused", "")
        if outcome != "shelved":
            self.srv.conditions.set_one_shot(key, False)
        if refused is not None:
            return refused
        if outcome == "out of range":
            return self.srv.refuse(what, getattr(self.caller(), "name", None), detail,
                                   ua.StatusCodes.BadShelvingTimeOutOfRange)
        if outcome != "shelved":
            return ua.StatusCode(ua.StatusCodes.BadConditionAlreadyShelved)
        log.info("OPC UA: alarm %s %s by %s from %s (%s)", key, what, who, origin or "?",
                 detail)
        return []

    async def unshelve(self, shelving_state: ua.NodeId) -> Any:
        refused, key, who, origin = self._request("unshelve", "shelve", shelving_state)
        if refused is not None:
            return refused
        done, refused = await self._desk("unshelve", "unshelve", key=key, user=who,
                                         origin=origin)
        if refused is not None:
            return refused
        if not done:
            return ua.StatusCode(ua.StatusCodes.BadConditionNotShelved)
        log.info("OPC UA: alarm %s unshelved by %s from %s", key, who, origin or "?")
        return []

    # ------------------------------------------------------------ in / out of service
    async def enable(self, condition: ua.NodeId) -> Any:
        """Enable: the desk's alarm back in service (it annunciates again if its
        condition stands); Bad_ConditionAlreadyEnabled when it is in service."""
        return await self._service("enable", condition, out=False)

    async def disable(self, condition: ua.NodeId) -> Any:
        """Disable: the desk's alarm out of service (ISA-18.2: a supervisor's act, with
        the reason "disabled from the control room" and where from);
        Bad_ConditionAlreadyDisabled when it is out of service already."""
        return await self._service("disable", condition, out=True)

    async def _service(self, what: str, node: ua.NodeId, out: bool) -> Any:
        refused, key, who, origin = self._request(what, "disable", node)
        if refused is not None:
            return refused
        done, refused = await self._desk(what, "service", key=key, out=out, user=who,
                                         origin=origin)
        if refused is not None:
            return refused
        if not done:
            return ua.StatusCode(ua.StatusCodes.BadConditionAlreadyDisabled if out
                                 else ua.StatusCodes.BadConditionAlreadyEnabled)
        log.info("OPC UA: alarm %s %sd by %s from %s", key, what, who, origin or "?")
        return []
