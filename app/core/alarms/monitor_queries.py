"""Questions put to the alarm monitor (no Qt): one alarm, the listed, active and
unacknowledged alarms in the order the operator reads them (most urgent, then
oldest), the priority standing on a channel, the gas stage, and the groups by
source shown during an alarm flood.

A mixin of :class:`~app.core.alarms.monitor.AlarmMonitor`, reading its entries.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from app.core.alarms.model import Alarm, AlarmState, Priority
from app.core.alarms.setpoints import gas_stage

__all__ = ["AlarmGroup", "AlarmQueries"]


@dataclass(frozen=True)
class AlarmGroup:
    """Listed alarms of one source, for the grouped view during a flood."""

    source: str
    priority: Priority  # the most urgent in the group
    count: int
    unacked: int
    keys: tuple[str, ...] = field(default=())


class AlarmQueries:
    """Read-only views of the monitor's alarms (mixin)."""

    def get(self, alarm_id: str) -> Alarm | None:
        e = self._entries.get(alarm_id)
        return None if e is None else e.snapshot()

    def state(self, alarm_id: str) -> AlarmState:
        e = self._entries.get(alarm_id)
        return AlarmState.NORMAL if e is None else e.state

    @staticmethod
    def _order(a: Alarm) -> tuple:
        return (-a.priority, a.raised_t)

    def alarms(self) -> list[Alarm]:
        """Every alarm the monitor has seen, in any state."""
        with self._lock:
            return sorted((e.snapshot() for e in self._entries.values()), key=self._order)

    def listed(self) -> list[Alarm]:
        """What the alarm list shows: every alarm not NORMAL, most urgent first."""
        return [a for a in self.alarms() if a.listed]

    def active(self) -> list[Alarm]:
        """Standing annunciated alarms (UNACK or ACKED), most urgent, then oldest first."""
        return [a for a in self.alarms()
                if a.state in (AlarmState.UNACK, AlarmState.ACKED)]

    def unacknowledged(self) -> list[Alarm]:
        return [a for a in self.alarms()
                if a.state in (AlarmState.UNACK, AlarmState.RTN_UNACK)]

    def most_severe(self) -> Alarm | None:
        act = self.active()
        return act[0] if act else None

    def most_severe_unacknowledged(self) -> Alarm | None:
        """The alarm for the header: the most urgent unacknowledged one, active
        before returned-to-normal, then the oldest."""
        un = sorted(self.unacknowledged(),
                    key=lambda a: (-a.priority, a.state is not AlarmState.UNACK, a.raised_t))
        return un[0] if un else None

    def is_active(self, key: str) -> bool:
        return self.state(key) in (AlarmState.UNACK, AlarmState.ACKED)

    def channel_priority(self, channel: str) -> Priority | None:
        """The highest priority standing on ``channel``, or None."""
        ps = [a.priority for a in self.active() if (a.channel or a.source) == channel]
        return max(ps) if ps else None

    def value_priority(self, channel: str) -> Priority | None:
        """The highest priority standing on ``channel``'s value (a limit, a rate of
        rise), or None. A stale-data alarm is left out: old data is shown with its
        age, never in a process alarm's colour (ISA-101)."""
        ps = [a.priority for a in self.active()
              if (a.channel or a.source) == channel and a.condition != "stale"]
        return max(ps) if ps else None

    @property
    def flood_active(self) -> bool:
        return self.flood.active

    def groups(self, within: Iterable[str] | None = None) -> list[AlarmGroup]:
        """Listed alarms grouped by source (the view during a flood), most urgent
        source first. ``within``: count and list only these keys (a filtered list);
        a group keeps the priority and the place its whole source has, and a
        source with none of them is left out."""
        by: dict[str, list[Alarm]] = {}
        for a in self.listed():  # the flood notice is its own group ("alarms")
            by.setdefault(a.source, []).append(a)
        out = [AlarmGroup(src, max(a.priority for a in al), len(al),
                          sum(1 for a in al if not a.acknowledged),
                          tuple(a.key for a in al)) for src, al in by.items()]
        out.sort(key=lambda g: (-g.priority, -g.count, g.source))
        if within is None:
            return out
        keep, kept = set(within), []
        for g in out:
            al = [a for a in by[g.source] if a.key in keep]
            if al:
                kept.append(AlarmGroup(g.source, g.priority, len(al),
                                       sum(1 for a in al if not a.acknowledged),
                                       tuple(a.key for a in al)))
        return kept

    def stage(self, channel: str) -> str | None:
        """The gas stage of ``channel`` (normal, A1, A2, over-range, fault), or
        None if it has no gas rule. Its ``high`` limit counts as A1."""
        if channel not in self._gas:
            return None
        act = {tr.sp.stage for k, tr in self._setpoints.items()
               if tr.sp.channel == channel and tr.sp.stage and self._raw_active(k)}
        if self._raw_active(f"{channel}.high"):
            act.add("A1")
        return gas_stage(act, self._raw_active(f"{channel}.fault"))

    def _raw_active(self, key: str) -> bool:
        e = self._entries.get(key)
        return bool(e and e.active)

