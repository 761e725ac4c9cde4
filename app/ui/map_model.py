"""MapModel: the latest map, pose, paths, obstacles, scan and patrol status.

Slots fed by the link (``on_map``, ``on_pose``, ``on_path``, ``on_obstacles``,
``on_scan``, ``on_patrol_status``) are guarded: a malformed message is logged,
counted and announced with ``malformed(str)``, never raised.

Change signals are throttled: the slots only mark layers dirty, and a timer
(10 Hz by default) emits ``changed(frozenset_of_layer_names)`` once for all that
changed since the last tick, so a 10 Hz pose plus a 5 Hz scan cost one redraw
per tick, not one per message. Layer names: ``map``, ``pose``, ``path``,
``obstacles``, ``scan``, ``patrol``.

Map decoding (app/core/mapimage, OpenCV): a map up to ``INLINE_DECODE_PX``
cells (1 Mpx; an 800 x 600 PNG takes about 2 ms) is decoded on the GUI thread
when it arrives — maps come rarely and this is cheaper than a thread hop. A
larger map (up to ~16 Mpx fit in a 1 MiB frame, tens of ms to decode) is
decoded on the model's own one-thread pool and the result comes back queued on
the GUI thread (app/gui_jobs); a result older than the latest map received is
dropped. A model deleted while a map decodes waits for the job and gets no
result.

A pose may carry the localisation's quality (covariance, match score,
status; app/core/pose_estimate): kept as ``quality`` with its 95 % ellipse
``ellipse_xy``.

The scan arrives in the robot frame; it is put into the map frame with the
latest pose (the robot's estimate, so a misaligned scan shows a poor
estimate at a glance) at the time it arrives (app/core/mapimage.scan_to_map). A scan
before any pose is kept only as a count.
"""

from __future__ import annotations

import functools
import logging
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal

from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.core.mapimage import MapGrid, decode_map, scan_to_map
from app.core.pose_estimate import PoseQuality, covariance_ellipse, quality_from_pose
from app.gui_jobs import GuiJobs
from app.ui.models import _GuardedModel, guarded

log = logging.getLogger(__name__)

__all__ = ["MapModel", "INLINE_DECODE_PX", "PATROL_ACTIVE", "PATROL_ABNORMAL", "RESUME_KEY",
           "patrol_line", "patrol_state_text"]

INLINE_DECODE_PX = 1_000_000
PATROL_ACTIVE = frozenset({"planning", "driving", "avoiding", "inspecting", "docking"})
PATROL_ABNORMAL = frozenset({"aborted", "failed"})
PATH_GLOBAL, PATH_LOCAL = 0, 1
RESUME_KEY = "F7"
# the robot's patrol and point states as the desk shows them (patrol_state_text)
_PATROL_STATES = {s: s for s in (
    QT_TRANSLATE_NOOP("PatrolState", "idle"), QT_TRANSLATE_NOOP("PatrolState", "planning"),
    QT_TRANSLATE_NOOP("PatrolState", "driving"), QT_TRANSLATE_NOOP("PatrolState", "avoiding"),
    QT_TRANSLATE_NOOP("PatrolState", "inspecting"), QT_TRANSLATE_NOOP("PatrolState", "paused"),
    QT_TRANSLATE_NOOP("PatrolState", "docking"), QT_TRANSLATE_NOOP("PatrolState", "done"),
    QT_TRANSLATE_NOOP("PatrolState", "aborted"), QT_TRANSLATE_NOOP("PatrolState", "failed"),
    QT_TRANSLATE_NOOP("PatrolState", "pending"), QT_TRANSLATE_NOOP("PatrolState", "current"),
    QT_TRANSLATE_NOOP("PatrolState", "skipped"), QT_TRANSLATE_NOOP("PatrolState", "meter"),
    QT_TRANSLATE_NOOP("PatrolState", "valve"), QT_TRANSLATE_NOOP("PatrolState", "waypoint"),
    QT_TRANSLATE_NOOP("PatrolState", "tank_wall"), QT_TRANSLATE_NOOP("PatrolState", "operator"),
    QT_TRANSLATE_NOOP("PatrolState", "estop"),
    QT_TRANSLATE_NOOP("PatrolState", "dock requested"),
    QT_TRANSLATE_NOOP("PatrolState", "running"), QT_TRANSLATE_NOOP("PatrolState", "default"),
    QT_TRANSLATE_NOOP("PatrolState", "operator took over (drive)"),
    QT_TRANSLATE_NOOP("PatrolState", "operator stop"))}


