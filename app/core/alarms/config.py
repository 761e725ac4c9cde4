"""Alarm configuration from TOML, validated point by point (no Qt).

The defaults are ``resources/alarms.toml``; a user file (``--alarms FILE`` or
the desk configuration's ``alarms_file``) overrides them table by table: a
``[limit.temp_c]`` in the user file replaces the keys it names of the default
``[limit.temp_c]``. In ISA-18.2 terms this is the *master alarm database*
(clause 9): every alarm's setpoint, deadband, delays and priority in one place.

Validation never raises for a bad file: :func:`load_alarm_config` returns the
configuration built from every valid entry plus a list of problems, each naming
the file, the key and what is wrong ("alarms.toml: [limit.temp_c] high: expected
a number, got 'hot'"). An invalid point keeps its default rule.
"""

from __future__ import annotations

import copy
import logging
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from app.comm.protocol import AlarmFlag
from app.core.alarms.model import Priority, parse_priority
from app.core.alarms.rules import ConditionRule, FlagRule, LimitRule, RateRule, StaleRule
from app.core.alarms.setpoints import GasRule, SetPoint

log = logging.getLogger(__name__)

__all__ = ["AlarmConfig", "DEFAULT_ALARMS_FILE", "default_alarm_config", "dump_alarm_config",
           "gas_rule",
           "load_alarm_config", "parse_alarm_config", "site_alarm_file", "use_alarm_file"]

DEFAULT_ALARMS_FILE = Path(__file__).resolve().parents[3] / "resources" / "alarms.toml"

_SECTIONS = ("flood", "shelving", "limit", "rate", "stale", "flag", "condition", "setpoint",
             "gas")
_KEYS = {
    "limit": {"label": str, "unit": str, "high": float, "low": float, "deadband": float,
              "priority": Priority, "on_delay_s": float, "off_delay_s": float, "source": str},
    "rate": {"label": str, "unit": str, "rise_per_min": float, "window_s": float,
             "deadband": float, "priority": Priority, "on_delay_s": float,
             "off_delay_s": float, "source": str},
    "stale": {"label": str, "after_s": float, "priority": Priority, "source": str},
    "flag": {"priority": Priority, "text": str},
    "condition": {"priority": Priority, "text": str},
    "setpoint": {"value": float, "direction": str, "deadband": float, "priority": Priority,
                 "latching": bool, "on_delay_s": float, "off_delay_s": float, "label": str,
                 "unit": str, "stage": str, "source": str},
    "gas": {"gas": str, "unit": str, "label": str, "fault_below": float, "stuck_band": float,
            "stuck_s": float, "fault_priority": Priority, "bump_test_days": float,
            "calibration_days": float, "service_priority": Priority, "source": str},
    "flood": {"max_per_minute": int, "window_s": float},
    "shelving": {"max_s": float},
}


@dataclass
class AlarmConfig:
    """Every alarm rule of the desk."""

    limits: list[LimitRule] = field(default_factory=list)
    rates: list[RateRule] = field(default_factory=list)
    stale: list[StaleRule] = field(default_factory=list)
    flags: dict[str, tuple[Priority, str]] = field(default_factory=dict)
    conditions: list[ConditionRule] = field(default_factory=list)
    setpoints: list[SetPoint] = field(default_factory=list)
    gas: list[GasRule] = field(default_factory=list)
    flood_per_minute: int = 10
    flood_window_s: float = 60.0
    max_shelve_s: float = 8 * 3600.0
    source: str = ""  # the files it came from

    def flag_rules(self) -> list[FlagRule]:
        """The MCU's flag bits as rules, with the configured priority and text."""
        out = []
        for f in AlarmFlag:
            pri, text = self.flags.get(f.name, (Priority.MEDIUM, f.name))
            out.append(FlagRule(int(f), f.name, pri, text))
        return out

    def limit(self, channel: str) -> LimitRule | None:
        return next((r for r in self.limits if r.channel == channel), None)


