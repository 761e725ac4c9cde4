"""``sim-robot --robot climber``: the wall climber wired as the patrol robot is
(:class:`sim_robot.sim.SimRobot`): the wall world and the climber's MCU model on
the board's end of a serial link (sim_robot.mcu_port), the relay on the other end, desks over TCP.

With ``--serial DEVICE`` (a real board, or any pyserial URL) the relay opens
DEVICE and there is no simulated wall, body, board or camera: the relay's map
is the wall file's (:class:`~.wall_world.WallMap`), the robot is taken to
stand with its probe over the start cell facing along +x, and what only the
simulator provides is off — the downward camera's sightings of seams, shell
edges and rims (so no landmark fixes: the estimate is the encoders', gyro's
and gravity heading's alone) and with them the detours to a vertical seam.

The wall comes from ``--wall FILE`` (TOML or JSON): the wall itself under
``[wall]`` (app/core/planner/coverage/wall.py's fields), and at the top level
``nominal_mm``, ``limit_mm`` (the thickness the desk alarms below), ``start``
([row, col] of the probe's first cell), ``body_stops`` (default true: the
simulated body is stopped at the wall's top and bottom and at obstacles,
:mod:`.contact`; false lets it pass through them as before) and
``[[patches]]`` of corrosion (``x_m``, ``y_m``, ``radius_m``, ``loss_mm``).
Without a file: the default 24 m × 9.6 m tank with six random patches (seeded).
"""

from __future__ import annotations

import json
import logging
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from app.core.planner.coverage.wall import WallSpec, default_wall, wall_from_dict

from ..config import SimConfig
from ..mcu_port import open_mcu_port
from ..sim import SimClock, open_serial
from .camera_capture import SeamCamera, board_clock
from .camera_view import M_PER_PX, render_view
from .contact import WallContact
from .kinematics import ClimberBody, ClimberParams, ClimberState
from .mcu import ClimberMcu, ClimberMcuThread
from .relay import ClimberRelay
from .wall_world import Patch, WallMap, WallWorld

log = logging.getLogger(__name__)


@dataclass
class ClimberSetup:
    spec: WallSpec = field(default_factory=default_wall)
    nominal_mm: float = 10.0
    limit_mm: float = 8.0
    start: tuple[int, int] | None = None
    patches: tuple[Patch, ...] | None = None  # None: random (seeded)
    name: str = "tank"
    body_stops: bool = True  # the body is stopped at the wall's edges and obstacles


def load_setup(path: str | Path | None) -> ClimberSetup:
    """The climber's wall file (see the module's docstring); ValueError with the file's
    name on anything wrong."""
    if path is None:
        return ClimberSetup()
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
        raw = json.loads(text) if p.suffix == ".json" else tomllib.loads(text)
        spec = wall_from_dict(raw.get("wall", {}))
        patches = tuple(Patch(float(d["x_m"]), float(d["y_m"]), float(d["radius_m"]),
                              float(d["loss_mm"])) for d in raw.get("patches", []))
        start = raw.get("start")
        if start is not None:
            start = (int(start[0]), int(start[1]))
        stops = raw.get("body_stops", True)
        if not isinstance(stops, bool):
            raise ValueError(f"body_stops must be true or false, got {stops!r}")
        return ClimberSetup(spec, float(raw.get("nominal_mm", 10.0)),
                            float(raw.get("limit_mm", 8.0)), start,
                            patches if "patches" in raw else None, p.stem, stops)
    except (OSError, ValueError, KeyError, TypeError, IndexError,
            tomllib.TOMLDecodeError) as e:
        raise ValueError(f"wall file {p}: {e}") from None


