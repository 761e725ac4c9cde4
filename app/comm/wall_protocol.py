"""The wall climber's link messages (docs/protocol.md, "Wall climber"): the wall
and its coverage plan, coverage progress, probe thickness readings, and the
climber's pose on the unrolled wall. Qt-free; registered with the frame codec on import
(:mod:`app.comm.protocol` imports this module; message types 20–23, apart from the
patrol robot's).

Grids travel as zlib-compressed, base64-encoded arrays (row-major, ``rows × cols``
from :class:`WallInfo`). The desk never receives a true thickness: only the
probe's readings, where the robot believes its probe was.
"""

from __future__ import annotations

import base64
import binascii
import struct
import zlib
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from app.comm.protocol import (
    MESSAGE_CLASSES,
    MsgType,
    ProtocolError,
    _JsonMessage,
    _unpack_exact,
)

MAX_CELLS = 1 << 21  # 2 M cells: a 24 m × 9.6 m wall at 0.1 m has 72 000


def pack_array(a: np.ndarray, dtype: str) -> str:
    """A numeric array as base64 text of its zlib-compressed bytes."""
    raw = np.ascontiguousarray(a, dtype=dtype).tobytes()
    return base64.b64encode(zlib.compress(raw, 6)).decode("ascii")


def unpack_array(text: Any, dtype: str, count: int) -> np.ndarray:
    """Inverse of :func:`pack_array`; ``count`` elements expected (ProtocolError else)."""
    if not isinstance(text, str):
        raise ProtocolError("packed array is not a string")
    want = count * np.dtype(dtype).itemsize
    try:  # never inflate past what the wall needs (a small payload cannot balloon)
        raw = zlib.decompressobj().decompress(base64.b64decode(text, validate=True),
                                              want + 1)
    except (binascii.Error, zlib.error, ValueError) as e:
        raise ProtocolError(f"packed array does not decode: {e}") from None
    if len(raw) != count * np.dtype(dtype).itemsize:
        raise ProtocolError(f"packed array has {len(raw)} bytes, expected "
                            f"{count} × {np.dtype(dtype).itemsize}")
    return np.frombuffer(raw, dtype=dtype).copy()


