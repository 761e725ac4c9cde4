"""Archive rows back into the messages the link delivers (no Qt).

Replay goes through the same ingest path as live data: :class:`ReplayFeed`
reads the archive's rows in a window of recorded time and turns each into the
message object the live link would have delivered (``P.Telemetry`` with its
``received_s`` and ``seq``, ``P.Pose``, a ``DecodedFrame`` from a stored
snapshot — its JPEG kept —, ``P.MapImage``, ``P.Path``, ``P.Event``,
``P.PatrolStatus``, a 4WS robot's ``TebPlan`` from its ``fws_teb`` records),
as ``(t, kind, message)`` in time order. The caller hands
them to :meth:`DeskPipeline.ingest` of a replay pipeline (which records
nothing and sends nothing). The recorded alarm transitions come out as
``alarm_transition`` items: a replay repeats the operator's recorded actions
with :func:`mirror_handling`; the alarms themselves are raised and cleared by
the pipeline's monitor from the replayed telemetry.
"""

from __future__ import annotations

import logging
import math
import struct
from typing import Any

import numpy as np

from app.comm import protocol as P
from app.core.desk.fws import TEB_EVENT, teb_plan_from_record
from app.core.replay import Window
from app.core.video import DecodedFrame, decode_jpeg_rgb

__all__ = ["LOOKBACK_S", "ReplayFeed", "mirror_handling", "png_size"]

log = logging.getLogger(__name__)

_TELEMETRY_INT = {"alarm_flags", "mode", "mcu_time_ms", "tel_seq"}
_TELEMETRY_FIELDS = set(P.Telemetry.__dataclass_fields__)
_PATH_KINDS = {"global": P.Path.GLOBAL, "plan": P.Path.GLOBAL, "0": P.Path.GLOBAL,
               "local": P.Path.LOCAL, "1": P.Path.LOCAL}
LOOKBACK_S = 6 * 3600.0  # how far back a seek looks for the last map, path, snapshot


def png_size(png: bytes) -> tuple[int, int]:
    if len(png) >= 24 and png.startswith(b"\x89PNG\r\n\x1a\n"):
        w, h = struct.unpack(">II", png[16:24])
        return int(w), int(h)
    return 0, 0


