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
from app.core.freshness import POSE_WIDEST, Age, pose_status_text
from app.ui import theme
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
    mode_name,
    refusals_text,
)
from app.ui.video_panel import VideoPanel
from app.ui.window_menus import build_menus
from app.widgets import StatusLamp, set_stale

log = logging.getLogger(__name__)

LINK_SIGNALS = ("state_changed", "telemetry_received", "event_received", "ack_received",
                "frame_decoded", "stats_changed")


_POSE_TIP = "The robot's own odometry estimate"


def _group(title: str, widget: QWidget) -> QGroupBox:
    box = QGroupBox(title)
    lay = QVBoxLayout(box)
    lay.setContentsMargins(4, 8, 4, 4)
    lay.addWidget(widget)
    return box


class MainWindow(QMainWindow):
    """``MainWindow(link)``: ``link`` is a RobotLink or anything with its signals
    (state_changed, telemetry_received, event_received, ack_received,
    frame_decoded, stats_changed) and its intents (drive, stop, estop,
    reset_estop)."""

    def __init__(self, link: Any, *, desk: Any = None, title: str = "Station Patrol",
                 alarm_config: AlarmConfig | None = None,
                 parent: QWidget | None = None) -> None:
        """``desk``: the DeskSession to show (app/session.py; None: one without an
        archive is made on ``link``)."""
        super().__init__(parent)
        for name in LINK_SIGNALS:
            if not hasattr(link, name):
                raise TypeError(f"the link has no signal {name!r}")
        self.link = link
        self.setWindowTitle(title)
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
        self.views.addTab(self.video_panel, "Camera")
        # --- map panel (tab) ---
        from app.ui.map_model import MapModel
        from app.ui.map_panel import MapPanel
        self.map_model = MapModel(self)
        self.map_panel = MapPanel(self.map_model, self)
        self.views.addTab(self.map_panel, "Map")
        for kind in ("map", "pose", "path", "obstacles", "scan", "patrol_status"):
            p.listen(kind, getattr(self.map_model, f"on_{kind}"))
        self.map_model.malformed.connect(self._on_malformed)
        self.map_model.changed.connect(self._on_map_changed)
        self.map_panel.command_requested.connect(
            lambda name, args: self._intent("send_command", name, args))
        self.map_panel.command_requested.connect(
            lambda name, args: self.alarm_panel.add_log("info", "desk", f"{name} requested"))
        # --- meter panel (tab) ---
        from app.ui.meter_panel import MeterModel, MeterPanel
        self.meter_model = MeterModel(desk, parent=self)
        self.meter_panel = MeterPanel(self.meter_model, self)
        self.views.addTab(self.meter_panel, "Meters")
        self.meter_model.log_line.connect(lambda lv, t: self.alarm_panel.add_log(lv, "meter", t))
        self.meter_model.overlays_changed.connect(self.video_panel.view.set_overlays)
        # calibrated inspection points: the route file open in the editor, else the
        # robot's default route
        from app.core.meter_service import DEFAULT_ROUTE_FILE
        editor = self.map_panel.editor
        self.meter_model.set_route(editor.path or DEFAULT_ROUTE_FILE)
        editor.file_changed.connect(self.meter_model.set_route)
        self.meter_panel.point_calibrated.connect(
            lambda _pt, _prof: editor.adopt_profiles(self.meter_model.service.route_path))

        # --- tank-wall panel (tab), shown when a wall climber is connected
        from app.ui.wall_panel import install_wall_tab
        install_wall_tab(self)

        top = QSplitter(Qt.Orientation.Horizontal)
        top.addWidget(self.views)
        top.addWidget(_group("Environment", self.data_panel))
        top.setStretchFactor(0, 3)
        top.setStretchFactor(1, 2)
        top.setSizes([840, 600])
        bottom = QSplitter(Qt.Orientation.Horizontal)
        bottom.addWidget(_group("Control", self.control_panel))
        bottom.addWidget(_group("Alarms and events", self.alarm_panel))
        bottom.setStretchFactor(0, 1)
        bottom.setStretchFactor(1, 2)
        bottom.setSizes([420, 1020])
        body = QSplitter(Qt.Orientation.Vertical)
        body.addWidget(top)
        body.addWidget(bottom)
        body.setStretchFactor(0, 3)
        body.setStretchFactor(1, 2)
        body.setSizes([560, 300])
        central = QWidget(self)
        cl = QVBoxLayout(central)
        cl.setContentsMargins(4, 4, 4, 4)
        # the patrol's state beside the banner: visible whichever tab is shown
        from app.ui.map_model import patrol_line
        self._patrol_line = patrol_line
        self.patrol_label = QLabel(patrol_line(None)[0], self)
        self.patrol_label.setObjectName("patrolLine")
        self.patrol_label.setToolTip("The autonomous patrol, as the robot last reported it "
                                     "(F7 resumes a paused patrol from any tab)")
        head = QHBoxLayout()
        head.addWidget(self.banner, 1)
        head.addWidget(self.patrol_label)
        cl.addLayout(head)
        cl.addWidget(body, 1)
        self.setCentralWidget(central)

        # ---- status bar
        sb = self.statusBar()
        self.link_lamp = StatusLamp("link disconnected", self)
        self.pose_label = QLabel("pose —", self)
        self.pose_label.setToolTip(_POSE_TIP)
        # wide enough for the longest form it takes (live, or stale with its age), so
        # the permanent fields at the right never squeeze it into "last known 1…"
        fm = self.pose_label.fontMetrics()
        self.pose_label.setMinimumWidth(max(fm.horizontalAdvance(t) for t in POSE_WIDEST) + 8)
        self.rtt_label = QLabel("RTT — ms", self)
        self.dropped_label = QLabel("dropped 0", self)
        self.rate_label = QLabel("0.0 msg/s", self)
        self.malformed_label = QLabel("malformed 0", self)
        # refusals on both sides (desk decoder, robot's counts), telemetry gaps, the lease
        self.refused_label = QLabel("refused 0 · tel lost 0", self)
        self.lease_status = QLabel("control —", self)
        sb.addWidget(self.pose_label)
        for w in (self.link_lamp, self.lease_status, self.rtt_label, self.dropped_label,
                  self.rate_label, self.refused_label, self.malformed_label):
            sb.addPermanentWidget(w)
        self._show_link_state("disconnected")

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

        # ---- models -> views
        tm = self.telemetry_model
        tm.alarm_changed.connect(self._on_alarm_changed)
        self.alarm_panel.alarm_selected.connect(self._on_alarm_selected)
        tm.values_changed.connect(self._on_values)
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
            self.statusBar().showMessage(f"{entry.name} {entry.outcome}: {entry.why}", 5000)
        return entry

    @property
    def intent_errors(self) -> int:
        """Intents the link failed to take (it raised)."""
        return self.gateway.errors

    def resume_patrol(self) -> None:
        """F7 (any tab): resume a paused patrol."""
        if self.replay_mode:
            self.statusBar().showMessage("replay is view-only: resume not sent", 4000)
            return
        if not self.map_panel.link_up:
            self.statusBar().showMessage("no link to the robot: resume not sent", 5000)
            return
        state = self.map_model.patrol_state()
        if state not in (None, "paused"):
            self.statusBar().showMessage(f"no paused patrol to resume (patrol {state})", 5000)
            return
        self._intent("send_command", "resume_patrol", {})
        self.alarm_panel.add_log("info", "desk", "resume_patrol requested (F7)")

    def _on_estop(self) -> None:
        if self.replay_mode:
            self.statusBar().showMessage("replay is view-only: no e-stop sent", 4000)
            return
        self.alarm_panel.add_log("alarm", "desk", "EMERGENCY STOP pressed")
        self._intent("estop")  # the gateway reports its delivery (_show_estop)

    def _show_estop(self, report: estop.EstopReport) -> None:
        """The e-stop's delivery (the pipeline raises or clears its alarm itself)."""
        failed = report.status == "not_delivered" and report.alarm is not False
        self.control_panel.set_estop_status(report.text, failed)
        self.statusBar().showMessage(report.text, 0 if failed else 15000)
        self.alarm_panel.add_log("alarm" if failed else "info", "desk", report.text)

    def _on_reset_estop(self) -> None:
        self._intent("reset_estop")
        self.alarm_panel.add_log("info", "desk", "e-stop reset requested")

    # ------------------------------------------------------------ model slots
    def _on_event(self, ev: Any) -> None:
        level, code, text = str(ev.level), str(ev.code), str(ev.text)
        self.alarm_panel.add_log(level, "robot", f"{code}: {text}" if code else text)

    def _on_pose(self, pose: Any) -> None:
        x, y, th = float(pose.x_m), float(pose.y_m), float(pose.theta_rad)
        self.freshness.note("pose", (x, y, th))
        self.show_pose()

    def _on_ack(self, ack: Any) -> None:
        if not bool(ack.ok):
            self.alarm_panel.add_log(
                "warning", "robot", f"command {int(ack.cmd_seq)} refused: {ack.reason}")

    def _on_malformed(self, why: str) -> None:
        self.malformed_total += 1
        self.malformed_label.setText(f"malformed {self.malformed_total}")
        self._set_abnormal(self.malformed_label, True)

    def _on_values(self, values: dict) -> None:
        v = values.get("battery_v", float("nan"))
        level = tile_level(self.telemetry_model.value_priority("battery_v"))
        self.control_panel.set_battery(v, battery_percent(v), level or None)
        self._show_latched()

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
        self.control_panel.set_mode(mode_name(mode), abnormal)
        self.alarm_panel.add_log("warning" if abnormal else "info", "robot",
                                 f"mode {mode_name(mode)}")

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
        self.alarm_panel.add_log("info", "desk", "alarm settings changed")
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
                                 "link", state)

    def _show_link_state(self, state: str) -> None:
        abnormal = state in ("lost", "reconnecting")
        color = theme.ALARM_HIGH if state == "lost" else (
            theme.ABNORMAL if abnormal else None)
        self.link_lamp.set_status(f"link {state}", color)
        # without a link nothing that sends a command may look sendable (the e-stop
        # stays: it is tried anyway and says whether it arrived)
        self.control_panel.set_link_up(state == "connected")
        self.map_panel.set_link_up(state == "connected")

    def link_status_text(self) -> str:
        return self.link_lamp.text()

    def _on_link_restored(self) -> None:
        self.statusBar().showMessage("Link restored", 8000)
        self.alarm_panel.add_log("info", "link", "link restored")

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

    def _no_link(self) -> bool:
        """No link to tell who has control: down, and no word from the robot since."""
        f = self.freshness
        return not f.link_up and f.freshness("control").age in (Age.NO_LINK, Age.NONE)

    def _show_lease(self) -> None:
        f = self.freshness
        if self._no_link():
            when = f.freshness("control").text()
            text = "control: no link" + (f" ({when})" if when else "")
        else:
            text = f.tracker.value("control") or "control —"
        self.lease_status.setText(text)
        set_stale(self.lease_status, self._no_link())

    def show_pose(self) -> None:
        """The robot's pose; once no longer current a short form with its age
        ("pose 12.3, 4.5 · 7 s ago") and the full text in the tooltip."""
        f = self.freshness.freshness("pose")
        text, full = pose_status_text(self.freshness.tracker.value("pose"), f)
        self.pose_label.setText(text)
        self.pose_label.setToolTip(f"{_POSE_TIP}: {full}" if full else _POSE_TIP)
        set_stale(self.pose_label, f.stale)

    def _show_rtt(self) -> None:
        f = self.freshness.freshness("rtt")
        rtt = self.freshness.tracker.value("rtt")
        text = "RTT — ms" if rtt is None else f"RTT {rtt:.0f} ms"
        self.rtt_label.setText(f"{text} ({f.text()})" if f.stale else text)
        set_stale(self.rtt_label, f.stale)

    def _show_stats(self, s: dict) -> None:
        text, tip = refusals_text(s)
        self.refused_label.setText(text)
        self.refused_label.setToolTip(tip)
        own = {k: v for k, v in s.get("by_reason", {}).items() if k != "garbage_bytes"}
        if own and own != getattr(self, "_own_refusals", {}):
            self.alarm_panel.add_log("warning", "link", "desk decoder refused: " + ", ".join(
                f"{k} {v}" for k, v in sorted(own.items())))
        self._own_refusals = own
        rtt = s.get("rtt_ms")
        if rtt is not None and self.freshness.link_up:
            self.freshness.note("rtt", rtt)
        self._show_rtt()
        self.dropped_label.setText(f"dropped {s.get('frames_dropped', 0)}")
        self.dropped_label.setToolTip(
            f"frames the decoder dropped or could not decode: {s.get('frames_dropped', 0)}\n"
            f"camera frames replaced by a newer one before shown: "
            f"{s.get('video_stale_dropped', 0)}")
        self._set_abnormal(self.dropped_label, False)
        self.rate_label.setText(f"{s.get('msgs_per_s', 0.0):.1f} msg/s")

    @staticmethod
    def _set_abnormal(label: QLabel, on: bool) -> None:
        label.setProperty("abnormal", "true" if on else "false")
        label.style().unpolish(label)
        label.style().polish(label)

    # ------------------------------------------------------------ lifecycle
    def closeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        self._intent("stop")
        super().closeEvent(event)

    def status_texts(self) -> dict[str, str]:
        return {"link": self.link_lamp.text(), "rtt": self.rtt_label.text(),
                "dropped": self.dropped_label.text(), "rate": self.rate_label.text(),
                "malformed": self.malformed_label.text(),
                "refused": self.refused_label.text(), "control": self.lease_status.text(),
                "message": self.statusBar().currentMessage()}