@dataclass
class WallInfo(_JsonMessage):
    """The wall the climber inspects and its plan, sent on connect and on a new plan.

    ``blocked`` (u8 per cell, 1 = obstacle), ``labels`` (i32 sub-region per cell,
    −1 blocked), ``path`` (i32 flat cell indices ``row * cols + col`` in the order
    the probe visits them) are :func:`pack_array` text; ``order`` the sub-regions'
    visiting order; ``limit_mm`` the thickness below which the wall is reported thin.
    Cell (row, col) spans x ∈ [col·cell_m, (col+1)·cell_m) round the tank from the
    shell's seam and y ∈ [row·cell_m, …) up from the bottom."""

    TYPE: ClassVar[MsgType] = MsgType.WALL_INFO
    _FIELDS: ClassVar[tuple[str, ...]] = ("name", "cell_m", "rows", "cols", "nominal_mm",
                                          "limit_mm", "blocked", "labels", "order", "path",
                                          "seams")
    name: str = ""
    cell_m: float = 0.1
    rows: int = 0
    cols: int = 0
    nominal_mm: float = 10.0
    limit_mm: float = 8.0
    blocked: str = ""
    labels: str = ""
    order: list[int] = field(default_factory=list)
    path: str = ""
    seams: list[list[float]] = field(default_factory=list)  # [x0, y0, x1, y1] m

    @classmethod
    def build(cls, name: str, cell_m: float, blocked: np.ndarray, labels: np.ndarray,
              order, path_cells, nominal_mm: float, limit_mm: float,
              seams=()) -> WallInfo:
        rows, cols = blocked.shape
        flat = np.array([r * cols + c for r, c in path_cells], dtype=np.int32)
        return cls(name, float(cell_m), int(rows), int(cols), float(nominal_mm),
                   float(limit_mm), pack_array(blocked.astype(np.uint8), "<u1"),
                   pack_array(labels, "<i4"), [int(i) for i in order],
                   pack_array(flat, "<i4"), [[float(v) for v in s] for s in seams])

    @classmethod
    def unpack(cls, b: bytes) -> WallInfo:
        w = super().unpack(b)
        if not (isinstance(w.name, str) and isinstance(w.cell_m, (int, float))
                and type(w.rows) is int and type(w.cols) is int
                and isinstance(w.nominal_mm, (int, float))
                and isinstance(w.limit_mm, (int, float)) and isinstance(w.order, list)
                and all(type(i) is int for i in w.order) and isinstance(w.seams, list)
                and isinstance(w.blocked, str) and isinstance(w.labels, str)
                and isinstance(w.path, str)):
            raise ProtocolError("wall info fields have the wrong types")
        if not (w.cell_m > 0 and w.rows > 0 and w.cols > 0 and w.rows * w.cols <= MAX_CELLS):
            raise ProtocolError(f"wall of {w.rows}×{w.cols} cells at {w.cell_m} m is not valid")
        return w

    def blocked_grid(self) -> np.ndarray:
        n = self.rows * self.cols
        return unpack_array(self.blocked, "<u1", n).reshape(self.rows, self.cols).astype(bool)

    def label_grid(self) -> np.ndarray:
        return unpack_array(self.labels, "<i4", self.rows * self.cols).reshape(self.rows,
                                                                              self.cols)

    def path_cells(self) -> np.ndarray:
        """The plan as an (n, 2) array of (row, col)."""
        try:
            raw = base64.b64decode(self.path, validate=True)
            flat = np.frombuffer(zlib.decompressobj().decompress(raw, 4 * MAX_CELLS),
                                 dtype="<i4")
        except (binascii.Error, zlib.error, ValueError) as e:
            raise ProtocolError(f"wall path does not decode: {e}") from None
        if flat.size and (flat.min() < 0 or flat.max() >= self.rows * self.cols):
            raise ProtocolError("wall path leaves the wall")
        return np.stack([flat // self.cols, flat % self.cols], axis=1)


class CoverageState:
    IDLE, RUNNING, PAUSED, DONE, ABORTED = range(5)
    NAMES: ClassVar[tuple[str, ...]] = ("idle", "running", "paused", "done", "aborted")


@dataclass
class CoverageProgress:
    """Where the inspection stands, ~2 Hz: ``<IIIIIB`` reachable cells (the plan's
    distinct cells), covered (probed, as the robot believes), visits (cells entered,
    counting repeats), plan_index, plan_len, state (:class:`CoverageState`); then the
    covered cells as a zlib-compressed bit mask (``np.packbits``, row-major)."""

    TYPE: ClassVar[MsgType] = MsgType.COVERAGE
    _S: ClassVar[struct.Struct] = struct.Struct("<IIIIIB")
    reachable: int = 0
    covered: int = 0
    visits: int = 0
    plan_index: int = 0
    plan_len: int = 0
    state: int = 0
    mask_z: bytes = b""

    @property
    def coverage_pct(self) -> float:
        return 100.0 * self.covered / self.reachable if self.reachable else 0.0

    @property
    def repetition_pct(self) -> float:
        """(visits − distinct) / reachable, as seed 001 and docs/coverage.md count it."""
        return 100.0 * max(0, self.visits - self.covered) / self.reachable \
            if self.reachable else 0.0

    @classmethod
    def build(cls, covered_mask: np.ndarray, reachable: int, visits: int, plan_index: int,
              plan_len: int, state: int) -> CoverageProgress:
        bits = np.packbits(np.asarray(covered_mask, dtype=bool).ravel())
        return cls(int(reachable), int(covered_mask.sum()), int(visits), int(plan_index),
                   int(plan_len), int(state), zlib.compress(bits.tobytes(), 6))

    def mask(self, rows: int, cols: int) -> np.ndarray:
        n = rows * cols
        try:
            raw = zlib.decompressobj().decompress(self.mask_z, (n + 7) // 8 + 1)
        except zlib.error as e:
            raise ProtocolError(f"coverage mask does not decode: {e}") from None
        if len(raw) != (n + 7) // 8:
            raise ProtocolError(f"coverage mask has {len(raw)} bytes for {rows}×{cols} cells")
        return np.unpackbits(np.frombuffer(raw, np.uint8))[:n].reshape(rows, cols).astype(bool)

    def pack(self) -> bytes:
        return self._S.pack(self.reachable, self.covered, self.visits, self.plan_index,
                            self.plan_len, self.state) + bytes(self.mask_z)

    @classmethod
    def unpack(cls, b: bytes) -> CoverageProgress:
        if len(b) < cls._S.size:
            raise ProtocolError("coverage payload too short")
        vals = cls._S.unpack_from(b)
        if vals[5] >= len(CoverageState.NAMES) or vals[1] > vals[0] or vals[0] > MAX_CELLS:
            raise ProtocolError("coverage fields out of range")
        return cls(*vals, bytes(b[cls._S.size:]))


@dataclass
class ProbeReadings:
    """Ultrasonic thickness readings, a batch: ``<I`` count, then rows of ``<fff``
    x_m, y_m (the probe's believed position on the unrolled wall), thickness_mm."""

    TYPE: ClassVar[MsgType] = MsgType.PROBE
    _S: ClassVar[struct.Struct] = struct.Struct("<I")
    rows: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.float32))

    def pack(self) -> bytes:
        r = np.asarray(self.rows, dtype="<f4").reshape(-1, 3)
        return self._S.pack(len(r)) + r.tobytes()

    @classmethod
    def unpack(cls, b: bytes) -> ProbeReadings:
        if len(b) < cls._S.size:
            raise ProtocolError("probe payload too short")
        (n,) = cls._S.unpack_from(b)
        if len(b) != cls._S.size + 12 * n:
            raise ProtocolError(f"{n} probe readings need {12 * n} bytes")
        r = np.frombuffer(b, dtype="<f4", count=3 * n, offset=cls._S.size)
        return cls(r.reshape(n, 3).astype(np.float32))


@dataclass
class WallPose:
    """The climber's own pose estimate on the unrolled wall (never ground truth):
    ``<dddfff`` x_m (round the tank, wraps at the circumference), y_m (up),
    theta_rad (from +x, counter-clockwise), v_mps, omega_rps, sigma_m (1σ of the
    position estimate)."""

    TYPE: ClassVar[MsgType] = MsgType.WALL_POSE
    _S: ClassVar[struct.Struct] = struct.Struct("<dddfff")
    x_m: float = 0.0
    y_m: float = 0.0
    theta_rad: float = 0.0
    v_mps: float = 0.0
    omega_rps: float = 0.0
    sigma_m: float = 0.0

    def pack(self) -> bytes:
        return self._S.pack(self.x_m, self.y_m, self.theta_rad, self.v_mps, self.omega_rps,
                            self.sigma_m)

    @classmethod
    def unpack(cls, b: bytes) -> WallPose:
        return cls(*_unpack_exact(cls._S, b))


WALL_MESSAGES: tuple[type, ...] = (WallInfo, CoverageProgress, ProbeReadings, WallPose)
MESSAGE_CLASSES.update({c.TYPE: c for c in WALL_MESSAGES})
