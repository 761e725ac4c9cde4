"""The control lease, the deadman and the desk failsafes.

One desk (connection) at a time holds the control lease: it may drive and send
mission commands; the others watch, and may stop the robot (:mod:`.commands`).
A desk takes the lease with its first command or ``request_control``, gives it
up with ``release_control`` or ``hand_over``, and loses it when it disconnects
or sends no heartbeat for ``lease_timeout_s``; a patrol then pauses
(``lease_lost_action = "pause"``).

A drive command holds for ``drive_valid_s`` (the deadman, 0.5 s by default,
wall time): the motors stop when it is not renewed in time, when the driving
desk disconnects or is silent for ``client_silence_s``, or when no desk is left.
None of this applies while a mission drives the motors by itself.
"""

from __future__ import annotations

import time

from app.comm.protocol import Command

from ..server import Client


class ControlLease:
    """Who may command the robot, and the watchdogs that stop it when teleop lapses."""

    def lease_info(self) -> dict:
        c = self.lease
        return {"holder": c.desk if c else None, "holder_session": c.session if c else None,
                "holder_client": c.name if c else None,
                "requested_by": self.lease_request.label if self.lease_request else None}

    def _lease_text(self) -> str:
        c = self.lease
        return f"{c.label} has control" if c else "control is free"

    def _set_lease(self, c: Client | None, code: str, text: str) -> None:
        with self._lock:
            old = self.lease
            self.lease = c
            if c is not None and c is self.lease_request:
                self.lease_request = None
            if old is not None and old is not c and self.driver is old:
                # the old holder's teleop ends with its lease (a patrol runs on)
                self.driver = None
                if self._moving() and not self.nav.executor.owns_motors:
                    self._set_cmd(0.0, 0.0)
            info = self.lease_info()
        self.event("info", code, text, **info)
        self.event("info", "lease", self._lease_text(), **info)

    def _holder_lost(self, c: Client, why: str) -> None:
        """The lease holder vanished without releasing control: a running patrol
        pauses and the robot stops (``lease_lost_action = "pause"``), until a desk
        holding control resumes it."""
        if self.cfg.lease_lost_action != "pause":
            return
        with self._lock:
            ex = self.nav.executor
            if not ex.owns_motors:
                return
            ok, _why = ex.pause(f"control lost: {c.label} {why}")
            if ok:
                self._set_cmd(0.0, 0.0)

    def _lease_command(self, c: Client, cmd: Command) -> tuple[bool, str]:
        holder = self.lease
        if cmd.name == "request_control":
            if holder is None or holder is c:
                if holder is None:
                    self._set_lease(c, "lease_granted", f"{c.label} took control")
                return True, ""
            self.lease_request = c
            self.event("info", "control_requested",
                       f"{c.label} asks for control ({holder.label} has it)",
                       by=c.desk, by_client=c.name, **self.lease_info())
            return False, f"view only — {holder.label} has control; asked it to hand over"
        if holder is not c:
            self._reject("no_lease", c.label)
            return False, "only the desk holding control can release or hand it over"
        if cmd.name == "release_control":
            self._set_lease(None, "lease_released", f"{c.label} released control")
            return True, ""
        # hand_over: to a named desk (desk name, session or client address), by
        # default to the desk that last asked
        to = cmd.args.get("to") if isinstance(cmd.args, dict) else None
        target = self.lease_request if to in (None, "") else next(
            (o for o in self.server.clients if o is not c and to in (o.desk, o.session, o.name)),
            None)
        if target is None or target.closed:
            return False, (f"no connected desk {to!r}" if to else
                           "no desk has asked for control")
        self._set_lease(target, "lease_handed_over",
                        f"{c.label} handed control to {target.label}")
        return True, ""

    def _on_disconnect(self, c: Client) -> None:
        n = len(self.server.clients)
        self.event("info", "client_disconnected", f"desk {c.name} disconnected",
                   client=c.name, clients=n)
        self._frame_drops_seen.pop(c.id, None)
        if c is self.driver:
            self.driver = None
            if self._moving():
                self._failsafe_stop("the driving desk disconnected")
        if c is self.lease_request:
            self.lease_request = None
        if c is self.lease:
            self._set_lease(None, "lease_released", f"{c.label} disconnected; control is free")
            self._holder_lost(c, "disconnected")

    def _failsafe_stop(self, why: str) -> None:
        with self._lock:
            self._set_cmd(0.0, 0.0)
        self.event("warning", "failsafe_stop", f"motors stopped: {why}", reason=why)

    def _next_wake(self, t: float) -> float:
        """Wake for the next periodic job, or sooner when a drive command expires,
        so the deadman acts on time rather than on the next telemetry tick."""
        d = self.drive_deadline + 0.002
        if self._moving() and not self.nav.executor.owns_motors and d > time.monotonic():
            return min(t, d)
        return t

    def _check_lease(self, now: float) -> None:
        """The lease lapses when its holder's heartbeats stop."""
        holder = self.lease
        if holder is not None:
            hb = holder.last_heartbeat
            last = hb[1] if hb else holder.connected_at
            if now - last > self.cfg.lease_timeout_s:
                self._set_lease(None, "lease_lapsed",
                                f"{holder.label} sent no heartbeat for "
                                f"{self.cfg.lease_timeout_s:g} s; control is free")
                self._holder_lost(holder, "sent no heartbeat")

    def _check_motion(self, now: float) -> None:
        """The deadman (an expired drive command) and the desk failsafes."""
        with self._lock:
            # a mission drives by itself: the teleop deadman and desk failsafes do not apply
            moving = self._moving() and not self.nav.executor.owns_motors
            expired = moving and now > self.drive_deadline
        if expired:
            with self._lock:
                self._set_cmd(0.0, 0.0)
                late_s = now - self.drive_deadline
            self.event("warning", "deadman_stop",
                       f"drive command not renewed within {self.cfg.drive_valid_s:g} s: "
                       f"motors stopped", valid_s=self.cfg.drive_valid_s,
                       late_s=round(late_s, 4))
        elif moving:
            clients = self.server.clients
            driver = self.driver
            if not clients:
                self._failsafe_stop("no desk connected")
            elif driver is not None and now - driver.last_rx > self.cfg.client_silence_s:
                self._failsafe_stop(f"the driving desk silent for > "
                                    f"{self.cfg.client_silence_s} s")
            elif driver is None and all(now - c.last_rx > self.cfg.client_silence_s
                                        for c in clients):
                self._failsafe_stop(f"every desk silent for > {self.cfg.client_silence_s} s")
