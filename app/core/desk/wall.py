"""The desk's model of a wall climber's inspection (no Qt): the unrolled wall
with its obstacles, sub-regions, their order and the planned path (from
``WALL_INFO``), the coverage (``COVERAGE``), the robot's pose on the wall
(``WALL_POSE``) and the thickness map built from the probe's readings
(``PROBE``), with the thin-wall alarm condition and the thinnest spots.

The pipeline (:mod:`app.core.desk.pipeline`) feeds every wall message to
:meth:`WallModel.ingest` and turns :meth:`WallModel.thin_condition` into an
ISA-18.2 alarm through its alarm monitor (``wall.thin``). Readings are placed
by the position the robot reports; a reading off the wall or over an obstacle
is counted in ``unplaced`` and kept out of the map.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from app.comm.wall_protocol import (
    CoverageProgress,
    CoverageState,
    ProbeReadings,
    WallInfo,
    WallPose,
)

__all__ = ["THIN_ALARM", "Spot", "WallModel"]

log = logging.getLogger(__name__)

THIN_ALARM = "wall.thin"
ALARM_APART_M = 0.5  # thin places nearer than this to an alarmed one share its alarm


@dataclass(frozen=True)
class Spot:
    """One measured cell: thickness and where it is on the unrolled wall."""

    thickness_mm: float
    row: int
    col: int
    x_m: float
    y_m: float

    def where(self) -> str:
        return f"x {self.x_m:.2f} m round, y {self.y_m:.2f} m up (cell {self.row}, {self.col})"


class WallModel:
    """What the desk knows of the wall under inspection. ``version`` rises on
    every change a view must redraw."""

    def __init__(self) -> None:
        self.info: WallInfo | None = None
        self.blocked = np.zeros((0, 0), bool)
        self.labels = np.zeros((0, 0), np.int32)
        self.path = np.zeros((0, 2), np.int64)
        self.covered = np.zeros((0, 0), bool)
        self.thickness = np.zeros((0, 0))  # mm, mean of the readings per cell; NaN unread
        self.reads = np.zeros((0, 0), np.int32)
        self.progress: CoverageProgress | None = None
        self.pose: WallPose | None = None
        self.readings = 0
        self.unplaced = 0
        self.alarmed: list[Spot] = []  # thin places already alarmed
        self.version = 0

    # ------------------------------------------------------------ input
    @property
    def ready(self) -> bool:
        return self.info is not None

    @property
    def limit_mm(self) -> float:
        return float(self.info.limit_mm) if self.info else math.nan

    def ingest(self, msg) -> str:
        """One wall message; returns its kind (info, coverage, probe, pose). Raises
        ValueError (ProtocolError) on a message that does not fit the wall."""
        if isinstance(msg, WallInfo):
            self._on_info(msg)
            kind = "info"
        elif isinstance(msg, CoverageProgress):
            if self.info is None:
                raise ValueError("coverage before the wall's description")
            self.covered = msg.mask(self.info.rows, self.info.cols)
            self.progress = msg
            kind = "coverage"
        elif isinstance(msg, ProbeReadings):
            if self.info is None:
                raise ValueError("probe readings before the wall's description")
            self._on_probe(np.asarray(msg.rows, float).reshape(-1, 3))
            kind = "probe"
        elif isinstance(msg, WallPose):
            if not all(math.isfinite(v) for v in (msg.x_m, msg.y_m, msg.theta_rad)):
                raise ValueError("wall pose is not finite")
            self.pose = msg
            kind = "pose"
        else:
            raise TypeError(f"not a wall message: {type(msg).__name__}")
        self.version += 1
        return kind

    def _on_info(self, info: WallInfo) -> None:
        blocked = info.blocked_grid()
        labels = info.label_grid()
        path = info.path_cells()
        same = self.info is not None and self.blocked.shape == blocked.shape \
            and self.info.cell_m == info.cell_m and self.info.name == info.name
        self.info, self.blocked, self.labels, self.path = info, blocked, labels, path
        if not same:  # a new wall: nothing measured on it yet
            self.thickness = np.full(blocked.shape, np.nan)
            self.reads = np.zeros(blocked.shape, np.int32)
            self.covered = np.zeros(blocked.shape, bool)
            self.progress = None
            self.readings = self.unplaced = 0
            self.alarmed = []

    def _on_probe(self, rows: np.ndarray) -> None:
        info = self.info
        ok = np.isfinite(rows).all(axis=1)
        r = np.floor(rows[:, 1] / info.cell_m)
        c = np.floor(np.mod(rows[:, 0], info.cols * info.cell_m) / info.cell_m)
        ok &= (r >= 0) & (r < info.rows) & (c >= 0) & (c < info.cols) & (rows[:, 2] > 0)
        r, c = r[ok].astype(int), c[ok].astype(int)
        mm = rows[ok, 2]
        free = ~self.blocked[r, c]
        self.unplaced += int((~ok).sum() + (~free).sum())
        for ri, ci, v in zip(r[free], c[free], mm[free], strict=True):
            n = self.reads[ri, ci]
            old = self.thickness[ri, ci]
            self.thickness[ri, ci] = v if n == 0 else old + (v - old) / (n + 1)
            self.reads[ri, ci] = n + 1
        self.readings += int(free.sum())

    # ------------------------------------------------------------ figures
    @property
    def coverage_pct(self) -> float:
        return self.progress.coverage_pct if self.progress else 0.0

    @property
    def repetition_pct(self) -> float:
        return self.progress.repetition_pct if self.progress else 0.0

    @property
    def state(self) -> str:
        return CoverageState.NAMES[self.progress.state] if self.progress else "—"

    def spot(self, row: int, col: int) -> Spot:
        d = self.info.cell_m
        return Spot(float(self.thickness[row, col]), int(row), int(col), (col + 0.5) * d,
                    (row + 0.5) * d)

    def thinnest(self, n: int = 5, apart_m: float = 0.5) -> list[Spot]:
        """The ``n`` thinnest measured cells, each at least ``apart_m`` from the
        thinner ones already listed (one spot per corroded patch)."""
        if not self.ready or not np.isfinite(self.thickness).any():
            return []
        flat = np.argsort(np.where(np.isfinite(self.thickness), self.thickness, np.inf),
                          axis=None)
        circ = self.info.cols * self.info.cell_m
        out: list[Spot] = []
        for i in flat:
            r, c = divmod(int(i), self.info.cols)
            if not math.isfinite(self.thickness[r, c]):
                break
            s = self.spot(r, c)
            if all(math.hypot((s.x_m - o.x_m + circ / 2) % circ - circ / 2, s.y_m - o.y_m)
                   >= apart_m - 1e-9 for o in out):
                out.append(s)
                if len(out) >= n:
                    break
        return out

    def thin_cells(self) -> int:
        if not self.ready:
            return 0
        with np.errstate(invalid="ignore"):
            return int((self.thickness < self.info.limit_mm).sum())

    def new_thin_spots(self, apart_m: float = ALARM_APART_M) -> list[tuple[str, str, Spot]]:
        """Thin places not yet alarmed: ``(alarm id, text, spot)`` for each measured
        cell below the limit that lies ``apart_m`` or more from every place already
        alarmed (one alarm per corroded patch, named by its cell)."""
        if not self.ready or not self.thin_cells():
            return []
        lim = self.info.limit_mm
        circ = self.info.cols * self.info.cell_m
        out = []
        for s in self.thinnest(64, apart_m):
            if s.thickness_mm >= lim:
                break
            if all(math.hypot((s.x_m - o.x_m + circ / 2) % circ - circ / 2, s.y_m - o.y_m)
                   >= apart_m for o in self.alarmed):
                self.alarmed.append(s)
                out.append((self.alarm_id(s), f"Wall {s.thickness_mm:.2f} mm, below limit "
                            f"{lim:g} mm, at {s.where()}", s))
        return out

    @staticmethod
    def alarm_id(s: Spot) -> str:
        return f"{THIN_ALARM}.r{s.row}c{s.col}"

    def summary(self) -> dict:
        """Figures for a report or a headless summary."""
        spots = self.thinnest(5)
        return {"wall": self.info.name if self.info else None,
                "coverage_pct": round(self.coverage_pct, 2),
                "repetition_pct": round(self.repetition_pct, 2),
                "state": self.state, "readings": self.readings, "unplaced": self.unplaced,
                "cells_measured": int(np.isfinite(self.thickness).sum()) if self.ready else 0,
                "limit_mm": self.limit_mm if self.ready else None,
                "thin_cells": self.thin_cells(),
                "thinnest": [s.__dict__ for s in spots]}


# ---------------------------------------------------------------- picture (no Qt)
REGION_TINTS = np.array([[214, 228, 240], [232, 222, 240], [222, 240, 226], [240, 232, 214],
                         [226, 226, 242], [240, 222, 226], [218, 238, 238]], np.uint8)


def thickness_colours(mm: np.ndarray, limit_mm: float, nominal_mm: float) -> np.ndarray:
    """RGB for thicknesses: red at and below the limit, through yellow, to green at
    the nominal plate thickness (a heat map the operator reads at a glance)."""
    span = max(nominal_mm - limit_mm, 1e-6)
    f = np.clip((np.asarray(mm, float) - limit_mm) / span, 0.0, 1.0)
    r = np.where(f < 0.5, 220, 220 - (f - 0.5) * 2 * 170)
    g = np.where(f < 0.5, 40 + f * 2 * 170, 210)
    b = np.full_like(f, 40)
    out = np.stack([r, g, b], axis=-1).astype(np.uint8)
    out[np.asarray(mm) < limit_mm] = (170, 0, 0)
    return out


def wall_picture(m: WallModel, regions: bool = True, covered: bool = True,
                 heat: bool = True) -> np.ndarray:
    """The unrolled wall as an RGB image (rows × cols × 3), row 0 at the bottom of
    the wall (a view flips it): obstacles dark, sub-regions tinted, covered cells
    green-grey, measured cells in the thickness colours."""
    if not m.ready:
        return np.zeros((1, 1, 3), np.uint8)
    rows, cols = m.blocked.shape
    img = np.full((rows, cols, 3), 236, np.uint8)
    if regions:
        lab = m.labels
        ok = lab >= 0
        img[ok] = REGION_TINTS[lab[ok] % len(REGION_TINTS)]
    if covered and m.covered.shape == (rows, cols):
        img[m.covered] = (150, 190, 160)
    if heat:
        seen = np.isfinite(m.thickness)
        img[seen] = thickness_colours(m.thickness[seen], m.info.limit_mm, m.info.nominal_mm)
    img[m.blocked] = (60, 60, 66)
    return img


def region_centres(m: WallModel) -> list[tuple[int, float, float]]:
    """(region, row, col) of each sub-region's centroid, in the plan's visiting order."""
    out = []
    for k in m.info.order if m.ready else []:
        rr, cc = np.nonzero(m.labels == k)
        if len(rr):
            out.append((int(k), float(rr.mean()), float(cc.mean())))
    return out


# ---------------------------------------------------------------- archive record
WALL_EVENT = "wall_inspection"  # the archive's event kind for a wall record


def archive_record(m: WallModel, spots: int = 10) -> dict:
    """The inspection as it stands, for the archive (an event's data): the figures,
    the thinnest spots, and the thickness map (f4, NaN unread), obstacles and
    covered cells packed as :func:`app.comm.wall_protocol.pack_array` text."""
    from app.comm.wall_protocol import pack_array

    rec = m.summary()
    rec["thinnest"] = [s.__dict__ for s in m.thinnest(spots)]
    info = m.info
    rec.update(name=info.name, cell_m=info.cell_m, rows=info.rows, cols=info.cols,
               nominal_mm=info.nominal_mm, limit_mm=info.limit_mm,
               thickness=pack_array(m.thickness.astype(np.float32), "<f4"),
               blocked=pack_array(m.blocked.astype(np.uint8), "<u1"),
               covered=pack_array(m.covered.astype(np.uint8), "<u1"))
    return rec


def model_from_record(rec: dict) -> WallModel:
    """A :class:`WallModel` holding an archived record's wall, map and figures
    (ValueError when the record does not decode)."""
    from app.comm.wall_protocol import unpack_array

    rows, cols = int(rec["rows"]), int(rec["cols"])
    n = rows * cols
    blocked = unpack_array(rec["blocked"], "<u1", n).reshape(rows, cols).astype(bool)
    info = WallInfo.build(str(rec.get("name", "")), float(rec["cell_m"]), blocked,
                          np.where(blocked, -1, 0), [], [], float(rec["nominal_mm"]),
                          float(rec["limit_mm"]))
    m = WallModel()
    m.ingest(info)
    m.thickness = unpack_array(rec["thickness"], "<f4", n).reshape(rows, cols).astype(float)
    m.covered = unpack_array(rec["covered"], "<u1", n).reshape(rows, cols).astype(bool)
    m.readings = int(rec.get("readings", 0))
    m.record = rec
    return m
