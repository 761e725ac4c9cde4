"""The operator's desk: video, data, control and alarms around one robot link.

Layout: an alarm banner on top (the most severe unacknowledged alarm), the video large
on the left with the data plots beside it, the control panel and the alarm list
with the event log below, and a status bar that always shows the link state,
round-trip time, frames dropped and messages per second.

The window runs the desk pipeline (app/core/desk, through the DeskSession Qt
adapter of app/session.py) that the headless desk and replay run too; its
models only adapt the pipeline to the views, and every intent leaves through
the pipeline's command gateway, which journals it. It never touches a socket.
A malformed message is logged, counted (shown in the status bar) and dropped.

Honest about what happened: an e-stop is reported as acknowledged by the robot
only when its ack arrives, and as NOT DELIVERED — an alarm — when the link is
down, drops, or the ack does not come (app/core/estop). Beside the banner a
line always shows the patrol's state, and a patrol the operator paused says that
F7 resumes it, from any tab. A replay (replay.attach_replay) hides every control.
The menus are built in app/ui/window_menus.py, the status bar's fields kept in
app/ui/window_status.py (a part of this class), the saved layout in
app/ui/window_settings.py.

Every value the robot sent (telemetry tiles, mode, battery, patrol state, pose,
round-trip time, the control line, video) is noted in a FreshnessModel; once the
link is down, or a stream goes quiet, each shows its age ("last known 15:17:21,
40 s ago") in the stale look, and control says "no link".
"""

from __future__ import annotations

import logging
from typing import Any

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QSplitter,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app.comm.protocol import RobotMode
from app.core import estop
from app.core.alarms import AlarmConfig, Priority
from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.ui.alarm_banner import AlarmBanner, latched_states, tile_level
from app.ui.alarm_dialogs import AlarmSettingsDialog
from app.ui.alarm_panel import AlarmPanel
from app.ui.control_panel import ControlPanel
from app.ui.data_panel import DataPanel
from app.ui.freshness_model import FreshnessModel
from app.ui.models import (
    LinkModel,
    TelemetryModel,
    VideoModel,
    battery_percent,
    control_text,
    link_state_text,
    mode_label,
)
from app.ui.video_panel import VideoPanel
from app.ui.window_menus import build_menus
from app.ui.window_status import StatusBarViews
from app.widgets import set_stale

log = logging.getLogger(__name__)

LINK_SIGNALS = ("state_changed", "telemetry_received", "event_received", "ack_received",
                "frame_decoded", "stats_changed")


# the splitters' sizes as built (by object name), which "Reset layout" returns to
DEFAULT_SPLITS = {"viewsSplitter": [840, 600], "controlSplitter": [420, 1020],
                  "bodySplitter": [560, 300]}


def _group(title: str, widget: QWidget) -> QGroupBox:
    box = QGroupBox(title)
    lay = QVBoxLayout(box)
    lay.setContentsMargins(4, 8, 4, 4)
    lay.addWidget(widget)
    return box


