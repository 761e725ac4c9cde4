"""One typed configuration for the simulated robot (dataclasses, TOML, CLI overrides)."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path

from app.core.paths import resources_root

RESOURCES = resources_root()  # the shipped resources, inside the app package
DEFAULT_STATION = RESOURCES / "station" / "station.json"


@dataclass
class McuLimits:
    """Warning limits the MCU checks locally (sent to it in a CONFIG frame)."""

    gas_lel_pct: float = 10.0
    temp_c: float = 45.0
    humidity_pct: float = 90.0
    obstacle_m: float = 0.35
    battery_low_v: float = 22.0


@dataclass
class RobotParams:
    radius_m: float = 0.35
    track_m: float = 0.40  # wheel track of the skid-steer base
    skid_factor: float = 1.35  # effective track / geometric track when turning on the spot
    wheel_radius_m: float = 0.0325  # 65 mm wheels
    ticks_per_rev: int = 390
    max_linear_mps: float = 1.0
    max_angular_rps: float = 1.5
    accel_mps2: float = 0.8
    brake_mps2: float = 2.0  # slowing down is quicker than speeding up
    angular_accel_rps2: float = 3.0


@dataclass
class SimConfig:
    host: str = "127.0.0.1"
    port: int = 0
    seed: int = 0
    time_scale: float = 1.0
    serial_device: str | None = None  # a real board (a device or a pyserial URL)
    mcu_link: str = "socket"  # the model's end: "socket" (loopback) or "pty" (Unix)
    log_truth: str | None = None
    video: bool = True
    fps: float = 12.0
    station_file: str = str(DEFAULT_STATION)
    start_at: str | None = None  # a gauge id: start in front of it, not at the dock
    patrol: str | None = None  # start this route file ("default": the default route) at once
    mcu_rate_hz: float = 20.0  # MCU sampling, sim time
    telemetry_hz: float = 10.0  # to the desk, wall time
    pose_hz: float = 10.0
    scan_hz: float = 5.0
    heartbeat_hz: float = 1.0
    keepalive_s: float = 0.1  # relay -> MCU, wall time (the link's clock)
    mcu_link_timeout_s: float = 0.5  # MCU failsafe when no valid frame, wall time
    # sim time runs at most this far past the navigation's last step (a starved
    # host slows the simulation rather than let the robot drive blind); 0 = off
    control_lead_s: float = 0.5
    drive_valid_s: float = 0.5  # deadman: a drive command holds this long (wall time)
    client_silence_s: float = 0.5  # failsafe when the driving desk is silent this long
    key_file: str | None = None  # station key (None: $STATION_PATROL_KEY_FILE or config dir)
    maps_dir: str | None = None  # where save_map writes (None: <config dir>/maps)
    auth_max_skew_s: float = 10.0  # a signed command's timestamp may differ this much
    lease_timeout_s: float = 3.0  # the control lease lapses after this much holder silence
    # what a running patrol does when the lease holder is lost (its heartbeats stop
    # or it disconnects without releasing control): "pause" stops the robot until a
    # desk resumes it; "continue" lets the patrol run on unwatched
    lease_lost_action: str = "pause"
    max_clients: int = 16  # desks connected at once
    max_clients_per_host: int = 8  # connections from one peer address
    command_rate_hz: float = 50.0  # commands per second one desk may send (burst as many)
    speed_limit_mps: float = 0.8
    client_queue_bytes: int = 2_000_000  # per-client budget before video is dropped
    client_max_backlog_bytes: int = 16_000_000  # beyond this a client is cut off
    baudrate: int = 115200
    lidar_beams: int = 360
    lidar_range_m: float = 12.0
    camera_width: int = 640
    camera_height: int = 480
    camera_hfov_deg: float = 70.0
    jpeg_quality: int = 80
    gas_offset_lel: float = 0.0  # a faulty gas element reads this much off (< 0: below zero)
    limits: McuLimits = field(default_factory=McuLimits)
    robot: RobotParams = field(default_factory=RobotParams)

    @classmethod
    def from_toml(cls, path: str | Path) -> SimConfig:
        with open(path, "rb") as f:
            data = tomllib.load(f)
        cfg = cls()
        _apply(cfg, data.get("sim_robot", data))
        if cfg.lease_lost_action not in ("pause", "continue"):
            raise ValueError(f"lease_lost_action must be \"pause\" or \"continue\", "
                             f"not {cfg.lease_lost_action!r}")
        return cfg


def _apply(obj, data: dict) -> None:
    names = {f.name for f in fields(obj)}
    for k, v in data.items():
        if k not in names:
            raise ValueError(f"unknown configuration key {k!r} in {type(obj).__name__}")
        cur = getattr(obj, k)
        if is_dataclass(cur) and isinstance(v, dict):
            _apply(cur, v)
        else:
            setattr(obj, k, v)
