"""A real recorded run: the headless desk records a short patrol of the simulated
robot into its archive; the report and the replay read it back."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from app.core.records import Archive
from app.core.records.paths import default_archive_path

pytestmark = pytest.mark.slow(14)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """3 s of the headless desk on a patrolling robot: about 30 telemetry samples and
    poses (10 a second), the tests below ask for more than 10."""
    d = tmp_path_factory.mktemp("run")
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen"}
    r = subprocess.run([sys.executable, "-m", "app.cli", "--demo", "--headless", "--patrol",
                        "--duration", "3", "--time-scale", "4", "--out", str(d / "out"),
                        "--data-dir", str(d / "data")],
                       env=env, capture_output=True, text=True, timeout=180)
    assert r.returncode == 0, r.stderr[-2000:]
    assert default_archive_path(d / "data").exists()
    return d


def _report(run_dir, out: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items()
           if k not in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")}
    return subprocess.run([sys.executable, "-m", "app.cli", "report", "--from", "-1h",
                           "--out", str(run_dir / out), "--data-dir", str(run_dir / "data")],
                          env=env, capture_output=True, text=True, timeout=120)


def test_report_of_a_recorded_run_holds_its_figures(run_dir):
    r = _report(run_dir, "run.html")
    assert r.returncode == 0, r.stderr
    html = (run_dir / "run.html").read_text(encoding="utf-8")
    a = Archive(default_archive_path(run_dir / "data"))
    try:
        t, _seq, names, v = a.telemetry_rows(-np.inf, np.inf)
        gas = v[:, names.index("gas_lel_pct")]
        n_poses = len(a.poses(-np.inf, np.inf))
    finally:
        a.close()
    assert len(t) > 10 and n_poses > 10
    row = re.search(r"Combustible gas.*?</tr>", html, re.S).group(0)
    cells = re.findall(r"<td>([^<]*)</td>", row)
    assert cells[-1] == str(len(t))  # every stored sample counted
    assert cells[0].startswith(f"{gas.min():.3f}") and cells[1].startswith(f"{gas.max():.3f}")
    assert cells[2].startswith(f"{gas.mean():.3f}")
    assert "m driven" in r.stdout and "<h2>Route</h2>" in html


def test_pdf_of_a_recorded_run(run_dir):
    r = _report(run_dir, "run.pdf")
    assert r.returncode == 0, r.stderr
    pdf = (run_dir / "run.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-") and len(re.findall(rb"/Type\s*/Page\b(?!s)", pdf)) >= 1


def test_replay_of_a_recorded_run_emits_every_stored_message_in_order(qtbot, run_dir):
    from app.ui.replay import ReplayLink

    a = Archive(default_archive_path(run_dir / "data"))
    try:
        stored, *_ = a.telemetry_rows(-np.inf, np.inf)
        link = ReplayLink(a)
        got: list[float] = []
        link.telemetry_received.connect(lambda m: got.append(m.received_s))
        link.start()
        link.set_speed(10.0)
        link.play()
        while link.playing:
            link.step(0.25)
        link.shutdown()
    finally:
        a.close()
    assert got == pytest.approx(list(stored))
