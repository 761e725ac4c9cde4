"""MapPanel: the station map with the robot, its paths, obstacles and scan, and a
side strip to run a patrol and edit its route.

The panel only emits intents: ``command_requested(name, args)`` — the main
window hands them to ``RobotLink.send_command``. Commands: ``start_patrol``
(``{"route": ...}`` for the edited route, ``{}`` for the robot's default),
``pause_patrol``, ``resume_patrol``, ``abort_patrol``, ``goto`` (``x_m``,
``y_m`` or ``point``), ``dock``, ``set_pose`` (``x_m``, ``y_m``, ``theta_rad``).

Localisation: a line under the patrol state says how the robot's estimate
fares (tracking with its match score and σ, or LOST), and the map draws the
estimate's 95 % uncertainty ellipse. **Set pose** (Ctrl+P) arms a one-shot
mode, as RViz's 2-D pose estimate: press on the map where the robot stands,
drag towards where it faces, release — ``set_pose`` is sent (a drag shorter
than 20 cm gives no heading and sends nothing). The arithmetic lives in
app/core/pose_estimate.

Go to: **Go to** (Ctrl+G) arms a one-shot mode; the next click on the map sends
``goto`` there, marks the target and disarms, so a later stray click never moves
the robot. "Go to selected" sends the robot to the point selected in the route
status list. Keys (while the map tab is shown): F5 start, F6 pause, F7 resume,
F8 abort, F9 dock, Ctrl+G go-to mode, Ctrl+0 fit the map. The main window
takes the resume action (F7) for itself, so F7 resumes from any tab.

Mapping (the robot builds a map while the operator drives it with the drive
keys): **Start mapping** sends ``start_mapping``; the robot then publishes the
growing map, drawn as any map; **Save map** sends ``save_map`` with the name in
the box; **Stop mapping** sends ``stop_mapping`` (the station map comes back).

The read-out of the patrol (state, route, localisation, progress, reason, and the
table of points) lives in app/ui/patrol_status; this panel places it and feeds it.

Read only (``set_read_only``, a replay): every patrol button and key is
disabled and nothing is sent. No link (``set_link_up(False)``): the same, for as
long as the link is down, and the panel says "no link"; anything that still asks
(a click in go-to mode, the route editor's start) is refused with that message.
"""

from __future__ import annotations

import logging

import numpy as np
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QSplitter,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app.core.i18n import QT_TRANSLATE_NOOP
from app.core.pose_estimate import MIN_DRAG_M, pose_from_drag
from app.ui import theme
from app.ui.map_model import PATROL_ACTIVE, MapModel
from app.ui.patrol_status import PatrolPointsTable, PatrolStatus
from app.ui.route_editor import RouteEditor
from app.widgets.map_view import MapView

log = logging.getLogger(__name__)

__all__ = ["MapPanel", "KEYS"]

KEYS = {"start": "F5", "pause": "F6", "resume": "F7", "abort": "F8", "dock": "F9",
        "goto": "Ctrl+G", "set_pose": "Ctrl+P"}
_NO_LINK = QT_TRANSLATE_NOOP("MapPanel",
                             "No link to the robot: patrol commands are off until it answers "
                             "again.")


