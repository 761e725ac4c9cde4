import gzip
import math

import numpy as np
import pytest

from app.core.localisation.__main__ import main
from app.core.localisation.carmen import parse_lines
from app.core.localisation.se2 import relative


@pytest.fixture(scope="module")
def head_lines(freiburg_path):
    """The real log's PARAM lines and its first 25 FLASER lines."""
    out, scans = [], 0
    with gzip.open(freiburg_path, "rt") as f:
        for line in f:
            if line.startswith("FLASER"):
                scans += 1
            out.append(line)
            if scans == 25:
                break
    return out


def _read_tsv(path):
    lines = path.read_text().splitlines()
    return np.array([[float(v) for v in line.split("\t")] for line in lines])


def test_cli_maps_a_short_real_log(tmp_path, head_lines, capsys):
    log = tmp_path / "short.log"
    log.write_text("".join(head_lines))
    rc = main(["carmen", str(log), "--out", str(tmp_path / "p.tsv"),
               "--map", str(tmp_path / "m.yaml")])
    assert rc == 0
    poses = _read_tsv(tmp_path / "p.tsv")
    assert poses.shape == (25, 4)
    assert poses[0, 1:] == pytest.approx([0.0, 0.0, 0.0], abs=1e-9)  # frame of the first pose
    ref = [tuple(map(float, ln.split()[2 + 360:2 + 363])) for ln in head_lines
           if ln.startswith("FLASER")]
    ref = np.array([relative(ref[0], p) for p in ref])
    assert np.max(np.hypot(*(poses[:, 1:3] - ref[:, :2]).T)) < 0.2
    assert poses[:, 0] == pytest.approx([float(ln.split()[-3]) for ln in head_lines
                                         if ln.startswith("FLASER")])
    assert (tmp_path / "m.pgm").exists() and "resolution: 0.05" in (tmp_path / "m.yaml").read_text()
    assert "25 scans, 0 bad lines" in capsys.readouterr().err


def test_cli_reports_bad_lines_with_their_numbers_and_goes_on(tmp_path, head_lines, capsys):
    lines = list(head_lines)
    flaser = [i for i, ln in enumerate(lines) if ln.startswith("FLASER")]
    t = lines[flaser[3]].split()
    lines[flaser[3]] = " ".join(t[:100]) + "\n"  # truncated
    t = lines[flaser[5]].split()
    t[50] = "nan"
    lines[flaser[5]] = " ".join(t) + "\n"
    t = lines[flaser[7]].split()
    t[20] = "-1.5"
    lines[flaser[7]] = " ".join(t) + "\n"
    lines.append("FLASER 3 1.0 2.0\n")  # truncated at the end of the file
    log = tmp_path / "bad.log"
    log.write_text("".join(lines))
    rc = main(["carmen", str(log), "--out", str(tmp_path / "p.tsv")])
    assert rc == 0
    err = capsys.readouterr().err
    for i, word in ((flaser[3], "truncated"), (flaser[5], "nan"), (flaser[7], "negative"),
                    (len(lines) - 1, "truncated")):
        assert f"bad.log:{i + 1}: skipped" in err
        assert word in [ln for ln in err.splitlines() if f":{i + 1}:" in ln][0].lower()
    assert "Traceback" not in err
    assert _read_tsv(tmp_path / "p.tsv").shape == (22, 4)


def test_cli_with_the_landmark_ekf_back_end(tmp_path, head_lines):
    log = tmp_path / "short.log"
    log.write_text("".join(head_lines))
    assert main(["carmen", str(log), "--out", str(tmp_path / "p.tsv"), "--backend", "ekf"]) == 0
    poses = _read_tsv(tmp_path / "p.tsv")
    assert poses.shape == (25, 4) and np.all(np.isfinite(poses[:, 1:]))


def test_cli_refuses_a_log_without_scans(tmp_path, capsys):
    log = tmp_path / "empty.log"
    log.write_text("PARAM robot_length 0.5 nohost 0\nODOM 0 0 0 0 0 0 1.0 host 1.0\n")
    assert main(["carmen", str(log), "--out", str(tmp_path / "p.tsv")]) == 2
    assert "no usable FLASER" in capsys.readouterr().err
    assert main(["carmen", str(tmp_path / "missing.log"), "--out", str(tmp_path / "p.tsv")]) == 2


def test_reader_keeps_params_and_ignores_timestamps():
    log = parse_lines(["PARAM laser_front_laser_fov 100 nohost 0",
                       "FLASER 3 1 2 3 0 0 0 0 0 0 0 host 0",
                       "FLASER 3 1 2 3 1 0 0 1 0 0 0 host 0",
                       "NEFF 1 2 3"])
    assert len(log.scans) == 2 and log.other_lines == 1
    assert log.fov_rad == pytest.approx(math.radians(100))
    assert log.beam_angles(3) == pytest.approx(np.radians([-50, 0, 50]))


def _thinned_variant(head_lines, beams: int, no_return: float) -> tuple[list[str], list[str]]:
    """The short log as another laser would have written it: every second beam
    (180 over 180°; 181 with the +90° beam repeated), the no-return value
    ``no_return``, the first and the eleventh scan blank (no return at all),
    timestamps zero, repeated and wrapping. Returns (lines, timestamps given)."""
    out, stamps, k = [], [], 0
    for ln in head_lines:
        if not ln.startswith("FLASER"):
            out.append(ln)
            continue
        t = ln.split()
        r = np.array([float(v) for v in t[2:2 + 360]])[::2]
        if beams == 181:
            r = np.r_[r, r[-1]]
        r[r >= 80.0] = no_return
        if k in (0, 10):
            r[:] = no_return
        stamp = ["0", "17.5", "17.5", "4294967.0", "3.25"][k % 5]
        stamps.append(stamp)
        out.append(" ".join(["FLASER", str(beams), *(f"{v:.2f}" for v in r), *t[362:368],
                             stamp, "host", stamp]) + "\n")
        k += 1
    return out, stamps


@pytest.mark.parametrize("beams,no_return", [(180, 81.9), (181, 32.8), (181, 50.0)])
def test_cli_on_other_lasers_blank_scans_and_bad_timestamps(tmp_path, head_lines, beams,
                                                            no_return, capsys):
    lines, stamps = _thinned_variant(head_lines, beams, no_return)
    log = tmp_path / "other.log"
    log.write_text("".join(lines))
    rc = main(["carmen", str(log), "--out", str(tmp_path / "p.tsv"),
               "--map", str(tmp_path / "m.yaml")])
    err = capsys.readouterr().err
    assert rc == 0 and "Traceback" not in err
    poses = _read_tsv(tmp_path / "p.tsv")
    assert poses.shape == (25, 4) and np.all(np.isfinite(poses))
    assert poses[:, 0] == pytest.approx([float(s) for s in stamps])  # echoed, in scan order
    ref = [tuple(map(float, ln.split()[2 + beams:2 + beams + 3])) for ln in lines
           if ln.startswith("FLASER")]
    ref = np.array([relative(ref[0], p) for p in ref])
    assert np.max(np.hypot(*(poses[:, 1:3] - ref[:, :2]).T)) < 0.3