def _typed(value: Any, kind: type, where: str) -> Any:
    """``value`` as ``kind`` or ValueError with ``where`` in the message."""
    if kind is Priority:
        try:
            return parse_priority(value)
        except ValueError as e:
            raise ValueError(f"{where}: {e}") from None
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where}: expected a number, got {value!r}")
        if not math.isfinite(value):
            raise ValueError(f"{where}: expected a finite number, got {value!r}")
        return float(value)
    if kind is bool:
        if not isinstance(value, bool):
            raise ValueError(f"{where}: expected true or false, got {value!r}")
        return value
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{where}: expected a whole number, got {value!r}")
        return value
    if not isinstance(value, str):
        raise ValueError(f"{where}: expected text, got {value!r}")
    return value


def _point(section: str, name: str, table: Any, where: str, problems: list[str]
           ) -> dict[str, Any] | None:
    """The checked keys of one point's table (None if the table is unusable)."""
    head = f"{where}: [{section}.{name}]"
    if not isinstance(table, dict):
        problems.append(f"{head}: expected a table of settings, got {table!r}")
        return None
    out: dict[str, Any] = {}
    ok = True
    for key, value in table.items():
        kind = _KEYS[section].get(key)
        if kind is None:
            problems.append(f"{head} {key}: unknown setting (known: "
                            f"{', '.join(sorted(_KEYS[section]))})")
            ok = False
            continue
        try:
            out[key] = _typed(value, kind, f"{head} {key}")
        except ValueError as e:
            problems.append(str(e))
            ok = False
    return out if ok else None


def _build(section: str, name: str, kw: dict[str, Any]):
    if section == "limit":
        return LimitRule(name, **kw)
    if section == "rate":
        return RateRule(name, **kw)
    if section == "stale":
        return StaleRule(name, **kw)
    if section == "flag":
        if name not in AlarmFlag.__members__:
            raise ValueError(f"unknown flag (known: {', '.join(AlarmFlag.__members__)})")
        return (kw.get("priority", Priority.MEDIUM), kw.get("text", name))
    if section == "setpoint":
        channel, _, sp_name = name.rpartition(".")
        if "value" not in kw:
            raise ValueError("a set-point needs a value")
        return SetPoint(channel, sp_name, **kw)
    if section == "gas":
        return GasRule(name, **kw)
    if section == "condition":
        return ConditionRule(name, kw.get("priority", Priority.MEDIUM), kw.get("text", ""))
    raise AssertionError(section)


def parse_alarm_config(data: dict[str, Any], where: str = "alarms",
                       base: dict[str, Any] | None = None) -> tuple[AlarmConfig, list[str]]:
    """An :class:`AlarmConfig` from parsed TOML ``data`` laid over ``base`` (both
    the raw tables); returns it and the problems found (never raises)."""
    problems: list[str] = []
    merged: dict[str, Any] = copy.deepcopy(base) if base else {}
    for section, tables in data.items():
        if section not in _SECTIONS:
            problems.append(f"{where}: unknown section [{section}] (known: "
                            f"{', '.join(_SECTIONS)})")
            continue
        if not isinstance(tables, dict):
            problems.append(f"{where}: [{section}] must be a table")
            continue
        if section in ("flood", "shelving"):
            checked = _point(section, "", tables, where, problems) if tables else {}
            if checked is not None:
                merged.setdefault(section, {}).update(checked)
            continue
        if section == "setpoint":
            tables = _flatten_setpoints(tables, where, problems)
        for name, table in tables.items():
            checked = _point(section, name, table, where, problems)
            if checked is None:
                continue
            old = merged.setdefault(section, {}).get(name, {})
            trial = {**old, **checked}
            try:
                _build(section, name, trial)
            except (ValueError, TypeError) as e:
                problems.append(f"{where}: [{section}.{name}]: {e}")
                continue
            merged[section][name] = trial
    cfg = AlarmConfig(source=where)
    for name, kw in merged.get("limit", {}).items():
        cfg.limits.append(_build("limit", name, kw))
    for name, kw in merged.get("rate", {}).items():
        cfg.rates.append(_build("rate", name, kw))
    for name, kw in merged.get("stale", {}).items():
        cfg.stale.append(_build("stale", name, kw))
    for name, kw in merged.get("flag", {}).items():
        cfg.flags[name] = _build("flag", name, kw)
    for name, kw in merged.get("condition", {}).items():
        cfg.conditions.append(_build("condition", name, kw))
    for name, kw in merged.get("setpoint", {}).items():
        cfg.setpoints.append(_build("setpoint", name, kw))
    for name, kw in merged.get("gas", {}).items():
        cfg.gas.append(_build("gas", name, kw))
    flood = merged.get("flood", {})
    n = flood.get("max_per_minute", cfg.flood_per_minute)
    if n < 1:
        problems.append(f"{where}: [flood] max_per_minute: must be >= 1, got {n}")
    else:
        cfg.flood_per_minute = n
    w = flood.get("window_s", cfg.flood_window_s)
    if w <= 0:
        problems.append(f"{where}: [flood] window_s: must be > 0, got {w}")
    else:
        cfg.flood_window_s = w
    m = merged.get("shelving", {}).get("max_s", cfg.max_shelve_s)
    if m <= 0:
        problems.append(f"{where}: [shelving] max_s: must be > 0, got {m}")
    else:
        cfg.max_shelve_s = m
    cfg._raw = merged  # type: ignore[attr-defined]
    return cfg, problems