class MapPanel(QWidget):
    command_requested = Signal(str, object)  # command name, args dict

    def __init__(self, model: MapModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self._held: set[str] = set()  # map layers changed while hidden (on_model_changed)
        self.view = MapView(self)
        self.editor = RouteEditor(self)

        # ---- patrol strip: the read-out (app/ui/patrol_status), buttons, points
        self.status = PatrolStatus(model, self)
        # its lines stay reachable as the panel's own, as the window and tests know them
        self.state_label = self.status.state_label
        self.route_label = self.status.route_label
        self.loc_label = self.status.loc_label
        self.progress = self.status.progress
        self.reason_label = self.status.reason_label
        self.buttons: dict[str, QPushButton] = {}
        self.actions_: dict[str, QAction] = {}
        grid = QGridLayout()
        for i, (key, text) in enumerate((("start", self.tr("Start")),
                                          ("pause", self.tr("Pause")),
                                          ("resume", self.tr("Resume")),
                                          ("abort", self.tr("Abort")),
                                          ("dock", self.tr("Dock")),
                                          ("goto", self.tr("Go to")),
                                          ("set_pose", self.tr("Set pose")))):
            b = QPushButton(f"{text}  ({KEYS[key]})", self)
            b.setFocusPolicy(Qt.FocusPolicy.NoFocus)
            self.buttons[key] = b
            grid.addWidget(b, i // 2, i % 2)
            a = QAction(text, self)
            a.setShortcut(QKeySequence(KEYS[key]))
            a.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
            self.addAction(a)
            self.actions_[key] = a
        self.buttons["goto"].setCheckable(True)
        self.buttons["goto"].setToolTip(
            self.tr("Arm: the next click on the map sends the robot there"))
        self.buttons["start"].clicked.connect(self.request_start)
        self.buttons["pause"].clicked.connect(lambda: self._send("pause_patrol"))
        self.buttons["resume"].clicked.connect(lambda: self._send("resume_patrol"))
        self.buttons["abort"].clicked.connect(lambda: self._send("abort_patrol"))
        self.buttons["dock"].clicked.connect(lambda: self._send("dock"))
        self.buttons["goto"].toggled.connect(self._on_goto_toggled)
        self.buttons["set_pose"].setCheckable(True)
        self.buttons["set_pose"].setToolTip(
            self.tr("Arm: press on the map where the robot is, drag the way it faces, release"))
        self.buttons["set_pose"].toggled.connect(self._on_set_pose_toggled)
        self.actions_["set_pose"].triggered.connect(self.buttons["set_pose"].toggle)
        self.actions_["start"].triggered.connect(self.buttons["start"].click)
        self.actions_["pause"].triggered.connect(self.buttons["pause"].click)
        self.actions_["resume"].triggered.connect(self.buttons["resume"].click)
        self.actions_["abort"].triggered.connect(self.buttons["abort"].click)
        self.actions_["dock"].triggered.connect(self.buttons["dock"].click)
        self.actions_["goto"].triggered.connect(self.buttons["goto"].toggle)

        self.points_table = PatrolPointsTable(self)
        self.goto_point_button = QPushButton(self.tr("Go to selected point"), self)
        self.goto_point_button.clicked.connect(self.request_goto_selected)
        self.hint = QLabel("", self)
        self.hint.setWordWrap(True)
        # ---- mapping strip
        self.map_name = QLineEdit("station-new", self)
        self.map_name.setToolTip(self.tr("Name of the saved map (letters, digits, '-' or '_')"))
        self.mapping_buttons = {k: QPushButton(t, self) for k, t in (
            ("start_mapping", self.tr("Start mapping")), ("save_map", self.tr("Save map")),
            ("stop_mapping", self.tr("Stop mapping")))}
        self.mapping_buttons["start_mapping"].clicked.connect(
            lambda: self._send("start_mapping"))
        self.mapping_buttons["stop_mapping"].clicked.connect(lambda: self._send("stop_mapping"))
        self.mapping_buttons["save_map"].clicked.connect(
            lambda: self._send("save_map", {"name": self.map_name.text().strip()}))

        patrol = QWidget(self)
        pl = QVBoxLayout(patrol)
        pl.setContentsMargins(4, 4, 4, 4)
        pl.addWidget(self.status)
        pl.addLayout(grid)
        pl.addWidget(self.points_table, 1)
        pl.addWidget(self.goto_point_button)
        # mapping is an engineer's mode, on a tab of its own (the patrol tab stays short)
        mapping = QWidget(self)
        ml = QVBoxLayout(mapping)
        ml.setContentsMargins(4, 4, 4, 4)
        for b in self.mapping_buttons.values():
            ml.addWidget(b)
        ml.addWidget(self.map_name)
        ml.addStretch(1)
        self.side_tabs = QTabWidget(self)
        self.side_tabs.addTab(patrol, self.tr("Patrol"))
        self.side_tabs.addTab(self.editor, self.tr("Route editor"))
        self.side_tabs.addTab(mapping, self.tr("Mapping"))

        side = QWidget(self)
        side.setMinimumWidth(240)
        side.setMaximumWidth(340)
        sl = QVBoxLayout(side)
        sl.setContentsMargins(2, 8, 2, 2)
        sl.addWidget(self.side_tabs, 1)
        sl.addWidget(self.hint)
        fit = QPushButton(self.tr("Fit map  (Ctrl+0)"), self)
        fit.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        fit.clicked.connect(self.view.fit)
        row = QHBoxLayout()
        row.addStretch(1)
        row.addWidget(fit)
        sl.addLayout(row)

        split = QSplitter(Qt.Orientation.Horizontal, self)
        split.addWidget(self.view)
        split.addWidget(side)
        split.setStretchFactor(0, 1)
        split.setStretchFactor(1, 0)
        split.setCollapsible(0, False)
        split.setSizes([560, 300])
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(split)

        # ---- wiring
        self.view.clicked.connect(self._on_map_clicked)
        self.view.dragged.connect(self._on_map_dragged)
        self.editor.add_mode_changed.connect(self._on_add_mode)
        self.editor.route_changed.connect(self._on_route_edited)
        self.editor.start_requested.connect(
            lambda route: self._send("start_patrol", {"route": route}))
        self.model.changed.connect(self.on_model_changed)
        self.side_tabs.currentChanged.connect(lambda _i: self._draw_markers())
        self.model.map_failed.connect(lambda why: self._hint(
            self.tr("Map not shown: {why}").format(why=why)))
        self.read_only = False
        self.link_up = True  # a panel on its own; the window says when there is no link
        self._update_start_label()
        self._update_buttons(None)

    def set_read_only(self, on: bool) -> None:
        """A replay: no patrol command leaves this panel."""
        self.read_only = bool(on)
        self.set_goto_mode(False)
        self.set_set_pose_mode(False)
        for a in self.actions_.values():
            a.setEnabled(not on)
        self.goto_point_button.setEnabled(not on)
        for b in self.mapping_buttons.values():
            b.setEnabled(not on)
        self._update_buttons(self.model.patrol_state())
        if on:
            self._hint(self.tr("Replay: view only, no commands are sent."))

    def set_link_up(self, up: bool) -> None:
        """Without a link no patrol command could reach the robot: disable them and
        say so; with it back, enable them as the patrol's state allows."""
        up = bool(up)
        if up == self.link_up:
            return
        self.link_up = up
        if not up:
            self.set_goto_mode(False)
        for key, a in self.actions_.items():
            if key != "resume":  # the window's F7 says itself why it sends nothing
                a.setEnabled(up and not self.read_only)
        self.goto_point_button.setEnabled(up and not self.read_only)
        self.editor.start_button.setEnabled(up and bool(self.editor.route.points))
        self._update_buttons(self.model.patrol_state())
        if not up and not self.read_only:
            self._hint(self.tr(_NO_LINK))
        elif self.hint.text() == self.tr(_NO_LINK) or self.hint.text().startswith(
                self.tr("No link to the robot: {name} not sent.").split("{")[0]):
            self._hint("")

    # ------------------------------------------------------------ intents
    def _refused(self, name: str) -> bool:
        """Replay or no link: say ``name`` was not sent (True), else False."""
        if self.read_only:
            self._hint(self.tr("Replay: view only, {name} not sent.").format(name=name))
        elif not self.link_up:
            self._hint(self.tr("No link to the robot: {name} not sent.").format(name=name))
        return self.read_only or not self.link_up

    def _send(self, name: str, args: dict | None = None) -> None:
        if self._refused(name):
            return
        self.command_requested.emit(name, dict(args or {}))
        self._hint(self.tr("sent {name}").format(name=name))

    def request_start(self) -> None:
        """Start with the edited route when it has points, else the robot's default."""
        if self.editor.route.points:
            route = self.editor.route_dict()
            if route is None:
                self.side_tabs.setCurrentWidget(self.editor)
                self._hint(self.tr("Route not valid; see the route editor."))
                return
            self._send("start_patrol", {"route": route})
        else:
            self._send("start_patrol", {})

    def request_goto(self, x_m: float, y_m: float) -> None:
        if self._refused("goto"):
            return
        self.view.set_target((x_m, y_m))
        self.command_requested.emit("goto", {"x_m": round(float(x_m), 3),
                                             "y_m": round(float(y_m), 3)})
        self._hint(self.tr("sent goto x {x} m, y {y} m").format(x=f"{x_m:.2f}", y=f"{y_m:.2f}"))

    def request_goto_selected(self) -> None:
        rows = self.points_table.selectionModel().selectedRows()
        pts = (self.model.patrol or {}).get("points", [])
        if not rows or rows[0].row() >= len(pts):
            self._hint(self.tr("Select a point in the list first."))
            return
        p = pts[rows[0].row()]
        self.view.set_target((p["x_m"], p["y_m"]))
        self._send("goto", {"point": p["name"]})

    def set_pose_mode(self) -> bool:
        return self.buttons["set_pose"].isChecked()

    def set_set_pose_mode(self, on: bool) -> None:
        self.buttons["set_pose"].setChecked(on)

    def request_set_pose(self, x0: float, y0: float, x1: float, y1: float) -> None:
        """The operator's pose: at (x0, y0), facing (x1, y1)."""
        args = pose_from_drag(x0, y0, x1, y1)
        if args is None:
            self._hint("Set pose: drag from the robot's place towards where it faces "
                       f"(at least {MIN_DRAG_M * 100:.0f} cm).")
            return
        self._send("set_pose", args)

    def goto_mode(self) -> bool:
        return self.buttons["goto"].isChecked()

    def set_goto_mode(self, on: bool) -> None:
        self.buttons["goto"].setChecked(on)

    # ------------------------------------------------------------ clicks and modes
    def _on_map_clicked(self, x: float, y: float) -> None:
        if self.goto_mode():
            self.set_goto_mode(False)  # one shot
            self.request_goto(x, y)
        elif self.editor.add_mode():
            self.editor.add_point(x, y)
        else:
            self._hint(self.tr("x {x} m, y {y} m — arm Go to ({key}) to send the robot there")
                       .format(x=f"{x:.2f}", y=f"{y:.2f}", key=KEYS["goto"]))

    def _on_map_dragged(self, x0: float, y0: float, x1: float, y1: float) -> None:
        if self.set_pose_mode():
            self.set_set_pose_mode(False)  # one shot
            self.request_set_pose(x0, y0, x1, y1)

    def _on_set_pose_toggled(self, on: bool) -> None:
        self.view.set_drag_mode(on)
        if on:
            self.set_goto_mode(False)
            self.editor.set_add_mode(False)
            self._hint("Set pose: press where the robot is, drag the way it faces, release.")

    def _on_goto_toggled(self, on: bool) -> None:
        if on:
            self.set_set_pose_mode(False)
            self.editor.set_add_mode(False)
            self._hint(self.tr("Go to: click the map where the robot should go."))
        self.view.setCursor(Qt.CursorShape.CrossCursor if on or self.editor.add_mode()
                            else Qt.CursorShape.ArrowCursor)

    def _on_add_mode(self, on: bool) -> None:
        if on:
            self.set_goto_mode(False)
            self.side_tabs.setCurrentWidget(self.editor)
            self._hint(self.tr("Add by click: each click on the map adds a point."))
        self.view.setCursor(Qt.CursorShape.CrossCursor if on or self.goto_mode()
                            else Qt.CursorShape.ArrowCursor)

    def _on_route_edited(self) -> None:
        self._update_start_label()
        self._draw_markers()

    # ------------------------------------------------------------ model -> view
    def on_model_changed(self, layers: frozenset) -> None:
        """The labels, table and buttons follow at once (shortcuts and the no-link
        rules depend on them); the map drawing only while the map is shown: a hidden
        map tab keeps which layers changed and draws the latest of them when it is
        shown again (``showEvent``), so the desk does not redraw a map nobody sees
        ten times a second."""
        m = self.model
        if "pose" in layers and m.pose is not None:
            self.status.show_quality(m.quality)
        if "patrol" in layers:
            self.status.show_patrol()
            self.points_table.show_points((m.patrol or {}).get("points", []))
            self._update_buttons((m.patrol or {}).get("state", ""))
        if self.isVisible():
            self._draw(layers | self._held)
            self._held = set()
        else:
            self._held |= layers

    def held_layers(self) -> frozenset:
        """The layers changed while the map was hidden, not drawn yet."""
        return frozenset(self._held)

    def showEvent(self, ev) -> None:  # noqa: N802 - Qt's name
        super().showEvent(ev)
        if self._held:
            layers, self._held = frozenset(self._held), set()
            self._draw(layers)

    def _draw(self, layers: frozenset | set) -> None:
        m, view = self.model, self.view
        if "map" in layers and m.grid is not None:
            g = m.grid
            x0, y0, x1, y1 = g.extent
            view.set_image(g.image, (x0, y0, x1 - x0, y1 - y0))
        if "pose" in layers and m.pose is not None:
            view.set_pose(*m.pose)
            lost = m.quality is not None and m.quality.lost
            view.set_polyline("uncertainty", m.ellipse_xy,
                              color=theme.ALARM_HIGH if lost else theme.ACCENT, width=1.5)
        if "path" in layers:
            view.set_polyline("global", m.global_path, color="#3a3a3a", width=2.5)
            view.set_polyline("local", m.local_path, color=theme.ACCENT, width=2, dashed=True)
        if "obstacles" in layers:
            view.set_circles(m.obstacles)
        if "scan" in layers:
            view.set_points(m.scan_xy)
        if "patrol" in layers:
            self._draw_markers()

    def show_freshness(self, patrol, pose=None) -> None:
        """``patrol``, ``pose``: the Freshness of the robot's patrol status and pose;
        once no longer current the state line says its age and loses its colour,
        and the robot's arrow is drawn hollow."""
        if pose is not None:
            self.view.set_pose_stale(pose.stale)
        self.status.show_age(patrol.text())

    def patrol_text(self) -> str:
        return self.state_label.text()

    def _draw_markers(self) -> None:
        """The patrol's points with their states while a patrol has a route; the
        edited route (all "pending", joined by a thin line) otherwise or while
        the editor is in use."""
        p = self.model.patrol or {}
        editing = self.side_tabs.currentWidget() is self.editor or not p.get("points")
        if editing:
            pts = self.editor.route.points
            self.view.set_markers([(q.x_m, q.y_m, q.name, "pending") for q in pts])
            xy = np.array([(q.x_m, q.y_m) for q in pts], float).reshape(-1, 2)
            self.view.set_polyline("route", xy, color="#8a8a8a", width=1, dashed=True)
        else:
            self.view.set_markers([(q["x_m"], q["y_m"], q["name"], q["state"])
                                   for q in p["points"]])
            self.view.set_polyline("route", None)

    def _update_buttons(self, state: str | None) -> None:
        b = self.buttons
        if self.read_only or not self.link_up:
            for k in b:
                b[k].setEnabled(False)
            return
        b["goto"].setEnabled(True)
        b["set_pose"].setEnabled(True)
        b["dock"].setEnabled(True)
        if state is None:  # no status from the robot yet: let the robot decide
            for k in ("start", "pause", "resume", "abort"):
                b[k].setEnabled(True)
            return
        active = state in PATROL_ACTIVE
        b["start"].setEnabled(not active and state != "paused")
        b["pause"].setEnabled(active)
        b["resume"].setEnabled(state == "paused")
        b["abort"].setEnabled(active or state == "paused")

    def _update_start_label(self) -> None:
        r = self.editor.route
        self.buttons["start"].setToolTip(
            self.tr("Start a patrol on route '{name}'").format(name=r.name) if r.points
            else self.tr("Start a patrol on the robot's default route"))

    def _hint(self, text: str) -> None:
        self.hint.setText(text)
