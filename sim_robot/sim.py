"""The simulation's clock, the ground-truth logger, and the wiring of one robot.

:class:`SimRobot` builds the world, the MCU model on the board's end of a serial
link (:mod:`sim_robot.mcu_port`: a loopback socket, or a pty pair on Unix) or
uses a real board on ``serial_device``, and the relay, which opens either with
pyserial's ``serial_for_url``; it starts their threads and tears them down again.
"""

from __future__ import annotations

import json
import threading
import time

import serial

from app.comm.protocol import now_us

from .config import SimConfig
from .mcu import McuModel, McuThread
from .mcu_port import McuPort, open_mcu_port
from .relay import Relay
from .world import World

SERIAL_READ_TIMEOUT_S = 0.1  # the relay's read waits at most this long for a byte


class SimClock:
    """Sim time runs ``time_scale`` times faster than wall time."""

    def __init__(self, time_scale: float = 1.0) -> None:
        if time_scale <= 0:
            raise ValueError("time scale must be positive")
        self.time_scale = time_scale
        self._t0 = time.monotonic()

    def now(self) -> float:
        """Sim seconds since start."""
        return (time.monotonic() - self._t0) * self.time_scale

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
        self.clock = SimClock(cfg.time_scale)
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
            self.mcu_thread.join(timeout=2)
        if self.truth:
            self.truth.close()
        if self.mcu_port is not None:
            self.mcu_port.close()


def open_serial(device: str, baudrate: int):
    """The relay's MCU port, a real board's device (``/dev/ttyUSB0``, ``COM3``) or the
    simulated board's URL (``socket://127.0.0.1:PORT``) alike."""
    return serial.serial_for_url(device, baudrate=baudrate, timeout=SERIAL_READ_TIMEOUT_S)
