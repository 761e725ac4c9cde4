"""The simulation's clock, the ground-truth logger, and the wiring of one robot.

:class:`SimRobot` builds the world, the MCU model on the board's end of a serial
link (:mod:`sim_robot.mcu_port`: a loopback socket, or a pty pair on Unix) or
uses a real board on ``serial_device``, and the relay, which opens either with
pyserial's ``serial_for_url``; it starts their threads and tears them down again.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections.abc import Callable

import serial

from app.comm.protocol import now_us

from .config import SimConfig
from .mcu import McuModel, McuThread
from .mcu_port import McuPort, open_mcu_port
from .relay import Relay
from .world import World

SERIAL_READ_TIMEOUT_S = 0.1  # the relay's read waits at most this long for a byte


class SimClock:
    """Sim time runs ``time_scale`` times faster than wall time, but no further
    than ``control_lead_s`` of sim time past the last step of the slowest of
    the robot's control loops once they report their steps
    (:meth:`control_step`): the navigation, and the MCU model's sampling.

    At a high time scale on a busy host the navigation thread may get no CPU
    for a fraction of a second of wall time: seconds of sim time, through
    which the MCU model held the last speed command and the robot drove
    blind (the desk soak at 36x, load 14, bumped a wall end). A real robot's
    controller runs in real time; so the simulation slows down instead
    (sim time is lost, not skipped), as a lock-step simulator waits for its
    controller. ``held_s`` counts the sim time held back.

    The MCU model's thread is a control loop too: starved, it fell 20 s of
    sim time behind the clock and then caught up in one burst, sampling 400
    periods with the last motor command it had read — the robot spun on the
    spot for 20 s with nobody steering, and a spin that long left the
    odometry's heading 40–120° off, beyond what the scan matcher searches, so
    localisation was lost (the desk soak at 36x, minute 13). A real board runs
    in real time; here sim time waits for it as for the navigation."""

    def __init__(self, time_scale: float = 1.0, control_lead_s: float = 0.0,
                 wall: Callable[[], float] = time.monotonic) -> None:
        if time_scale <= 0:
            raise ValueError("time scale must be positive")
        if control_lead_s < 0:
            raise ValueError("control lead must not be negative")
        self.time_scale = time_scale
        self.control_lead_s = control_lead_s
        self._wall = wall
        self._t0 = wall()
        self._lock = threading.Lock()
        self._limit = math.inf  # sim time may not pass this (the slowest loop's step + lead)
        self._marks: dict[str, float] = {}  # each control loop's last step (sim time)
        self._last = 0.0
        self.held_s = 0.0

    def now(self) -> float:
        """Sim seconds since start."""
        with self._lock:
            t = (self._wall() - self._t0) * self.time_scale - self.held_s
            if t > self._limit:
                self.held_s += t - self._limit
                t = self._limit
            t = max(t, self._last)
            self._last = t
            return t

    def expect(self, loops: tuple[str, ...]) -> None:
        """The control loops that will report their steps: until each has
        stepped, sim time waits ``control_lead_s`` past now as for a starved
        loop. A robot's loops start only once it is built and its kernels
        compiled (a minute and more of wall time on a first run under load):
        sim time ran free meanwhile, thousands of seconds at 36x, and again
        between the board's first sample and the navigation's first step."""
        t = self.now()
        for loop in loops:
            self.control_step(t, loop)

    def control_step(self, t_s: float, loop: str = "navigation") -> None:
        """A control loop (``loop``: "navigation", "board") stepped at sim time
        ``t_s``: sim time may run on to ``control_lead_s`` past the slowest
        loop's last step (no limit while the lead is 0)."""
        if self.control_lead_s > 0:
            with self._lock:
                self._marks[loop] = max(self._marks.get(loop, 0.0), t_s)
                self._limit = min(self._marks.values()) + self.control_lead_s

    def wall_until(self, t_sim: float) -> float:
        """Wall seconds until sim time ``t_sim`` (negative when past)."""
        return (t_sim - self.now()) / self.time_scale


