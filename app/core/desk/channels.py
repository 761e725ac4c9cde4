"""The telemetry channels the desk keeps, and how each is named and shown (no Qt)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.comm.protocol import RobotMode

__all__ = ["ChannelSpec", "PLOT_CHANNELS", "SPECS", "TELEMETRY_CHANNELS", "battery_percent",
           "mode_name"]


@dataclass(frozen=True)
class ChannelSpec:
    key: str
    label: str
    unit: str
    fmt: str = "{:.1f}"


# every numeric telemetry field, kept as a series and fed to the alarm monitor
TELEMETRY_CHANNELS: tuple[ChannelSpec, ...] = (
    ChannelSpec("gas_lel_pct", "Gas", "%LEL"),
    ChannelSpec("temp_c", "Temperature", "°C"),
    ChannelSpec("humidity_pct", "Humidity", "%RH", "{:.0f}"),
    ChannelSpec("battery_v", "Battery", "V", "{:.2f}"),
    ChannelSpec("obstacle_left_m", "Obstacle left", "m", "{:.2f}"),
    ChannelSpec("obstacle_front_m", "Obstacle front", "m", "{:.2f}"),
    ChannelSpec("obstacle_right_m", "Obstacle right", "m", "{:.2f}"),
    ChannelSpec("wheel_left_mps", "Wheel left", "m/s", "{:.2f}"),
    ChannelSpec("wheel_right_mps", "Wheel right", "m/s", "{:.2f}"),
    ChannelSpec("yaw_rate_rps", "Yaw rate", "rad/s", "{:.2f}"),
    ChannelSpec("cmd_linear_mps", "Commanded speed", "m/s", "{:.2f}"),
    ChannelSpec("cmd_angular_rps", "Commanded turn", "rad/s", "{:.2f}"),
)
PLOT_CHANNELS: tuple[str, ...] = ("gas_lel_pct", "temp_c", "humidity_pct")
SPECS: dict[str, ChannelSpec] = {c.key: c for c in TELEMETRY_CHANNELS}


def mode_name(mode: int) -> str:
    try:
        return RobotMode(int(mode)).name
    except ValueError:
        return f"UNKNOWN({mode})"


def battery_percent(v: float, empty_v: float = 21.0, full_v: float = 25.5) -> float:
    """A rough state of charge of the 24 V pack from its voltage: a straight
    line from ``empty_v`` (0 %) to ``full_v`` (100 %), clipped. Under load the
    voltage sags, so this is a hint for the operator, not a fuel gauge."""
    if not math.isfinite(v):
        return float("nan")
    return float(np.clip((v - empty_v) / (full_v - empty_v) * 100.0, 0.0, 100.0))
