"""Several set-points per channel, and the gas detector model (no Qt).

A :class:`SetPoint` is one alarm set-point of one channel with its own
direction (rising: alarm above the value; falling: alarm below it), priority,
deadband, on/off delays and *latching*. A latched alarm stays active after the
value returns inside its deadband until an operator resets it; a reset is not
an acknowledgement (ISA-18.2 clause 11: acknowledging silences, it never
clears a latched condition) and it is refused while the value is still beyond
the set-point less its deadband.

:class:`GasRule` is the fixed gas detection practice of IEC 60079-29-2
(selection, installation, use and maintenance of flammable gas detectors,
clause 8 "alarm set-points" and clause 10 "maintenance"), as every detector
maker ships it:

* alarm 1 (A1) at 10 %LEL, rising, self-resetting — the channel's ``[limit]``
  high alarm, or a set-point whose ``stage`` is ``A1``;
* alarm 2 (A2) at 20 %LEL, rising, latching until reset;
* over-range above 100 %LEL, latching (the sensor may be poisoned or
  saturated: the reading can no longer be trusted);
* sensor fault: the signal below ``fault_below`` (e.g. -5 %LEL, a drifted or
  broken sensor) or stuck — no change beyond ``stuck_band`` for ``stuck_s``
  while other channels keep updating (a frozen transmitter);
* bump tests and calibrations due every ``bump_test_days`` / ``calibration_days``
  (see :mod:`app.core.alarms.service`).

:func:`gas_stage` names the worst of them: ``normal``, ``A1``, ``A2``,
``over-range`` or ``fault``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from app.core.alarms.model import Priority
from app.core.alarms.rules import Debounce

__all__ = ["GAS_STAGES", "FaultTracker", "GasRule", "SetPoint", "SetPointTracker",
           "STAGE_RANK", "gas_stage"]

GAS_STAGES = ("normal", "A1", "A2", "over-range", "fault")
STAGE_RANK = {s: i for i, s in enumerate(GAS_STAGES)}


def _num(v, what: str, where: str, positive: bool = False) -> None:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ValueError(f"{where}: {what} must be a finite number, got {v!r}")
    if positive and v <= 0:
        raise ValueError(f"{where}: {what} must be > 0, got {v!r}")
    if not positive and what != "value" and v < 0:
        raise ValueError(f"{where}: {what} must be >= 0, got {v!r}")


@dataclass(frozen=True)
class SetPoint:
    """One set-point of ``channel``; its alarm id is ``"<channel>.<name>"``."""

    channel: str
    name: str
    value: float
    direction: str = "rising"  # "rising" (alarm above value) or "falling" (below)
    deadband: float = 0.0
    priority: Priority = Priority.MEDIUM
    latching: bool = False
    on_delay_s: float = 0.0
    off_delay_s: float = 0.0
    label: str = ""
    unit: str = ""
    stage: str = ""  # for a gas channel: "A1", "A2" or "over-range"
    source: str = ""

    def __post_init__(self) -> None:
        where = f"set-point {self.channel}.{self.name}"
        if not self.name or "." in self.name:
            raise ValueError(f"{where}: the name must be non-empty and without '.'")
        if self.name in ("high", "low", "rate", "stale", "fault"):
            raise ValueError(f"{where}: {self.name!r} is reserved for another rule")
        if self.direction not in ("rising", "falling"):
            raise ValueError(f"{where}: direction must be 'rising' or 'falling', "
                             f"not {self.direction!r}")
        _num(self.value, "value", where)
        _num(self.deadband, "deadband", where)
        _num(self.on_delay_s, "on_delay_s", where)
        _num(self.off_delay_s, "off_delay_s", where)
        if self.stage and self.stage not in GAS_STAGES[1:4]:
            raise ValueError(f"{where}: stage must be one of A1, A2, over-range, "
                             f"not {self.stage!r}")

    @property
    def key(self) -> str:
        return f"{self.channel}.{self.name}"

    @property
    def condition(self) -> str:
        """``high`` or ``low``: the alarm's text reads "above/below limit"."""
        return "high" if self.direction == "rising" else "low"


