"""The desk's OPC UA server (asyncua), fed from the desk pipeline, never in its way.

::

    desk thread (GUI / headless)              thread "opcua" (its own asyncio loop)
    DeskPipeline listeners ─ call_soon_threadsafe ─▶ asyncio.Queue ─▶ DeskSpace (staged)
      values, mode, link_state, pose,                 freshness every 0.25 s → quality
                                                      flush at the publishing rate → nodes
      patrol_status, control, meter_record            client sessions, subscriptions
    drain() ◀── desk_calls (queue.SimpleQueue) ◀─── Control methods (role, lease checked)
      └─▶ CommandGateway.send / .estop (journaled with "opcua:<user>")

A listener only posts to the loop (a few microseconds); nothing on the desk's thread
waits for OPC UA. The methods do not touch the gateway from the server's thread: they
queue a call that the desk's thread runs in :meth:`OpcUaDeskServer.drain` (the window
and the headless desk call it from a timer every 50 ms) and wait for its journal entry.

Users come from :class:`~app.interop.opcua.users.UserStore`; the caller of a method is
known through a context variable set by the permission ruleset, which asyncua runs for
every request of a session just before serving it, on the same task.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextvars
import gc
import logging
import queue
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

from asyncua import Server, ua
from asyncua.crypto.permission_rules import SimpleRoleRuleset, User, UserRole
from asyncua.server.user_managers import UserManager

from app.core.desk.channels import battery_percent, mode_name
from app.core.freshness import FreshnessTracker
from app.interop.opcua import browse_cache, event_filter
from app.interop.opcua.alarm_methods import AlarmMethods
from app.interop.opcua.alarms import ConditionEvents
from app.interop.opcua.loop_probe import CallbackProbe, StallWatch
from app.interop.opcua.security import setup_security
from app.interop.opcua.space import DeskSpace, quality_codes
from app.interop.opcua.users import METHOD_ROLES, UserStore

__all__ = ["OpcUaDeskServer", "DeskUser"]

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


async def _call(fn: Any) -> Any:
    return fn()


def _freeze_startup_objects() -> None:
    """Move every object alive now (the address space, the desk's models: long-lived)
    out of the collector's sight, so that a full collection no longer walks them
    (``gc.freeze``): with the server's address space and the desk's models (some
    550 000 objects in bench/opcua_bench.py) a full collection took 170 ms of CPU,
    stopping every thread; after, 1-2 ms. Garbage made from now on is collected as
    before; an object alive now that later becomes cyclic garbage is not freed."""
    t0 = time.perf_counter()
    gc.collect()
    gc.freeze()
    log.info("OPC UA: %d start-up objects frozen out of the collector (%.0f ms)",
             gc.get_freeze_count(), (time.perf_counter() - t0) * 1000)


class OpcUaDeskServer:
    """``settings``: app.config.OpcuaSettings (``endpoint`` set). ``users``: the user
    store (default: the settings' users file). ``pki_dir``: where the desk's certificate
    lives when the settings do not say. ``freshness``: the tracker that judges staleness
    (default: the desk's rules, app/core/freshness.py)."""

    def __init__(self, settings: Any, *, users: UserStore | None = None,
                 pki_dir: str | Path = "", tick_s: float = 0.25, min_flush_s: float = 0.05,
                 freshness: FreshnessTracker | None = None, gc_freeze: bool = True,
                 cache_browsing: bool = True) -> None:
        self.settings = settings
        self.gc_freeze = gc_freeze  # both True in service; a bench turns them off to compare
        self.cache_browsing = cache_browsing
        self.quality = quality_codes(getattr(settings, "link_lost_status", "bad"))
        self.users = users if users is not None else UserStore(settings.users_file)
        self.pki_dir = Path(settings.pki_dir or pki_dir or "opcua-pki")
        self.tick_s = tick_s
        self.min_flush_s = min(min_flush_s, tick_s)
        self.desk_calls: queue.SimpleQueue = queue.SimpleQueue()
        self.fresh = freshness if freshness is not None else FreshnessTracker()
        self.fresh.expect("patrol", periodic=False)
        self.fresh.expect("control", periodic=False)
        self.lease_mine = False
        self.refused_calls = 0
        self.stalls = StallWatch()  # the loop's stalls, and the CPU its thread used then
        self.probe: CallbackProbe | None = None  # see probe_callbacks()
        self.port: int | None = None
        self.native_id: int | None = None
        self.error: str | None = None
        self._pipeline: Any = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._q: asyncio.Queue | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._stop: asyncio.Event | None = None
        self.space: DeskSpace | None = None
        self._server: Any = None
        self.conditions: ConditionEvents | None = None
        self.alarm_methods: AlarmMethods | None = None
        self._user_mgr = _Users(self.users, settings.allow_anonymous)
        self._listeners: list[tuple[str, Any]] = []

    # ------------------------------------------------------------ desk side
    def attach(self, pipeline: Any) -> None:
        """Listen to ``pipeline`` (call on the desk's thread, before or after start)."""
        self._pipeline = pipeline
        for kind in ("values", "mode", "link_state", "pose", "patrol_status", "control",
                     "meter_record", "alarm"):
            fn = (lambda k: lambda *a: self._post(k, a))(kind)
            pipeline.listen(kind, fn)
            self._listeners.append((kind, fn))
        self._post("link_state", (pipeline.link_state,))
        self._post("identity", (pipeline.robot_id(),))

    def _post(self, kind: str, args: tuple) -> None:
        loop, q = self._loop, self._q
        if loop is None or q is None or loop.is_closed():
            return
        t = self._pipeline.latest_t if kind == "values" and self._pipeline else None
        try:
            loop.call_soon_threadsafe(q.put_nowait, (kind, args, t or time.time(),
                                                     time.monotonic()))
        except RuntimeError:  # the loop has just closed
            pass

    def drain(self) -> int:
        """Run the control room's calls on the desk's thread; returns how many ran."""
        n = 0
        while True:
            try:
                fn, fut = self.desk_calls.get_nowait()
            except queue.Empty:
                return n
            n += 1
            if fut.set_running_or_notify_cancel():
                try:
                    fut.set_result(fn())
                except Exception as e:  # noqa: BLE001 - reported to the caller
                    fut.set_exception(e)

    @property
    def url(self) -> str:
        u = urlparse(self.settings.endpoint)
        host = u.hostname or "127.0.0.1"
        return f"opc.tcp://{host}:{self.port if self.port is not None else u.port}"

    # ------------------------------------------------------------ the thread
    def start(self, timeout_s: float = 60.0) -> None:
        """Start serving; raises RuntimeError with the reason when it cannot."""
        self._thread = threading.Thread(target=self._run, name="opcua", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout_s):
            raise RuntimeError("OPC UA server did not start in time")
        if self.error is not None:
            raise RuntimeError(f"OPC UA server could not start: {self.error}")
        if self._pipeline is not None:  # what the desk knew before the loop ran
            self._post("link_state", (self._pipeline.link_state,))
            self._post("identity", (self._pipeline.robot_id(),))
            for a in self._pipeline.monitor.listed():  # standing alarms: conditions now
                self._post("alarm_state", (a,))

    def stop(self) -> None:
        for kind, fn in self._listeners:
            if self._pipeline is not None:
                self._pipeline.unlisten(kind, fn)
        self._listeners.clear()
        loop = self._loop
        if loop is not None and self._stop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(self._stop.set)
        if self._thread is not None:
            self._thread.join(10.0)

    def _run(self) -> None:
        self.native_id = threading.get_native_id()  # for a bench's per-thread CPU time
        try:
            asyncio.run(self._main())
        except Exception as e:  # noqa: BLE001 - said to start() and in the log
            log.exception("OPC UA server failed")
            self.error = f"{type(e).__name__}: {e}"
            self._ready.set()

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._q, self._stop = asyncio.Queue(), asyncio.Event()
        server = Server(user_manager=self._user_mgr)
        # ConditionRefresh / ConditionRefresh2 with RefreshStart and RefreshEnd events
        server.iserver.bind_condition_methods = True
        await server.init()
        if self.cache_browsing:  # a condition made while serving: 70 % less CPU
            browse_cache.install(server)
        self._server = server
        server.set_server_name("Station Patrol desk")
        await server.set_application_uri("urn:station-patrol:desk")
        server.set_endpoint(self.settings.endpoint)
        tokens = [ua.UserNameIdentityToken]
        if self.settings.allow_anonymous:
            tokens.append(ua.AnonymousIdentityToken)
        server.set_identity_tokens(tokens)
        await setup_security(server, self.settings, self.pki_dir, _Ruleset())
        event_filter.install(server)  # OfType(LimitAlarmType) matches our alarms' events
        self.space = DeskSpace(server)
        await self.space.build()
        await self._add_methods()
        self.conditions = ConditionEvents(self.space)
        self.alarm_methods = AlarmMethods(self, caller=_caller.get)
        await self.conditions.build(self.space.root, self.alarm_methods.acknowledge,
                                    self.alarm_methods.add_comment,
                                    self.alarm_methods.shelving_handlers())
        if self._pipeline is not None:  # every alarm the rules can raise, before serving
            t0 = time.process_time()
            n = await self.conditions.prepare(self._pipeline.monitor.configured())
            log.info("OPC UA: %d alarm conditions made in %.2f s of CPU", n,
                     time.process_time() - t0)
        if self.gc_freeze:
            _freeze_startup_objects()
        async with server:
            self.port = server.bserver._server.sockets[0].getsockname()[1]
            log.info("OPC UA server listening on %s", self.url)
            self._ready.set()
            tasks = [asyncio.create_task(self._consume()), asyncio.create_task(self._ticker()),
                     asyncio.create_task(self._flusher()),
                     asyncio.create_task(self.stalls.run())]
            await self._stop.wait()
            for t in tasks:
                t.cancel()

    # ------------------------------------------------------------ feeding the nodes
    async def _consume(self, slice_s: float = 0.005) -> None:
        """Serve the desk's messages in order. A queue that is not empty is read without
        the loop running anything else (asyncio's Queue.get does not suspend then, nor
        do asyncua's writes), so a burst — a flood of alarms, the standing alarms at
        start, a backlog after the machine did not run the thread — is served in slices
        of ``slice_s``, the loop serving its clients between them."""
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
        sp = self.space
        assert sp is not None
        if kind == "values":
            values = args[0]
            self.fresh.note("telemetry", mono_s=mono, utc_s=t)
            self._quality()
            for key, v in values.items():
                if f"Environment.{key}" in sp.items:
                    sp.set(f"Environment.{key}", v, t)
            sp.set("Robot.BatteryPercent", battery_percent(values["battery_v"]), t)
        elif kind == "mode":
            sp.set("Robot.Mode", mode_name(args[0]), t)
            sp.set("Robot.ModeCode", int(args[0]), t)
        elif kind == "link_state":
            self.fresh.set_link_up(args[0] == "connected", mono)
            if args[0] != "connected":  # the robot tells the lease anew on connecting
                self.lease_mine = False
            sp.set("Robot.LinkState", str(args[0]), t)
            self._quality()
        elif kind == "identity":
            sp.set("Robot.Identity", str(args[0]), t)
        elif kind == "pose":
            p = args[0]
            self.fresh.note("pose", mono_s=mono, utc_s=t)
            for name, v in (("X", p.x_m), ("Y", p.y_m), ("Theta", p.theta_rad)):
                sp.set(f"Robot.Pose.{name}", v, t)
        elif kind == "patrol_status":
            st = args[0]
            self.fresh.note("patrol", mono_s=mono, utc_s=t)
            for name, v in (("State", str(st.state)), ("Route", str(st.route)),
                            ("Index", int(st.index)), ("Progress", float(st.progress)),
                            ("Reason", str(st.reason))):
                sp.set(f"Robot.Patrol.{name}", v, t)
        elif kind == "control":
            c = args[0]
            self.lease_mine = bool(getattr(c, "mine", False))
            self.fresh.note("control", mono_s=mono, utc_s=t)
            sp.set("Robot.LeaseHolder", str(getattr(c, "holder", None) or ""), t)
            sp.set("Robot.DeskHoldsLease", self.lease_mine, t)
        elif kind == "meter_record":
            await sp.meter(args[0])
        elif kind == "alarm" and self.conditions is not None:
            await self.conditions.transition(args[0])
        elif kind == "alarm_state" and self.conditions is not None:
            a = args[0]
            await self.conditions.publish(a, a.raised_t, a.acked_by, a.reason, a.text)

    def _quality(self) -> None:
        assert self.space is not None
        now = time.monotonic()
        for g in _GROUPS:
            self.space.set_quality(g, self.quality[self.fresh.freshness(g, now).age.value])

    async def _ticker(self) -> None:
        while True:
            await asyncio.sleep(self.tick_s)
            self._quality()
            try:
                if self.alarm_methods is not None:
                    self.alarm_methods.end_one_shots()
            except Exception:  # noqa: BLE001 - the quality must go on being judged
                log.exception("OPC UA: one-shot shelving not checked")

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
        assert self.space is not None
        while True:
            await asyncio.sleep(self.flush_period_s())
            try:
                await self.space.flush()
            except Exception:  # noqa: BLE001 - the next flush tries again
                log.exception("OPC UA: values not written")

    @property
    def max_stall_s(self) -> float:
        """The longest the loop was late waking up (an event-loop stall) so far."""
        return self.stalls.max_stall_s

    def probe_callbacks(self, on: bool = True) -> CallbackProbe | None:
        """Time every callback of the server's loop (wall and thread CPU; a bench's
        diagnosis, not for a desk in service); returns the probe."""
        assert self._loop is not None, "the server is not running"

        def switch() -> CallbackProbe | None:
            if on and self.probe is None:
                self.probe = CallbackProbe().install()
            elif not on and self.probe is not None:
                self.probe.uninstall()
                self.probe = None
            return self.probe
        return asyncio.run_coroutine_threadsafe(_call(switch), self._loop).result(10)

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
        user = _caller.get()
        name, role = getattr(user, "name", None), getattr(user, "desk_role", None)
        if role not in METHOD_ROLES[command]:
            return self._refuse(command, name, f"role {role or 'none'} may not",
                                ua.StatusCodes.BadUserAccessDenied)
        if not self.lease_mine:
            return self._refuse(command, name, "the desk does not hold the control lease",
                                ua.StatusCodes.BadInvalidState)
        gateway = self._pipeline.gateway
        who = f"opcua:{name}"
        if command == "estop":
            def fn() -> Any:
                return gateway.estop(user=who)
        else:
            def fn() -> Any:
                return gateway.send(command, {}, user=who)
        try:
            entry = await self._on_desk(fn)
        except TimeoutError:
            return self._refuse(command, name, "the desk did not take the call",
                                ua.StatusCodes.BadTimeout)
        log.info("OPC UA: %s by %s: %s %s", command, name, entry.outcome, entry.why)
        if entry.outcome != "sent":
            return ua.StatusCode(ua.StatusCodes.BadNoCommunication
                                 if entry.outcome == "not delivered"
                                 else ua.StatusCodes.BadInvalidState)
        return [ua.Variant(f"sent (seq {entry.seq})", ua.VariantType.String)]

    async def _on_desk(self, fn: Any, timeout_s: float = 5.0) -> Any:
        """Run ``fn`` on the desk's thread (its next drain) and return its result."""
        fut: concurrent.futures.Future = concurrent.futures.Future()
        self.desk_calls.put((fn, fut))
        return await asyncio.wait_for(asyncio.wrap_future(fut), timeout_s)

    def _refuse(self, command: str, name: str | None, why: str, code: int) -> ua.StatusCode:
        self.refused_calls += 1
        log.warning("OPC UA: %s by %s refused: %s", command, name, why)
        return ua.StatusCode(code)