class MainWindow(StatusBarViews, QMainWindow):
    """``MainWindow(link)``: ``link`` is a RobotLink or anything with its signals
    (state_changed, telemetry_received, event_received, ack_received,
    frame_decoded, stats_changed) and its intents (drive, stop, estop,
    reset_estop)."""

    def __init__(self, link: Any, *, desk: Any = None,
                 title: str = QT_TRANSLATE_NOOP("MainWindow", "Station Patrol"),
                 alarm_config: AlarmConfig | None = None,
                 parent: QWidget | None = None) -> None:
        """``desk``: the DeskSession to show (app/session.py; None: one without an
        archive is made on ``link``)."""
        super().__init__(parent)
        for name in LINK_SIGNALS:
            if not hasattr(link, name):
                raise TypeError(f"the link has no signal {name!r}")
        self.link = link
        self.setWindowTitle(self.tr(title))
        if desk is None:
            from app.session import DeskSession
            desk = DeskSession(link, alarm_config=alarm_config, parent=self)
        self.desk = self.session = desk
        p = self.pipeline = desk.pipeline
        self.gateway = desk.gateway
        self.telemetry_model = TelemetryModel(self, pipeline=p)
        self.video_model = VideoModel(self)
        p.listen("frame", self.video_model.on_frame)
        self.link_model = LinkModel(self, pipeline=p)
        self.freshness = FreshnessModel(self)
        self.malformed_total = 0
        self.replay_mode = False
        self.window_settings = None  # the saved layout, once keep_layout() is called
        self.estop_delivery = self.gateway.estop_delivery
        p.listen("estop", self._show_estop)

        # ---- views
        self.banner = AlarmBanner(self.telemetry_model.monitor, self)
        self.video_panel = VideoPanel(self.video_model, self)
        self.data_panel = DataPanel(self.telemetry_model, self)
        self.control_panel = ControlPanel(self)
        # the operator's actions are timed on the telemetry's clock, as the alarm timers are
        self.alarm_panel = AlarmPanel(self.telemetry_model.monitor, self,
                                      clock=self.telemetry_model.alarm_time)

        # the large view area: camera first; the map and the meter table are
        # further tabs (keyboard: Ctrl+Tab cycles)
        self.views = QTabWidget(self)
        self.views.setDocumentMode(True)
        self.views.addTab(self.video_panel, self.tr("Camera"))
        # --- map panel (tab) ---
        from app.ui.map_model import MapModel
        from app.ui.map_panel import MapPanel
        self.map_model = MapModel(self)
        self.map_panel = MapPanel(self.map_model, self)
        self.views.addTab(self.map_panel, self.tr("Map"))
        for kind in ("map", "pose", "path", "obstacles", "scan", "patrol_status"):
            p.listen(kind, getattr(self.map_model, f"on_{kind}"))
        self.map_model.malformed.connect(self._on_malformed)
        self.map_model.changed.connect(self._on_map_changed)
        self.map_panel.command_requested.connect(
            lambda name, args: self._intent("send_command", name, args))
        self.map_panel.command_requested.connect(
            lambda name, args: self.alarm_panel.add_log(
                "info", "desk", self.tr("{name} requested").format(name=name)))
        # --- meter panel (tab) ---
        from app.ui.meter_panel import MeterModel, MeterPanel
        self.meter_model = MeterModel(desk, parent=self)
        self.meter_panel = MeterPanel(self.meter_model, self)
        self.views.addTab(self.meter_panel, self.tr("Meters"))
        self.meter_model.log_line.connect(lambda lv, t: self.alarm_panel.add_log(lv, "meter", t))
        self.meter_model.overlays_changed.connect(self.video_panel.view.set_overlays)
        # calibrated inspection points: the route file open in the editor, else the
        # robot's default route
        from app.core.paths import default_route_file
        editor = self.map_panel.editor
        self.meter_model.set_route(editor.path or default_route_file())
        editor.file_changed.connect(self.meter_model.set_route)
        self.meter_panel.point_calibrated.connect(
            lambda _pt, _prof: editor.adopt_profiles(self.meter_model.service.route_path))

        # --- tank-wall panel (tab), shown when a wall climber is connected
        from app.ui.wall_panel import install_wall_tab
        install_wall_tab(self)

        # splitters are named: their state is saved by name (app/ui/window_settings.py)
        top = QSplitter(Qt.Orientation.Horizontal)
        top.setObjectName("viewsSplitter")
        top.addWidget(self.views)
        top.addWidget(_group(self.tr("Environment"), self.data_panel))
        top.setStretchFactor(0, 3)
        top.setStretchFactor(1, 2)
        top.setSizes(DEFAULT_SPLITS["viewsSplitter"])
        bottom = QSplitter(Qt.Orientation.Horizontal)
        bottom.setObjectName("controlSplitter")
        bottom.addWidget(_group(self.tr("Control"), self.control_panel))
        bottom.addWidget(_group(self.tr("Alarms and events"), self.alarm_panel))
        bottom.setStretchFactor(0, 1)
        bottom.setStretchFactor(1, 2)
        bottom.setSizes(DEFAULT_SPLITS["controlSplitter"])
        body = QSplitter(Qt.Orientation.Vertical)
        body.setObjectName("bodySplitter")
        body.addWidget(top)
        body.addWidget(bottom)
        body.setStretchFactor(0, 3)
        body.setStretchFactor(1, 2)
        body.setSizes(DEFAULT_SPLITS["bodySplitter"])
        # what "Reset layout" returns to (sizes() means nothing before the first show)
        self.default_splitter_sizes = DEFAULT_SPLITS
        central = QWidget(self)
        cl = QVBoxLayout(central)
        cl.setContentsMargins(4, 4, 4, 4)
        # the patrol's state beside the banner: visible whichever tab is shown
        from app.ui.map_model import patrol_line
        self._patrol_line = patrol_line
        self.patrol_label = QLabel(patrol_line(None)[0], self)
        self.patrol_label.setObjectName("patrolLine")
        self.patrol_label.setToolTip(self.tr("The autonomous patrol, as the robot last reported it "
                                             "(F7 resumes a paused patrol from any tab)"))
        head = QHBoxLayout()
        head.addWidget(self.banner, 1)
        head.addWidget(self.patrol_label)
        cl.addLayout(head)
        cl.addWidget(body, 1)
        self.setCentralWidget(central)

        self._build_status_bar()

        # ---- wiring: the pipeline (fed by the link through the desk session) -> models
        p.listen("event", self._on_event)
        p.listen("ack", self._on_ack)
        p.listen("pose", self._on_pose)
        p.listen("control", self._on_control)
        p.listen("patrol_status", lambda _m: self.freshness.note("patrol"))
        p.listen("malformed", self._on_malformed)
        self.video_model.malformed.connect(self._on_malformed)
        self.link_model.malformed.connect(self._on_malformed)
        tm_ = self.telemetry_model
        tm_.values_changed.connect(lambda v: self.freshness.note("telemetry", v))
        self.video_model.frame_changed.connect(lambda _f: self.freshness.note("video"))
        self.link_model.state_changed.connect(self.freshness.on_link_state)
        self.freshness.changed.connect(self._on_freshness)
        # the 4WS robot's wheels (control panel) and TEB plan (map), shown once it reports
        from app.ui.fws_panel import install_fws_view
        install_fws_view(self)

        # ---- models -> views
        tm = self.telemetry_model
        tm.alarm_changed.connect(self._on_alarm_changed)
        self.alarm_panel.alarm_selected.connect(self._on_alarm_selected)
        tm.values_changed.connect(self._on_values)
        # the battery figure and the status bar's pose show the newest of the messages
        # that came in one pass of the event loop (app/ui/frame_batch.py)
        from app.ui.frame_batch import Coalesced
        self.battery_batch = Coalesced(self._show_battery, self)
        self.pose_batch = Coalesced(self.show_pose, self)
        tm.mode_changed.connect(self._on_mode)
        self.link_model.state_changed.connect(self._on_link_state)
        self.link_model.stats_changed.connect(self._show_stats)
        self.link_model.link_restored.connect(self._on_link_restored)

        # ---- views -> link (intents)
        cp = self.control_panel
        cp.drive_requested.connect(lambda lin, ang: self._intent("drive", lin, ang))
        cp.stop_requested.connect(lambda: self._intent("stop"))
        cp.estop_requested.connect(self._on_estop)
        cp.reset_estop_requested.connect(self._on_reset_estop)
        cp.control_requested.connect(lambda: self._intent("request_control"))

        self._build_actions()
        # history, replay and the patrol report (Review menu; docs/review.md)
        from app.ui.history_window import install_review_menu
        self.review = install_review_menu(self, replay_window=MainWindow)

    # ------------------------------------------------------------ actions
    def _build_actions(self) -> None:
        build_menus(self)  # app/ui/window_menus.py

    # ------------------------------------------------------------ intents
    def _intent(self, name: str, *args: Any) -> Any:
        """Hand an intent to the command gateway (which journals what became of it)."""
        g = self.gateway
        call = {"drive": g.drive, "stop": g.stop, "estop": g.estop,
                "reset_estop": g.reset_estop, "send_command": g.send}.get(name)
        entry = call(*args) if call is not None else g.send(name, *args)
        if entry is not None and entry.outcome != "sent" and entry.why:
            self.statusBar().showMessage(self.tr("{name} {outcome}: {why}").format(
                name=entry.name, outcome=translate("Gateway", entry.outcome),
                why=translate("Gateway", entry.why)), 5000)
        return entry

    @property
    def intent_errors(self) -> int:
        """Intents the link failed to take (it raised)."""
        return self.gateway.errors

    def resume_patrol(self) -> None:
        """F7 (any tab): resume a paused patrol."""
        if self.replay_mode:
            self.statusBar().showMessage(self.tr("replay is view-only: resume not sent"), 4000)
            return
        if not self.map_panel.link_up:
            self.statusBar().showMessage(self.tr("no link to the robot: resume not sent"), 5000)
            return
        state = self.map_model.patrol_state()
        if state not in (None, "paused"):
            self.statusBar().showMessage(
                self.tr("no paused patrol to resume (patrol {state})").format(state=state), 5000)
            return
        self._intent("send_command", "resume_patrol", {})
        self.alarm_panel.add_log("info", "desk", self.tr("resume_patrol requested (F7)"))

    def _on_estop(self) -> None:
        if self.replay_mode:
            self.statusBar().showMessage(self.tr("replay is view-only: no e-stop sent"), 4000)
            return
        self.alarm_panel.add_log("alarm", "desk", self.tr("EMERGENCY STOP pressed"))
        self._intent("estop")  # the gateway reports its delivery (_show_estop)

    def _show_estop(self, report: estop.EstopReport) -> None:
        """The e-stop's delivery (the pipeline raises or clears its alarm itself)."""
        failed = report.status == "not_delivered" and report.alarm is not False
        self.control_panel.set_estop_status(report.text, failed)
        self.statusBar().showMessage(report.text, 0 if failed else 15000)
        self.alarm_panel.add_log("alarm" if failed else "info", "desk", report.text)

    def _on_reset_estop(self) -> None:
        self._intent("reset_estop")
        self.alarm_panel.add_log("info", "desk", self.tr("e-stop reset requested"))

    # ------------------------------------------------------------ model slots
    def _on_event(self, ev: Any) -> None:
        level, code, text = str(ev.level), str(ev.code), str(ev.text)
        self.alarm_panel.add_log(level, "robot", f"{code}: {text}" if code else text)

    def _on_pose(self, pose: Any) -> None:
        x, y, th = float(pose.x_m), float(pose.y_m), float(pose.theta_rad)
        self.freshness.note("pose", (x, y, th))
        self.pose_batch.take()

    def _on_ack(self, ack: Any) -> None:
        if not bool(ack.ok):
            self.alarm_panel.add_log(
                "warning", "robot", self.tr("command {seq} refused: {reason}").format(
                    seq=int(ack.cmd_seq), reason=ack.reason))

    def _on_values(self, values: dict) -> None:
        self.battery_batch.take(values.get("battery_v", float("nan")))
        self._show_latched()

    def _show_battery(self, v: float) -> None:
        level = tile_level(self.telemetry_model.value_priority("battery_v"))
        self.control_panel.set_battery(v, battery_percent(v), level or None)

    def _show_latched(self) -> None:
        """The robot's latched safety states stay in the banner while they hold,
        acknowledged or not (the flags are this sample's; the mode too, once
        ``mode_changed`` has run)."""
        tm = self.telemetry_model
        states = latched_states(tm.mode, tm.alarm_flags)
        self.banner.set_latched(states)
        if states and states[0][0] == Priority.EMERGENCY:
            self.gateway.on_robot_estop()

    def _on_mode(self, mode: int) -> None:
        self._show_latched()
        abnormal = mode in (RobotMode.ESTOP, RobotMode.FAILSAFE)
        self.control_panel.set_mode(mode_label(mode), abnormal)
        self.alarm_panel.add_log("warning" if abnormal else "info", "robot",
                                 self.tr("mode {mode}").format(mode=mode_label(mode)))

    def _on_alarm_changed(self, tr) -> None:
        self.alarm_panel.on_transition(tr)
        self.banner.refresh()

    def _on_alarm_selected(self, alarm) -> None:
        """The selected alarm's channel, with its limits, on the data plot."""
        if alarm.channel:
            self.data_panel.show_channel(alarm.channel)

    def open_alarm_settings(self, dialog: AlarmSettingsDialog | None = None) -> bool:
        """Edit the limit rules; OK applies them to the running monitor."""
        dlg = dialog or AlarmSettingsDialog(self.telemetry_model.alarm_config, self)
        if dialog is None and dlg.exec() != AlarmSettingsDialog.DialogCode.Accepted:
            return False
        cfg = dlg.config()
        if cfg is None:
            return False
        self.telemetry_model.apply_alarm_config(cfg)
        self.data_panel.update_limits()
        self.alarm_panel.add_log("info", "desk", self.tr("alarm settings changed"))
        return True

    def banner_text(self) -> str:
        return self.banner.text()

    def _on_map_changed(self, layers: frozenset) -> None:
        if "patrol" in layers:
            self._show_patrol_line()

    def _show_patrol_line(self) -> None:
        """The header's patrol line; once no longer current, with its age in the stale
        look (no attention colour: the patrol may have moved on since)."""
        patrol = self.map_model.patrol
        text, attention = self._patrol_line(patrol)
        age = self.freshness.freshness("patrol").text() if patrol else ""
        self.patrol_label.setText(f"{text} ({age})" if age else text)
        self._set_abnormal(self.patrol_label, attention and not age)
        set_stale(self.patrol_label, bool(age))

    def patrol_text(self) -> str:
        return self.patrol_label.text()

    def _on_link_state(self, state: str) -> None:
        self._show_link_state(state)  # the pipeline decided it, and raised link.lost
        self.alarm_panel.add_log("warning" if state in LinkModel.ABNORMAL else "info",
                                 "link", link_state_text(state))

    def _on_link_restored(self) -> None:
        self.statusBar().showMessage(self.tr("Link restored"), 8000)
        self.alarm_panel.add_log("info", "link", self.tr("link restored"))

    def _on_control(self, c) -> None:
        text = control_text(getattr(c, "holder", None), bool(getattr(c, "mine", False)),
                            getattr(c, "requested_by", None))
        self.freshness.note("control", text)
        self.control_panel.set_view_only(bool(getattr(c, "view_only", False)), text)
        self._show_lease()
        self.alarm_panel.add_log("info", "control", text)

    # ------------------------------------------------------------ age of what is shown
    def _on_freshness(self, snap: dict) -> None:
        """Each robot-derived display with its age once it is no longer current."""
        f = self.freshness
        tel = f.freshness("telemetry")
        self.data_panel.show_freshness(tel)
        self.control_panel.show_freshness(tel, f.freshness("control"), not self._no_link())
        self.map_panel.show_freshness(f.freshness("patrol"), f.freshness("pose"))
        self._show_patrol_line()
        self._show_lease()
        self.show_pose()
        self._show_rtt()
        video = f.freshness("video")
        if video.stale:
            self.video_panel.show_stale(True, video.text())

    # ------------------------------------------------------------ lifecycle
    def closeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        self._intent("stop")
        if self.window_settings is not None:
            self.window_settings.save()
        super().closeEvent(event)

    def keep_layout(self, settings: Any = None) -> bool:
        """Restore this window's saved layout and save it on close (the live desk's
        window; a replay window does not). Returns False when none was saved."""
        from app.ui.window_settings import WindowSettings

        self.window_settings = WindowSettings(self, settings)
        return self.window_settings.restore()

    def reset_layout(self) -> None:
        """The layout the window was built with; the saved one is forgotten."""
        if self.window_settings is not None:
            self.window_settings.reset()
            self.statusBar().showMessage(self.tr("Layout reset"), 5000)

    def show_log_folder(self) -> str:
        """Open the log folder in the system's file manager; returns its path."""
        from app.ui.window_settings import open_log_folder

        return open_log_folder(self.statusBar())
