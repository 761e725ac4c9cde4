"""The desk's model of a four-wheel-steer patrol robot (no Qt): the four wheels'
steering angles and speeds with the steering mode (``WHEEL_STATE``), and the
TEB local plan (``TEB_PLAN``) — app/comm/fws_protocol.py.

:meth:`FwsModel.wheels_view` turns the last wheel state and its
:class:`~app.core.freshness.Freshness` into what the wheel display draws: per
wheel its place on the chassis, angle and speed, the mode, and whether the
whole is stale (then with "last known HH:MM:SS, N s ago"): a stale value is
never presented as live. :meth:`FwsModel.teb_view` does the same for the map's
overlay of the TEB plan.

:meth:`FwsModel.wheel_record` is the compact record of the wheels the desk
keeps (archive event ``fws_wheels``, so the report and the MCAP export's
``/events`` show it): one on every change of steering mode, and at most every
``WHEEL_RECORD_S`` of desk time while the wheels turn — the mode, the MCU's
time, and the four angles (0.1°) and speeds (mm/s).

:meth:`FwsModel.teb_record` is the compact record of the TEB plans (archive
event ``fws_teb``; replay turns it back into a :class:`TebPlan` for the map's
overlay, the MCAP export draws it on ``/path/teb``): at once when the base
starts or stops turning in place, otherwise at most every ``TEB_RECORD_S`` of
desk time and only when the plan changed (an end moved by more than
``TEB_MOVED_M``) — at most ``TEB_RECORD_POSES`` poses (every k-th, the last
kept; the intervals between kept poses summed), positions to the centimetre,
headings to 0.01 rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.comm.fws_protocol import WHEELS, TebPlan, WheelState
from app.core.freshness import Age, Freshness
from app.core.kinematics import FwsGeometry

__all__ = ["TEB_EVENT", "TEB_RECORD_S", "WHEEL_RECORD_S", "FwsModel", "TebView", "WheelView",
           "WheelsView", "teb_plan_from_record"]

WHEEL_RECORD_S = 2.0
TEB_EVENT = "fws_teb"  # the archive event of a TEB plan: data for the map, not a happening
TEB_RECORD_S = 1.0
TEB_MOVED_M = 0.05
TEB_RECORD_POSES = 16


@dataclass(frozen=True)
class WheelView:
    name: str  # front_left, front_right, rear_left, rear_right
    x: float  # place on the chassis: forward, in units of half the wheelbase
    y: float  # to the left, in units of half the wheelbase
    angle_deg: float
    speed_mps: float


@dataclass(frozen=True)
class WheelsView:
    """What the wheel display shows. ``wheels`` is empty before any state arrived."""

    wheels: tuple[WheelView, ...]
    mode: str
    stale: bool
    note: str  # "" while live; "last known …" when stale; why nothing is shown

    @property
    def shown(self) -> bool:
        return bool(self.wheels)


@dataclass(frozen=True)
class TebView:
    """The TEB plan for the map: xy (n × 2) and whether it is stale."""

    xy: np.ndarray
    turning_in_place: bool
    stale: bool


class FwsModel:
    """The last wheel state and TEB plan received, and how many of each."""

    def __init__(self, geometry: FwsGeometry | None = None) -> None:
        g = geometry or FwsGeometry()
        half = g.wheelbase_m / 2
        self.layout = g.wheel_xy / half  # FL, FR, RL, RR in units of half the wheelbase
        self.wheels: WheelState | None = None
        self.teb: TebPlan | None = None
        self.counts = {"wheels": 0, "teb": 0}
        self._recorded: tuple[str, float] | None = None  # mode and desk time of the last record
        self._teb_recorded: tuple[bool, float, np.ndarray] | None = None  # turning, t, ends

    def ingest(self, msg) -> str:
        """A 4WS message; returns its kind ("wheels" or "teb"). TypeError for
        anything else, ValueError for values that are not finite."""
        if isinstance(msg, WheelState):
            vals = tuple(msg.angles_rad) + tuple(msg.speeds_mps)
            if len(vals) != 8 or not all(math.isfinite(float(v)) for v in vals):
                raise ValueError("a wheel state needs four finite angles and speeds")
            self.wheels = msg
            kind = "wheels"
        elif isinstance(msg, TebPlan):
            if not np.all(np.isfinite(np.asarray(msg.poses, dtype=float))):
                raise ValueError("a TEB plan with values that are not finite")
            self.teb = msg
            kind = "teb"
        else:
            raise TypeError(f"not a 4WS message: {type(msg).__name__}")
        self.counts[kind] += 1
        return kind

    def wheel_record(self, t: float) -> dict | None:
        """The record of the last wheel state to keep at desk time ``t`` (see the
        module docstring), or None when it would repeat the last one."""
        w = self.wheels
        if w is None:
            return None
        mode = w.mode_name
        turning = any(abs(float(v)) > 1e-3 for v in w.speeds_mps)
        last = self._recorded
        if last is not None and mode == last[0] and not (turning and t - last[1]
                                                        >= WHEEL_RECORD_S):
            return None
        self._recorded = (mode, t)
        return {"mode": mode, "mcu_time_ms": int(w.mcu_time_ms),
                "angles_deg": [round(math.degrees(float(a)), 1) for a in w.angles_rad],
                "speeds_mps": [round(float(v), 3) for v in w.speeds_mps]}

    def teb_record(self, t: float) -> dict | None:
        """The record of the last TEB plan to keep at desk time ``t`` (see the
        module docstring), or None when it is too soon or nothing changed."""
        plan = self.teb
        if plan is None or len(plan.poses) == 0:
            return None
        poses = np.asarray(plan.poses, dtype=float).reshape(-1, 3)
        turning = bool(plan.turning_in_place)
        ends = np.r_[poses[0, :2], poses[-1, :2]]
        last = self._teb_recorded
        if last is not None and turning == last[0] and (
                t - last[1] < TEB_RECORD_S or np.max(np.abs(ends - last[2])) <= TEB_MOVED_M):
            return None
        self._teb_recorded = (turning, t, ends)
        n = len(poses)
        keep = np.unique(np.r_[np.arange(0, n, max(1, -(-n // TEB_RECORD_POSES))), n - 1])
        if len(keep) > TEB_RECORD_POSES:  # the last one replaces the one before it
            keep = np.r_[keep[:TEB_RECORD_POSES - 1], n - 1]
        dts = np.asarray(plan.dts_s, dtype=float).reshape(-1)
        cum = np.r_[0.0, np.cumsum(dts)] if len(dts) == n - 1 else np.arange(n, dtype=float)
        return {"turning_in_place": turning,
                "poses": [[round(float(x), 2), round(float(y), 2), round(float(th), 2)]
                          for x, y, th in poses[keep]],
                "dts_s": [round(float(d), 3) for d in np.diff(cum[keep])]}

    def wheels_view(self, freshness: Freshness) -> WheelsView:
        w = self.wheels
        if w is None or freshness.age is Age.NONE:
            return WheelsView((), "", False, "no wheel data")
        wheels = tuple(
            WheelView(name, float(self.layout[i, 0]), float(self.layout[i, 1]),
                      math.degrees(float(w.angles_rad[i])), float(w.speeds_mps[i]))
            for i, name in enumerate(WHEELS))
        return WheelsView(wheels, w.mode_name, freshness.stale, freshness.text())

    def teb_view(self, freshness: Freshness) -> TebView | None:
        t = self.teb
        if t is None or freshness.age is Age.NONE or len(t.poses) == 0:
            return None
        return TebView(np.asarray(t.poses[:, :2], dtype=float), bool(t.turning_in_place),
                       freshness.stale)


def teb_plan_from_record(rec: dict) -> TebPlan:
    """A :class:`TebPlan` from an ``fws_teb`` record (:meth:`FwsModel.teb_record`).
    ValueError for a record that is not one."""
    try:
        poses = np.asarray(rec["poses"], dtype=np.float32).reshape(-1, 3)
        dts = np.asarray(rec.get("dts_s", []), dtype=np.float32).reshape(-1)
        turning = bool(rec.get("turning_in_place", False))
    except (KeyError, TypeError, ValueError) as e:
        raise ValueError(f"not a TEB plan record: {e}") from None
    if len(poses) and len(dts) != len(poses) - 1:
        raise ValueError(f"a TEB plan record of {len(poses)} poses with {len(dts)} intervals")
    if not (np.all(np.isfinite(poses)) and np.all(np.isfinite(dts))):
        raise ValueError("a TEB plan record with values that are not finite")
    return TebPlan(turning, poses, dts)
