"""A tape of what a robot link reported, recorded once and played back into a desk.

A live patrol on a loaded machine never sends the same messages twice, so two
versions of the desk cannot be compared on it. ``TapeRecorder`` keeps every
signal a RobotLink emitted (``LinkSignals.RELAYED``), with its time, as pickled
payloads; camera frames keep their metadata and one of a few stored images (the
pixels' content does not change what the desk does with them). ``TapePlayer`` is
a stand-in link (tests/ui/fakes.FakeLink's intents, recorded and not sent) that
emits the tape again at the recorded pace, the times the desk stamps on arrival
(``received_s``) set to now, round after round.

Recorded by ``bench/desk_soak.py --record FILE``; played by ``bench/desk_replay_ab.py``.
"""

from __future__ import annotations

import copy
import pickle
import time
from pathlib import Path

from app.comm.link import LinkSignals

KEEP_IMAGES = 8


class TapeRecorder:
    def __init__(self, link: LinkSignals, keep_images: int = KEEP_IMAGES) -> None:
        self.t0 = time.perf_counter()
        self.events: list[tuple[float, str, bytes, int]] = []  # t, signal, payload, image
        self.images: list = []
        self.keep_images = keep_images
        self.frames = 0
        for name in LinkSignals.RELAYED:
            getattr(link, name).connect(lambda *args, name=name: self._on(name, args))

    def _on(self, name: str, args: tuple) -> None:
        image = -1
        if name == "frame_decoded" and args and hasattr(args[0], "image"):
            frame = copy.copy(args[0])
            if len(self.images) < self.keep_images:
                self.images.append(frame.image.copy())
            image = self.frames % len(self.images)
            self.frames += 1
            frame.image = None
            args = (frame,)
        self.events.append((time.perf_counter() - self.t0, name, pickle.dumps(args), image))

    def save(self, path: str | Path) -> None:
        with open(path, "wb") as f:
            pickle.dump({"events": self.events, "images": self.images}, f)


def _fake_link_class():
    from tests.ui.fakes import FakeLink

    return FakeLink


class TapePlayer(_fake_link_class()):
    """Plays a tape into whatever listens to its signals, from :meth:`start`."""

    def __init__(self, path: str | Path, tick_ms: int = 5) -> None:
        super().__init__()
        from PySide6.QtCore import Qt, QTimer

        with open(path, "rb") as f:
            tape = pickle.load(f)
        self.events = tape["events"]
        self.images = tape["images"]
        self.length_s = self.events[-1][0] if self.events else 0.0
        self.emitted = 0
        self.rounds = 0
        self._i = 0
        self._t0 = 0.0
        self._timer = QTimer(self)
        self._timer.setTimerType(Qt.TimerType.PreciseTimer)
        self._timer.setInterval(tick_ms)
        self._timer.timeout.connect(self._tick)

    def start(self) -> None:
        """Connected, then the tape (a tape begins after the desk's warm-up: the
        link had long been connected when it was recorded)."""
        if self.state != "connected":
            self.set_state("connected")
        self._t0 = time.perf_counter()
        self._timer.start()

    def stop(self) -> None:
        self._timer.stop()

    def _tick(self) -> None:
        elapsed = time.perf_counter() - self._t0
        while self._i < len(self.events) and self.events[self._i][0] <= elapsed:
            _t, name, payload, image = self.events[self._i]
            self._i += 1
            args = pickle.loads(payload)
            if image >= 0:
                args[0].image = self.images[image]
            for a in args:
                if hasattr(a, "received_s"):
                    a.received_s = time.time()
            if name == "state_changed":
                self.state = args[0]
            getattr(self, name).emit(*args)
            self.emitted += 1
        if self._i >= len(self.events):  # round again
            self._i = 0
            self.rounds += 1
            self._t0 = time.perf_counter()
