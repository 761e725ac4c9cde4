"""The desk's OPC UA address space: what the control room browses, and how each value
is written with its source timestamp and quality.

::

    Objects/StationPatrol
      Robot        Identity, LinkState, Mode, ModeCode, BatteryPercent, LeaseHolder,
                   DeskHoldsLease
        Pose       X, Y (m), Theta (rad)
        Patrol     State, Route, Index, Progress, Reason
      Environment  one variable per telemetry channel (app/core/desk/channels.py) with an
                   EngineeringUnits property (EUInformation, UNECE code, Part 8 §5.6.3)
      Meters       one object per gauge, created on its first reading: Value (its unit),
                   Confidence (0..1), State, Point
      Control      methods: StartPatrol, PausePatrol, ResumePatrol, ReturnToDock,
                   EmergencyStop
      Alarms       one object per desk alarm (its ConditionId), see alarms.py

Quality (StatusCode) follows the desk's freshness rules (app/core/freshness.py):
``Good`` while live, ``Uncertain_LastUsableValue`` while a periodic source has gone
quiet with the link up, ``Bad_NoCommunication`` once the link is lost (or, when the
site chooses it, ``Uncertain_NoCommunicationLastUsableValue`` with the last value);
before the first value ``Bad_WaitingForInitialData``. The value kept is the last one
received, with its source timestamp (when the desk received it from the robot); a Bad
code carries no value (Part 4 §7.7.1), the kept one is written again with the next
Good or Uncertain code.

What it costs: the pipeline's values are staged (:meth:`DeskSpace.set`, no I/O) and
written together by :meth:`DeskSpace.flush`, which the server runs at its subscriptions'
publishing rate, so a value that changes faster than a client is told is written once
per publishing interval, all with one server timestamp. A value whose value and quality
are what was last written is not written again until ``refresh_s`` has passed (its
newer source timestamp only): a subscription with the default trigger (StatusValue)
would not be told of it anyway. And the DataValues are :class:`_Frozen`: asyncua
deep-copies a written DataValue for every monitored item of the variable, which was
most of the server's cost; ours are never changed once written and hold only
immutable scalars, so the copy is the value itself.
"""

from __future__ import annotations

import asyncio
import math
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, NamedTuple

from asyncua import Server, ua

from app.interop.opcua.fast_path import scalar_variant, value_writer

__all__ = ["NS_URI", "QUALITY", "DeskSpace", "MeterValue", "eu_information", "quality_codes"]

NS_URI = "urn:station-patrol:desk"
UNECE_URI = "http://www.opcfoundation.org/UA/units/un/cefact"
GOOD = ua.StatusCodes.Good
STALE = ua.StatusCodes.UncertainLastUsableValue
NO_COMM = ua.StatusCodes.BadNoCommunication
NO_COMM_LAST = ua.StatusCodes.UncertainNoCommunicationLastUsableValue
WAITING = ua.StatusCodes.BadWaitingForInitialData
QUALITY = {"live": GOOD, "old": STALE, "no link": NO_COMM, "none": WAITING}
LINK_LOST = {"bad": NO_COMM, "uncertain": NO_COMM_LAST}


def quality_codes(link_lost: str = "bad") -> dict[str, int]:
    """The StatusCode of each freshness state; ``link_lost`` says which code a lost link
    gives: "bad" (Bad_NoCommunication: the value is null, OPC UA Part 4 §7.7.1 says a
    Bad value is to be ignored and asyncua sets it so) or "uncertain"
    (Uncertain_NoCommunicationLastUsableValue, Part 8: the last good value, sent)."""
    if link_lost not in LINK_LOST:
        raise ValueError(f"[opcua] link_lost_status must be \"bad\" or \"uncertain\", "
                         f"not {link_lost!r}")
    return {**QUALITY, "no link": LINK_LOST[link_lost]}

# the desk's unit text → UNECE Rec. 20 common code (P1: percent; %LEL and %RH are
# percentages, their display names say of what)
_UNECE = {"%LEL": "P1", "%RH": "P1", "%": "P1", "°C": "CEL", "V": "VLT", "m": "MTR",
          "m/s": "MTS", "rad/s": "2A", "rad": "C81", "bar": "BAR", "MPa": "MPA",
          "kPa": "KPA", "Pa": "PAL"}


def eu_information(unit: str) -> ua.EUInformation:
    """EUInformation for a unit text: UnitId from its UNECE code as Part 8 §5.6.3 says
    (each character shifted in, 8 bits at a time), -1 when the unit has no code."""
    code = _UNECE.get(unit)
    unit_id = -1
    if code is not None:
        unit_id = 0
        for ch in code:
            unit_id = (unit_id << 8) | ord(ch)
    return ua.EUInformation(NamespaceUri=UNECE_URI, UnitId=unit_id,
                            DisplayName=ua.LocalizedText(unit), Description=ua.LocalizedText(unit))


_STATUS: dict[int, ua.StatusCode] = {}
_NULL = ua.Variant(None, ua.VariantType.Null)