class ReplayFeed:
    """Messages from ``archive`` (its read API only: telemetry_rows, poses, snapshots,
    snapshot, paths, events, alarm_transitions, latest_map)."""

    def __init__(self, archive: Any, *, prime_s: float = 60.0) -> None:
        self.archive = archive
        self.prime_s = float(prime_s)
        self._last_values: dict[str, float] = {}
        self._map_geometry: dict[str, Any] = {}
        self._route_points: list[dict] = []  # the patrol's points, last recorded with them
        self.bad_snapshots = 0
        self.bad_records = 0  # archived records that do not make their message

    def rewind(self) -> None:
        self._last_values.clear()

    # ------------------------------------------------------------ windows
    def window(self, w: Window) -> list[tuple[float, str, Any]]:
        """What the archive holds in the window ``w``, in time order."""
        a = self.archive
        out: list[tuple[float, str, Any]] = []
        t, seq, names, vals = a.telemetry_rows(w.start, w.end)
        keep = np.ones(len(t), bool) if w.inclusive else t > w.start
        out += self._telemetry(t[keep], seq[keep], names, vals[keep])
        out += [(float(r[0]), "pose", _pose(r)) for r in a.poses(w.start, w.end)
                if w.contains(r[0])]
        for s in a.snapshots(w.start, w.end):
            if w.contains(s["t"]):
                out += self._snapshot(s)
        out += [(float(m["t"]), "path", _path(m)) for m in a.paths(w.start, w.end)
                if w.contains(m["t"])]
        for ev in a.events(w.start, w.end):
            if w.contains(ev["t"]):
                out += self._event(ev)
        out += [(float(tr["t"]), "alarm_transition", dict(tr))
                for tr in a.alarm_transitions(w.start, w.end) if w.contains(tr["t"])]
        out.sort(key=lambda item: item[0])  # stable: same-time rows keep their kind order
        return out

    def state_at(self, t: float) -> list[tuple[float, str, Any]]:
        """The state at ``t`` after a seek: the last map, paths, snapshot and pose, the
        telemetry of the ``prime_s`` before, and what happened at that very moment."""
        a = self.archive
        back = t - LOOKBACK_S
        out: list[tuple[float, str, Any]] = []
        for ev in a.events(back, t, kinds=["map"]):
            if isinstance(ev.get("data"), dict):
                self._map_geometry = ev["data"]
        png = a.latest_map(t)
        if png:
            out.append((t, "map", self._map(png)))
        latest_paths: dict[str, dict] = {}
        for m in a.paths(back, t):
            latest_paths[str(m["kind"])] = m
        out += [(float(m["t"]), "path", _path(m)) for m in latest_paths.values()]
        status = self._patrol_before(back, t)
        if status is not None:
            out.append(status)
        snaps = a.snapshots(back, t)
        if snaps:
            out += self._snapshot(snaps[-1])
        poses = a.poses(t - self.prime_s, t)
        if len(poses):
            out.append((float(poses[-1][0]), "pose", _pose(poses[-1])))
        tt, seq, names, vals = a.telemetry_rows(t - self.prime_s, t)
        out += self._telemetry(tt, seq, names, vals)
        for ev in a.events(t, t):
            out += self._event(ev)
        out += [(float(tr["t"]), "alarm_transition", dict(tr))
                for tr in a.alarm_transitions(t, t)]
        return out

    def _patrol_before(self, back: float, t: float) -> tuple[float, str, Any] | None:
        """The patrol's last recorded status before ``t`` (its route points from the
        last status that carried them), or None."""
        self._route_points = []
        last = None
        for ev in self.archive.events(back, t, kinds=["patrol", "patrol_status"]):
            if ev["t"] < t:
                last = self._patrol_status(ev)
        return last

    def _patrol_status(self, ev: dict) -> tuple[float, str, Any] | None:
        d = ev.get("data")
        if not isinstance(d, dict) or "state" not in d:
            return None
        if isinstance(d.get("points"), list):
            self._route_points = [p for p in d["points"] if isinstance(p, dict)]
        fields = P.PatrolStatus.__dataclass_fields__
        st = P.PatrolStatus(**{k: v for k, v in d.items() if k in fields})
        # recorded without points (older archives): the route is still the last one seen
        st.points = list(self._route_points)
        return float(ev["t"]), "patrol_status", st

    # ------------------------------------------------------------ rows -> messages
    def _telemetry(self, t: np.ndarray, seq: np.ndarray, names: list[str],
                   vals: np.ndarray) -> list[tuple[float, str, Any]]:
        cols = [(j, n) for j, n in enumerate(names) if n in _TELEMETRY_FIELDS]
        last = self._last_values
        out = []
        for i in range(len(t)):
            for j, name in cols:
                v = vals[i, j]
                if math.isfinite(v):
                    last[name] = float(v)
            msg = P.Telemetry(**{k: (int(v) if k in _TELEMETRY_INT else v)
                                 for k, v in last.items()})
            msg.received_s = float(t[i])
            msg.seq = int(seq[i])
            out.append((float(t[i]), "telemetry", msg))
        return out

    def _snapshot(self, s: dict) -> list[tuple[float, str, Any]]:
        jpeg = self.archive.snapshot(s["id"])
        img = decode_jpeg_rgb(jpeg) if jpeg else None
        if img is None:
            log.warning("replay: snapshot %s does not decode", s.get("id"))
            self.bad_snapshots += 1
            return []
        t = float(s["t"])
        return [(t, "frame", DecodedFrame(int(s["id"]), int(t * 1e6), img, float("nan"),
                                          img.shape[1], img.shape[0], jpeg=bytes(jpeg)))]

    def _map(self, png: bytes) -> P.MapImage:
        g = self._map_geometry
        w, h = png_size(png)
        try:
            res = float(g.get("resolution_m", 0.1))
            ox, oy = float(g.get("origin_x_m", 0.0)), float(g.get("origin_y_m", 0.0))
        except (TypeError, ValueError):
            res, ox, oy = 0.1, 0.0, 0.0
        return P.MapImage(res, ox, oy, w, h, bytes(png))

    def _event(self, ev: dict) -> list[tuple[float, str, Any]]:
        t = float(ev["t"])
        kind = str(ev.get("kind", ""))
        d = ev.get("data") if isinstance(ev.get("data"), dict) else {"text": str(ev.get("data"))}
        if kind == "map":
            self._map_geometry = d
            return []
        if kind == TEB_EVENT:  # a 4WS robot's TEB plan: back onto the map, no log line
            try:
                return [(t, "fws", teb_plan_from_record(d))]
            except ValueError as e:
                log.warning("replay: %s", e)
                self.bad_records += 1
                return []
        if kind == "wall_inspection":  # a wall climber's record: one log line, no arrays
            w = d.get("wall") if isinstance(d.get("wall"), dict) else {}
            return [(t, "event", P.Event("info", kind, f"wall inspection {w.get('state', '?')}:"
                                         f" coverage {w.get('coverage_pct', '?')} %", {}))]
        out: list[tuple[float, str, Any]] = []
        if kind in ("patrol", "patrol_status"):
            status = self._patrol_status({"t": t, "data": d})
            if status is not None:
                out.append(status)
        level = str(d.get("level", "info"))
        code = str(d.get("code", kind))
        text = str(d.get("text") or d.get("state") or "")
        if kind == "link_state":
            code, text = "link", f"link {d.get('state', '?')} (recorded)"
        extra = d.get("data") if kind == "robot_event" and isinstance(d.get("data"), dict) \
            else d
        out.append((t, "event", P.Event(level=level, code=code, text=text, data=extra)))
        return out


