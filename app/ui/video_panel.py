"""Video panel: the live camera image with its frame rate and latency.

The figures under the image change with every frame; they are SteadyLabels, so a
new text repaints only its label and does not ask the window's layouts (the panel,
the tab widget, the splitters, the main window) to be worked out again, as a
plain QLabel whose text width changes does."""

from __future__ import annotations

import logging
import math

from PySide6.QtWidgets import QHBoxLayout, QLabel, QVBoxLayout, QWidget

from app.ui.models import VideoModel
from app.widgets import ImageView, SteadyLabel, set_stale

log = logging.getLogger(__name__)


class VideoPanel(QWidget):
    def __init__(self, model: VideoModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.view = ImageView(self, placeholder=self.tr("no video yet"))
        self.fps_label = SteadyLabel(self.tr("— fps"), self)
        self.latency_label = SteadyLabel(self.tr("latency — ms"), self)
        self.frame_label = SteadyLabel("", self)
        self.stale_label = QLabel("", self)
        info = QHBoxLayout()
        for w in (self.fps_label, self.latency_label, self.frame_label):
            info.addWidget(w)
        info.addStretch(1)
        info.addWidget(self.stale_label)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addWidget(self.view, 1)
        lay.addLayout(info)
        model.frame_changed.connect(self.show_frame)
        model.stats_changed.connect(self.show_stats)
        model.stale_changed.connect(self.show_stale)

    def show_frame(self, frame) -> None:
        try:
            self.view.set_image(frame.image)
        except ValueError as e:  # the model checks frames; this is a last guard
            log.warning("frame not shown: %s", e)
            return
        self.frame_label.setText(self.tr("frame {id}  {w}×{h}").format(
            id=frame.frame_id, w=frame.image.shape[1], h=frame.image.shape[0]))

    def show_stats(self, fps: float, latency_ms: float) -> None:
        self.fps_label.setText(f"{fps:.1f} fps")
        self.latency_label.setText(self.tr("latency — ms") if not math.isfinite(latency_ms)
                                   else self.tr("latency {ms} ms").format(ms=f"{latency_ms:.0f}"))

    def show_stale(self, stale: bool, age_text: str = "") -> None:
        """Old video is grey and outlined, with its age; not an alarm colour."""
        self.view.set_caption(self.tr("VIDEO STALE") if stale else "")
        self.stale_label.setText((self.tr("video stale") + (f" — {age_text}" if age_text else ""))
                                 if stale else "")
        set_stale(self.stale_label, stale)
