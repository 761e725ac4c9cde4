"""Fixed-capacity time series for live plots (no Qt).

A :class:`RingBuffer` holds the last ``capacity`` samples of one channel as two
float64 arrays (time in UTC epoch seconds, value). Memory is allocated (and
touched) once and never grows. :meth:`RingBuffer.window` returns the samples of the last
``seconds``; when they lie in one contiguous run of the ring it returns views
(no copy), otherwise it copies only the samples inside the window.

Times are expected to be non-decreasing. A sample older than the newest one (a
wall-clock step backwards) is stored at the newest time and counted in
``out_of_order``, so the window search (a binary search) stays valid.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np

__all__ = ["RingBuffer", "SeriesSet"]


class RingBuffer:
    """The last ``capacity`` (t, y) samples of one channel."""

    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"capacity must be >= 1, got {capacity}")
        self.capacity = int(capacity)
        # filled here, not np.zeros: a large zeroed array's pages are mapped lazily, so
        # the desk's resident memory crept up for hours as the ring filled (14 MB over
        # the first two hours of a 10 Hz desk); written once, the bound is there at once
        self._t = np.full(self.capacity, 0.0)
        self._y = np.full(self.capacity, 0.0)
        self._head = 0  # index the next sample is written to
        self._n = 0
        self.out_of_order = 0
        self.appended = 0  # samples ever appended (a change counter for views)

    def __len__(self) -> int:
        return self._n

    @property
    def nbytes(self) -> int:
        return self._t.nbytes + self._y.nbytes

    def clear(self) -> None:
        self._head = 0
        self._n = 0

    def append(self, t: float, y: float) -> None:
        t = float(t)
        if self._n and t < self._t[self._head - 1]:
            self.out_of_order += 1
            t = float(self._t[self._head - 1])
        self._t[self._head] = t
        self._y[self._head] = y
        self._head = (self._head + 1) % self.capacity
        self._n = min(self._n + 1, self.capacity)
        self.appended += 1

    def latest(self) -> tuple[float, float] | None:
        """The newest sample, or None when empty."""
        if not self._n:
            return None
        i = self._head - 1
        return float(self._t[i]), float(self._y[i])

    def _segments(self) -> list[tuple[int, int]]:
        """Index ranges [a, b) of the stored samples, oldest first."""
        if self._n < self.capacity:
            return [(0, self._n)]
        if self._head == 0:
            return [(0, self.capacity)]
        return [(self._head, self.capacity), (0, self._head)]

    def data(self) -> tuple[np.ndarray, np.ndarray]:
        """All stored samples, oldest first."""
        return self.window(math.inf)

    def window(self, seconds: float, end_t: float | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        """Samples with ``end_t - seconds <= t <= end_t`` (``end_t`` defaults to
        the newest sample's time), oldest first.

        The arrays may be views into the ring: they are valid until the next
        :meth:`append`; copy them to keep them longer.
        """
        empty = np.zeros(0, np.float64)
        if not self._n:
            return empty, empty.copy()
        if end_t is None:
            end_t = float(self._t[self._head - 1])
        start_t = end_t - seconds
        parts: list[tuple[int, int]] = []
        for a, b in self._segments():
            seg = self._t[a:b]
            lo = a + int(np.searchsorted(seg, start_t, side="left"))
            hi = a + int(np.searchsorted(seg, end_t, side="right"))
            if hi > lo:
                parts.append((lo, hi))
        if not parts:
            return empty, empty.copy()
        if len(parts) == 1:
            lo, hi = parts[0]
            return self._t[lo:hi], self._y[lo:hi]
        return (np.concatenate([self._t[a:b] for a, b in parts]),
                np.concatenate([self._y[a:b] for a, b in parts]))


class SeriesSet:
    """One :class:`RingBuffer` per named channel, all of the same capacity."""

    def __init__(self, channels: Iterable[str], capacity: int) -> None:
        self.capacity = int(capacity)
        self._buffers = {name: RingBuffer(capacity) for name in channels}

    @property
    def channels(self) -> list[str]:
        return list(self._buffers)

    def __contains__(self, channel: str) -> bool:
        return channel in self._buffers

    def __getitem__(self, channel: str) -> RingBuffer:
        return self._buffers[channel]

    def append(self, t: float, values: Mapping[str, float]) -> None:
        """Append one sample time with a value per channel; channels missing
        from ``values`` or holding NaN are skipped (a gap, not a zero)."""
        for name, buf in self._buffers.items():
            v = values.get(name)
            if v is None or not math.isfinite(v):
                continue
            buf.append(t, v)

    def window(self, channel: str, seconds: float, end_t: float | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        return self._buffers[channel].window(seconds, end_t)

    def clear(self) -> None:
        for buf in self._buffers.values():
            buf.clear()
