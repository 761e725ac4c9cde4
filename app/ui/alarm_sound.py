"""Alarm sounds per priority, with a mute toggle.

Each priority has its own tone pattern (higher priority: higher pitch, faster
pulses), played with QtMultimedia's QSoundEffect when PySide6 ships it, else
as that many system beeps (PySide6-Essentials has no QtMultimedia). Nothing
plays on an offscreen or minimal platform (tests, headless runs) — the requests
are still counted — and nothing while muted.
"""

from __future__ import annotations

import logging
import math
import struct
import tempfile
import wave
from pathlib import Path

from PySide6.QtCore import QObject, QTimer, QUrl, Signal
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QApplication

from app.core.alarms import Priority

log = logging.getLogger(__name__)

try:  # QtMultimedia is not in every PySide6 build
    from PySide6.QtMultimedia import QSoundEffect
except ImportError:  # pragma: no cover - depends on the installed wheel
    QSoundEffect = None

# priority -> (tone Hz, pulses, pulse length s)
TONES: dict[Priority, tuple[float, int, float]] = {
    Priority.EMERGENCY: (1400.0, 5, 0.08),
    Priority.HIGH: (1000.0, 3, 0.12),
    Priority.MEDIUM: (750.0, 2, 0.15),
    Priority.LOW: (500.0, 1, 0.2),
}


def tone_wav(path: Path, hz: float, pulses: int, pulse_s: float, rate: int = 22050) -> Path:
    """Write a short mono 16-bit WAV of ``pulses`` beeps at ``hz``."""
    frames = bytearray()
    n = int(pulse_s * rate)
    for _ in range(pulses):
        for i in range(n):
            env = min(1.0, i / 200, (n - i) / 200)  # no clicks
            frames += struct.pack("<h", int(12000 * env * math.sin(2 * math.pi * hz * i / rate)))
        frames += b"\0\0" * n  # a gap as long as the pulse
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes(bytes(frames))
    return path


class AlarmSound(QObject):
    muted_changed = Signal(bool)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.muted = False
        platform = QGuiApplication.platformName() if QGuiApplication.instance() else ""
        self.silent = platform in ("offscreen", "minimal", "")
        self.requested: dict[Priority, int] = {p: 0 for p in Priority}
        self.played = 0
        self._effects: dict[Priority, object] = {}
        self._dir: tempfile.TemporaryDirectory | None = None

    def set_muted(self, on: bool) -> None:
        if bool(on) != self.muted:
            self.muted = bool(on)
            if self.muted:
                for e in self._effects.values():
                    e.stop()
            self.muted_changed.emit(self.muted)

    def play(self, priority: Priority) -> bool:
        """Sound the tone of ``priority``; True when something was played."""
        p = Priority(priority)
        self.requested[p] += 1
        if self.muted or self.silent:
            return False
        try:
            effect = self._effect(p)
            if effect is not None:
                effect.play()
            else:  # the system beep, as many times as the priority's pulses
                pulses = TONES[p][1]
                QApplication.beep()
                for k in range(1, pulses):
                    QTimer.singleShot(250 * k, QApplication.beep)
            self.played += 1
            return True
        except Exception:  # a sound problem must never take the desk down
            log.exception("alarm sound failed")
            return False

    def _effect(self, p: Priority):
        if QSoundEffect is None:
            return None
        if p not in self._effects:
            if self._dir is None:
                self._dir = tempfile.TemporaryDirectory(prefix="station-patrol-sounds-")
            hz, pulses, pulse_s = TONES[p]
            f = tone_wav(Path(self._dir.name) / f"{p.name.lower()}.wav", hz, pulses, pulse_s)
            e = QSoundEffect(self)
            e.setSource(QUrl.fromLocalFile(str(f)))
            e.setVolume(0.8)
            self._effects[p] = e
        return self._effects[p]