def first_start(blocked: np.ndarray, params: ClimberParams, cell_m: float) -> tuple[int, int]:
    """A free cell near the bottom left where the whole body fits behind the probe."""
    rows, cols = blocked.shape
    margin = math.ceil(params.width_m / 2 / cell_m) + 1
    back = math.ceil(params.length_m / cell_m) + 1
    for r in range(margin, rows - margin):
        for c in range(back, cols):
            if not blocked[r - margin:r + margin + 1, c - back:c + 1].any():
                return r, c
    raise ValueError("no free cell on the wall to start from")


class ClimberSim:
    """Wires the wall world, the climber's MCU model (on a socket or pty) and the relay."""

    def __init__(self, cfg: SimConfig, setup: ClimberSetup | None = None,
                 seam_camera: str = "sightings", camera_device: str | None = None,
                 camera_m_per_px: float | None = None) -> None:
        """``seam_camera``: "sightings" (the camera's view of seams and edges as
        geometry with noise, :meth:`WallWorld.seam_sightings`) or "pixels" (grey
        frames drawn by :mod:`.camera_view`, the seams, the shell's edges and the rims
        of manholes and nozzles found in them by the relay). With a real board
        (``cfg.serial_device``), ``camera_device`` is the real seam camera
        (:mod:`.camera_capture`) and ``camera_m_per_px`` its scale on the wall."""
        if seam_camera not in ("sightings", "pixels"):
            raise ValueError(f"seam camera {seam_camera!r}: expected 'sightings' or 'pixels'")
        if camera_device is not None and not cfg.serial_device:
            raise ValueError("a seam camera device goes with a real board (--serial); the "
                             "simulated climber draws its own frames (--seam-camera pixels)")
        if camera_device is not None and not (camera_m_per_px and camera_m_per_px > 0):
            raise ValueError("the seam camera's scale (mm a pixel on the wall) is needed "
                             "with its device")
        self.camera = None
        self.cfg = cfg
        setup = setup or ClimberSetup()
        board = cfg.serial_device  # a real board: no simulated wall, body or camera
        # sim time waits for the relay's navigation and the board model as the patrol
        # robot's does (SimClock): starved, they let the body drive blind on the last
        # command (a recoil ran on 0.2–0.65 m on the tank while a contact fix held the
        # relay's lock); a board of its own runs in real time
        self.clock = SimClock(cfg.time_scale, 0.0 if board else cfg.control_lead_s)
        if not board:  # sim time starts when the navigation and the board run
            self.clock.expect(("navigation", "board"))
        params = ClimberParams()
        self.map = (WallMap(setup.spec, setup.nominal_mm) if board else
                    WallWorld(setup.spec, setup.nominal_mm, setup.patches, seed=cfg.seed))
        start = setup.start or first_start(self.map.blocked, params, self.map.cell_m)
        if self.map.blocked[start]:
            raise ValueError(f"start cell {start} is blocked")
        lead = params.length_m / 2
        x0, y0 = self.map.cell_centre(*start)
        pose0 = ((x0 - lead) % self.map.circ_m, y0, 0.0)
        if board:
            self.wall = self.contact = self.body = self.model = None
            self.mcu_thread = self.mcu_port = None
            self.device = board
            if camera_device is None:
                log.warning("climber on the board at %s: the wall's map from %s; no simulated "
                            "wall, body or camera and no seam camera given, so no seam, "
                            "shell-edge or rim fixes and no detours to a vertical seam; the "
                            "robot must stand with its probe over cell %s facing along +x",
                            board, setup.name, start)
            else:
                self.camera = SeamCamera(camera_device)
                log.warning("climber on the board at %s: the wall's map from %s; seams, "
                            "the shell's edges and rims from the camera %s (%.2f mm a pixel); "
                            "the robot must stand with its probe over cell %s facing "
                            "along +x", board, setup.name, camera_device,
                            camera_m_per_px * 1000, start)

            def open_port():
                return open_serial(board, cfg.baudrate)

            self.relay = ClimberRelay(cfg, open_port, self.map, pose0, start, None,
                                      self.clock.now, params, setup.limit_mm, setup.name,
                                      seam_frames=self.camera,
                                      camera_m_per_px=camera_m_per_px or 0.001)
            if self.camera is not None:
                self.camera.board_time = board_clock(self.relay)
            return
        self.wall = self.map
        # the body stops at the wall's top and bottom and at obstacles (contact.py)
        self.contact = WallContact(setup.spec, self.wall.blocked, params.length_m,
                                   params.width_m)
        self.body = ClimberBody(params, ClimberState(*pose0), self.wall.circ_m,
                                seed=cfg.seed, height_m=setup.spec.height_m,
                                contact=self.contact.depth if setup.body_stops else None)
        self.mcu_port = open_mcu_port(cfg.mcu_link)
        self.device = self.mcu_port.url
        self.model = ClimberMcu(self.wall, self.body, cfg.limits, cfg.seed,
                                cfg.mcu_link_timeout_s)
        self.mcu_thread = ClimberMcuThread(self.model, self.mcu_port, self.clock, cfg.mcu_rate_hz)
        self._rng = np.random.default_rng(cfg.seed + 3000)

        def open_port():
            return open_serial(self.device, cfg.baudrate)

        pixels = seam_camera == "pixels"
        self.relay = ClimberRelay(cfg, open_port, self.wall, pose0, start,
                                  None if pixels else self._seams_seen,
                                  self.clock.now, params, setup.limit_mm, setup.name,
                                  rims_seen=None if pixels else self._rims_seen,
                                  seam_frames=self._frame if pixels else None,
                                  camera_m_per_px=M_PER_PX)
        self.relay.on_control_step = self.clock.control_step

    def _camera(self) -> tuple[float, float, float, float]:
        """The downward camera's point (under the probe, ``lead`` ahead of the
        axle) and heading, and the time of the body's state it shows."""
        s = self.body.s
        lead = self.body.p.length_m / 2
        return (self.model.t_s, s.x_m + lead * math.cos(s.theta_rad),
                s.y_m + lead * math.sin(s.theta_rad), s.theta_rad)

    def _seams_seen(self) -> tuple[float, list[tuple[bool, float, float]]]:
        """The camera's view of weld seams round the probe: direction in the
        image (relative to the body's heading) and offset from the image
        centre, with noise (:meth:`WallWorld.seam_sightings`), and the time
        of the body's state it shows: the MCU model's last step, which a
        loaded machine leaves behind the sim clock (by 0.5 s of sim time on
        average at 80×; stamping frames with the clock made the relay carry
        the offsets back over motion that had not happened)."""
        t_s, x, y, theta = self._camera()
        return t_s, self.wall.seam_sightings(x, y, theta, self._rng)

    def _frame(self) -> tuple[float, np.ndarray]:
        """The downward camera's grey frame (:func:`.camera_view.render_view`),
        stamped like :meth:`_seams_seen`."""
        t_s, x, y, theta = self._camera()
        return t_s, render_view(self.wall, x, y, theta, self._rng)

    def _rims_seen(self) -> tuple[float, list[tuple[float, float, float, float]]]:
        """The same camera's view of manhole and nozzle rims
        (:meth:`WallWorld.rim_sightings`), stamped like :meth:`_seams_seen`."""
        t_s, x, y, theta = self._camera()
        return t_s, self.wall.rim_sightings(x, y, theta, self._rng)

    def start(self) -> None:
        self.relay.prepare()
        if self.camera is not None:
            self.camera.start()
        if self.mcu_thread is not None:
            self.mcu_thread.start()
        self.relay.start()

    @property
    def address(self) -> tuple[str, int]:
        return self.relay.address

    def close(self) -> None:
        self.relay.close()
        if self.camera is not None:
            self.camera.close()
        if self.mcu_thread is None:  # a real board
            return
        self.mcu_thread.stop()
        if self.mcu_thread.is_alive():  # a sim closed before start() has no thread to join
            self.mcu_thread.join(timeout=2)
        self.mcu_port.close()
