"""CARMEN log reader: PARAM, ODOM and FLASER lines.

A FLASER line is ``FLASER n r1..rn x y θ odom_x odom_y odom_θ ipc_ts host
logger_ts``: n ranges in metres, evenly spread over the laser's field of
view (180° unless a PARAM says otherwise, from the robot's right, −fov/2, to
its left, +fov/2), then the laser pose and the raw odometry pose. An ODOM line
is ``ODOM x y θ tv rv accel ipc_ts host logger_ts``.

Timestamps are kept for the output only; nothing here relies on them (logs
repeat them, hold zeros or wrap). A bad line — truncated, a NaN or infinite
number, a negative range, a wrong beam count — is reported with its line
number, counted and skipped, never raised.
"""

from __future__ import annotations

import gzip
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LaserScan:
    """One FLASER message. ``odom`` is the raw odometry pose, ``pose`` the
    laser pose field (equal to ``odom`` in raw logs)."""

    line_no: int
    ranges_m: np.ndarray
    pose: tuple[float, float, float]
    odom: tuple[float, float, float]
    timestamp: float


@dataclass(frozen=True)
class OdomRecord:
    line_no: int
    pose: tuple[float, float, float]
    timestamp: float


@dataclass
class CarmenLog:
    scans: list[LaserScan] = field(default_factory=list)
    odometry: list[OdomRecord] = field(default_factory=list)
    params: dict[str, str] = field(default_factory=dict)
    bad_lines: list[tuple[int, str]] = field(default_factory=list)
    other_lines: int = 0

    @property
    def fov_rad(self) -> float:
        """Front laser field of view (PARAM laser_front_laser_fov in degrees; 180°)."""
        for key in ("laser_front_laser_fov", "laser_fov", "robot_front_laser_fov"):
            v = _param_float(self.params, key)
            if v is not None and 0 < v <= 360:
                return math.radians(v)
        return math.pi

    @property
    def laser_offset_m(self) -> tuple[float, float]:
        """Forward and left offset of the front laser from the robot's centre."""
        fwd = _param_float(self.params, "robot_frontlaser_offset") or 0.0
        side = _param_float(self.params, "robot_frontlaser_side_offset") or 0.0
        return fwd, side

    def beam_angles(self, n: int) -> np.ndarray:
        """Bearing of each of n beams, the first at −fov/2 (the robot's right).
        An odd count spans the whole field, ends included (181 or 361 beams:
        1° or 0.5° apart); an even count steps fov/n (180 or 360 beams: 1° or
        0.5°, the last beam half a step short of +fov/2), as a laser with a
        fixed angular resolution gives them. On freiburg-101 (360 beams) this
        agrees with the reference better than spreading them end to end."""
        fov = self.fov_rad
        if n < 2:
            return np.zeros(n)
        step = fov / (n - 1) if n % 2 else fov / n
        return -fov / 2 + np.arange(n) * step

    def no_return_m(self) -> float | None:
        """The value this log writes for 'no return': the largest range, when it
        (within 0.5 %, as some lasers jitter there) is the reading of at least
        1 % of all beams (32.8, 50, 51.15, 81.9 m, …)."""
        if not self.scans:
            return None
        allr = np.concatenate([s.ranges_m for s in self.scans])
        top = float(allr.max())
        if np.count_nonzero(allr >= 0.995 * top) >= 0.01 * allr.size:
            return 0.995 * top
        return None


def _param_float(params: dict[str, str], key: str) -> float | None:
    try:
        v = float(params[key])
    except (KeyError, ValueError):
        return None
    return v if math.isfinite(v) else None


class BadLine(ValueError):
    pass


def _floats(tokens: list[str], what: str) -> list[float]:
    out = []
    for t in tokens:
        try:
            v = float(t)
        except ValueError:
            raise BadLine(f"{what}: not a number {t!r}") from None
        if not math.isfinite(v):
            raise BadLine(f"{what}: {t}")
        out.append(v)
    return out


def _timestamp(tokens: list[str]) -> float:
    try:
        v = float(tokens[0])
    except (IndexError, ValueError):
        return float("nan")
    return v


def parse_flaser(tokens: list[str], line_no: int) -> LaserScan:
    if len(tokens) < 2:
        raise BadLine("truncated: no beam count")
    try:
        n = int(tokens[1])
    except ValueError:
        raise BadLine(f"beam count {tokens[1]!r} is not an integer") from None
    if not 1 <= n <= 100_000:
        raise BadLine(f"beam count {n} out of range")
    if len(tokens) < 2 + n + 6:
        raise BadLine(f"truncated: {len(tokens) - 2} fields after the count, need {n + 6}")
    ranges = np.array(_floats(tokens[2:2 + n], "range"))
    if (ranges < 0).any():
        i = int(np.argmax(ranges < 0))
        raise BadLine(f"negative range {ranges[i]} at beam {i}")
    p = _floats(tokens[2 + n:2 + n + 6], "pose")
    return LaserScan(line_no, ranges, (p[0], p[1], p[2]), (p[3], p[4], p[5]),
                     _timestamp(tokens[2 + n + 6:]))


def parse_odom(tokens: list[str], line_no: int) -> OdomRecord:
    if len(tokens) < 4:
        raise BadLine("truncated ODOM line")
    p = _floats(tokens[1:4], "pose")
    return OdomRecord(line_no, (p[0], p[1], p[2]), _timestamp(tokens[7:]))


def parse_lines(lines, source: str = "log") -> CarmenLog:
    """Parse CARMEN lines (an iterable of str). Bad lines are logged and kept in
    ``bad_lines`` as (line number, reason)."""
    out = CarmenLog()
    for line_no, raw in enumerate(lines, 1):
        tokens = raw.split()
        if not tokens or tokens[0].startswith("#"):
            continue
        kind = tokens[0]
        try:
            if kind == "FLASER":
                out.scans.append(parse_flaser(tokens, line_no))
            elif kind == "ODOM":
                out.odometry.append(parse_odom(tokens, line_no))
            elif kind == "PARAM":
                if len(tokens) < 3:
                    raise BadLine("PARAM without a value")
                out.params[tokens[1]] = tokens[2]
            else:
                out.other_lines += 1
        except BadLine as e:
            out.bad_lines.append((line_no, str(e)))
            log.warning("%s line %d: %s %s; line skipped", source, line_no, kind, e)
    if out.scans:
        counts = {s.ranges_m.size for s in out.scans}
        if len(counts) > 1:
            log.info("%s: beam counts differ between scans: %s", source, sorted(counts))
    return out


def read_log(path: str | Path) -> CarmenLog:
    """Read a CARMEN log (plain or .gz). Undecodable bytes are replaced, so a
    damaged file yields bad lines rather than an exception."""
    path = Path(path)
    opener = gzip.open if path.suffix == ".gz" else open
    lines: list[str] = []
    with opener(path, "rt", encoding="utf-8", errors="replace") as f:
        try:
            for line in f:
                lines.append(line)
        except (EOFError, OSError) as e:  # a cut .gz: keep what was read
            log.warning("%s: stopped reading after line %d: %s", path, len(lines), e)
    return parse_lines(lines, source=str(path))