def patrol_state_text(state: str, upper: bool = False) -> str:
    """A patrol or point state (or a point kind) in the desk's language; the English
    source in capitals when ``upper`` (as the header has always shown it)."""
    text = translate("PatrolState", state)
    return text.upper() if upper and text == state else text


def patrol_line(patrol: dict[str, Any] | None) -> tuple[str, bool]:
    """The patrol's state in one line for the always-visible header, and whether
    it needs the operator (paused, aborted, failed). A patrol the operator paused
    (a drive key, Stop, the e-stop, Pause) says so and names the key that resumes it."""
    if not patrol:
        return translate("MapModel", "Patrol: —"), False
    state = str(patrol.get("state", "")) or "—"
    reason = str(patrol.get("reason", "") or "")
    route = patrol_state_text(str(patrol.get("route", "") or ""))  # "default": translated
    where = translate("MapModel", " · route {route}").format(route=route) if route else ""
    reason_text = patrol_state_text(reason)
    if state == "paused":
        if reason.startswith("operator") or reason == "estop":
            why = f" ({reason_text})" if reason != "operator" else ""
            return translate("MapModel", "Patrol: paused by operator — {key} resumes").format(
                key=RESUME_KEY) + why + where, True
        why = f" ({reason_text})" if reason else ""
        return translate("MapModel", "Patrol: paused{why} — {key} resumes").format(
            why=why, key=RESUME_KEY) + where, True
    shown = translate("MapModel", "Patrol: {state}").format(
        state=patrol_state_text(state, upper=True))
    if state in PATROL_ABNORMAL:
        return shown + (f" ({reason_text})" if reason else "") + where, True
    pct = float(patrol.get("progress", 0.0) or 0.0)
    prog = f" · {pct * 100:.0f} %" if state in PATROL_ACTIVE and 0.0 < pct <= 1.0 else ""
    return f"{shown}{where}{prog}", False


