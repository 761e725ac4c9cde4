"""The ISA-18.2 alarm states, the transitions between them, and the records
that carry them (no Qt).

ISA-18.2 (ANSI/ISA-18.2-2016, "Management of Alarm Systems for the Process
Industries", clause 11, the alarm state transition diagram) names these states;
the letters are the standard's:

* A **normal** — process in range, nothing to acknowledge (``NORMAL``);
* B **unacknowledged** — the alarm is active and annunciated, the operator has
  not yet acknowledged it (``UNACK``);
* C **acknowledged** — active and acknowledged (``ACKED``);
* D **returned to normal unacknowledged** — the condition cleared before the
  operator acknowledged it; it stays listed until acknowledged (``RTN_UNACK``);
* E **shelved** — suppressed by the operator for a set time with a reason; it
  returns by itself when the time is up (``SHELVED``);
* G **out of service** — removed for maintenance by an authorised person
  (``OUT_OF_SERVICE``).

(F, suppressed by design, is not used by this desk.)

:func:`next_state` is the whole diagram as a pure function; the monitor only
keeps the bookkeeping around it. A :class:`Transition` is one edge taken, and
:meth:`Transition.as_record` is the form every listener (and so the archive)
receives.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from app.core.i18n import QT_TRANSLATE_NOOP, translate

# the labels and texts of the shipped alarm rules (resources/alarms.toml, the default
# rules, the monitor's derived labels), marked so the desk shows them translated; a
# site's own labels are shown as written
SHIPPED_TEXTS = (
    QT_TRANSLATE_NOOP("AlarmText", "Gas"), QT_TRANSLATE_NOOP("AlarmText", "Temperature"),
    QT_TRANSLATE_NOOP("AlarmText", "Humidity"), QT_TRANSLATE_NOOP("AlarmText", "Battery"),
    QT_TRANSLATE_NOOP("AlarmText", "Gas A2"), QT_TRANSLATE_NOOP("AlarmText", "Gas over-range"),
    QT_TRANSLATE_NOOP("AlarmText", "Gas high (robot)"),
    QT_TRANSLATE_NOOP("AlarmText", "Temperature high (robot)"),
    QT_TRANSLATE_NOOP("AlarmText", "Humidity high (robot)"),
    QT_TRANSLATE_NOOP("AlarmText", "Obstacle near"),
    QT_TRANSLATE_NOOP("AlarmText", "Battery low (robot)"),
    QT_TRANSLATE_NOOP("AlarmText", "Fail-safe stop"),
    QT_TRANSLATE_NOOP("AlarmText", "Emergency stop active"),
    QT_TRANSLATE_NOOP("AlarmText", "Sensor fault"),
    QT_TRANSLATE_NOOP("AlarmText", "Link to the robot lost"),
    QT_TRANSLATE_NOOP("AlarmText", "Archive writes failing (data held in memory)"),
    QT_TRANSLATE_NOOP("AlarmText", "Gas sensor fault"),
    QT_TRANSLATE_NOOP("AlarmText", "Gas rate of rise"),
    QT_TRANSLATE_NOOP("AlarmText", "Gas stale"),
    QT_TRANSLATE_NOOP("AlarmText", "Temperature stale"),
    QT_TRANSLATE_NOOP("AlarmText", "Humidity stale"),
    QT_TRANSLATE_NOOP("AlarmText", "Battery stale"),
)

__all__ = [
    "Alarm", "AlarmChange", "AlarmEvent", "AlarmState", "Priority", "Transition",
    "next_state", "parse_priority", "parse_state", "select_alarms",
]


class Priority(enum.IntEnum):
    """Alarm priority (ISA-18.2 clause 6.5); higher is more urgent."""

    LOW = 1
    MEDIUM = 2
    HIGH = 3
    EMERGENCY = 4


def parse_priority(text: str | Priority) -> Priority:
    """``"high"``/``"HIGH"``/``Priority.HIGH`` → ``Priority.HIGH``; ValueError otherwise."""
    if isinstance(text, Priority):
        return text
    if isinstance(text, str) and text.strip().upper() in Priority.__members__:
        return Priority[text.strip().upper()]
    raise ValueError(f"unknown priority {text!r} (one of "
                     f"{', '.join(p.name for p in sorted(Priority, reverse=True))})")


class AlarmState(enum.Enum):
    """ISA-18.2 alarm states (see the module docstring for the letters)."""

    NORMAL = "NORMAL"
    UNACK = "UNACK"
    ACKED = "ACKED"
    RTN_UNACK = "RTN_UNACK"
    SHELVED = "SHELVED"
    OUT_OF_SERVICE = "OUT_OF_SERVICE"


def parse_state(text: str | AlarmState) -> AlarmState:
    if isinstance(text, AlarmState):
        return text
    try:
        return AlarmState(str(text).strip().upper())
    except ValueError:
        raise ValueError(f"unknown alarm state {text!r}") from None


class AlarmEvent(enum.Enum):
    """What can happen to one alarm."""

    ACTIVATE = "activate"  # the condition became true (after its on-delay)
    CLEAR = "clear"  # the condition became false (after its off-delay)
    ACK = "acknowledge"  # the operator acknowledged
    SHELVE = "shelve"
    UNSHELVE = "unshelve"  # by the operator, or the shelving time ran out
    REMOVE = "out_of_service"
    RETURN = "in_service"


S, E = AlarmState, AlarmEvent

# (state, event) -> next state; pairs not listed leave the state as it is.
# ACTIVATE/CLEAR while shelved or out of service change nothing visible: the
# condition is tracked and decides the state on unshelve / return to service.
_TABLE: dict[tuple[AlarmState, AlarmEvent], AlarmState] = {
    (S.NORMAL, E.ACTIVATE): S.UNACK,
    (S.UNACK, E.ACK): S.ACKED,
    (S.UNACK, E.CLEAR): S.RTN_UNACK,
    (S.ACKED, E.CLEAR): S.NORMAL,
    (S.RTN_UNACK, E.ACK): S.NORMAL,
    (S.RTN_UNACK, E.ACTIVATE): S.UNACK,
}
_SHELVABLE = (S.NORMAL, S.UNACK, S.ACKED, S.RTN_UNACK)


def next_state(state: AlarmState, event: AlarmEvent, active: bool) -> AlarmState:
    """The state after ``event`` in ``state``; ``active`` is the alarm condition
    *after* the event (it decides where unshelving and return to service lead).

    >>> next_state(AlarmState.NORMAL, AlarmEvent.ACTIVATE, True).name
    'UNACK'
    """
    if event is E.SHELVE:
        return S.SHELVED if state in _SHELVABLE else state
    if event is E.UNSHELVE:
        if state is not S.SHELVED:
            return state
        return S.UNACK if active else S.NORMAL
    if event is E.REMOVE:
        return S.OUT_OF_SERVICE
    if event is E.RETURN:
        if state is not S.OUT_OF_SERVICE:
            return state
        return S.UNACK if active else S.NORMAL
    return _TABLE.get((state, event), state)


def beside_limit(value: float, limit: float) -> str:
    """``value`` with one decimal, or more (up to four) when one decimal would read
    the same as ``limit`` ("1.25 above limit 1.2", not "1.2 above limit 1.2").

    >>> beside_limit(12.54, 10.0), beside_limit(1.25, 1.2)
    ('12.5', '1.25')
    """
    for digits in range(1, 5):
        text = f"{value:.{digits}f}"
        if float(text) != limit or value == limit:
            return text
    return text


@dataclass(frozen=True)
class Alarm:
    """A snapshot of one alarm: what it is, its state and its latest value.

    ``key`` is the stable alarm id ("gas_lel_pct.high", "link.lost",
    "flag.FAILSAFE_STOP"); ``source`` names where it comes from (the channel,
    "link", "robot", "meter:<point>", "archive", "alarms"); ``active`` is the
    alarm *condition*, which under shelving or out of service may differ from
    what the operator is shown.
    """

    key: str
    source: str
    condition: str  # "high" | "low" | "rate" | "stale" | flag name | condition name
    priority: Priority
    raised_t: float  # UTC epoch seconds of the latest activation
    value: float | None  # value when raised
    limit: float | None
    unit: str = ""
    label: str = ""
    active: bool = True
    cleared_t: float | None = None
    last_value: float | None = None
    state: AlarmState = AlarmState.UNACK
    channel: str | None = None  # the measured channel behind it, if any
    description: str = ""  # fixed text of a discrete condition
    acked_t: float | None = None
    acked_by: str | None = None
    shelved_until: float | None = None
    reason: str | None = None  # shelving / out-of-service reason
    in_flood: bool = False  # raised while the flood guard was on
    # the latest comment on this occurrence (e.g. a control room's OPC UA AddComment):
    # its text, who made it and when; a new occurrence starts without one
    comment: str | None = None
    comment_by: str | None = None
    comment_t: float | None = None

    @property
    def text(self) -> str:
        """One line for the operator, e.g. "Gas 12.5 %LEL above limit 10 %LEL" (in the
        desk's language: app/core/i18n; shipped labels are in SHIPPED_TEXTS)."""
        name = translate("AlarmText", self.label or self.source)
        unit = f" {self.unit}" if self.unit else ""
        v = self.last_value if self.last_value is not None else self.value
        if self.description:
            return translate("AlarmText", self.description)
        if self.condition in ("high", "low") and self.limit is not None and v is not None:
            words = (translate("Alarm", "{name} {value}{unit} above limit {limit}{unit}")
                     if self.condition == "high" else
                     translate("Alarm", "{name} {value}{unit} below limit {limit}{unit}"))
            return words.format(name=name, value=beside_limit(v, self.limit), unit=unit,
                                limit=f"{self.limit:g}")
        if self.condition == "rate" and self.limit is not None and v is not None:
            return translate("Alarm", "{name} rising {value}{unit}/min (limit {limit}{unit}/min)"
                             ).format(name=name, value=f"{v:.2f}", unit=unit,
                                      limit=f"{self.limit:g}")
        if self.condition == "stale" and self.limit is not None:
            return translate("Alarm", "{name}: no data for more than {limit} s").format(
                name=name, limit=f"{self.limit:g}")
        return name if self.label else f"{self.source}: {self.condition}"

    @property
    def cleared_text(self) -> str:
        """One line for the return to normal."""
        name = translate("AlarmText", self.label or self.source)
        if self.condition not in ("high", "low") or self.limit is None:
            return translate("Alarm", "{text}: cleared").format(text=self.text)
        unit = f" {self.unit}" if self.unit else ""
        v = self.last_value if self.last_value is not None else self.value
        return translate("Alarm", "{name} back to {value}{unit} (limit {limit}{unit})").format(
            name=name, value=beside_limit(v, self.limit), unit=unit, limit=f"{self.limit:g}")

    @property
    def acknowledged(self) -> bool:
        return self.state in (AlarmState.NORMAL, AlarmState.ACKED)

    @property
    def listed(self) -> bool:
        """Shown in the alarm list (everything but NORMAL)."""
        return self.state is not AlarmState.NORMAL


@dataclass(frozen=True)
class Transition:
    """One edge of the ISA-18.2 state diagram taken by one alarm."""

    alarm: Alarm  # the alarm after the transition
    t: float  # UTC epoch seconds
    from_state: AlarmState
    to_state: AlarmState
    event: AlarmEvent
    user: str | None = None
    reason: str | None = None  # shelving reason, the comment given with an ack, "reset"
    origin: str | None = None  # where the user acted from, when not at this desk

    @property
    def raised(self) -> bool:
        """True when this transition annunciates the alarm (to UNACK)."""
        return self.to_state is AlarmState.UNACK and self.from_state is not AlarmState.UNACK

    @property
    def cleared(self) -> bool:
        """True when the alarm's condition returned to normal in this transition."""
        return self.event is AlarmEvent.CLEAR

    def as_record(self) -> dict:
        """The flat form listeners store (keys fixed by the archive's schema)."""
        a = self.alarm
        v = a.last_value if a.last_value is not None else a.value
        return {
            "t": float(self.t), "alarm": a.key, "source": a.source,
            "priority": a.priority.name, "from_state": self.from_state.value,
            "to_state": self.to_state.value,
            "value": None if v is None else float(v),
            "limit": None if a.limit is None else float(a.limit),
            "unit": a.unit, "text": a.text, "user": self.user, "reason": self.reason,
            "origin": self.origin,
        }


# Older name: each change the monitor reports is a transition.
AlarmChange = Transition


def select_alarms(alarms, *, states=None, priorities=None, sources=None) -> list[Alarm]:
    """The alarms whose state, priority and source are in the given sets (None:
    any). A source filter ``"meter"`` also matches ``"meter:P3"``."""
    out = []
    for a in alarms:
        if states is not None and a.state not in states:
            continue
        if priorities is not None and a.priority not in priorities:
            continue
        if sources is not None and not any(
                a.source == s or a.source.startswith(f"{s}:") for s in sources):
            continue
        out.append(a)
    return out
