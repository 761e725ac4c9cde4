"""The desk's wall model: plan, coverage and thickness map from the climber's
messages; the thin-wall alarm through the pipeline's alarm monitor."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.comm import protocol as P
from app.comm import wall_protocol as W
from app.core.desk import DeskPipeline
from app.core.desk.wall import THIN_ALARM, WallModel


def wall_info(limit_mm: float = 8.0) -> W.WallInfo:
    blocked = np.zeros((6, 10), bool)
    blocked[2:4, 4:6] = True  # a nozzle
    labels = np.where(blocked, -1, 0)
    path = [(r, c) for r in range(6) for c in range(10) if not blocked[r, c]]
    return W.WallInfo.build("w", 0.1, blocked, labels, [0], path, 10.0, limit_mm)


def probe(*rows) -> W.ProbeReadings:
    return W.ProbeReadings(np.array(rows, np.float32).reshape(-1, 3))


def test_model_places_readings_and_lists_thinnest_spots_apart():
    m = WallModel()
    with pytest.raises(ValueError):
        m.ingest(probe((0.05, 0.05, 9.0)))  # no wall yet
    m.ingest(wall_info())
    assert m.ready and m.blocked.sum() == 4 and len(m.path) == 56
    m.ingest(probe((0.05, 0.05, 9.0), (0.05, 0.05, 9.2), (0.95, 0.55, 7.0),
                   (0.85, 0.55, 7.1), (0.45, 0.25, 5.0),  # over the nozzle: not placed
                   (0.15, 0.95, 8.5), (float("nan"), 0.1, 9.0)))  # off the wall, NaN
    assert m.thickness[0, 0] == pytest.approx(9.1)
    assert m.unplaced == 3 and m.readings == 4
    spots = m.thinnest(3, apart_m=0.3)
    # (5, 8) at 7.1 mm lies 0.1 m from the thinner (5, 9): the same patch, not listed
    assert [(s.row, s.col) for s in spots] == [(5, 9), (0, 0)]
    assert [(s.row, s.col) for s in m.thinnest(3, apart_m=0.0)] == [(5, 9), (5, 8), (0, 0)]
    assert spots[0].thickness_mm == pytest.approx(7.0)
    assert (spots[0].x_m, spots[0].y_m) == pytest.approx((0.95, 0.55))
    assert all(math.hypot(a.x_m - b.x_m, a.y_m - b.y_m) >= 0.3
               for a in spots for b in spots if a is not b)
    assert m.thin_cells() == 2
    (key, text, spot), = m.new_thin_spots()  # one patch: one alarm
    assert key == "wall.thin.r5c9" and spot.thickness_mm == pytest.approx(7.0)
    assert "0.95 m" in text and "0.55 m" in text and "below limit 8" in text
    assert m.new_thin_spots() == []  # already alarmed
    m.ingest(probe((0.45, 0.05, 7.5)))  # a second patch, 0.7 m from the first
    assert [k for k, _, _ in m.new_thin_spots()] == ["wall.thin.r0c4"]


def test_wrap_places_a_reading_past_the_seam():
    m = WallModel()
    m.ingest(wall_info())
    m.ingest(probe((1.05, 0.05, 9.0)))  # 1.05 m round a 1.0 m wall: column 0
    assert m.thickness[0, 0] == pytest.approx(9.0)


def test_coverage_message_gives_the_live_figures():
    m = WallModel()
    m.ingest(wall_info())
    mask = np.zeros((6, 10), bool)
    mask[0] = True
    m.ingest(W.CoverageProgress.build(mask, 56, 12, 10, 60, W.CoverageState.RUNNING))
    assert m.coverage_pct == pytest.approx(100 * 10 / 56)
    assert m.repetition_pct == pytest.approx(100 * 2 / 56)
    assert m.state == "running" and m.covered.sum() == 10


def test_pipeline_raises_the_thin_wall_alarm_with_its_place_once_per_patch():
    t = [1000.0]
    p = DeskPipeline(clock=lambda: t[0], mono=lambda: t[0])
    seen = []
    p.listen("wall", seen.append)
    assert p.ingest("wall", wall_info(limit_mm=8.0))
    assert p.ingest("wall", probe((0.05, 0.05, 9.5)))
    assert not [a for a in p.monitor.active() if a.key.startswith(THIN_ALARM)]
    assert p.ingest("wall", probe((0.75, 0.45, 7.4)))
    a = p.monitor.get(f"{THIN_ALARM}.r4c7")
    assert a is not None and a.active and a.source == "wall"
    assert "7.40 mm" in a.description and "x 0.75 m" in a.description
    assert p.ingest("wall", probe((0.85, 0.45, 7.2)))  # the same patch: no second alarm
    assert len([a for a in p.monitor.active() if a.key.startswith(THIN_ALARM)]) == 1
    assert seen == ["info", "probe", "probe", "probe"]
    # a coverage for another wall's size is malformed: counted, not raised
    bad = W.CoverageProgress.build(np.zeros((3, 3), bool), 9, 0, 0, 0, 1)
    assert not p.ingest("wall", bad) and p.malformed == 1


def test_pipeline_wall_messages_come_from_the_codec():
    p = DeskPipeline()
    dec = P.FrameDecoder()
    for fr in dec.feed(P.encode(wall_info()) + P.encode(W.WallPose(0.5, 0.3, 0.0, 0.1, 0, 0.01))):
        assert p.ingest("wall", fr.message)
    assert p.wall.pose.x_m == 0.5
