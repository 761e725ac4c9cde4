"""The desk's typed configuration: dataclasses loaded from TOML, overridden by flags."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any

from app.comm.settings import LinkSettings


@dataclass
class ArchiveSettings:
    """The patrol archive ([archive] in the desk TOML); see docs/archive.md."""

    enabled: bool = True
    retention_days: float = 30.0  # rows older than this are pruned (0: keep everything)
    export_before_prune: bool = False  # write pruned rows to CSV files first
    export_dir: str = ""  # where (default: <data dir>/exported)


@dataclass
class FoxgloveSettings:
    """The live Foxglove WebSocket view ([foxglove] in the desk TOML; docs/interop.md).
    Off unless enabled here or by ``--foxglove [PORT]``; loopback unless ``host`` says
    otherwise (the protocol has no authentication of its own)."""

    enabled: bool = False
    host: str = "127.0.0.1"
    port: int = 8765


@dataclass
class OpcuaSettings:
    """The desk's OPC UA server ([opcua] in the desk TOML); see docs/opcua.md."""

    endpoint: str = ""  # e.g. "opc.tcp://0.0.0.0:4840" ("": no server)
    users_file: str = ""  # "": <data dir>/opcua/users.json
    pki_dir: str = ""  # the desk's certificate and key ("": <data dir>/opcua/pki)
    trusted_dir: str = ""  # trusted client certificates ("": <pki dir>/trusted)
    allow_anonymous: bool = False  # anonymous clients (read only), said loudly when on
    allow_none_security: bool = False  # unsigned, unencrypted endpoint, said loudly when on


@dataclass
class DeskConfig:
    host: str = "127.0.0.1"
    port: int = 0
    seed: int = 1
    time_scale: float = 1.0  # the demo robot's sim time per wall second, with a window
    # ... and without one: a 20 s headless demo then covers 80 s of patrol, so it
    # drives to the first gauges and reads them (a window shows real time)
    headless_time_scale: float = 4.0
    headless_duration_s: float = 20.0
    out_dir: str = "results"
    start_patrol: bool = False  # ask the robot to patrol its default route once connected
    link: LinkSettings = field(default_factory=LinkSettings)
    data_dir: str = ""  # the archive's folder ("": the platform's user-data folder)
    alarms_file: str = ""  # alarm rules overriding resources/alarms.toml ("": none)
    archive: ArchiveSettings = field(default_factory=ArchiveSettings)
    foxglove: FoxgloveSettings = field(default_factory=FoxgloveSettings)
    opcua: OpcuaSettings = field(default_factory=OpcuaSettings)


class ConfigError(ValueError):
    pass


def _merge(obj: Any, data: dict[str, Any], where: str) -> None:
    known = {f.name: f for f in fields(obj)}
    for key, value in data.items():
        if key not in known:
            raise ConfigError(f"{where}: unknown setting '{key}' "
                              f"(known: {', '.join(sorted(known))})")
        current = getattr(obj, key)
        if is_dataclass(current):
            if not isinstance(value, dict):
                raise ConfigError(f"{where}.{key}: expected a table")
            _merge(current, value, f"{where}.{key}")
            continue
        if isinstance(current, float) and type(value) is int:
            value = float(value)
        if type(value) is not type(current):
            raise ConfigError(f"{where}.{key}: expected {type(current).__name__}, "
                              f"got {type(value).__name__}")
        setattr(obj, key, value)


def load_config(path: str | Path | None) -> DeskConfig:
    """Defaults, then the TOML file if given. Raises ConfigError with a clear message."""
    cfg = DeskConfig()
    if path is None:
        return cfg
    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"configuration file not found: {p}") from None
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{p}: not valid TOML: {e}") from None
    _merge(cfg, data, p.name)
    if cfg.archive.retention_days < 0:
        raise ConfigError(f"{p.name}: archive.retention_days must be 0 (keep everything) "
                          f"or a positive number of days")
    return cfg
