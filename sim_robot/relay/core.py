"""The Raspberry Pi's role: bridge the MCU's serial link and the desks' TCP link.

:class:`Relay` holds the robot's shared state (commanded speeds, e-stop, the
lease, the MCU's last report, counters) under one lock and assembles the parts
of the job, one module each:

- :mod:`.serial_bridge` — the MCU side: serial port, frames in and out, keep-alive
- :mod:`.commands`      — desk commands: authentication, refusals, carrying them out
- :mod:`.lease`         — the control lease, the deadman and the desk failsafes
- :mod:`.missions`      — patrol / goto / dock commands and route checks
- :mod:`.nav_thread`    — localisation, perception and the mission executor thread
- :mod:`.publishers`    — periodic telemetry, pose, scans, heartbeats to the desks
- :mod:`.video`         — the camera stream

Desk-side timing (heartbeats, drive validity, client silence) is wall time.

Trust (docs/security.md): every command must be signed with the station key
(:class:`app.comm.auth.CommandGuard` refuses unsigned, forged, replayed and
stale ones); one desk holds the control lease and the others may watch and
stop the robot but not drive it; a drive command holds for ``drive_valid_s``
(the deadman); the lease lapses when its holder's heartbeats stop. Every
refusal is counted by reason and reported to the desks as events.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path

import numpy as np

from app.comm.auth import REJECT_REASONS, CommandGuard, config_dir, load_or_create_key
from app.comm.protocol import Event

from ..camera import Camera
from ..config import SimConfig
from ..lidar import Lidar
from ..mapping_mode import MappingMode
from ..mcu_link import McuDecoder, McuEncoder, MotorCmd, SensorReport
from ..navigation import Navigation, map_image
from ..odometry import Odometry
from ..server import Client, TcpServer
from ..world import World
from .commands import CommandHandling
from .lease import ControlLease
from .missions import Missions
from .nav_thread import NavigationThread
from .publishers import Publishers
from .serial_bridge import SerialBridge
from .video import VideoStream

log = logging.getLogger(__name__)


class Relay(SerialBridge, CommandHandling, ControlLease, Missions, NavigationThread,
            Publishers, VideoStream):
    """The robot's relay. Each base class is one part of the job (its module says
    which); they share the state set up here, which ``_lock`` guards.

    ``open_port`` opens the MCU's serial port (the MCU model's socket or pty, or a real
    board); ``camera_pose`` gives the camera's pose in the world; ``sim_time`` is
    the sim clock (routes and the executor run on it).
    """

    def __init__(self, cfg: SimConfig, open_port: Callable[[], object], world: World,
                 camera_pose: Callable[[], tuple[float, float, float]],
                 sim_time: Callable[[], float] = lambda: 0.0) -> None:
        self.world = world
        self.camera_pose = camera_pose
        rng = np.random.default_rng(cfg.seed + 2000)
        self.lidar = Lidar(world, rng, cfg.lidar_beams, cfg.lidar_range_m)
        self.camera = Camera(world, cfg.camera_width, cfg.camera_height, cfg.camera_hfov_deg,
                             cfg.jpeg_quality) if cfg.video else None
        r = cfg.robot
        p0 = world.pose  # where the robot stands when it is switched on
        self.odom = Odometry(r.ticks_per_rev / (2 * math.pi * r.wheel_radius_m), r.track_m,
                             p0.x, p0.y, p0.theta)
        self._init_link(cfg, open_port, sim_time, cfg.speed_limit_mps)
        self.odom_trail: deque[tuple[float, float, float, float]] = deque(maxlen=400)
        # navigation: map localisation on the lidar and the odometry, lidar obstacle
        # tracking, mission executor. No ground truth is read, so a real board
        # (--serial) may run missions too.
        self.nav = Navigation(world, cfg.seed, self.event, self._nav_publish, self._look_at,
                              lidar_beams=cfg.lidar_beams, lidar_range_m=cfg.lidar_range_m,
                              initial_pose=(p0.x, p0.y, p0.theta))
        self.map_msg = map_image(self.nav.grid)
        maps_dir = Path(cfg.maps_dir).expanduser() if cfg.maps_dir else config_dir() / "maps"
        self.nav.mapping = MappingMode(maps_dir)
        self.nav_ready = threading.Event()
        world.on_collision = self._on_collision

    def _init_link(self, cfg: SimConfig, open_port: Callable[[], object],
                   sim_time: Callable[[], float], speed_limit_mps: float,
                   counters: tuple[str, ...] = ()) -> None:
        """The state every relay shares, the patrol robot's and the wall climber's
        (:class:`sim_robot.climber.relay.ClimberRelay`): the station key and the
        command guard, the desks' TCP server, refusal counts, the control lease,
        the MCU's codec and last report, the commanded speeds, the lock and the
        counters (``counters`` adds a relay's own)."""
        self.cfg = cfg
        self.open_port = open_port
        self.port = None
        self.sim_time = sim_time
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
        self.speed_limit = speed_limit_mps
        self.estop = False
        # MCU state
        self.report: SensorReport | None = None
        self.report_mono = 0.0
        self.report_stamp: tuple[float, float] | None = None  # (board s, host monotonic s)
        self.mcu_reports = 0
        self.mcu_silent = True
        self.last_flags = 0
        self.mcu_acks = {"ok": 0, "rejected": 0}
        self.serial_errors = 0
        self._drops_reported: dict[str, int] = {}  # per link
        self._last_drop_event: dict[str, float] = {}
        self.counters = {k: 0 for k in ("telemetry", "pose", "scan", "video", "heartbeat",
                                        "commands", "nav_steps", *counters)}

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
        log.info("preparing navigation (a first run compiles the planner: a minute or more)")
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

    # ------------------------------------------------------------------ motors

    def _set_cmd(self, v: float, w: float) -> None:
        changed = (v, w) != (self.cmd_v, self.cmd_w)
        self.cmd_v, self.cmd_w = v, w
        if changed:
            self._mcu_send(self._motor_msg())

    def _motor_msg(self):
        """The frame that carries the commanded motion to the board (and keeps
        it alive while moving); a base with more to command overrides this."""
        return MotorCmd(self.cmd_v, self.cmd_w)

    def _moving(self) -> bool:
        return bool(self.cmd_v or self.cmd_w)

    def _watchdogs(self, now: float) -> None:
        """Run after every periodic tick: the lease, the deadman and desk
        failsafes (:mod:`.lease`), then the MCU's silence (:mod:`.serial_bridge`)."""
        self._check_lease(now)
        self._check_motion(now)
        self._check_mcu_silence(now)

    # ------------------------------------------------------------------ stats

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
