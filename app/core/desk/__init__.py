"""The desk pipeline: one Qt-free model of the desk run by window, headless and replay."""

from app.core.desk.channels import (
    PLOT_CHANNELS,
    SPECS,
    TELEMETRY_CHANNELS,
    ChannelSpec,
    battery_percent,
    channel_label,
    mode_label,
    mode_name,
)
from app.core.desk.gateway import CommandGateway, JournalEntry
from app.core.desk.pipeline import KINDS, LINK_ABNORMAL, DeskPipeline

__all__ = ["ChannelSpec", "CommandGateway", "DeskPipeline", "JournalEntry", "KINDS",
           "LINK_ABNORMAL", "PLOT_CHANNELS", "SPECS", "TELEMETRY_CHANNELS",
           "battery_percent", "channel_label", "mode_label", "mode_name"]
