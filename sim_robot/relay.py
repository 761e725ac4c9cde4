"""The Raspberry Pi's role: bridge the MCU's serial link and the desks' TCP link.

Reads MCU frames (pyserial), keeps the robot's own odometry, and streams
telemetry, pose, lidar scans, camera frames, heartbeats and events to every
connected desk; turns desk commands into MCU motor / e-stop frames. Desk-side
timing (heartbeats, drive validity, client silence) is wall time.

Trust (docs/security.md): every command must be signed with the station key
(:class:`app.comm.auth.CommandGuard` refuses unsigned, forged, replayed and
stale ones); one desk holds the control lease and the others may watch and
stop the robot but not drive it; a drive command holds for ``drive_valid_s``
(the deadman); the lease lapses when its holder's heartbeats stop. Every
refusal is counted by reason and reported to the desks as events.
"""

from __future__ import annotations

import json
import logging
import math
import pathlib
import select
import threading
import time
from collections.abc import Callable

import numpy as np

from app.comm.auth import REJECT_REASONS, CommandGuard, load_or_create_key
from app.comm.protocol import (
    AlarmFlag,
    Command,
    CommandAck,
    DecoderStats,
    Event,
    Frame,
    Heartbeat,
    MsgType,
    Obstacles,
    Path,
    Pose,
    RobotMode,
    Telemetry,
    VideoFrame,
    now_us,
)

from .camera import Camera
from .config import SimConfig
from .lidar import Lidar
from .mcu_link import (
    Ack,
    ConfigLimits,
    Estop,
    Keepalive,
    McuDecoder,
    McuEncoder,
    McuType,
    MotorCmd,
    SensorReport,
)
from .navigation import Navigation, map_image
from .odometry import Odometry
from .route import DEFAULT_ROUTE, Route, RoutePoint, load_route, parse_route
from .server import Client, TcpServer
from .world import World

log = logging.getLogger(__name__)

CONFIG_PERIOD_S = 5.0
MCU_SILENT_S = 1.0
DROP_EVENT_MIN_S = 2.0
STATS_LOG_S = 60.0
NAV_STATUS_S = 0.5  # PatrolStatus at 2 Hz (and on every change), wall time
NAV_OBSTACLES_S = 0.2  # Obstacles at 5 Hz
NAV_LOCAL_S = 0.2  # the LOCAL path at 5 Hz while a mission drives


MISSION_COMMANDS = ("start_patrol", "pause_patrol", "resume_patrol", "abort_patrol", "goto",
                    "dock")
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