def _flatten_setpoints(tables: dict[str, Any], where: str, problems: list[str]
                       ) -> dict[str, Any]:
    """``[setpoint.<channel>.<name>]`` tables as ``{"<channel>.<name>": table}``."""
    out: dict[str, Any] = {}
    for channel, points in tables.items():
        if "." in channel and isinstance(points, dict):  # already "<channel>.<name>"
            out[channel] = points
            continue
        if not isinstance(points, dict) or not all(isinstance(v, dict)
                                                   for v in points.values()):
            problems.append(f"{where}: [setpoint.{channel}] must hold one table per "
                            f"set-point, e.g. [setpoint.{channel}.a2]")
            continue
        for sp_name, table in points.items():
            out[f"{channel}.{sp_name}"] = table
    return out


def gas_rule(cfg: AlarmConfig, channel: str) -> GasRule | None:
    return next((g for g in cfg.gas if g.channel == channel), None)


def _read(path: Path) -> tuple[dict[str, Any] | None, str | None]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8")), None
    except FileNotFoundError:
        return None, f"{path}: file not found"
    except (OSError, UnicodeDecodeError) as e:
        return None, f"{path}: cannot be read ({e})"
    except tomllib.TOMLDecodeError as e:
        return None, f"{path}: not valid TOML ({e})"


_DEFAULT_CACHE: dict[str, Any] | None = None


def _default_raw() -> dict[str, Any]:
    global _DEFAULT_CACHE
    if _DEFAULT_CACHE is None:
        data, err = _read(DEFAULT_ALARMS_FILE)
        if data is None:  # the shipped file is missing: the built-in rules
            log.error("alarm defaults unusable (%s); built-in limits used", err)
            data = {"limit": {r.channel: {"high": r.high, "low": r.low, "deadband": r.deadband,
                                          "unit": r.unit, "label": r.label,
                                          "priority": r.priority.name}
                              for r in _builtin_limits()}}
            for t in data["limit"].values():
                for k in ("high", "low"):
                    if t[k] is None:
                        del t[k]
        _DEFAULT_CACHE = data
    return _DEFAULT_CACHE


def _builtin_limits():
    from app.core.alarms.rules import DEFAULT_LIMITS
    return DEFAULT_LIMITS


_SITE_FILE: Path | None = None


def use_alarm_file(path: str | Path | None) -> list[str]:
    """Make ``path`` (``--alarms FILE``, the desk configuration's ``alarms_file``)
    the desk's alarm rules from now on: :func:`default_alarm_config` returns the
    shipped rules overridden by it. Returns the problems found in it (the desk
    says them and carries on with what is valid); None goes back to the shipped
    rules."""
    global _SITE_FILE
    if path is None or str(path) == "":
        _SITE_FILE = None
        return []
    _SITE_FILE = Path(path).expanduser()
    _, problems = load_alarm_config(_SITE_FILE)
    return problems


def site_alarm_file() -> Path | None:
    return _SITE_FILE


