"""Alarm management by ISA-18.2 (no Qt).

* :mod:`.model` — priorities, the ISA-18.2 states and :func:`next_state` (the
  state diagram), the :class:`Alarm` snapshot and the :class:`Transition`
  record every listener receives;
* :mod:`.rules` — limits with deadband and on/off delays, rate of rise, stale
  data, the MCU's flag bits, discrete conditions;
* :mod:`.flood` — the alarm flood guard;
* :mod:`.monitor` — :class:`AlarmMonitor`, the manager that ties them together;
* :mod:`.config` — the TOML rule file, validated with clear messages.

docs/alarms.md describes the life cycle, the rules and the file.
"""

from app.core.alarms.config import (
    DEFAULT_ALARMS_FILE,
    AlarmConfig,
    default_alarm_config,
    dump_alarm_config,
    load_alarm_config,
    parse_alarm_config,
    site_alarm_file,
    use_alarm_file,
)
from app.core.alarms.flood import FloodGuard
from app.core.alarms.model import (
    Alarm,
    AlarmChange,
    AlarmEvent,
    AlarmState,
    Priority,
    Transition,
    next_state,
    parse_priority,
    parse_state,
    select_alarms,
)
from app.core.alarms.monitor import FLOOD_ID, MAX_SHELVE_S, AlarmGroup, AlarmMonitor
from app.core.alarms.rules import (
    DEFAULT_LIMITS,
    ConditionRule,
    Debounce,
    FlagRule,
    LimitRule,
    LimitTracker,
    RateRule,
    RateTracker,
    StaleRule,
    slope_per_min,
)

AlarmManager = AlarmMonitor

__all__ = [
    "Alarm", "AlarmChange", "AlarmConfig", "AlarmEvent", "AlarmGroup", "AlarmManager",
    "AlarmMonitor", "AlarmState", "ConditionRule", "Debounce", "DEFAULT_ALARMS_FILE",
    "DEFAULT_LIMITS", "FLOOD_ID", "FlagRule", "FloodGuard", "LimitRule", "LimitTracker",
    "MAX_SHELVE_S", "Priority", "RateRule", "RateTracker", "StaleRule", "Transition",
    "default_alarm_config", "dump_alarm_config", "load_alarm_config", "next_state",
    "parse_alarm_config", "parse_priority", "parse_state", "select_alarms", "site_alarm_file",
    "slope_per_min", "use_alarm_file",
]