def _status(code: int) -> ua.StatusCode:
    """One StatusCode object per code (they are never changed)."""
    sc = _STATUS.get(code)
    if sc is None:
        sc = _STATUS[code] = ua.StatusCode(code)
    return sc


_EMPTY = {ua.VariantType.String: "", ua.VariantType.Double: float("nan"),
          ua.VariantType.Int32: 0, ua.VariantType.Boolean: False}


class _Frozen(ua.DataValue):
    """A DataValue that is never changed once written, holding an immutable scalar
    (float, int, str, bool) and datetimes: its copies are itself. asyncua deep-copies
    the DataValue it hands each monitored item (MonitoredItemValues.set_current_datavalue,
    so that a writer changing its object later cannot change what was sent), some
    0.1-0.2 ms a copy with two timestamps."""

    __slots__ = ()
    never_changed = True  # fast_path.py keeps it as it is

    def __copy__(self) -> _Frozen:
        return self

    def __deepcopy__(self, memo: dict) -> _Frozen:
        return self


def _same(a: Any, b: Any) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float)
                      and math.isnan(a) and math.isnan(b))


@dataclass
class _Item:
    node: Any
    vtype: ua.VariantType
    group: str  # whose freshness judges it: telemetry, pose, patrol, control, meter, desk
    value: Any = None
    t: float | None = None
    status: int = WAITING
    shown: tuple[Any, int] | None = None  # (value, status) last written
    shown_mono: float = -math.inf  # when (monotonic seconds)
    put: Any = None  # fast_path.value_writer of its node (None: asyncua's write)


def _desk_channels() -> list[tuple[str, str, str]]:
    """The desk's telemetry channels as (key, unit, label)."""
    from app.core.desk.channels import TELEMETRY_CHANNELS
    return [(c.key, c.unit, c.label) for c in TELEMETRY_CHANNELS]


class MeterValue(NamedTuple):
    """What the address space shows of a meter record (app/core/meter_service.py's
    MeterRecord has these fields, and more)."""

    gauge_id: str
    unit: str
    t: float  # UTC epoch seconds
    value: float | None
    confidence: float
    state: str
    point: str


