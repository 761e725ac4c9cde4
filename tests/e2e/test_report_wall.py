"""The patrol report's wall-inspection section: a desk pipeline on a wall
climber archives its inspection; the report (HTML and PDF) shows coverage, the
thickness map and the thinnest spots with their positions."""

from __future__ import annotations

import time

import numpy as np
import pytest

from app.comm import wall_protocol as W
from app.core.desk import DeskPipeline
from app.core.records import Archive
from app.core.records.paths import default_archive_path
from app.report.cli import main as report_main

from .pdf_text import pdf_text


@pytest.fixture(autouse=True)
def _app(qapp):
    return qapp


@pytest.fixture
def inspected(tmp_path):
    """An archive holding a finished inspection of a 2 m × 0.6 m wall with a thin
    patch round (1.25 m, 0.35 m)."""
    d = tmp_path / "data"
    archive = Archive(default_archive_path(d))
    p = DeskPipeline(archive=archive)
    blocked = np.zeros((6, 20), bool)
    blocked[1:3, 15:17] = True
    path = [(r, c) for c in range(20) for r in range(6) if not blocked[r, c]]
    p.ingest("wall", W.WallInfo.build("tank-7", 0.1, blocked, np.where(blocked, -1, 0), [0],
                                      path, 10.0, 8.0))
    cov = np.zeros_like(blocked)
    rows = []
    for r, c in path:
        x, y = (c + 0.5) * 0.1, (r + 0.5) * 0.1
        rows.append((x, y, 10.0 - 3.0 * np.exp(-((x - 1.25) ** 2 + (y - 0.35) ** 2) / 0.02)))
        cov[r, c] = True
        if len(rows) % 20 == 0:
            p.ingest("wall", W.ProbeReadings(np.array(rows, np.float32)))
            rows = []
            p.ingest("wall", W.CoverageProgress.build(cov, len(path), int(cov.sum()) + 2,
                                                      0, len(path), W.CoverageState.RUNNING))
    p.ingest("wall", W.ProbeReadings(np.array(rows, np.float32).reshape(-1, 3)))
    p.ingest("wall", W.CoverageProgress.build(cov, len(path), len(path) + 2, len(path),
                                              len(path), W.CoverageState.DONE))
    p.close()
    archive.close()
    return d


def test_report_has_the_wall_section_with_the_thinnest_spots(inspected, tmp_path):
    out = tmp_path / "r.html"
    assert report_main(["--from", "-10m", "--to", "+1m", "--out", str(out),
                        "--data-dir", str(inspected)]) == 0
    html = out.read_text(encoding="utf-8")
    assert "<h2>Wall inspection</h2>" in html and "tank-7" in html
    assert "<b>done</b>" in html and "<td>100.0 %</td>" in html  # coverage
    assert "<td>1.7 %</td>" in html  # repetition: 2 repeats of 116 cells
    # the thinnest spot: 7.00 mm at the patch's centre cell (row 3, col 12)
    first = html.index("<tr><td>1</td>", html.index("<h2>Wall inspection</h2>"))
    row = html[first:html.index("</tr>", first)]
    assert "7.00 mm" in row and "<td>1.25</td><td>0.35</td>" in row and "3, 12" in row
    # the thin-wall alarm the pipeline raised is in the alarm table too
    assert "below limit 8 mm" in html


def test_pdf_report_carries_the_wall_section(inspected, tmp_path):
    out = tmp_path / "r.pdf"
    assert report_main(["--from", "-10m", "--to", "+1m", "--out", str(out),
                        "--data-dir", str(inspected)]) == 0
    text = " ".join(pdf_text(out).split())
    assert "Wall inspection" in text and "tank-7" in text


def test_a_report_without_a_climber_has_no_wall_section(tmp_path):
    d = tmp_path / "data"
    a = Archive(default_archive_path(d))
    a.add_event(time.time() - 5, "note", {"text": "nothing"})
    a.close()
    out = tmp_path / "r.html"
    assert report_main(["--from", "-10m", "--to", "now", "--out", str(out),
                        "--data-dir", str(d)]) == 0
    assert "Wall inspection" not in out.read_text(encoding="utf-8")