class TruthLogger:
    """Writes ground truth as JSON lines for offline evaluation (never to the desk)."""

    def __init__(self, path: str, world: World, clock: SimClock, period_s: float = 0.5) -> None:
        self.world = world
        self.clock = clock
        self.period_s = period_s
        self._f = open(path, "w", encoding="utf-8")  # noqa: SIM115 - closed in close()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="truth-log", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            t = self.clock.now()
            w = self.world
            p = w.pose
            temp, hum = w.ambient(t)
            wd, ws = w.wind_at(t)
            rec = {"utc_us": now_us(), "sim_s": round(t, 3), "x_m": p.x, "y_m": p.y,
                   "theta_rad": p.theta, "v_mps": p.v, "omega_rps": p.omega,
                   "gas_lel_pct": w.gas_lel_pct(p.x, p.y, t), "temp_c": temp,
                   "humidity_pct": hum, "wind_dir_rad": wd, "wind_mps": ws,
                   "gauges": {g.id: g.value(t) for g in w.gauges},
                   "people": [[round(v, 2) for v in row[:2]] for row in w.people(t)]}
            self._f.write(json.dumps(rec) + "\n")
            self._f.flush()

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2)
        self._f.close()


class SimRobot:
    """Wires world, MCU model (on a socket or pty) and relay together; ``close()``
    undoes it. Another robot on the station (the 4WS one) names its own parts here."""

    mcu_model = McuModel
    mcu_thread_class = McuThread
    relay_class = Relay

    def __init__(self, cfg: SimConfig) -> None:
        self.cfg = cfg
        # a board of its own runs in real time: pace by the navigation only the model
        lead = cfg.control_lead_s if not cfg.serial_device else 0.0
        self.clock = SimClock(cfg.time_scale, lead)
        if not cfg.serial_device:  # sim time starts when the navigation and the board run
            self.clock.expect(("navigation", "board"))
        self.world = World(cfg.station_file, cfg.seed)
        self.world.clock = self.clock.now
        if cfg.start_at:
            self.world.set_pose(*self.world.pose_facing_gauge(cfg.start_at))
        self.mcu_thread = None
        self.mcu_port: McuPort | None = None
        if cfg.serial_device:
            device = cfg.serial_device
        else:
            self.mcu_port = open_mcu_port(cfg.mcu_link)
            device = self.mcu_port.url
            model = self.mcu_model(self.world, cfg.robot, cfg.limits, cfg.seed,
                                   cfg.mcu_link_timeout_s)
            model.gas.offset_lel = cfg.gas_offset_lel
            self.mcu_thread = self.mcu_thread_class(model, self.mcu_port, self.clock,
                                                    cfg.mcu_rate_hz)
        self.device = device

        def open_port():
            return open_serial(device, cfg.baudrate)

        def camera_pose():
            p = self.world.pose
            return p.x, p.y, p.theta

        self.relay = self.relay_class(cfg, open_port, self.world, camera_pose, self.clock.now)
        self.relay.on_control_step = self.clock.control_step
        self.truth = TruthLogger(cfg.log_truth, self.world, self.clock) if cfg.log_truth \
            else None

    def start(self) -> None:
        # navigation first (a first run compiles its kernels): the MCU's link
        # watchdog starts counting only once the relay can feed it
        self.relay.prepare()
        if self.mcu_thread is not None:
            self.mcu_thread.start()
        self.relay.start()
        if self.truth:
            self.truth.start()

    @property
    def address(self) -> tuple[str, int]:
        return self.relay.address

    def close(self) -> None:
        self.relay.close()
        if self.mcu_thread is not None:
            self.mcu_thread.stop()
            if self.mcu_thread.is_alive():  # (a robot built but never started has none)
                self.mcu_thread.join(timeout=2)
        if self.truth:
            self.truth.close()
        if self.mcu_port is not None:
            self.mcu_port.close()


def open_serial(device: str, baudrate: int):
    """The relay's MCU port, a real board's device (``/dev/ttyUSB0``, ``COM3``) or the
    simulated board's URL (``socket://127.0.0.1:PORT``) alike."""
    return serial.serial_for_url(device, baudrate=baudrate, timeout=SERIAL_READ_TIMEOUT_S)