class DeskSpace:
    """The nodes, their last values and qualities. Only the server's loop calls it.
    ``channels``: the telemetry channels as (key, unit, label) (default: the desk's,
    app/core/desk/channels.py; the desk gives them, so that the server's process need
    not import the desk's pipeline)."""

    def __init__(self, server: Server, refresh_s: float = 1.0,
                 channels: list[tuple[str, str, str]] | None = None) -> None:
        self.server = server
        self.channels = channels
        self.refresh_s = refresh_s
        self.items: dict[str, _Item] = {}
        self.status: dict[str, int] = {}
        self.dirty: set[str] = set()  # staged, not yet written
        self.staged = asyncio.Event()  # set when a value is staged
        self.writes = 0
        self.idx = 0
        self.control: Any = None
        self.root: Any = None
        self._meters: Any = None
        self._gauges: set[str] = set()

    async def build(self) -> None:
        s = self.server
        self.idx = idx = await s.register_namespace(NS_URI)
        root = await s.nodes.objects.add_object(ua.NodeId("StationPatrol", idx),
                                              ua.QualifiedName("StationPatrol", idx))
        robot = await root.add_object(ua.NodeId("Robot", idx), ua.QualifiedName("Robot", idx))
        S, D = ua.VariantType.String, ua.VariantType.Double
        for name, vt, group in (("Identity", S, "desk"), ("LinkState", S, "desk"),
                                ("Mode", S, "telemetry"), ("ModeCode", ua.VariantType.Int32,
                                                           "telemetry"),
                                ("LeaseHolder", S, "control"),
                                ("DeskHoldsLease", ua.VariantType.Boolean, "control")):
            await self._var(robot, f"Robot.{name}", name, vt, group)
        await self._var(robot, "Robot.BatteryPercent", "BatteryPercent", D, "telemetry", "%")
        pose = await robot.add_object(ua.NodeId("Robot.Pose", idx), ua.QualifiedName("Pose", idx))
        for name, unit in (("X", "m"), ("Y", "m"), ("Theta", "rad")):
            await self._var(pose, f"Robot.Pose.{name}", name, D, "pose", unit)
        patrol = await robot.add_object(ua.NodeId("Robot.Patrol", idx),
                                        ua.QualifiedName("Patrol", idx))
        for name, vt in (("State", S), ("Route", S), ("Index", ua.VariantType.Int32),
                         ("Progress", D), ("Reason", S)):
            await self._var(patrol, f"Robot.Patrol.{name}", name, vt, "patrol")
        env = await root.add_object(ua.NodeId("Environment", idx),
                                     ua.QualifiedName("Environment", idx))
        for key, unit, label in self.channels or _desk_channels():
            await self._var(env, f"Environment.{key}", key, D, "telemetry", unit,
                            description=label)
        self._meters = await root.add_object(ua.NodeId("Meters", idx),
                                             ua.QualifiedName("Meters", idx))
        self.control = await root.add_object(ua.NodeId("Control", idx),
                                             ua.QualifiedName("Control", idx))
        self.root = root

    async def _var(self, parent: Any, key: str, name: str, vtype: ua.VariantType, group: str,
                   unit: str | None = None, description: str = "") -> Any:
        node = await parent.add_variable(ua.NodeId(key, self.idx),
                                         ua.QualifiedName(name, self.idx),
                                         ua.Variant(_EMPTY[vtype], vtype), varianttype=vtype)
        if description:
            await node.write_attribute(ua.AttributeIds.Description, ua.DataValue(
                ua.Variant(ua.LocalizedText(description), ua.VariantType.LocalizedText)))
        if unit is not None:
            await node.add_property(self.idx, "EngineeringUnits", eu_information(unit))
        self.items[key] = _Item(node, vtype, group, _EMPTY[vtype],
                                put=value_writer(self.server, node.nodeid))
        await self._write(self.items[key], datetime.now(UTC), time.monotonic(), {})
        return node

    async def _ensure_gauge(self, gauge_id: str, unit: str) -> None:
        if gauge_id in self._gauges:
            return
        self._gauges.add(gauge_id)
        g = await self._meters.add_object(ua.NodeId(f"Meters.{gauge_id}", self.idx),
                                          ua.QualifiedName(gauge_id, self.idx))
        D, S = ua.VariantType.Double, ua.VariantType.String
        await self._var(g, f"Meters.{gauge_id}.Value", "Value", D, "meter", unit)
        await self._var(g, f"Meters.{gauge_id}.Confidence", "Confidence", D, "meter")
        await self._var(g, f"Meters.{gauge_id}.State", "State", S, "meter")
        await self._var(g, f"Meters.{gauge_id}.Point", "Point", S, "meter")

    # ------------------------------------------------------------ values
    def set(self, key: str, value: Any, t: float) -> None:
        """A new value received at ``t`` (UTC epoch seconds), with its group's quality:
        staged for the next :meth:`flush`."""
        item = self.items[key]
        if item.vtype == ua.VariantType.Double:
            value = float(value)
        item.value, item.t = value, t
        item.status = GOOD if item.group in ("desk", "meter") else \
            self.status.get(item.group, GOOD)
        self.dirty.add(key)
        self.staged.set()

    def set_quality(self, group: str, status: int) -> None:
        """A group's quality changed: its values are staged again with the new code (a
        value never received stays Bad_WaitingForInitialData)."""
        if self.status.get(group) == status:
            return
        self.status[group] = status
        for key, item in self.items.items():
            if item.group == group and item.t is not None and item.status != status:
                item.status = status
                self.dirty.add(key)
                self.staged.set()

    async def flush(self) -> int:
        """Write the staged values, all with one server timestamp; returns how many.
        One whose value and quality were last written as they are now waits (staged)
        until ``refresh_s`` after that write."""
        if not self.dirty:
            return 0
        now, server_ts, stamps = time.monotonic(), datetime.now(UTC), {}
        n = 0
        for key in list(self.dirty):
            item = self.items[key]
            shown = item.shown
            if shown is not None and shown[1] == item.status and \
                    _same(shown[0], item.value) and now - item.shown_mono < self.refresh_s:
                continue
            self.dirty.discard(key)
            dv = self._datavalue(item, server_ts, stamps)
            if item.put is not None:
                rest = item.put(dv)  # not a coroutine (fast_path.value_writer)
                if rest is not None:
                    await rest
            else:
                await self.server.write_attribute_value(item.node.nodeid, dv)
            item.shown, item.shown_mono = (item.value, item.status), now
            n += 1
        self.writes += n
        return n

    @staticmethod
    def _datavalue(item: _Item, server_ts: datetime,
                   stamps: dict[float, datetime]) -> _Frozen:
        t = item.t
        if t is None:
            source_ts = None
        else:  # the values of one message share their timestamp: convert it once
            source_ts = stamps.get(t)
            if source_ts is None:
                source_ts = stamps[t] = datetime.fromtimestamp(t, UTC)
        status = _status(item.status)
        # a Bad code's value is null (Part 4 §7.7.1; asyncua's write makes it so too)
        variant = _NULL if status.is_bad() else scalar_variant(item.value, item.vtype)
        return _Frozen(variant, StatusCode=status, SourceTimestamp=source_ts,
                       ServerTimestamp=server_ts)

    async def _write(self, item: _Item, server_ts: datetime, now: float,
                     stamps: dict[float, datetime]) -> None:
        dv = self._datavalue(item, server_ts, stamps)
        rest = item.put(dv) if item.put is not None else \
            self.server.write_attribute_value(item.node.nodeid, dv)
        if rest is not None:
            await rest
        item.shown, item.shown_mono = (item.value, item.status), now
        self.writes += 1

    async def meter(self, rec: Any) -> None:
        gid = str(rec.gauge_id)
        await self._ensure_gauge(gid, str(rec.unit))
        t = float(rec.t)
        value = float("nan") if rec.value is None else float(rec.value)
        self.set(f"Meters.{gid}.Value", value, t)
        self.set(f"Meters.{gid}.Confidence", float(rec.confidence), t)
        self.set(f"Meters.{gid}.State", str(rec.state), t)
        self.set(f"Meters.{gid}.Point", str(rec.point), t)