class Relay:
    def __init__(self, cfg: SimConfig, open_port: Callable[[], object], world: World,
                 camera_pose: Callable[[], tuple[float, float, float]],
                 sim_time: Callable[[], float] = lambda: 0.0) -> None:
        self.cfg = cfg
        self.open_port = open_port
        self.port = None
        self.world = world
        self.camera_pose = camera_pose
        self.sim_time = sim_time
        rng = np.random.default_rng(cfg.seed + 2000)
        self.lidar = Lidar(world, rng, cfg.lidar_beams, cfg.lidar_range_m)
        self.camera = Camera(world, cfg.camera_width, cfg.camera_height, cfg.camera_hfov_deg,
                             cfg.jpeg_quality) if cfg.video else None
        r = cfg.robot
        p0 = world.pose  # where the robot stands when it is switched on
        self.odom = Odometry(r.ticks_per_rev / (2 * math.pi * r.wheel_radius_m), r.track_m,
                             p0.x, p0.y, p0.theta)
        key, created = load_or_create_key(cfg.key_file)
        self.guard = CommandGuard(key, cfg.auth_max_skew_s)
        log.info("station key %s%s (fingerprint %s)", cfg.key_file or "default",
                 " created" if created else "", self.guard.fingerprint)
        self.server = TcpServer(cfg.host, cfg.port, self._on_frame, self._on_connect,
                                self._on_disconnect, self._on_client_decoder,
                                cfg.client_queue_bytes, cfg.client_max_backlog_bytes,
                                cfg.max_clients, cfg.max_clients_per_host,
                                self._on_connection_refused)
        # every refusal by reason: commands (REJECT_TEXT), connections, and frames the
        # decoders dropped ("frame:<reason>" from desks, "mcu:<reason>" from the MCU)
        self.rejections: dict[str, int] = {r: 0 for r in (*REJECT_REASONS, "no_lease",
                                                          "rate_limited", "conn_limit")}
        self._reject_event_at: dict[str, float] = {}
        self._rejections_reported: dict[str, int] = {}
        self._frame_drops_seen: dict[int, dict[str, int]] = {}
        self._mcu_drops_seen: dict[str, int] = {}
        # the control lease: the desk (connection) allowed to drive and command
        self.lease: Client | None = None
        self.lease_request: Client | None = None  # the last desk that asked for it
        self.mcu_decoder = McuDecoder()
        self.mcu_encoder = McuEncoder()
        self._tx_lock = threading.Lock()
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        # commanded state
        self.cmd_v = 0.0
        self.cmd_w = 0.0
        self.drive_deadline = 0.0
        self.driver: Client | None = None  # the desk whose drive command is in force
        self.speed_limit = cfg.speed_limit_mps
        self.estop = False
        # MCU state
        self.report: SensorReport | None = None
        self.report_mono = 0.0
        self.mcu_reports = 0
        self.mcu_silent = True
        self.last_flags = 0
        self.mcu_acks = {"ok": 0, "rejected": 0}
        self.serial_errors = 0
        self._drops_reported: dict[str, int] = {}  # per link
        self._last_drop_event: dict[str, float] = {}
        self.counters = {"telemetry": 0, "pose": 0, "scan": 0, "video": 0, "heartbeat": 0,
                         "commands": 0, "nav_steps": 0}
        # navigation: localisation stand-in, lidar obstacle tracking, mission executor.
        # With a real board (--serial) the sim's pose does not move: publish odometry.
        self.nav = Navigation(world, cfg.seed, self.event, self._nav_publish, self._look_at,
                              lidar_beams=cfg.lidar_beams, lidar_range_m=cfg.lidar_range_m)
        self.localise = cfg.serial_device is None
        self.map_msg = map_image(self.nav.grid)
        self.nav_ready = threading.Event()
        world.on_collision = self._on_collision

    # ------------------------------------------------------------------ lifecycle

    @property
    def address(self) -> tuple[str, int]:
        return self.server.address

    def prepare(self) -> None:
        """Load (on a first run: compile) the navigation kernels, once.

        Done before the MCU link and the desk server start: compiling takes tens of
        seconds of CPU on a first run, and done while serving it starved the
        threads that keep the MCU's 0.5 s link watchdog fed (a fail-safe stop a
        few seconds into every fresh start) and left a patrol planning meanwhile.
        """
        if self.nav_ready.is_set():
            return
        log.info("preparing navigation (a first run compiles the planner: up to a minute)")
        t0 = time.monotonic()
        try:
            self.nav.warm_up()
        except Exception:  # noqa: BLE001 - a mission will report its own failure
            log.exception("navigation warm-up failed")
        log.info("navigation ready after %.1f s", time.monotonic() - t0)
        self.nav_ready.set()

    def start(self) -> None:
        self.prepare()
        self._open_serial()
        self.server.start()
        for name, fn in (("relay-serial", self._serial_loop), ("relay-control", self._control),
                         ("relay-nav", self._nav_loop), ("relay-video", self._video)):
            if name == "relay-video" and self.camera is None:
                continue
            t = threading.Thread(target=fn, name=name, daemon=True)
            t.start()
            self._threads.append(t)

    def close(self) -> None:
        self._stop.set()
        try:
            self._mcu_send(MotorCmd(0.0, 0.0))
        except Exception:  # noqa: BLE001 - best effort on the way out
            pass
        self.server.close()
        for t in self._threads:
            t.join(timeout=2)
        if self.port is not None:
            try:
                self.port.close()
            except Exception:  # noqa: BLE001
                pass

    # ------------------------------------------------------------------ events

    def event(self, level: str, code: str, text: str, **data) -> None:
        log.log(logging.WARNING if level != "info" else logging.INFO, "%s: %s", code, text)
        self.server.broadcast(Event(level, code, text, data))

    # ------------------------------------------------------------------ serial side

    def _open_serial(self) -> bool:
        try:
            self.port = self.open_port()
            return True
        except Exception as e:  # noqa: BLE001 - serial.SerialException, OSError
            self.port = None
            self.serial_errors += 1
            self.event("alarm", "serial_error", f"cannot open the MCU serial port: {e}")
            return False

    def _serial_failed(self, e: Exception) -> None:
        self.serial_errors += 1
        self.event("alarm", "serial_error", f"MCU serial link failed: {e}")
        try:
            self.port.close()
        except Exception:  # noqa: BLE001
            pass
        self.port = None

    def _mcu_send(self, msg) -> None:
        port = self.port
        if port is None:
            return
        with self._tx_lock:
            data = self.mcu_encoder.encode(msg)
            try:
                port.write(data)
            except Exception as e:  # noqa: BLE001
                self._serial_failed(e)

    def _serial_loop(self) -> None:
        while not self._stop.is_set():
            port = self.port
            if port is None:
                if self._stop.wait(1.0):
                    return
                if self._open_serial():
                    self.event("info", "serial_restored", "MCU serial port reopened")
                continue
            try:
                ready, _, _ = select.select([port.fileno()], [], [], 0.1)
                data = port.read(4096) if ready else b""
            except Exception as e:  # noqa: BLE001
                if not self._stop.is_set():
                    self._serial_failed(e)
                continue
            if not data:
                continue
            for fr in self.mcu_decoder.feed(data):
                if fr.msg_type == McuType.SENSOR_REPORT:
                    self._on_report(fr.message)
                elif fr.msg_type == McuType.ACK:
                    a: Ack = fr.message
                    self.mcu_acks["ok" if a.status == 0 else "rejected"] += 1
            self._check_drops("mcu_serial", self.mcu_decoder.stats.dropped,
                              self.mcu_decoder.last_error)
            self._count_drops("mcu", self.mcu_decoder.stats.as_dict(), self._mcu_drops_seen)

    def _check_drops(self, link: str, dropped: int, why: str) -> None:
        now = time.monotonic()
        before = self._drops_reported.get(link, 0)
        if dropped > before and now - self._last_drop_event.get(link, -1e9) > DROP_EVENT_MIN_S:
            self.event("warning", "decoder_drop", f"{link}: dropped frames ({why})",
                       link=link, dropped=dropped, new=dropped - before)
            self._drops_reported[link] = dropped
            self._last_drop_event[link] = now

    def _count_drops(self, prefix: str, stats: dict[str, int], seen: dict[str, int]) -> None:
        for k, v in stats.items():
            if k in ("frames", "bytes_in", "dropped", "garbage_bytes") or not v:
                continue
            new = v - seen.get(k, 0)
            if new > 0:
                with self._lock:
                    key = f"{prefix}:{k}"
                    self.rejections[key] = self.rejections.get(key, 0) + new
                seen[k] = v

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

    def _on_report(self, rep: SensorReport) -> None:
        with self._lock:
            self.report = rep
            self.report_mono = time.monotonic()
            self.mcu_reports += 1
            self.odom.update(rep.mcu_time_ms, rep.enc_left_ticks, rep.enc_right_ticks,
                             rep.yaw_rate_rps, rep.imu_yaw_rad)
            changed = rep.alarm_flags ^ self.last_flags
            self.last_flags = rep.alarm_flags
        if self.mcu_silent:
            self.mcu_silent = False
            self.event("info", "mcu_link_up", "MCU sensor reports are arriving")
        for flag in AlarmFlag:
            if changed & flag:
                active = bool(rep.alarm_flags & flag)
                self.event("alarm" if active else "info", "mcu_alarm",
                           f"MCU {flag.name} {'raised' if active else 'cleared'}",
                           flag=flag.name, active=active)

    # ------------------------------------------------------------------ desk side

    def _on_connect(self, c: Client) -> None:
        self.event("info", "client_connected", f"desk {c.name} connected", client=c.name,
                   clients=len(self.server.clients))
        c.send(Heartbeat(Heartbeat.ROLE_ROBOT, 0, 0, 0))
        c.send(Event("info", "lease", self._lease_text(), self.lease_info()))
        c.send(self.map_msg)
        with self._lock:
            ex = self.nav.executor
            c.send(ex.status())
            if ex.running and len(ex.planner.path):
                c.send(Path(Path.GLOBAL, ex.planner.path.astype("float32")))

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

    # ------------------------------------------------------------------ trust

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

    # ------------------------------------------------------------------ missions

    def _mission_command(self, name: str, args: dict) -> tuple[bool, str]:
        """start_patrol / pause_patrol / resume_patrol / abort_patrol / goto / dock
        (called with the lock held)."""
        ex = self.nav.executor
        if name in ("start_patrol", "resume_patrol", "goto", "dock") and self.estop:
            return False, "estop latched; send reset_estop first"
        if not self.localise and name in ("start_patrol", "goto", "dock"):
            return False, "no localisation with a real MCU board (--serial)"
        if name == "start_patrol":
            try:
                route = self._route_from(args.get("route"))
            except ValueError as e:
                return False, str(e)
            ok, why = ex.start(route, self.sim_time())
        elif name == "pause_patrol":
            ok, why = ex.pause("operator")
            self._set_cmd(0.0, 0.0)
        elif name == "resume_patrol":
            ok, why = ex.resume()
        elif name == "abort_patrol":
            ok, why = ex.abort("operator")
            self._set_cmd(0.0, 0.0)
        elif name == "dock":
            ok, why = ex.dock_now()
        else:  # goto
            try:
                x, y, label = self._goto_target(args)
            except ValueError as e:
                return False, str(e)
            ok, why = ex.goto(x, y, label)
        return ok, why

    def _route_from(self, obj) -> Route:
        gauges = {g.id for g in self.world.gauges}
        if obj is None or obj == {}:
            route = load_route(DEFAULT_ROUTE, gauges, self.world.size_m)
        else:
            route = parse_route(obj, gauges, self.world.size_m)
        self.nav.executor.check_route(route)
        return route

    def _goto_target(self, args: dict) -> tuple[float, float, str]:
        if args.get("point") is not None:
            name = str(args["point"])
            pts: list[RoutePoint] = []
            m = self.nav.executor.mission
            if m is not None:
                pts += [RoutePoint(p["name"], p["kind"], p["x_m"], p["y_m"]) for p in m.points]
            try:
                pts += load_route(DEFAULT_ROUTE).points
            except ValueError:
                pass
            for p in pts:
                if p.name == name:
                    return p.x_m, p.y_m, name
            if any(g.id == name for g in self.world.gauges):
                x, y, _ = self.world.pose_facing_gauge(name)
                return x, y, name
            raise ValueError(f"no route point or gauge named {name!r}")
        try:
            x, y = float(args["x_m"]), float(args["y_m"])
        except (KeyError, TypeError, ValueError):
            raise ValueError("goto needs numeric x_m and y_m, or a point name") from None
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError("goto needs finite x_m and y_m")
        return x, y, str(args.get("name") or f"({x:.1f}, {y:.1f})")

    def _auto_patrol(self, which: str) -> None:
        """``--patrol``: start a route as soon as navigation is ready."""
        try:
            obj = {} if which == "default" else json.loads(
                pathlib.Path(which).read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            log.error("--patrol %s: %s", which, e)
            return
        with self._lock:
            ok, why = self._mission_command("start_patrol", {"route": obj})
        if not ok:
            log.error("--patrol %s: %s", which, why)

    def _nav_publish(self, msg) -> None:
        self.server.broadcast(msg)

    def _look_at(self, gauge: str | None) -> None:
        if self.camera is not None:
            try:
                self.camera.set_target(gauge)
            except ValueError as e:
                log.warning("camera: %s", e)

    def _on_collision(self, rec: dict) -> None:
        self.event("alarm", "collision", f"the robot touched {rec['what']} at "
                   f"({rec['x_m']:.2f}, {rec['y_m']:.2f})", **rec)

    def _nav_loop(self) -> None:
        """Localisation, perception and the mission executor, one step per
        control period of sim time (``control_dt_s``), paced in wall time: at a
        time scale X the loop runs X times as often (5 ms at 20x)."""
        nav = self.nav
        if self.cfg.patrol:
            self._auto_patrol(self.cfg.patrol)
        dt_sim = nav.executor.cfg.control_dt_s
        period = min(0.1, max(0.004, dt_sim / self.cfg.time_scale))
        t_prev = self.sim_time()
        nxt = time.monotonic()
        due = {"status": nxt, "obstacles": nxt, "local": nxt}
        version = -1
        idle_scan_s = 0.2  # sim time between scans while no mission drives (tracks stay alive)
        while not self._stop.wait(max(0.0, nxt - time.monotonic())):
            now = time.monotonic()
            nxt = max(nxt + period, now)
            t = self.sim_time()
            dt = min(max(t - t_prev, 1e-3), 0.5)
            t_prev = t
            ex = nav.executor
            with self._lock:
                if self.localise:
                    odom = (self.odom.x, self.odom.y, self.odom.theta)
                    v, w, send = nav.step(t, dt, odom)
                    if send and not self.estop:
                        self._set_cmd(v, w)
                self.counters["nav_steps"] += 1
                driving = ex.owns_motors
                changed = ex.version != version
                version = ex.version
                status = ex.status() if changed or now >= due["status"] else None
            if not self.server.clients:
                continue
            if not driving and self.localise and (nav.scan_t is None
                                                  or t - nav.scan_t >= idle_scan_s):
                with self._lock:
                    nav.perceive(t)
            if status is not None:
                due["status"] = now + NAV_STATUS_S
                self.server.broadcast(status)
            if now >= due["obstacles"]:
                due["obstacles"] = now + NAV_OBSTACLES_S
                with self._lock:
                    rows = nav.obstacles.astype("float32")
                self.server.broadcast(Obstacles(rows))
            if driving and now >= due["local"]:
                due["local"] = now + NAV_LOCAL_S
                with self._lock:
                    traj = ex.local_trajectory(nav.localiser.pose)
                self.server.broadcast(Path(Path.LOCAL, traj))

    def _set_cmd(self, v: float, w: float) -> None:
        changed = (v, w) != (self.cmd_v, self.cmd_w)
        self.cmd_v, self.cmd_w = v, w
        if changed:
            self._mcu_send(MotorCmd(v, w))

    def _moving(self) -> bool:
        return bool(self.cmd_v or self.cmd_w)

    def _failsafe_stop(self, why: str) -> None:
        with self._lock:
            self._set_cmd(0.0, 0.0)
        self.event("warning", "failsafe_stop", f"motors stopped: {why}", reason=why)

    # ------------------------------------------------------------------ periodic work

    def _control(self) -> None:
        cfg = self.cfg
        t = time.monotonic()
        nxt = {"keepalive": t, "config": t, "telemetry": t, "pose": t, "scan": t,
               "heartbeat": t, "log_stats": t + STATS_LOG_S}
        period = {"keepalive": cfg.keepalive_s, "config": CONFIG_PERIOD_S,
                  "telemetry": 1 / cfg.telemetry_hz, "pose": 1 / cfg.pose_hz,
                  "scan": 1 / cfg.scan_hz, "heartbeat": 1 / cfg.heartbeat_hz,
                  "log_stats": STATS_LOG_S}
        while not self._stop.wait(max(0.0, self._next_wake(min(nxt.values()))
                                      - time.monotonic())):
            now = time.monotonic()
            due = [k for k, v in nxt.items() if v <= now]
            for k in due:
                nxt[k] = max(nxt[k] + period[k], now)  # never burst to catch up
                getattr(self, "_tick_" + k)()
            self._watchdogs(now)

    def _next_wake(self, t: float) -> float:
        """Wake for the next periodic job, or sooner when a drive command expires,
        so the deadman acts on time rather than on the next telemetry tick."""
        d = self.drive_deadline + 0.002
        if self._moving() and not self.nav.executor.owns_motors and d > time.monotonic():
            return min(t, d)
        return t

    def _watchdogs(self, now: float) -> None:
        holder = self.lease
        if holder is not None:
            hb = holder.last_heartbeat
            last = hb[1] if hb else holder.connected_at
            if now - last > self.cfg.lease_timeout_s:
                self._set_lease(None, "lease_lapsed",
                                f"{holder.label} sent no heartbeat for "
                                f"{self.cfg.lease_timeout_s:g} s; control is free")
                self._holder_lost(holder, "sent no heartbeat")
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
        if not self.mcu_silent and now - self.report_mono > MCU_SILENT_S:
            self.mcu_silent = True
            self.event("alarm", "mcu_link_lost", "no MCU sensor report for 1 s")

    def _tick_keepalive(self) -> None:
        with self._lock:
            if self.estop:
                msg = Estop(True)
            elif self._moving():
                msg = MotorCmd(self.cmd_v, self.cmd_w)
            else:
                msg = Keepalive()
        self._mcu_send(msg)

    def _tick_config(self) -> None:
        lim = self.cfg.limits
        self._mcu_send(ConfigLimits(lim.gas_lel_pct, lim.temp_c, lim.humidity_pct,
                                    lim.obstacle_m, lim.battery_low_v))

    def _tick_telemetry(self) -> None:
        with self._lock:
            r = self.report
            if r is None or self.mcu_silent:
                return
            mode = RobotMode.ESTOP if self.estop else r.mode
            if not self.estop and self.nav.executor.owns_motors:
                mode = RobotMode.PATROL
        self.counters["telemetry"] += 1
        self.server.broadcast(Telemetry(
            r.mcu_time_ms, r.gas_lel_pct, r.temp_c, r.humidity_pct, r.obstacle_left_m,
            r.obstacle_front_m, r.obstacle_right_m, r.battery_v, r.wheel_left_mps,
            r.wheel_right_mps, r.yaw_rate_rps, r.cmd_linear_mps, r.cmd_angular_rps,
            r.alarm_flags, int(mode), self.counters["telemetry"]))

    def _tick_pose(self) -> None:
        with self._lock:
            o = self.odom
            if self.localise and self.nav.localiser.fixes:
                x, y, th = self.nav.localiser.pose  # map-based (stand-in), does not drift
                p = Pose(x, y, th, o.v, o.omega)
            else:
                p = Pose(o.x, o.y, o.theta, o.v, o.omega)
        self.server.broadcast(p)
        self.counters["pose"] += 1

    def _tick_scan(self) -> None:
        if not self.server.clients:
            return
        self.server.broadcast(self.lidar.scan(*self.camera_pose()))
        self.counters["scan"] += 1

    def _tick_heartbeat(self) -> None:
        now_m = time.monotonic()
        for c in self.server.clients:
            hb = c.last_heartbeat
            echo_ts, hold = (hb[0], int((now_m - hb[1]) * 1e6)) if hb else (0, 0)
            c.send(Heartbeat(Heartbeat.ROLE_ROBOT, echo_ts, hold, c.rx_frames))
        self.counters["heartbeat"] += 1
        with self._lock:
            counts = dict(self.rejections)
            # the table starts with every reason at 0: only a refusal is news
            changed = (any(counts.values())
                       and {k: v for k, v in counts.items() if v}
                       != {k: v for k, v in self._rejections_reported.items() if v})
            self._rejections_reported = counts
        if changed:
            self.event("warning", "rejections", "refusals so far: " + ", ".join(
                f"{k} {v}" for k, v in counts.items() if v), counts=counts)

    def _video(self) -> None:
        period = 1.0 / self.cfg.fps
        nxt = time.monotonic()
        while not self._stop.wait(max(0.0, nxt - time.monotonic())):
            nxt = max(nxt + period, time.monotonic())
            if not self.server.clients:
                continue
            x, y, th = self.camera_pose()
            ts = now_us()
            fid, jpeg = self.camera.capture_jpeg(x, y, th, self.sim_time())
            self.server.broadcast(VideoFrame(fid, ts, self.camera.w, self.camera.h, 0.0, jpeg),
                                  is_video=True)
            self.counters["video"] += 1

    def _tick_log_stats(self) -> None:
        log.info("stats: %s", self.stats())

    def stats(self) -> dict:
        clients = self.server.clients
        return {"sim_s": round(self.sim_time(), 1), "counters": dict(self.counters),
                "mcu_decoder": self.mcu_decoder.stats.as_dict(),
                "mcu_reports": self.mcu_reports, "mcu_acks": dict(self.mcu_acks),
                "serial_errors": self.serial_errors, "clients": len(clients),
                "tcp_dropped": {c.name: c.decoder.stats.dropped for c in clients},
                "rejections": dict(self.rejections), "auth_accepted": self.guard.accepted,
                "lease": self.lease_info(),
                "sent": {c.name: c.sent_frames for c in clients},
                "video_dropped": {c.name: c.video_dropped for c in clients},
                "camera_ms": round(self.camera.last_ms, 2) if self.camera else None,
                "patrol": self.nav.executor.state, "collisions": len(self.world.collisions)}
