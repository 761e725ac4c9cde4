"""The telemetry channels the desk keeps, and how each is named and shown (no Qt)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.comm.protocol import RobotMode
from app.core.i18n import QT_TRANSLATE_NOOP, translate

__all__ = ["ChannelSpec", "PLOT_CHANNELS", "SPECS", "TELEMETRY_CHANNELS", "battery_percent",
           "channel_label", "mode_label", "mode_name"]


@dataclass(frozen=True)
class ChannelSpec:
    key: str
    label: str
    unit: str
    fmt: str = "{:.1f}"


# every numeric telemetry field, kept as a series and fed to the alarm monitor (the
# labels are marked for translation: channel_label shows them in the desk's language)
TELEMETRY_CHANNELS: tuple[ChannelSpec, ...] = (
    ChannelSpec("gas_lel_pct", QT_TRANSLATE_NOOP("Channel", "Gas"), "%LEL"),
    ChannelSpec("temp_c", QT_TRANSLATE_NOOP("Channel", "Temperature"), "°C"),
    ChannelSpec("humidity_pct", QT_TRANSLATE_NOOP("Channel", "Humidity"), "%RH", "{:.0f}"),
    ChannelSpec("battery_v", QT_TRANSLATE_NOOP("Channel", "Battery"), "V", "{:.2f}"),
    ChannelSpec("obstacle_left_m", QT_TRANSLATE_NOOP("Channel", "Obstacle left"), "m", "{:.2f}"),
    ChannelSpec("obstacle_front_m", QT_TRANSLATE_NOOP("Channel", "Obstacle front"), "m",
                "{:.2f}"),
    ChannelSpec("obstacle_right_m", QT_TRANSLATE_NOOP("Channel", "Obstacle right"), "m",
                "{:.2f}"),
    ChannelSpec("wheel_left_mps", QT_TRANSLATE_NOOP("Channel", "Wheel left"), "m/s", "{:.2f}"),
    ChannelSpec("wheel_right_mps", QT_TRANSLATE_NOOP("Channel", "Wheel right"), "m/s", "{:.2f}"),
    ChannelSpec("yaw_rate_rps", QT_TRANSLATE_NOOP("Channel", "Yaw rate"), "rad/s", "{:.2f}"),
    ChannelSpec("cmd_linear_mps", QT_TRANSLATE_NOOP("Channel", "Commanded speed"), "m/s",
                "{:.2f}"),
    ChannelSpec("cmd_angular_rps", QT_TRANSLATE_NOOP("Channel", "Commanded turn"),
                "rad/s", "{:.2f}"),
)
PLOT_CHANNELS: tuple[str, ...] = ("gas_lel_pct", "temp_c", "humidity_pct")
SPECS: dict[str, ChannelSpec] = {c.key: c for c in TELEMETRY_CHANNELS}


def mode_name(mode: int) -> str:
    try:
        return RobotMode(int(mode)).name
    except ValueError:
        return f"UNKNOWN({mode})"


# the modes as the desk shows them (mode_name stays the protocol's name, for logs)
_MODE_LABELS = (QT_TRANSLATE_NOOP("RobotMode", "IDLE"), QT_TRANSLATE_NOOP("RobotMode", "TELEOP"),
                QT_TRANSLATE_NOOP("RobotMode", "PATROL"), QT_TRANSLATE_NOOP("RobotMode", "ESTOP"),
                QT_TRANSLATE_NOOP("RobotMode", "FAILSAFE"),
                QT_TRANSLATE_NOOP("RobotMode", "DOCKED"))


def mode_label(mode: int) -> str:
    """The mode in the desk's language."""
    return translate("RobotMode", mode_name(mode))


def channel_label(key: str) -> str:
    """A channel's label in the desk's language (the key itself when unknown)."""
    spec = SPECS.get(key)
    return translate("Channel", spec.label) if spec else key


def battery_percent(v: float, empty_v: float = 21.0, full_v: float = 25.5) -> float:
    """A rough state of charge of the 24 V pack from its voltage: a straight
    line from ``empty_v`` (0 %) to ``full_v`` (100 %), clipped. Under load the
    voltage sags, so this is a hint for the operator, not a fuel gauge."""
    if not math.isfinite(v):
        return float("nan")
    return float(np.clip((v - empty_v) / (full_v - empty_v) * 100.0, 0.0, 100.0))
