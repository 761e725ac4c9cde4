"""RouteEditor: build and edit a patrol route (app/core/route) on the desk.

Add a point by clicking the map while **Add by click** is on (the panel calls
:meth:`add_point`), remove, move up/down, rename, set kind / gauge / dwell,
open and save route files, and ask for a patrol on this route
(``start_requested(route_dict)``).

Names and gauge ids are typed in small dialogs, not in cells: the desk's drive
keys (W A S D, Space, + and -) are caught window-wide before any child widget,
so a text field inside the window could not take those letters; a dialog is a
window of its own. Bad files give a message in the editor, never a crash.
"""

from __future__ import annotations

import logging
from pathlib import Path

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QGridLayout,
    QHBoxLayout,
    QInputDialog,
    QLabel,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.core.paths import resource, user_routes_dir
from app.core.route import KINDS, Route, RoutePoint, load_route, save_route

log = logging.getLogger(__name__)

__all__ = ["RouteEditor"]

COLUMNS = ("#", QT_TRANSLATE_NOOP("RouteEditor", "name"), QT_TRANSLATE_NOOP("RouteEditor", "kind"),
           "x m", "y m", QT_TRANSLATE_NOOP("RouteEditor", "gauge"),
           QT_TRANSLATE_NOOP("RouteEditor", "dwell s"))