def default_alarm_config() -> AlarmConfig:
    """The desk's rules: the shipped ``resources/alarms.toml``, overridden by the
    file given to :func:`use_alarm_file` if any."""
    if _SITE_FILE is not None:
        cfg, problems = load_alarm_config(_SITE_FILE)
    else:
        cfg, problems = parse_alarm_config(_default_raw(), DEFAULT_ALARMS_FILE.name)
    for p in problems:
        log.error("alarm rules: %s", p)
    return cfg


def load_alarm_config(path: str | Path | None = None) -> tuple[AlarmConfig, list[str]]:
    """The defaults overridden by the file at ``path`` (if any).

    Returns the configuration and the problems found; a file that cannot be
    read or parsed leaves the defaults in place, a bad entry keeps that point's
    default, and each problem names file, key and what is wrong."""
    base = _default_raw()
    if path is None:
        return parse_alarm_config(base, DEFAULT_ALARMS_FILE.name)
    p = Path(path)
    data, err = _read(p)
    if data is None:
        cfg, problems = parse_alarm_config(base, DEFAULT_ALARMS_FILE.name)
        return cfg, [f"{err}; the default alarm rules are kept"] + problems
    cfg, problems = parse_alarm_config(data, p.name, base=_checked_base(base))
    cfg.source = f"{DEFAULT_ALARMS_FILE.name} + {p}"
    return cfg, problems


def _checked_base(base: dict[str, Any]) -> dict[str, Any]:
    cfg, _ = parse_alarm_config(base, DEFAULT_ALARMS_FILE.name)
    return cfg._raw  # type: ignore[attr-defined]


def _toml_value(v: Any) -> str:
    if isinstance(v, Priority):
        return f'"{v.name}"'
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def dump_alarm_config(cfg: AlarmConfig) -> str:
    """``cfg`` as TOML that :func:`load_alarm_config` reads back to the same rules."""
    lines = ["[flood]", f"max_per_minute = {cfg.flood_per_minute}",
             f"window_s = {float(cfg.flood_window_s)!r}", "", "[shelving]",
             f"max_s = {float(cfg.max_shelve_s)!r}", ""]
    for r in cfg.limits:
        lines.append(f"[limit.{r.channel}]")
        for k in ("label", "unit", "high", "low", "deadband", "priority", "on_delay_s",
                  "off_delay_s", "source"):
            v = getattr(r, k)
            if v is None or v == "":
                continue
            lines.append(f"{k} = {_toml_value(v)}")
        lines.append("")
    for r in cfg.rates:
        lines.append(f"[rate.{r.channel}]")
        for k in ("label", "unit", "rise_per_min", "window_s", "deadband", "priority",
                  "on_delay_s", "off_delay_s", "source"):
            v = getattr(r, k)
            if v != "":
                lines.append(f"{k} = {_toml_value(v)}")
        lines.append("")
    for r in cfg.stale:
        lines.append(f"[stale.{r.channel}]")
        for k in ("label", "after_s", "priority", "source"):
            v = getattr(r, k)
            if v != "":
                lines.append(f"{k} = {_toml_value(v)}")
        lines.append("")
    for sp in cfg.setpoints:
        lines.append(f"[setpoint.{sp.channel}.{sp.name}]")
        for k in ("label", "unit", "value", "direction", "deadband", "priority", "latching",
                  "on_delay_s", "off_delay_s", "stage", "source"):
            v = getattr(sp, k)
            if v != "":
                lines.append(f"{k} = {_toml_value(v)}")
        lines.append("")
    for g in cfg.gas:
        lines.append(f"[gas.{g.channel}]")
        for k in ("gas", "label", "unit", "fault_below", "stuck_band", "stuck_s",
                  "fault_priority", "bump_test_days", "calibration_days", "service_priority",
                  "source"):
            v = getattr(g, k)
            if v != "":
                lines.append(f"{k} = {_toml_value(v)}")
        lines.append("")
    for name, (pri, text) in cfg.flags.items():
        lines += [f"[flag.{name}]", f"priority = {_toml_value(pri)}",
                  f"text = {_toml_value(text)}", ""]
    for c in cfg.conditions:
        lines += [f'[condition."{c.alarm_id}"]', f"priority = {_toml_value(c.priority)}",
                  f"text = {_toml_value(c.text)}", ""]
    return "\n".join(lines)
