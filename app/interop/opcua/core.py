"""The OPC UA server proper (asyncua), in the server's process: the address space, the
alarm conditions, the control room's sessions and methods, fed by the desk's messages.

::

    desk process                          server process (app/interop/opcua/child.py)
    OpcUaDeskServer ── pipe: batches ──▶ reader thread ─ call_soon_threadsafe ─▶ receive()
      values, mode, link_state, pose,        asyncio.Queue ─▶ DeskSpace (staged)
      patrol_status, control, meter_record,    freshness every 0.25 s → quality
      alarm (with its text), replies           flush at the publishing rate → nodes
    drain() ◀── pipe ◀── desk(op, ...) ◀─── Control / Acknowledge / AddComment / shelving
      runs the call on the desk's thread       (role checked here; lease, archive: the desk)

The server never touches the desk's objects: a method or a condition's Acknowledge
asks the desk (:meth:`ServerCore.desk`) and awaits its answer. The caller of a request
is known through a context variable set by the permission ruleset, which asyncua runs
for every request of a session just before serving it, on the same task.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import gc
import itertools
import logging
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from asyncua import Server, ua
from asyncua.crypto.permission_rules import SimpleRoleRuleset, User, UserRole
from asyncua.server.user_managers import UserManager

from app.core.freshness import FreshnessTracker
from app.interop.opcua import aspace_cache, browse_cache, event_filter, fast_path
from app.interop.opcua.alarm_methods import AlarmMethods
from app.interop.opcua.alarms import ConditionEvents
from app.interop.opcua.child import ServerConfig
from app.interop.opcua.loop_probe import StallWatch
from app.interop.opcua.security import setup_security
from app.interop.opcua.space import DeskSpace, MeterValue, quality_codes
from app.interop.opcua.users import METHOD_ROLES, UserStore
from app.interop.opcua.wire import DeskRefused

__all__ = ["ServerCore", "DeskUser"]

log = logging.getLogger(__name__)

_caller: contextvars.ContextVar[Any] = contextvars.ContextVar("opcua_caller", default=None)
_GROUPS = ("telemetry", "pose", "patrol", "control")
_METHODS = (("StartPatrol", "start_patrol"), ("PausePatrol", "pause_patrol"),
            ("ResumePatrol", "resume_patrol"), ("ReturnToDock", "dock"),
            ("EmergencyStop", "estop"))


@dataclass
class DeskUser(User):
    desk_role: str = "viewer"
    app_uri: str = ""  # the client application's URI (from its certificate, if any)
    origin: str = ""  # "<peer address> <application URI>", found on its first request


def _app_uri(certificate: Any) -> str:
    """The application URI in a client certificate (DER bytes), or ""."""
    if not certificate:
        return ""
    try:
        from cryptography import x509
        cert = x509.load_der_x509_certificate(bytes(certificate))
        san = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
        uris = san.get_values_for_type(x509.UniformResourceIdentifier)
        return uris[0] if uris else ""
    except Exception:  # noqa: BLE001 - no URI is not an error
        return ""


class _Users(UserManager):
    """User name and password from the users file; anonymous only when the site allows
    it (a viewer). A wrong password is refused and counted."""

    def __init__(self, store: UserStore, allow_anonymous: bool) -> None:
        self.store, self.allow_anonymous = store, allow_anonymous
        self.refused = 0

    def get_user(self, iserver: Any, username: str | None = None, password: str | None = None,
                 certificate: Any = None) -> User | None:
        # no user name: anonymous (X509 user tokens are not offered; ``certificate`` is the
        # client application's, whatever the token)
        if username is None:
            if self.allow_anonymous:
                return DeskUser(role=UserRole.User, name="anonymous", desk_role="viewer",
                                app_uri=_app_uri(certificate))
            self.refused += 1
            return None
        role = self.store.check(username, password)
        if role is None:
            self.refused += 1
            log.warning("OPC UA: user %r refused (unknown user or wrong password); %d so far",
                        username, self.refused)
            return None
        log.info("OPC UA: user %s (%s) signed in", username, role)
        return DeskUser(role=UserRole.User, name=username, desk_role=role,
                        app_uri=_app_uri(certificate))


class _Ruleset(SimpleRoleRuleset):
    """asyncua's role rules, noting who makes each request for the methods."""

    def check_validity(self, user: Any, action_type_id: Any, body: Any) -> bool:
        _caller.set(user)
        return super().check_validity(user, action_type_id, body)