def _pose(row: Any) -> P.Pose:
    return P.Pose(x_m=float(row[1]), y_m=float(row[2]), theta_rad=float(row[3]))


def _path(m: dict) -> P.Path:
    kind = _PATH_KINDS.get(str(m["kind"]).lower(), P.Path.GLOBAL)
    return P.Path(kind, np.asarray(m["points"], np.float32))


def transition_event(tr: dict) -> P.Event:
    """A recorded alarm transition as a line of the event log."""
    to = str(tr.get("to_state", ""))
    who = f" by {tr['user']}" if tr.get("user") else ""
    text = f"{tr.get('text') or tr.get('alarm')}: {tr.get('from_state')} → {to}{who}"
    return P.Event(level="alarm" if to == "UNACK" else "info", code=str(tr.get("alarm", "")),
                   text=text, data={"replayed_alarm": True})


def mirror_handling(monitor: Any, tr: dict) -> bool:
    """Repeat a recorded operator action (acknowledge, shelve, unshelve, out of
    service and back) on the replay's alarm monitor, so its alarm list shows the
    alarms as they were handled. The monitor raises and clears alarms itself
    from the replayed telemetry; an action on an alarm it does not hold is
    skipped. Returns True when the action was applied."""
    alarm, t = str(tr.get("alarm", "")), float(tr.get("t", 0.0))
    frm, to = str(tr.get("from_state", "")), str(tr.get("to_state", ""))
    user, reason = tr.get("user"), tr.get("reason") or "recorded"
    try:
        if to == "ACKED" or (frm in ("UNACK", "RTN_UNACK") and to == "NORMAL" and user):
            return bool(monitor.acknowledge(alarm, t, user))
        if to == "SHELVED":
            return bool(monitor.shelve(alarm, t, monitor.max_shelve_s, reason, user))
        if frm == "SHELVED":
            return bool(monitor.unshelve(alarm, t, user))
        if to == "OUT_OF_SERVICE":
            return bool(monitor.set_out_of_service(alarm, True, t, reason, user))
        if frm == "OUT_OF_SERVICE":
            return bool(monitor.set_out_of_service(alarm, False, t, reason, user))
    except (AttributeError, KeyError, TypeError, ValueError) as e:
        log.debug("replay: recorded %s of %s not repeated: %s", to, alarm, e)
    return False