class SetPointTracker:
    """One set-point's condition: deadband, delays and the latch."""

    def __init__(self, sp: SetPoint) -> None:
        self.sp = sp
        self.debounce = Debounce(sp.on_delay_s, sp.off_delay_s)
        self.latched = False
        self.value: float | None = None

    def beyond(self, value: float, clearing: bool) -> bool:
        """Is ``value`` in alarm? ``clearing``: judged against the deadband."""
        sp = self.sp
        if sp.direction == "rising":
            return value > sp.value - sp.deadband if clearing else value > sp.value
        return value < sp.value + sp.deadband if clearing else value < sp.value

    def feed(self, value: float, t: float) -> bool | None:
        """The alarm's new state when it changes, else None."""
        self.value = value
        flip = self.debounce.feed(self.beyond(value, self.debounce.state), t)
        return self._latch(flip)

    def poll(self, t: float) -> bool | None:
        return self._latch(self.debounce.poll(t))

    def _latch(self, flip: bool | None) -> bool | None:
        if flip is True and self.sp.latching:
            self.latched = True
        if flip is False and self.latched:
            return None  # held until an operator resets it
        return flip

    def reset(self) -> tuple[bool, str]:
        """Release the latch: (True, "") when the condition clears now; (False,
        why) when it is refused because the value is still in alarm."""
        if not self.latched:
            return False, f"{self.sp.key} is not latched"
        v = self.value
        if v is not None and self.beyond(v, True):
            unit = f" {self.sp.unit}" if self.sp.unit else ""
            edge = (self.sp.value - self.sp.deadband if self.sp.direction == "rising"
                    else self.sp.value + self.sp.deadband)
            word = "below" if self.sp.direction == "rising" else "above"
            return False, (f"reset refused: {self.sp.label or self.sp.key} still "
                           f"{v:g}{unit}; it must be {word} {edge:g}{unit}")
        self.latched = False
        self.debounce.state = False
        self.debounce._since = None
        return True, ""


@dataclass(frozen=True)
class GasRule:
    """The gas detector model of one channel (see the module docstring)."""

    channel: str
    gas: str = "CH4"
    unit: str = "%LEL"
    label: str = "Gas"
    fault_below: float = -5.0
    stuck_band: float = 0.01
    stuck_s: float = 3600.0  # 0 turns the stuck check off
    fault_priority: Priority = Priority.HIGH
    bump_test_days: float = 30.0
    calibration_days: float = 180.0
    service_priority: Priority = Priority.LOW
    source: str = ""

    def __post_init__(self) -> None:
        where = f"gas rule for {self.channel!r}"
        _num(self.fault_below, "value", where)
        _num(self.stuck_band, "stuck_band", where)
        _num(self.stuck_s, "stuck_s", where)
        _num(self.bump_test_days, "bump_test_days", where, positive=True)
        _num(self.calibration_days, "calibration_days", where, positive=True)
        if not self.gas.strip():
            raise ValueError(f"{where}: gas must name the gas, e.g. 'CH4'")


class FaultTracker:
    """Sensor fault of a gas channel: below ``fault_below``, or stuck.

    Stuck: every sample for ``stuck_s`` within ``stuck_band`` of the value that
    started the still period, while some *other* channel's value moved in that
    period (so a robot whose every reading is frozen, or a silent link, is a
    stale-data matter, not a gas sensor fault)."""

    def __init__(self, rule: GasRule) -> None:
        self.rule = rule
        self.negative = False
        self.stuck = False
        self._still_v: float | None = None
        self._still_t = 0.0
        self._others_t: float | None = None  # last time another channel moved

    @property
    def active(self) -> bool:
        return self.negative or self.stuck

    def feed(self, value: float, t: float) -> None:
        r = self.rule
        self.negative = value < r.fault_below
        if self._still_v is None or abs(value - self._still_v) > r.stuck_band:
            self._still_v, self._still_t = value, t
        self.stuck = (r.stuck_s > 0 and t - self._still_t >= r.stuck_s
                      and self._others_t is not None and self._others_t > self._still_t)

    def other_moved(self, t: float) -> None:
        """Another channel's value changed at ``t``."""
        self._others_t = t

    def why(self) -> str:
        r = self.rule
        if self.negative:
            return f"{r.label} sensor fault: signal below {r.fault_below:g} {r.unit}"
        return f"{r.label} sensor fault: reading stuck for more than {r.stuck_s:g} s"


def gas_stage(active: set[str], fault: bool) -> str:
    """The worst stage among the active set-point stages (``fault`` wins)."""
    if fault:
        return "fault"
    return max(active | {"normal"}, key=lambda s: STAGE_RANK.get(s, 0))
