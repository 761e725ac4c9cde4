"""``station-patrol report`` over a short recorded patrol: PDF and HTML, bad input."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from datetime import UTC, datetime

import numpy as np
import pytest

from app.core.records import Archive
from app.core.records.paths import default_archive_path
from app.report.cli import main as report_main
from app.report.cli import parse_range, parse_time
from app.report.sample import write_sample

from .pdf_text import pdf_text


@pytest.fixture(autouse=True)
def _app(qapp):
    """The in-process runs share pytest-qt's QApplication (the command alone
    would make a QGuiApplication, which later widget tests cannot use)."""
    return qapp


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A data folder holding a 30 s patrol that ended a minute ago."""
    d = tmp_path_factory.mktemp("data")
    a = Archive(default_archive_path(d))
    run = write_sample(a, time.time() - 90.0)
    a.close()
    return d, run


def _run_cli(*args: str, env_extra: dict | None = None) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items()
           if k not in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")}
    env.update(env_extra or {})
    return subprocess.run([sys.executable, "-m", "app.cli", "report", *args], env=env,
                          capture_output=True, text=True, timeout=120)


def test_pdf_report_without_a_display(recorded, tmp_path):
    data_dir, _run = recorded
    out = tmp_path / "patrol.pdf"
    r = _run_cli("--from", "-10m", "--out", str(out), "--data-dir", str(data_dir))
    assert r.returncode == 0, r.stderr
    assert "3 meter readings" in r.stdout and "2 alarms" in r.stdout
    pdf = out.read_bytes()
    assert pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF")
    pages = len(re.findall(rb"/Type\s*/Page\b(?!s)", pdf))
    assert pages >= 2  # route, readings with snapshots, alarms, stats and plots
    images = len(re.findall(rb"/Subtype\s*/Image", pdf))
    assert images >= 1 + 3 + 5  # the route, three snapshots, five plots
    # the readings, their states and the alarm handling are in the PDF's text
    text = re.sub(r"\s+", "", pdf_text(out))
    for reading in _run.readings:
        assert f"{reading['point']}{reading['value']:.3f}MPa" in text
    assert "high" in text and "normal" in text
    assert "shelvedbybob(sensormaintenance)" in text and "byann" in text
    g = np.array(_run.gas)
    assert f"{g.min():.3f}%LEL{g.max():.3f}%LEL{g.mean():.3f}%LEL" in text


def test_html_report_holds_the_readings_alarms_and_statistics(recorded, tmp_path):
    data_dir, run = recorded
    out = tmp_path / "patrol.html"
    assert report_main(["--from", "-10m", "--to", "now", "--out", str(out),
                        "--data-dir", str(data_dir)]) == 0
    html = out.read_text(encoding="utf-8")
    for r in run.readings:  # every reading, its value and state
        assert r["point"] in html
        assert f"{r['value']:.3f} MPa" in html
    assert ">high<" in html and ">normal<" in html
    # snapshots and figures embedded, nothing linked from outside
    assert html.count("data:image/png;base64,") >= 1 + 3 + 5
    assert not re.search(r"src='(?!data:)", html)
    # the gas alarm: raised, acknowledged by ann, cleared; the humidity alarm shelved
    assert "Gas high" in html and "by ann" in html
    assert "shelved by bob (sensor maintenance)" in html
    # min / max / mean of the gas channel over every sample
    g = np.array(run.gas)
    assert f"{g.min():.3f} %LEL" in html
    assert f"{g.max():.3f} %LEL" in html
    assert f"{g.mean():.3f} %LEL" in html
    assert f"<td>{len(g)}</td>" in html


def test_a_range_without_data_still_makes_a_report(recorded, tmp_path):
    data_dir, _ = recorded
    out = tmp_path / "empty.html"
    assert report_main(["--from", "2001-01-01T00:00", "--to", "2001-01-01T01:00",
                        "--out", str(out), "--data-dir", str(data_dir)]) == 0
    html = out.read_text(encoding="utf-8")
    assert "No meter readings in this range" in html and "No alarms in this range" in html


@pytest.mark.parametrize("args, message", [
    (["--from", "yesterday-ish"], "is not a time"),
    (["--from", "-1h", "--to", "-2h"], "is not after"),
    (["--out", "{tmp}/r.docx"], "end it in .pdf or .html"),
    (["--out", "{tmp}/no/such/folder/r.pdf"], "does not exist"),
    (["--data-dir", "{tmp}/empty"], "no archive at"),
    (["--frobnicate"], "unrecognized arguments"),
])
def test_bad_input_exits_2_with_one_line(recorded, tmp_path, capsys, args, message):
    data_dir, _ = recorded
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    full = ["--data-dir", str(data_dir), "--out", str(tmp_path / "r.html"), *args]
    assert report_main(full) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_bad_input_through_the_installed_command(tmp_path):
    r = _run_cli("--from", "soon", "--out", str(tmp_path / "r.pdf"))
    assert r.returncode == 2
    assert r.stderr.strip().startswith("station-patrol report:")


def test_time_forms():
    now = 1_800_000_000.0
    assert parse_time("now", now) == now
    assert parse_time("-2h", now) == now - 7200
    assert parse_time("-30m", now) == now - 1800
    assert parse_time("-1d", now) == now - 86400
    jan15 = datetime(2027, 1, 15, 8, 0, tzinfo=UTC).timestamp()
    assert parse_time("2027-01-15T08:00:00Z", now) == jan15
    assert parse_time("2027-01-15T08:00", now) == jan15  # no zone: UTC
    assert parse_time("2027-01-15T10:00:00+02:00", now) == parse_time("2027-01-15T08:00", now)
    assert parse_range(None, None, now) == (now - 86400, now)  # the last 24 hours


def test_a_damaged_archive_is_named_and_exits_2(tmp_path, capsys):
    (tmp_path / "archive.sqlite3").write_bytes(b"this is not a database" * 100)
    assert report_main(["--out", str(tmp_path / "r.html"), "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "cannot open the archive" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "r.html").exists()


def test_distance_driven_counts_every_pose_across_chunks(recorded):
    from app.report.data import driven_distance, path_length

    data_dir, run = recorded
    a = Archive(default_archive_path(data_dir))
    try:
        every = path_length(a.poses(run.t0, run.t1))
        assert every > 30.0  # most of a 6 m x 5 m ellipse
        for chunk in (1.0, 0.7, 3600.0):  # boundaries on and between samples
            assert driven_distance(a, run.t0, run.t1, chunk_s=chunk) == pytest.approx(every)
    finally:
        a.close()