class RouteEditor(QWidget):
    route_changed = Signal()
    file_changed = Signal(object)  # the route file opened or saved (Path)
    start_requested = Signal(object)  # route dict (app/core/route format)
    add_mode_changed = Signal(bool)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.route = Route(self.tr("route"), [])
        self.path: Path | None = None
        self._syncing = False

        self.name_label = QLabel(self)
        self.rename_route_button = QPushButton(self.tr("Route name…"), self)
        self.table = QTableWidget(0, len(COLUMNS), self)
        self.table.setHorizontalHeaderLabels([self.tr(c) for c in COLUMNS])
        self.table.verticalHeader().setVisible(False)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.horizontalHeader().setStretchLastSection(True)

        self.add_button = QPushButton(self.tr("Add by click"), self)
        self.add_button.setCheckable(True)
        self.add_button.setToolTip(self.tr("While on, a click on the map adds a point there"))
        self.remove_button = QPushButton(self.tr("Remove"), self)
        self.up_button = QPushButton(self.tr("Up"), self)
        self.down_button = QPushButton(self.tr("Down"), self)
        self.rename_button = QPushButton(self.tr("Rename…"), self)
        self.gauge_button = QPushButton(self.tr("Gauge…"), self)
        self.kind_combo = QComboBox(self)
        for kind in KINDS:  # shown translated, the kind itself kept as the item's data
            self.kind_combo.addItem(translate("PatrolState", kind), kind)
        self.dwell_spin = QDoubleSpinBox(self)
        self.dwell_spin.setRange(0.0, 600.0)
        self.dwell_spin.setSuffix(self.tr(" s"))
        self.dwell_spin.setDecimals(1)
        self.open_button = QPushButton(self.tr("Open…"), self)
        self.save_button = QPushButton(self.tr("Save…"), self)
        self.new_button = QPushButton(self.tr("New"), self)
        self.start_button = QPushButton(self.tr("Start patrol with this route"), self)
        self.message = QLabel("", self)
        self.message.setWordWrap(True)
        self.message.setObjectName("routeMessage")

        head = QHBoxLayout()
        head.addWidget(self.name_label, 1)
        head.addWidget(self.rename_route_button)
        edit = QGridLayout()
        for i, b in enumerate((self.add_button, self.remove_button, self.up_button,
                               self.down_button)):
            edit.addWidget(b, 0, i)
        edit.addWidget(self.rename_button, 1, 0)
        edit.addWidget(self.gauge_button, 1, 1)
        edit.addWidget(self.kind_combo, 1, 2)
        edit.addWidget(self.dwell_spin, 1, 3)
        files = QHBoxLayout()
        for b in (self.new_button, self.open_button, self.save_button):
            files.addWidget(b)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addLayout(head)
        lay.addWidget(self.table, 1)
        lay.addLayout(edit)
        lay.addLayout(files)
        lay.addWidget(self.start_button)
        lay.addWidget(self.message)

        self.add_button.toggled.connect(self.add_mode_changed)
        self.remove_button.clicked.connect(lambda: self.remove_point(self.current_row()))
        self.up_button.clicked.connect(lambda: self.move_point(self.current_row(), -1))
        self.down_button.clicked.connect(lambda: self.move_point(self.current_row(), +1))
        self.rename_button.clicked.connect(self._ask_rename)
        self.gauge_button.clicked.connect(self._ask_gauge)
        self.rename_route_button.clicked.connect(self._ask_route_name)
        self.kind_combo.activated.connect(
            lambda i: self.set_kind(self.current_row(), self.kind_combo.itemData(i)))
        self.dwell_spin.valueChanged.connect(self._on_dwell)
        self.open_button.clicked.connect(self._ask_open)
        self.save_button.clicked.connect(self._ask_save)
        self.new_button.clicked.connect(self.clear)
        self.start_button.clicked.connect(self.request_start)
        self.table.itemSelectionChanged.connect(self._sync_form)
        self._refresh()

    # ------------------------------------------------------------ editing
    def add_mode(self) -> bool:
        return self.add_button.isChecked()

    def set_add_mode(self, on: bool) -> None:
        self.add_button.setChecked(on)

    def current_row(self) -> int:
        rows = self.table.selectionModel().selectedRows()
        return rows[0].row() if rows else -1

    def select(self, row: int) -> None:
        if 0 <= row < len(self.route.points):
            self.table.selectRow(row)

    def add_point(self, x_m: float, y_m: float, *, name: str | None = None,
                  kind: str = "waypoint") -> RoutePoint:
        """Append a point (after the selected one, if any) and select it."""
        p = RoutePoint(name or self.route.unique_name(), kind, round(float(x_m), 3),
                       round(float(y_m), 3))
        row = self.current_row()
        at = row + 1 if row >= 0 else len(self.route.points)
        self.route.points.insert(at, p)
        self._changed(select=at)
        return p

    def remove_point(self, row: int) -> None:
        if 0 <= row < len(self.route.points):
            del self.route.points[row]
            self._changed(select=min(row, len(self.route.points) - 1))

    def move_point(self, row: int, delta: int) -> None:
        to = row + delta
        pts = self.route.points
        if 0 <= row < len(pts) and 0 <= to < len(pts):
            pts[row], pts[to] = pts[to], pts[row]
            self._changed(select=to)

    def rename_point(self, row: int, name: str) -> bool:
        name = name.strip()
        if not (0 <= row < len(self.route.points)):
            return False
        if not name:
            self._say(self.tr("A point needs a name."), error=True)
            return False
        if name in (p.name for i, p in enumerate(self.route.points) if i != row):
            self._say(self.tr("There is already a point named {name}.").format(name=repr(name)),
                      error=True)
            return False
        self.route.points[row].name = name
        self._changed(select=row)
        return True

    def set_kind(self, row: int, kind: str) -> None:
        if 0 <= row < len(self.route.points) and kind in KINDS:
            self.route.points[row].kind = kind
            self._changed(select=row)

    def set_gauge(self, row: int, gauge: str | None) -> None:
        if 0 <= row < len(self.route.points):
            self.route.points[row].gauge = (gauge or "").strip() or None
            self._changed(select=row)

    def set_dwell(self, row: int, dwell_s: float) -> None:
        if 0 <= row < len(self.route.points):
            self.route.points[row].dwell_s = max(0.0, float(dwell_s))
            self._changed(select=row)

    def set_route_name(self, name: str) -> None:
        if name.strip():
            self.route.name = name.strip()
            self._changed(select=self.current_row())

    def clear(self) -> None:
        self.route = Route(self.tr("route"), [])
        self.path = None
        self._changed(select=-1)
        self._say(self.tr("New route: click the map in 'Add by click' mode to add points."))

    def set_route(self, route: Route) -> None:
        self.route = route
        self._changed(select=0 if route.points else -1)

    # ------------------------------------------------------------ files
    def load(self, path: str | Path) -> bool:
        """Open a route file; on a bad file say why and keep the current route."""
        try:
            route = load_route(path)
        except ValueError as e:
            self._say(self.tr("Could not open the route: {why}").format(why=e), error=True)
            log.warning("route not opened: %s", e)
            return False
        self.path = Path(path)
        self.set_route(route)
        self._say(self.tr("Opened {file}: {n} points.").format(file=self.path.name,
                                                                n=len(route.points)))
        self.file_changed.emit(self.path)
        return True

    def save(self, path: str | Path) -> bool:
        try:
            save_route(self.route, path)
        except (ValueError, OSError) as e:
            self._say(self.tr("Could not save the route: {why}").format(why=e), error=True)
            log.warning("route not saved: %s", e)
            return False
        old = self.path
        self.path = Path(path)
        note = ""
        calibrated = [p for p in self.route.points if p.profile is not None]
        if calibrated and old is not None and old.resolve().parent != \
                self.path.resolve().parent:
            # the points' profiles are relative to the route file's folder
            note = self.tr(" {n} calibrated point(s) name profiles beside {old}; copy its "
                           ".points folder too, or calibrate them again.").format(
                n=len(calibrated), old=old.name)
        self._say(self.tr("Saved {file}.").format(file=self.path.name) + note,
                  error=bool(note))
        self.file_changed.emit(self.path)
        return True

    def adopt_profiles(self, path: str | Path) -> int:
        """Take the points' calibrated profiles from the route file at ``path`` (after a
        point was calibrated there) when it is this editor's file; unsaved edits stay.
        Returns how many points got one."""
        if self.path is None or Path(path).resolve() != self.path.resolve():
            return 0
        try:
            on_disk = {p.name: p.profile for p in load_route(path).points}
        except ValueError as e:
            log.warning("profiles not taken from %s: %s", path, e)
            return 0
        n = 0
        for p in self.route.points:
            prof = on_disk.get(p.name)
            if prof is not None and prof != p.profile:
                p.profile = prof
                n += 1
        return n

    def route_dict(self) -> dict | None:
        """The route in the file format, or None (with a message) if it is not valid."""
        try:
            self.route.validate()
        except ValueError as e:
            self._say(self.tr("The route is not ready: {why}").format(why=e), error=True)
            return None
        return self.route.to_dict()

    def request_start(self) -> None:
        d = self.route_dict()
        if d is not None:
            self.start_requested.emit(d)

    # ------------------------------------------------------------ dialogs
    def _ask_rename(self) -> None:
        row = self.current_row()
        if row < 0:
            return
        name, ok = QInputDialog.getText(self, self.tr("Rename point"), self.tr("Name:"),
                                        text=self.route.points[row].name)
        if ok:
            self.rename_point(row, name)

    def _ask_gauge(self) -> None:
        row = self.current_row()
        if row < 0:
            return
        gauge, ok = QInputDialog.getText(self, self.tr("Gauge"), self.tr("Gauge id (empty: none):"),
                                         text=self.route.points[row].gauge or "")
        if ok:
            self.set_gauge(row, gauge)

    def _ask_route_name(self) -> None:
        name, ok = QInputDialog.getText(self, self.tr("Route name"), self.tr("Name:"),
                                        text=self.route.name)
        if ok:
            self.set_route_name(name)

    def _ask_open(self) -> None:
        fn, _ = QFileDialog.getOpenFileName(self, self.tr("Open route"), self._dir(),
                                            self.tr("Routes (*.json);;All files (*)"))
        if fn:
            self.load(fn)

    def _ask_save(self) -> None:
        fn, _ = QFileDialog.getSaveFileName(self, self.tr("Save route"), self._dir(),
                                            self.tr("Routes (*.json)"))
        if fn:
            self.save(fn if fn.endswith(".json") else fn + ".json")

    def _dir(self) -> str:
        if self.path is not None:
            return str(self.path)
        # the operator's routes folder (platformdirs), else the shipped routes: never a
        # folder relative to the working directory
        d = user_routes_dir()
        return str(d if d.is_dir() else resource("routes"))

    # ------------------------------------------------------------ view
    def _say(self, text: str, *, error: bool = False) -> None:
        self.message.setText(text)
        self.message.setProperty("abnormal", "true" if error else "false")
        self.message.style().unpolish(self.message)
        self.message.style().polish(self.message)

    def message_text(self) -> str:
        return self.message.text()

    def _changed(self, *, select: int) -> None:
        self._refresh()
        if select >= 0:
            self.select(select)
        self._sync_form()
        self.route_changed.emit()

    def _refresh(self) -> None:
        self.name_label.setText(self.tr("Route: <b>{name}</b>").format(name=self.route.name))
        pts = self.route.points
        self.table.setRowCount(len(pts))
        for r, p in enumerate(pts):
            cells = (str(r + 1), p.name, translate("PatrolState", p.kind), f"{p.x_m:.2f}",
                     f"{p.y_m:.2f}",
                     p.gauge or "—", f"{p.dwell_s:g}")
            for c, text in enumerate(cells):
                item = QTableWidgetItem(text)
                if c in (0, 3, 4, 6):
                    item.setTextAlignment(Qt.AlignmentFlag.AlignRight
                                          | Qt.AlignmentFlag.AlignVCenter)
                self.table.setItem(r, c, item)
        self.start_button.setEnabled(bool(pts))
        self.save_button.setEnabled(bool(pts))

    def _sync_form(self) -> None:
        row = self.current_row()
        has = row >= 0
        for w in (self.remove_button, self.up_button, self.down_button, self.rename_button,
                  self.gauge_button, self.kind_combo, self.dwell_spin):
            w.setEnabled(has)
        if has:
            p = self.route.points[row]
            self._syncing = True
            try:
                self.kind_combo.setCurrentIndex(max(0, self.kind_combo.findData(p.kind)))
                self.dwell_spin.setValue(p.dwell_s)
            finally:
                self._syncing = False

    def _on_dwell(self, v: float) -> None:
        if not self._syncing:
            self.set_dwell(self.current_row(), v)
