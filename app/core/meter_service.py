"""Desk-side meter reading, Qt-free: which gauge is inspected, its profile, fusion, records.

The desk learns which gauge the camera is looking at from the robot's events
(``inspection_started`` / ``inspection_done`` with ``{point, gauge}``) or from the operator
asking for a reading.  A :class:`MeterSession` collects the readings of the frames taken
while the camera head is on that gauge, fuses them with :class:`~app.core.meter.MeterFusion`
and ends in one :class:`MeterRecord`: a value with its confidence, or "no reading" with a
reason.  The gauge id -> type table comes from the station configuration
(the shipped ``station/station.json``, :mod:`app.core.paths`); the profile of a type is
``gauges/<type>.json`` (the operator's folder first, then the shipped one).  When the
active route (:meth:`MeterService.set_route`) has a calibrated profile for the inspected
point (see :mod:`app.core.inspection_points`), that profile is used instead of the gauge
type's.

Nothing here touches Qt: the Qt model (``app/ui/meter_model.py``) runs
:func:`read_frame` on a worker thread and feeds the results back to the session.
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections import deque
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import cv2
import numpy as np

from app.core.alarms import LimitRule, Priority
from app.core.i18n import QT_TRANSLATE_NOOP
from app.core.meter import (
    MIN_CONFIDENCE,
    GaugeProfile,
    MeterFusion,
    Reading,
    load_profile,
    read_gauge,
)
from app.core.paths import resource, user_gauges_dir
from app.core.route import load_route

__all__ = [
    "DEFAULT_GAUGE_DIR", "DEFAULT_ROUTE_FILE", "DEFAULT_STATION_FILE", "GaugeInfo",
    "MeterRecord", "MeterService", "MeterSession", "NO_READING", "NORMAL", "OUT_OF_BAND",
    "REFERENCE_SNAPSHOT_REASON", "load_station_gauges", "meter_channel", "read_frame",
]

log = logging.getLogger(__name__)

DEFAULT_STATION_FILE = resource("station", "station.json")
DEFAULT_GAUGE_DIR = resource("gauges")  # shipped; the operator's own in user_gauges_dir()
DEFAULT_ROUTE_FILE = resource("routes", "default.json")  # the robot's default

NORMAL, OUT_OF_BAND, NO_READING = "normal", "out of band", "no reading"
# the states as the desk shows them (translated at the view)
STATE_TEXTS = (QT_TRANSLATE_NOOP("MeterState", "normal"),
               QT_TRANSLATE_NOOP("MeterState", "out of band"),
               QT_TRANSLATE_NOOP("MeterState", "no reading"))
# the archive's snapshot reason for a calibrated point's reference frame, stored beside an
# out-of-band reading (the report shows the two side by side)
REFERENCE_SNAPSHOT_REASON = "meter_reference"
MAX_RECORDS = 1000  # readings kept in memory for the panel (the archive keeps all)


@dataclass(frozen=True)
class GaugeInfo:
    """One gauge of the station configuration."""

    id: str
    type: str
    min_value: float
    max_value: float
    unit: str


def load_station_gauges(path: str | Path = DEFAULT_STATION_FILE) -> dict[str, GaugeInfo]:
    """gauge id -> :class:`GaugeInfo` from the station configuration's ``gauges`` list.

    Raises ValueError naming the problem for a missing or malformed file."""
    try:
        with open(path, encoding="utf-8") as f:
            spec = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        raise ValueError(f"station configuration {path}: {e}") from e
    out: dict[str, GaugeInfo] = {}
    for i, g in enumerate(spec.get("gauges", [])):
        try:
            out[str(g["id"])] = GaugeInfo(str(g["id"]), str(g["type"]), float(g["min"]),
                                          float(g["max"]), str(g.get("unit", "")))
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"station configuration {path}: gauge {i} malformed ({e})") from e
    return out


def meter_channel(gauge_id: str) -> str:
    """The alarm channel of a meter, e.g. ``meter.PG-102``."""
    return f"meter.{gauge_id}"


def read_frame(image_rgb: np.ndarray, profile: GaugeProfile) -> Reading:
    """Read one decoded camera frame (RGB, as the link delivers it).  Never raises."""
    try:
        bgr = cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR)
        return read_gauge(bgr, profile)
    except Exception as e:  # noqa: BLE001 - a bad frame is a refusal, not a crash
        log.warning("meter read failed: %s", e)
        return Reading(None, profile.unit, 0.0, f"read failed: {type(e).__name__}: {e}")


def prepare_references(profiles: list[tuple[str, GaugeProfile]]) -> list[str | None]:
    """Each (point, profile)'s reference geometry found now and kept in-process
    (:func:`app.core.meter.calibrated.prepare`): None where done (or nothing to do), else
    "point: why".  Never raises; slow, so run off the GUI thread."""
    from app.core.meter.calibrated import prepare

    out = []
    for point, prof in profiles:
        why = prepare(prof)
        out.append(None if why is None else f"{point}: {why}")
    return out


@dataclass(frozen=True)
class MeterRecord:
    """One recorded meter reading (or a recorded failure to read)."""

    gauge_id: str
    point: str
    value: float | None
    unit: str
    normal_min: float | None
    normal_max: float | None
    state: str  # "normal" | "out of band" | "no reading"
    confidence: float
    reason: str | None
    time_utc: str  # ISO 8601
    t: float  # UTC epoch seconds
    n_used: int
    n_total: int
    source: str  # "patrol" | "operator"
    profile: str = ""  # the profile's name
    method: str | None = None  # how the last frame was read (Reading.method), if told
    reference_image: str | None = None  # the calibrated profile's reference frame, if any

    @property
    def band_text(self) -> str:
        lo = "" if self.normal_min is None else f"{self.normal_min:g}"
        hi = "" if self.normal_max is None else f"{self.normal_max:g}"
        return "—" if not lo and not hi else f"{lo} … {hi}"


@dataclass
class MeterSession:
    """The frames of one inspection of one gauge."""

    gauge_id: str
    point: str
    source: str
    profile: GaugeProfile
    fusion: MeterFusion
    started_mono: float
    started_utc_us: int
    frames_wanted: int
    attempts: int = 0
    last_reading: Reading | None = None
    done: bool = False
    reasons: dict[str, int] = field(default_factory=dict)


class MeterService:
    """Sessions, profiles and records for the meters of one station (no Qt, no threads).

    ``frames_per_reading`` frames are fused into one record; frames captured during the
    first ``settle_s`` after a session starts (while the head is still turning) are skipped.
    """

    def __init__(self, gauges: dict[str, GaugeInfo] | None = None,
                 gauge_dir: str | Path | None = None, *, frames_per_reading: int = 7,
                 settle_s: float = 0.5, min_confidence: float = MIN_CONFIDENCE,
                 clock=time.monotonic, utc_clock=time.time) -> None:
        self.gauges = dict(gauges) if gauges is not None else load_station_gauges()
        # gauge_dir None: the operator's profiles (user_gauges_dir) override the shipped ones
        self.gauge_dir = DEFAULT_GAUGE_DIR if gauge_dir is None else Path(gauge_dir)
        self._user_gauge_dir = user_gauges_dir() if gauge_dir is None else None
        self.frames_per_reading = int(frames_per_reading)
        self.settle_s = float(settle_s)
        self.min_confidence = float(min_confidence)
        self._clock = clock
        self._utc = utc_clock
        self._profiles: dict[str, GaugeProfile] = {}
        self.route_path: Path | None = None
        self._point_profiles: dict[str, tuple[str, Path]] = {}  # point -> (gauge, file)
        self._loaded_points: dict[Path, tuple[float, GaugeProfile]] = {}  # file -> mtime
        self._references: dict[tuple, np.ndarray | None] = {}  # (path, mtime, size)
        self.profile_errors = 0  # calibrated profiles that could not be loaded
        self.session: MeterSession | None = None
        # the latest readings for the panel's history; the archive keeps them all,
        # so a desk running for days holds a bounded number in memory
        self.records: deque[MeterRecord] = deque(maxlen=MAX_RECORDS)
        self.latest: dict[str, MeterRecord] = {}

    # ------------------------------------------------------------ profiles
    def profile(self, gauge_id: str) -> GaugeProfile:
        """The profile of a gauge (cached); ValueError names an unknown gauge or bad file."""
        info = self.gauges.get(gauge_id)
        if info is None:
            raise ValueError(f"no gauge {gauge_id!r} in the station configuration")
        prof = self._profiles.get(info.type)
        if prof is None:
            prof = load_profile(self.profile_file(info.type))
            self._profiles[info.type] = prof
        return prof

    def profile_file(self, type_name: str) -> Path:
        """The profile file of a gauge type: the operator's own when there is one, else
        the shipped one."""
        if self._user_gauge_dir is not None:
            mine = self._user_gauge_dir / f"{type_name}.json"
            if mine.is_file():
                return mine
        return self.gauge_dir / f"{type_name}.json"

    def set_route(self, route_path: str | Path | None) -> str | None:
        """Make ``route_path`` the active route: its points' calibrated profiles are
        preferred from now on.  None clears it.  Returns None, or the message why the route
        could not be read (its points then read with their gauge types' profiles)."""
        self.route_path = None if route_path is None else Path(route_path)
        self._point_profiles = {}
        self._loaded_points.clear()
        if self.route_path is None:
            return None
        try:
            route = load_route(self.route_path)
        except ValueError as e:
            log.warning("route for meter profiles: %s", e)
            return str(e)
        base = self.route_path.resolve().parent
        self._point_profiles = {p.name: (p.gauge, base / p.profile) for p in route.points
                                if p.profile is not None and p.gauge is not None}
        return None

    def route_profiles(self) -> list[tuple[str, GaugeProfile]]:
        """(point, profile) of the active route's points that have a calibrated profile
        that loads (one that does not is logged and counted, see :meth:`profile_for`)."""
        out = []
        for point, (gauge, _) in list(self._point_profiles.items()):
            before = self.profile_errors
            try:
                prof = self.profile_for(gauge, point)
            except ValueError as e:  # (the calibrated profile failed, and the type's too)
                log.warning("profile of %s not loaded: %s", point, e)
                continue
            if self.profile_errors == before:
                out.append((point, prof))
        return out

    def prepare_route(self) -> int:
        """Find the active route's calibrated points' reference geometry now
        (:func:`prepare_references`), so that a point's first frame of a patrol does not
        pay it.  Slow (a few tenths of a second per reference): the GUI runs
        :func:`prepare_references` on its worker instead.  Returns how many points are
        ready; a reference that fails is logged and counted in ``profile_errors`` (its
        frames then refuse as before)."""
        profs = self.route_profiles()
        failed = [w for w in prepare_references(profs) if w is not None]
        self.references_failed(failed)
        return len(profs) - len(failed)

    def references_failed(self, whys: list[str]) -> None:
        """Count and log the references :func:`prepare_references` could not measure."""
        for why in whys:
            self.profile_errors += 1
            log.warning("reference not prepared: %s", why)

    def route_points(self) -> list[tuple[str, str]]:
        """(point, gauge id) of the active route's meter points, in route order."""
        if self.route_path is None:
            return []
        try:
            route = load_route(self.route_path)
        except ValueError as e:
            log.warning("route points: %s", e)
            return []
        return [(p.name, p.gauge) for p in route.points if p.gauge in self.gauges]

    def point_profile_path(self, point: str | None, gauge_id: str) -> Path | None:
        """The calibrated profile file of ``point`` when the active route has one for it
        and it names this gauge."""
        entry = self._point_profiles.get(point) if point is not None else None
        if entry is None or entry[0] != gauge_id:
            return None
        return entry[1]

    def profile_for(self, gauge_id: str, point: str | None = None) -> GaugeProfile:
        """The point's calibrated profile when the active route has one (re-read when its
        file changes), else the gauge type's profile.  A calibrated profile that cannot be
        loaded is logged and counted, and the type's profile is used."""
        path = self.point_profile_path(point, gauge_id)
        if path is None:
            return self.profile(gauge_id)
        try:
            mtime = path.stat().st_mtime
            cached = self._loaded_points.get(path)
            if cached is not None and cached[0] == mtime:
                return cached[1]
            prof = load_profile(path)
        except (OSError, ValueError) as e:
            self.profile_errors += 1
            log.warning("calibrated profile of %s not used: %s", point, e)
            return self.profile(gauge_id)
        self._loaded_points[path] = (mtime, prof)
        return prof

    def reference_image(self, path: str | Path | None) -> np.ndarray | None:
        """A reference frame as RGB (cached while its file is unchanged), or None when
        absent or unreadable."""
        if path is None:
            return None
        try:
            st = Path(path).stat()
        except OSError:
            log.warning("reference frame %s is missing", path)
            return None
        key = (str(path), st.st_mtime_ns, st.st_size)
        if key not in self._references:
            bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if bgr is None:
                log.warning("reference frame %s could not be read", path)
            self._references = {key: None if bgr is None else
                                cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)} | {
                k: v for k, v in self._references.items() if k[0] != str(path)}
        return self._references[key]

    def alarm_rule(self, gauge_id: str) -> LimitRule | None:
        """A limit rule on ``meter.<id>`` from the profile's normal band (None without one).
        The deadband is 1 % of full scale, so a reading at the limit does not chatter."""
        prof = self.profile(gauge_id)
        if prof.normal_min is None and prof.normal_max is None:
            return None
        return LimitRule(meter_channel(gauge_id), high=prof.normal_max, low=prof.normal_min,
                         deadband=0.01 * prof.full_scale, unit=prof.unit,
                         label=f"Meter {gauge_id}", priority=Priority.MEDIUM)

    # ------------------------------------------------------------ sessions
    def start(self, gauge_id: str, point: str | None = None, source: str = "patrol"
              ) -> MeterSession:
        """Begin reading ``gauge_id``; an unfinished session of another gauge is dropped."""
        prof = self.profile_for(gauge_id, point)
        fusion = MeterFusion(prof.full_scale, prof.unit, window=self.frames_per_reading,
                             min_confidence=self.min_confidence)
        self.session = MeterSession(
            gauge_id, point or gauge_id, source, prof, fusion, self._clock(),
            int(self._utc() * 1e6), self.frames_per_reading)
        return self.session

    def wants_frame(self, capture_ts_us: int | None = None) -> bool:
        """True while a session is open, settled, and the frame was taken after it began."""
        s = self.session
        if s is None or s.done:
            return False
        if self._clock() - s.started_mono < self.settle_s:
            return False
        return capture_ts_us is None or capture_ts_us >= s.started_utc_us

    def add(self, gauge_id: str, reading: Reading) -> MeterRecord | None:
        """Feed a reading taken for ``gauge_id``; returns the record once enough frames are
        in (the session then ends).  A reading for a gauge no longer inspected is ignored."""
        s = self.session
        if s is None or s.done or s.gauge_id != gauge_id:
            return None
        s.attempts += 1
        s.last_reading = reading
        if reading.value is None:
            why = reading.error or "no reading"
            s.reasons[why] = s.reasons.get(why, 0) + 1
        s.fusion.add(reading)
        if s.attempts >= s.frames_wanted:
            return self.finish(gauge_id)
        return None

    def finish(self, gauge_id: str | None = None) -> MeterRecord | None:
        """End the open session (of ``gauge_id`` if given) and record what it has."""
        s = self.session
        if s is None or s.done or (gauge_id is not None and s.gauge_id != gauge_id):
            return None
        s.done = True
        self.session = None
        prof = s.profile
        if s.attempts == 0:
            value, conf, reason, n_used = None, 0.0, "no frames while the camera was on it", 0
        else:
            f = s.fusion.fused()
            value, conf, reason, n_used = f.value, f.confidence, f.error, f.n_used
            if value is None and s.reasons:
                top = max(s.reasons, key=s.reasons.get)
                reason = f"{reason}; most often: {top}"
        if value is None:
            state = NO_READING
        else:
            lo = prof.normal_min if prof.normal_min is not None else -math.inf
            hi = prof.normal_max if prof.normal_max is not None else math.inf
            state = NORMAL if lo <= value <= hi else OUT_OF_BAND
        t = self._utc()
        rec = MeterRecord(
            s.gauge_id, s.point, value, prof.unit, prof.normal_min, prof.normal_max, state,
            float(conf), reason,
            datetime.fromtimestamp(t, UTC).isoformat(timespec="seconds"), t, n_used,
            s.attempts, s.source, prof.name,
            getattr(s.last_reading, "method", None) if s.last_reading else None,
            _reference_of(prof))
        self.records.append(rec)
        self.latest[rec.gauge_id] = rec
        return rec


def _reference_of(profile: GaugeProfile) -> str | None:
    """The calibrated profile's reference frame path, or None."""
    cal = getattr(profile, "calibration", None)
    image = getattr(cal, "image_path", None) if cal is not None else None
    return None if image is None else str(image)
