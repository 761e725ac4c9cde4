"""Desk commands at the relay: authenticate, refuse, carry out.

Every command frame is rate-limited per desk, checked by the station key's
:class:`app.comm.auth.CommandGuard` (unsigned, malformed, forged, stale and
replayed commands are refused) and, unless it is a safety command (stop,
e-stop) or a lease command, needs the control lease (:mod:`.lease`). Every
refusal is counted by reason in ``rejections`` and reported to the desks as a
``command_rejected`` (or ``connection_rejected``) event, at most once a second
per reason. Accepted commands are carried out by :meth:`handle_command`;
patrol commands go on to :mod:`.missions`.
"""

from __future__ import annotations

import math
import time

from app.comm.protocol import Command, CommandAck, DecoderStats, Frame, MsgType

from ..mcu_link import Estop
from ..server import Client

MISSION_COMMANDS = ("start_patrol", "pause_patrol", "resume_patrol", "abort_patrol", "goto",
                    "dock", "set_pose", "start_mapping", "stop_mapping", "save_map")
LEASE_COMMANDS = ("request_control", "release_control", "hand_over")
# any signed desk may stop the robot, lease or not
SAFETY_COMMANDS = ("stop", "estop")
REJECT_EVENT_MIN_S = 1.0  # at most one command_rejected event per reason per second
REJECT_TEXT = {
    "unsigned": "the command is not signed with the station key",
    "malformed": "the command's signature block is malformed",
    "bad_mac": "the command's signature does not match the station key",
    "stale": "the command's timestamp is too old or too far from the robot's clock",
    "replay": "the command's counter did not rise (a replayed command)",
    "no_lease": "another desk holds the control lease",
    "rate_limited": "too many commands per second",
}


class CommandHandling:
    """Command frames from the desks: checks, refusals, and the commands themselves."""

    def _reject(self, reason: str, who: str) -> None:
        """Count one refusal; an event per reason at most once a second (the
        1 Hz ``rejections`` summary carries the rest)."""
        now = time.monotonic()
        with self._lock:
            self.rejections[reason] = self.rejections.get(reason, 0) + 1
            counts = dict(self.rejections)
            due = now - self._reject_event_at.get(reason, -1e9) >= REJECT_EVENT_MIN_S
            if due:
                self._reject_event_at[reason] = now
                self._rejections_reported = counts
        if due:
            self.event("warning", "command_rejected" if reason in REJECT_TEXT
                       else "connection_rejected",
                       f"refused from {who}: {REJECT_TEXT.get(reason, reason)}",
                       reason=reason, peer=who, counts=counts)

    def _on_connection_refused(self, addr, why: str) -> None:
        self._reject("conn_limit", f"{addr[0]}:{addr[1]} ({why})")

    def _on_client_decoder(self, c: Client, stats: DecoderStats) -> None:
        if stats.dropped:
            self._check_drops(f"tcp {c.name}", stats.dropped, c.decoder.last_error)
            self._count_drops("frame", stats.as_dict(), self._frame_drops_seen.setdefault(c.id, {}))

    def _on_frame(self, c: Client, fr: Frame) -> None:
        if fr.msg_type == MsgType.HEARTBEAT:
            c.last_heartbeat = (fr.timestamp_us, time.monotonic())
        elif fr.msg_type == MsgType.COMMAND:
            self.counters["commands"] += 1
            ok, reason = self.command_from(c, fr)
            c.send(CommandAck(fr.seq, ok, reason))

    def command_from(self, c: Client, fr: Frame) -> tuple[bool, str]:
        """Check a desk's command frame (signature, freshness, replay, rate, lease)
        and carry it out if it passes."""
        if not c.take_token(self.cfg.command_rate_hz):
            self._reject("rate_limited", c.label)
            return False, f"refused: {REJECT_TEXT['rate_limited']}"
        with self._lock:
            why, auth = self.guard.check(fr)
        if why:
            self._reject(why, c.label)
            return False, f"refused: {REJECT_TEXT[why]}"
        c.desk, c.session = auth["desk"], auth["session"]
        cmd: Command = fr.message
        if cmd.name in LEASE_COMMANDS:
            return self._lease_command(c, cmd)
        if cmd.name not in SAFETY_COMMANDS:
            with self._lock:
                holder = self.lease
                if holder is None:
                    self._set_lease(c, "lease_granted", f"{c.label} took control")
                elif holder is not c:
                    refused = f"view only — {holder.label} has control"
                else:
                    refused = ""
            if holder is not None and holder is not c:
                self._reject("no_lease", c.label)
                return False, refused
        return self.handle_command(cmd, c)

    def handle_command(self, cmd: Command, client: Client | None = None) -> tuple[bool, str]:
        """Carry out one desk command; ``client`` is the desk that sent it (the
        last desk to send a drive command is the driver the failsafe watches)."""
        args = cmd.args if isinstance(cmd.args, dict) else {}
        with self._lock:
            if cmd.name == "drive":
                if self.estop:
                    return False, "estop latched; send reset_estop first"
                try:
                    v = float(args.get("linear_mps", 0.0))
                    w = float(args.get("angular_rps", 0.0))
                except (TypeError, ValueError):
                    return False, "drive needs numeric linear_mps and angular_rps"
                if not (math.isfinite(v) and math.isfinite(w)):
                    return False, "drive needs finite numbers"
                if self.nav.executor.owns_motors:
                    self.nav.executor.pause("operator took over (drive)")
                lim = self.speed_limit
                wmax = self.cfg.robot.max_angular_rps
                self._set_cmd(max(-lim, min(lim, v)), max(-wmax, min(wmax, w)))
                self.drive_deadline = time.monotonic() + self.cfg.drive_valid_s
                self.driver = client
                return True, ""
            if cmd.name == "stop":
                if self.nav.executor.owns_motors:
                    self.nav.executor.pause("operator stop")
                self._set_cmd(0.0, 0.0)
                return True, ""
            if cmd.name == "estop":
                if self.nav.executor.owns_motors:
                    self.nav.executor.pause("estop")
                self._set_cmd(0.0, 0.0)
                first = not self.estop
                self.estop = True
                self._mcu_send(Estop(True))
                if first:
                    self.event("alarm", "estop", "emergency stop engaged by the operator")
                return True, ""
            if cmd.name == "reset_estop":
                was = self.estop
                self.estop = False
                self._mcu_send(Estop(False))
                if was:
                    self.event("info", "estop_reset", "emergency stop released")
                return True, ""
            if cmd.name in ("set_speed_limit", "set_speed"):
                try:
                    v = float(args.get("linear_mps"))
                except (TypeError, ValueError):
                    return False, "set_speed_limit needs linear_mps"
                if not 0.0 <= v <= self.cfg.robot.max_linear_mps:
                    return False, f"speed limit must be 0..{self.cfg.robot.max_linear_mps} m/s"
                self.speed_limit = v
                if abs(self.cmd_v) > v:
                    self._set_cmd(math.copysign(v, self.cmd_v), self.cmd_w)
                return True, ""
            if cmd.name == "look_at":
                if self.camera is None:
                    return False, "this robot streams no video"
                try:
                    self.camera.set_target(args.get("gauge"))
                except ValueError as e:
                    return False, str(e)
                return True, ""
            if cmd.name in MISSION_COMMANDS:
                return self._mission_command(cmd.name, args)
        return False, f"unknown command {cmd.name!r}"

