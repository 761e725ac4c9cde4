"""The link's settings (no Qt: the desk's configuration loads them without Qt)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["LinkSettings"]


@dataclass
class LinkSettings:
    heartbeat_s: float = 1.0
    lost_after_s: float = 3.0  # silence that means the link is lost
    reconnect_every_s: float = 0.5
    drive_resend_s: float = 0.2  # a held drive command is renewed this often
    connect_timeout_s: float = 2.0
    key_file: str | None = None  # station key (None: $STATION_PATROL_KEY_FILE or config dir)
    desk_name: str | None = None  # shown to other desks (default user@host)
    request_control: bool = True  # ask for the control lease on every connect
    gui_alive_s: float = 0.35  # a held drive is renewed only while the GUI ticked this recently