def freeze_startup_objects() -> None:
    """Move every object alive now (the address space: long-lived) out of the
    collector's sight, so that a full collection no longer walks them (``gc.freeze``):
    the address space alone is some 550 000 objects (the standard nodes, ours, the
    alarm conditions), and a full collection of them took 170 ms of CPU; after, 1-2 ms.
    Garbage made from now on is collected as before; an object alive now that later
    becomes cyclic garbage is not freed."""
    t0 = time.perf_counter()
    gc.collect()
    gc.freeze()
    log.info("OPC UA: %d start-up objects frozen out of the collector (%.0f ms)",
             gc.get_freeze_count(), (time.perf_counter() - t0) * 1000)


async def end_clock(server: Server) -> None:
    """End asyncua's clock task (it writes the ServerStatus' CurrentTime once a second)
    at once: asyncua's ``Server.stop`` waits for it to wake from its one-second sleep,
    up to 1 s of every stop (1.0 s measured, sessions already closed by then)."""
    iserver = server.iserver
    task, iserver.time_task = iserver.time_task, None
    iserver._time_task_stop = True  # noqa: SLF001 - as asyncua's own stop sets it
    if task is not None and not task.done():
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


class ServerCore:
    """The server, run by :meth:`main` on the process's asyncio loop. ``to_desk(msg)``
    sends a message to the desk (never blocks)."""

    def __init__(self, cfg: ServerConfig, to_desk: Callable[[tuple], None]) -> None:
        self.cfg = cfg
        self.settings = settings = cfg.settings
        self.to_desk = to_desk
        self.quality = quality_codes(getattr(settings, "link_lost_status", "bad"))
        self.tick_s = cfg.tick_s
        self.min_flush_s = min(cfg.min_flush_s, cfg.tick_s)
        self.fresh = cfg.freshness if cfg.freshness is not None else FreshnessTracker()
        self.fresh.expect("patrol", periodic=False)
        self.fresh.expect("control", periodic=False)
        self.refused_calls = 0
        self.stalls = StallWatch()  # the loop's stalls, and the CPU its thread used then
        self.port: int | None = None
        self.space: DeskSpace | None = None
        self.conditions: ConditionEvents | None = None
        self.alarm_methods: AlarmMethods | None = None
        self._server: Any = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._q: asyncio.Queue | None = None
        self._stop: asyncio.Event | None = None
        self._ids = itertools.count(1)
        self._waiting: dict[int, asyncio.Future] = {}
        self.user_mgr = _Users(cfg.users, settings.allow_anonymous)

    # ------------------------------------------------------------ from the desk
    def receive(self, batch: list[tuple]) -> None:
        """A batch from the desk (on the loop): replies to our calls are answered at
        once, the rest is served in order by :meth:`_consume`."""
        for msg in batch:
            kind = msg[0]
            if kind == "reply":
                fut = self._waiting.pop(msg[1], None)
                if fut is not None and not fut.done():
                    fut.set_result(msg[2:])
            elif kind == "stop":
                self.stop()
            elif self._q is not None:
                self._q.put_nowait(msg)

    def stop(self) -> None:
        if self._stop is not None:
            self._stop.set()

    async def desk(self, op: str, timeout_s: float = 5.0, **kw: Any) -> Any:
        """Run the desk's call ``op`` (app/interop/opcua/desk_calls.py) on the desk's
        thread and return its answer; DeskRefused when it does not come in time."""
        loop = asyncio.get_running_loop()
        n = next(self._ids)
        fut = self._waiting[n] = loop.create_future()
        self.to_desk(("call", n, op, kw))
        try:
            ok, answer = await asyncio.wait_for(fut, timeout_s)
        except TimeoutError:
            raise DeskRefused(f"the desk did not answer {op} in {timeout_s:g} s") from None
        finally:
            self._waiting.pop(n, None)
        if not ok:
            raise DeskRefused(f"the desk could not {op}: {answer}")
        return answer

    # ------------------------------------------------------------ serving
    async def main(self, on_ready: Callable[[int], None],
                   more_tasks: Callable[[], list] = list) -> None:
        """Build the address space, serve until :meth:`stop`; ``on_ready(port)`` once
        listening (an error before: raised)."""
        self._loop = asyncio.get_running_loop()
        self._q, self._stop = asyncio.Queue(), asyncio.Event()
        def make_server() -> Server:
            s = Server(user_manager=self.user_mgr)
            # ConditionRefresh / ConditionRefresh2 with RefreshStart and RefreshEnd events
            s.iserver.bind_condition_methods = True
            return s

        server, _ = await aspace_cache.initialised(make_server,
                                                   enabled=self.cfg.cache_address_space)
        if self.cfg.cache_browsing:  # a condition made while serving: 70 % less CPU
            browse_cache.install(server)
        if self.cfg.fast_path:  # each value written and sent: 60 % less CPU
            fast_path.install()
        self._server = server
        server.set_server_name("Station Patrol desk")
        await server.set_application_uri("urn:station-patrol:desk")
        server.set_endpoint(self.settings.endpoint)
        tokens = [ua.UserNameIdentityToken]
        if self.settings.allow_anonymous:
            tokens.append(ua.AnonymousIdentityToken)
        server.set_identity_tokens(tokens)
        await setup_security(server, self.settings, Path(self.cfg.pki_dir), _Ruleset())
        event_filter.install(server)  # OfType(LimitAlarmType) matches our alarms' events
        self.space = DeskSpace(server, channels=self.cfg.channels or None)
        await self.space.build()
        await self._add_methods()
        self.conditions = ConditionEvents(self.space)
        self.alarm_methods = AlarmMethods(self, caller=_caller.get)
        await self.conditions.build(self.space.root, self.alarm_methods.acknowledge,
                                    self.alarm_methods.add_comment,
                                    self.alarm_methods.shelving_handlers())
        t0 = time.process_time()  # every alarm the rules can raise, before serving
        n = await self.conditions.prepare(self.cfg.configured)
        log.info("OPC UA: %d alarm conditions made in %.2f s of CPU", n,
                 time.process_time() - t0)
        self.cfg.configured = []
        if self.cfg.gc_freeze:
            freeze_startup_objects()
        async with server:
            self.port = server.bserver._server.sockets[0].getsockname()[1]
            tasks = [asyncio.create_task(self._consume()), asyncio.create_task(self._ticker()),
                     asyncio.create_task(self._flusher()),
                     asyncio.create_task(self.stalls.run()), *more_tasks()]
            on_ready(self.port)
            await self._stop.wait()
            for t in tasks:
                t.cancel()
            await end_clock(server)

    async def _consume(self, slice_s: float = 0.005) -> None:
        """Serve the desk's messages in order. A queue that is not empty is read without
        the loop running anything else (asyncio's Queue.get does not suspend then, nor
        do asyncua's writes), so a burst — a flood of alarms, the standing alarms at
        start, a backlog after the machine did not run the process — is served in
        slices of ``slice_s``, the loop serving its clients between them."""
        q = self._q
        assert q is not None
        began = time.perf_counter()
        while True:
            if q.empty():
                item = await q.get()
                began = time.perf_counter()
            else:
                item = q.get_nowait()
            kind, args, t, mono = item
            try:
                await self._apply(kind, args, t, mono)
            except Exception:  # noqa: BLE001 - one bad message must not stop the server
                log.exception("OPC UA: %s not served", kind)
            if time.perf_counter() - began > slice_s:
                await asyncio.sleep(0)
                began = time.perf_counter()

    async def _apply(self, kind: str, args: tuple, t: float, mono: float) -> None:
        """One desk message (see OpcUaDeskServer._post for what each carries); ``mono``
        is the desk's ``time.monotonic`` at posting (the same clock in every process of
        the machine, on Linux, Windows and macOS)."""
        sp = self.space
        assert sp is not None
        if kind == "values":
            values, battery_pct = args
            self.fresh.note("telemetry", mono_s=mono, utc_s=t)
            self._quality()
            for key, v in values.items():
                if f"Environment.{key}" in sp.items:
                    sp.set(f"Environment.{key}", v, t)
            if battery_pct is not None:
                sp.set("Robot.BatteryPercent", battery_pct, t)
        elif kind == "mode":
            code, name = args
            sp.set("Robot.Mode", name, t)
            sp.set("Robot.ModeCode", code, t)
        elif kind == "link_state":
            self.fresh.set_link_up(args[0] == "connected", mono)
            sp.set("Robot.LinkState", str(args[0]), t)
            self._quality()
        elif kind == "identity":
            sp.set("Robot.Identity", str(args[0]), t)
        elif kind == "pose":
            self.fresh.note("pose", mono_s=mono, utc_s=t)
            for name, v in zip(("X", "Y", "Theta"), args, strict=True):
                sp.set(f"Robot.Pose.{name}", v, t)
        elif kind == "patrol_status":
            self.fresh.note("patrol", mono_s=mono, utc_s=t)
            for name, v in zip(("State", "Route", "Index", "Progress", "Reason"), args,
                               strict=True):
                sp.set(f"Robot.Patrol.{name}", v, t)
        elif kind == "control":
            holder, mine = args
            self.fresh.note("control", mono_s=mono, utc_s=t)
            sp.set("Robot.LeaseHolder", holder, t)
            sp.set("Robot.DeskHoldsLease", mine, t)
        elif kind == "meter_record":
            await sp.meter(MeterValue(*args))
        elif kind == "alarm" and self.conditions is not None:
            await self.conditions.transition(*args)
        elif kind == "alarm_state" and self.conditions is not None:
            a, text = args
            await self.conditions.publish(a, a.raised_t, a.acked_by, a.reason, text)

    def _quality(self) -> None:
        assert self.space is not None
        now = time.monotonic()
        for g in _GROUPS:
            self.space.set_quality(g, self.quality[self.fresh.freshness(g, now).age.value])

    async def _ticker(self) -> None:
        while True:
            await asyncio.sleep(self.tick_s)
            self._quality()

    def flush_period_s(self) -> float:
        """How often the staged values are written: the fastest publishing interval of
        the clients' subscriptions (a value changing faster is told once per interval
        anyway), within [min_flush_s, tick_s]; tick_s with no subscription."""
        subs = getattr(getattr(self._server, "iserver", None), "subscription_service", None)
        ms = [s.data.RevisedPublishingInterval
              for s in list(getattr(subs, "subscriptions", {}).values())]
        if not ms:
            return self.tick_s
        return min(max(min(ms) / 1000.0, self.min_flush_s), self.tick_s)

    async def _flusher(self) -> None:
        """Write the staged values at most once per :meth:`flush_period_s`; with
        nothing staged it sleeps until something is (an idle server does not wake ten
        times a second to find nothing to write)."""
        sp = self.space
        assert sp is not None
        loop = asyncio.get_running_loop()
        last = -math.inf
        while True:
            if not sp.dirty:
                sp.staged.clear()
                await sp.staged.wait()
            wait_s = last + self.flush_period_s() - loop.time()
            if wait_s > 0:
                await asyncio.sleep(wait_s)
            last = loop.time()
            try:
                await sp.flush()
            except Exception:  # noqa: BLE001 - the next flush tries again
                log.exception("OPC UA: values not written")

    # ------------------------------------------------------------ methods
    async def _add_methods(self) -> None:
        sp = self.space
        assert sp is not None
        for browse, command in _METHODS:
            async def call(parent: Any, _c: str = command) -> Any:
                return await self._call(_c)
            await sp.control.add_method(ua.NodeId(f"Control.{browse}", sp.idx),
                                        ua.QualifiedName(browse, sp.idx), call,
                                        [], [ua.VariantType.String])

    async def _call(self, command: str) -> Any:
        """A Control method: the caller's role is checked here; the desk checks that it
        holds the control lease, sends the command and journals it (``opcua:<user>``)."""
        user = _caller.get()
        name, role = getattr(user, "name", None), getattr(user, "desk_role", None)
        if role not in METHOD_ROLES[command]:
            return self.refuse(command, name, f"role {role or 'none'} may not",
                               ua.StatusCodes.BadUserAccessDenied)
        try:
            outcome, why, seq = await self.desk("command", command=command,
                                                user=f"opcua:{name}")
        except DeskRefused as e:
            return self.refuse(command, name, str(e), ua.StatusCodes.BadTimeout)
        log.info("OPC UA: %s by %s: %s %s", command, name, outcome, why)
        if outcome == "no lease":
            return self.refuse(command, name, why, ua.StatusCodes.BadInvalidState)
        if outcome != "sent":
            return ua.StatusCode(ua.StatusCodes.BadNoCommunication
                                 if outcome == "not delivered"
                                 else ua.StatusCodes.BadInvalidState)
        return [ua.Variant(f"sent (seq {seq})", ua.VariantType.String)]

    def refuse(self, command: str, name: str | None, why: str, code: int) -> ua.StatusCode:
        self.refused_calls += 1
        log.warning("OPC UA: %s by %s refused: %s", command, name, why)
        return ua.StatusCode(code)

    # ------------------------------------------------------------ figures
    def stats(self) -> dict[str, Any]:
        """Counts for tests and benches (read on the loop)."""
        sp, cond = self.space, self.conditions
        times = os.times()
        return {"port": self.port, "cpu_s": time.process_time(),
                "loop_cpu_s": time.thread_time(),  # the loop's thread (stats runs on it)
                "sys_cpu_s": times.system,  # in the kernel, every thread
                "writes": sp.writes if sp else 0,
                "items": sorted(sp.items) if sp else [],
                "events": cond.sent if cond else 0,
                "write_errors": cond.write_errors if cond else 0,
                "users_refused": self.user_mgr.refused,
                "refused_calls": self.refused_calls,
                "max_stall_s": self.stalls.max_stall_s}
