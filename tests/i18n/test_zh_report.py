"""The patrol report in zh_CN: Chinese headings as text in the PDF and the HTML, drawn
with the CJK font the package ships (no system CJK font needed, never boxes)."""

from __future__ import annotations

import re
import time

import pytest

from app.core.records import Archive
from app.core.records.queries import choose_session
from app.report.data import gather
from app.report.render import write_html, write_pdf
from app.report.sample import write_sample
from tests.e2e.pdf_text import pdf_text

HEADINGS = ("场站巡检报告", "巡检路线", "仪表读数", "报警及处置", "环境监测")


@pytest.fixture(scope="module")
def sample_data(tmp_path_factory):
    path = tmp_path_factory.mktemp("arch") / "archive.db"
    a = Archive(path)
    run = write_sample(a, time.time() - 90.0)
    a.close()  # written through; read as the report command does
    a = Archive(path)
    yield a, run
    a.close()


def _gather(sample_data):
    a, run = sample_data
    rows, _which = choose_session(a, "latest", run.t0 - 1, run.t1 + 1)
    return gather(rows, run.t0 - 1, run.t1 + 1)


def test_pdf_report_in_chinese_has_its_headings_as_text_in_the_shipped_font(
        zh, sample_data, tmp_path):
    data = _gather(sample_data)
    assert data.readings and data.alarms  # every section has rows to translate
    out = write_pdf(data, tmp_path / "report.pdf")
    text = re.sub(r"\s+", "", pdf_text(out))
    for h in HEADINGS:
        assert h in text, f"{h} not in the PDF's text"
    assert "时间（UTC）" in text and "置信度" in text  # table headers
    assert "MPa" in text or "%LEL" in text  # units keep their form
    raw = out.read_bytes()
    # the Chinese glyphs come from the embedded subset font, not a missing-glyph box
    assert re.search(rb"/BaseFont\s*/\w*StationPatrolCJK", raw), "CJK font not embedded"


def test_html_report_in_chinese_carries_its_font(zh, sample_data, tmp_path):
    data = _gather(sample_data)
    html = write_html(data, tmp_path / "report.html").read_text(encoding="utf-8")
    for h in HEADINGS:
        assert h in html
    assert "@font-face{font-family:'Station Patrol CJK'" in html
    assert "font/ttf;base64," in html


def test_report_in_english_stays_english_and_light(qapp, sample_data, tmp_path):
    data = _gather(sample_data)
    html = write_html(data, tmp_path / "report.html").read_text(encoding="utf-8")
    assert "Station patrol report" in html and "Meter readings" in html
    assert "@font-face" not in html  # no CJK text: no font carried
