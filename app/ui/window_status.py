"""The main window's status bar: the link lamp, the robot's pose, round-trip time,
frames dropped, messages per second, malformed messages, refusals and who holds
control; each robot-derived field shows its age once it is no longer current.
The fields that change every second or faster are SteadyLabels (app/widgets), so
a new text does not make the status bar lay itself out again.

:class:`StatusBarViews` is a part of :class:`app.ui.main_window.MainWindow` (a
mixin): it builds the fields and keeps them up to date from the window's models
(``freshness``, the link model's statistics). Its texts are translated in the
``MainWindow`` context, as when they were built in the window itself.
"""

from __future__ import annotations

from PySide6.QtWidgets import QLabel

from app.core.freshness import POSE_WIDEST, Age, pose_status_text
from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.ui import theme
from app.ui.models import link_state_text, refusals_text
from app.widgets import StatusLamp, SteadyLabel, set_stale

__all__ = ["StatusBarViews"]

_POSE_TIP = QT_TRANSLATE_NOOP("MainWindow", "The robot's own odometry estimate")


class StatusBarViews:
    """The status bar's fields and their updates (see the module docstring)."""

    def _build_status_bar(self) -> None:
        sb = self.statusBar()
        self.link_lamp = StatusLamp(translate("MainWindow", "link disconnected"), self)
        self.pose_label = SteadyLabel(translate("MainWindow", "pose —"), self)
        self.pose_label.setToolTip(translate("MainWindow", _POSE_TIP))
        # wide enough for the longest form it takes (live, or stale with its age), so
        # the permanent fields at the right never squeeze it into "last known 1…"
        fm = self.pose_label.fontMetrics()
        self.pose_label.setMinimumWidth(max(fm.horizontalAdvance(t) for t in POSE_WIDEST) + 8)
        self.rtt_label = SteadyLabel(translate("MainWindow", "RTT — ms"), self)
        self.dropped_label = SteadyLabel(translate("MainWindow", "dropped {n}").format(n=0), self)
        self.rate_label = SteadyLabel(
            translate("MainWindow", "{rate} msg/s").format(rate="0.0"), self)
        self.malformed_label = SteadyLabel(
            translate("MainWindow", "malformed {n}").format(n=0), self)
        # refusals on both sides (desk decoder, robot's counts), telemetry gaps, the lease
        self.refused_label = SteadyLabel(translate("MainWindow", "refused 0 · tel lost 0"), self)
        self.lease_status = QLabel(translate("MainWindow", "control —"), self)
        sb.addWidget(self.pose_label)
        for w in (self.link_lamp, self.lease_status, self.rtt_label, self.dropped_label,
                  self.rate_label, self.refused_label, self.malformed_label):
            sb.addPermanentWidget(w)
        self._show_link_state("disconnected")

    def _on_malformed(self, why: str) -> None:
        self.malformed_total += 1
        self.malformed_label.setText(
            translate("MainWindow", "malformed {n}").format(n=self.malformed_total))
        self._set_abnormal(self.malformed_label, True)

    def _show_link_state(self, state: str) -> None:
        abnormal = state in ("lost", "reconnecting")
        color = theme.ALARM_HIGH if state == "lost" else (
            theme.ABNORMAL if abnormal else None)
        self.link_lamp.set_status(
            translate("MainWindow", "link {state}").format(state=link_state_text(state)), color)
        # without a link nothing that sends a command may look sendable (the e-stop
        # stays: it is tried anyway and says whether it arrived)
        self.control_panel.set_link_up(state == "connected")
        self.map_panel.set_link_up(state == "connected")

    def link_status_text(self) -> str:
        return self.link_lamp.text()

    def _no_link(self) -> bool:
        """No link to tell who has control: down, and no word from the robot since."""
        f = self.freshness
        return not f.link_up and f.freshness("control").age in (Age.NO_LINK, Age.NONE)

    def _show_lease(self) -> None:
        f = self.freshness
        if self._no_link():
            when = f.freshness("control").text()
            text = translate("MainWindow", "control: no link") + (f" ({when})" if when else "")
        else:
            text = f.tracker.value("control") or translate("MainWindow", "control —")
        self.lease_status.setText(text)
        set_stale(self.lease_status, self._no_link())

    def show_pose(self) -> None:
        """The robot's pose; once no longer current a short form with its age
        ("pose 12.3, 4.5 · 7 s ago") and the full text in the tooltip."""
        f = self.freshness.freshness("pose")
        text, full = pose_status_text(self.freshness.tracker.value("pose"), f)
        self.pose_label.setText(text)
        tip = translate("MainWindow", _POSE_TIP)
        tip = f"{tip}: {full}" if full else tip
        if tip != self.pose_label.toolTip():
            self.pose_label.setToolTip(tip)
        set_stale(self.pose_label, f.stale)

    def _show_rtt(self) -> None:
        f = self.freshness.freshness("rtt")
        rtt = self.freshness.tracker.value("rtt")
        text = (translate("MainWindow", "RTT — ms") if rtt is None
                else translate("MainWindow", "RTT {ms} ms").format(ms=f"{rtt:.0f}"))
        self.rtt_label.setText(f"{text} ({f.text()})" if f.stale else text)
        set_stale(self.rtt_label, f.stale)

    def _show_stats(self, s: dict) -> None:
        text, tip = refusals_text(s)
        self.refused_label.setText(text)
        self.refused_label.setToolTip(tip)
        own = {k: v for k, v in s.get("by_reason", {}).items() if k != "garbage_bytes"}
        if own and own != getattr(self, "_own_refusals", {}):
            self.alarm_panel.add_log(
                "warning", "link", translate("MainWindow", "desk decoder refused: ")
                + ", ".join(f"{k} {v}" for k, v in sorted(own.items())))
        self._own_refusals = own
        rtt = s.get("rtt_ms")
        if rtt is not None and self.freshness.link_up:
            self.freshness.note("rtt", rtt)
        self._show_rtt()
        self.dropped_label.setText(
            translate("MainWindow", "dropped {n}").format(n=s.get("frames_dropped", 0)))
        self.dropped_label.setToolTip(
            translate("MainWindow", "frames the decoder dropped or could not decode: {n}\n"
                    "camera frames replaced by a newer one before shown: {stale}").format(
                n=s.get("frames_dropped", 0), stale=s.get("video_stale_dropped", 0)))
        self._set_abnormal(self.dropped_label, False)
        self.rate_label.setText(
            translate("MainWindow", "{rate} msg/s").format(rate=f"{s.get('msgs_per_s', 0.0):.1f}"))

    @staticmethod
    def _set_abnormal(label: QLabel, on: bool) -> bool:
        """The attention look on ``label`` (style sheet: ``[abnormal="true"]``); True
        when it changed. Re-polishing is dear and the status comes every second: an
        unchanged look is left alone."""
        want = "true" if on else "false"
        if label.property("abnormal") == want:
            return False
        label.setProperty("abnormal", want)
        label.style().unpolish(label)
        label.style().polish(label)
        return True

    def status_texts(self) -> dict[str, str]:
        return {"link": self.link_lamp.text(), "rtt": self.rtt_label.text(),
                "dropped": self.dropped_label.text(), "rate": self.rate_label.text(),
                "malformed": self.malformed_label.text(),
                "refused": self.refused_label.text(), "control": self.lease_status.text(),
                "message": self.statusBar().currentMessage()}