class MapModel(_GuardedModel):
    changed = Signal(object)  # frozenset of layer names changed since the last tick
    map_failed = Signal(str)  # a map that did not decode: why

    def __init__(self, parent: QObject | None = None, *, refresh_hz: float = 10.0) -> None:
        super().__init__(parent)
        self._jobs = GuiJobs(self)  # large maps decode here (see the module's docstring)
        self.grid: MapGrid | None = None
        self.pose: tuple[float, float, float] | None = None  # x_m, y_m, theta_rad
        self.velocity: tuple[float, float] = (0.0, 0.0)  # v_mps, omega_rps
        self.quality: PoseQuality | None = None  # the pose's localisation quality, if sent
        self._ellipse: np.ndarray | None = np.zeros((0, 2), np.float32)  # None: not yet
        self.global_path = np.zeros((0, 2), np.float32)
        self.local_path = np.zeros((0, 2), np.float32)
        self.obstacles = np.zeros((0, 5), np.float32)
        self.scan_xy = np.zeros((0, 2), np.float32)
        self.patrol: dict[str, Any] | None = None
        self.maps_received = 0
        self.scans_received = 0
        self._generation = 0
        self._dirty: set[str] = set()
        self._timer = QTimer(self)
        self._timer.setInterval(max(10, int(1000 / refresh_hz)))
        self._timer.timeout.connect(self._flush)
        self._timer.start()

    # ------------------------------------------------------------ link slots
    @guarded
    def on_map(self, msg: Any) -> None:
        w, h = int(msg.width), int(msg.height)
        self.maps_received += 1
        self._generation += 1
        gen = self._generation
        if w * h <= INLINE_DECODE_PX:
            try:
                grid = decode_map(msg)
            except ValueError as e:
                self._map_error(str(e))
                return
            self._set_grid(grid)
        else:
            self._jobs.start(functools.partial(decode_map, msg),
                             functools.partial(self._on_decoded, gen),
                             functools.partial(self._on_decode_failed, gen))

    def on_pose(self, msg: Any) -> None:
        """A malformed pose is dropped here without counting: the window's status
        bar slot gets the same message and counts it once."""
        try:
            x, y, th = float(msg.x_m), float(msg.y_m), float(msg.theta_rad)
        except (AttributeError, TypeError, ValueError):
            log.debug("map: malformed pose ignored")
            return
        if not np.all(np.isfinite([x, y, th])):
            return
        self.pose = (x, y, th)
        self.velocity = (float(getattr(msg, "v_mps", 0.0)), float(getattr(msg, "omega_rps", 0.0)))
        self.quality = quality_from_pose(msg)
        self._ellipse = None  # ellipse_xy works it out when asked
        self._mark("pose")

    @property
    def ellipse_xy(self) -> np.ndarray:
        """(n, 2) the 95 % position ellipse of the latest pose (none without a quality)."""
        if self._ellipse is None:
            if self.quality is None or self.pose is None:
                self._ellipse = np.zeros((0, 2), np.float32)
            else:
                self._ellipse = covariance_ellipse(self.quality.cov,
                                                   self.pose[:2]).astype(np.float32)
        return self._ellipse

    @guarded
    def on_path(self, msg: Any) -> None:
        pts = np.asarray(msg.points_xy, np.float32).reshape(-1, 2)
        if int(msg.kind) == PATH_LOCAL:
            self.local_path = pts
        else:
            self.global_path = pts
        self._mark("path")

    @guarded
    def on_obstacles(self, msg: Any) -> None:
        self.obstacles = np.asarray(msg.rows, np.float32).reshape(-1, 5)
        self._mark("obstacles")

    @guarded
    def on_scan(self, msg: Any) -> None:
        self.scans_received += 1
        if self.pose is None:
            return
        self.scan_xy = scan_to_map(msg.ranges_m, float(msg.angle_min_rad),
                                   float(msg.angle_increment_rad), float(msg.range_max_m),
                                   *self.pose)
        self._mark("scan")

    @guarded
    def on_patrol_status(self, msg: Any) -> None:
        points = []
        for p in list(msg.points or []):
            points.append({"name": str(p["name"]), "kind": str(p.get("kind", "")),
                           "x_m": float(p["x_m"]), "y_m": float(p["y_m"]),
                           "state": str(p.get("state", "pending"))})
        self.patrol = {"state": str(msg.state), "route": str(msg.route or ""),
                       "index": int(msg.index), "points": points,
                       "reason": str(msg.reason or ""), "progress": float(msg.progress or 0.0),
                       "local_planner": str(getattr(msg, "local_planner", "") or "")}
        self._mark("patrol")

    # ------------------------------------------------------------ queries
    def patrol_state(self) -> str | None:
        return None if self.patrol is None else self.patrol["state"]

    # ------------------------------------------------------------ internals
    def _mark(self, layer: str) -> None:
        self._dirty.add(layer)

    def flush(self) -> None:
        """Emit pending changes now (the timer does this at ``refresh_hz``)."""
        self._flush()

    def _flush(self) -> None:
        if self._dirty:
            layers, self._dirty = frozenset(self._dirty), set()
            self.changed.emit(layers)

    def _set_grid(self, grid: MapGrid) -> None:
        self.grid = grid
        self._mark("map")

    def _map_error(self, why: str) -> None:
        self._note_malformed(f"on_map: {why}")
        self.map_failed.emit(why)

    def _on_decoded(self, gen: int, grid: MapGrid) -> None:
        if gen == self._generation:  # else a newer map arrived meanwhile
            self._set_grid(grid)

    def _on_decode_failed(self, gen: int, e: BaseException) -> None:
        if gen == self._generation:
            self._map_error(f"{type(e).__name__}: {e}")
