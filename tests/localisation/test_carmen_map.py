"""The map of a short stretch of a real log: unknown cells stay unknown, the
free rays of no-return beams clear what they cross, the CLI writes YAML + PGM."""

import gzip

import numpy as np
import pytest

from app.core.localisation.__main__ import main
from app.core.localisation.carmen import parse_lines
from app.core.localisation.map_io import FREE, UNKNOWN, load_map, save_map
from app.core.localisation.preprocess import PreprocessConfig
from app.core.localisation.se2 import transform_points
from app.core.localisation.slam import (
    free_rays,
    landmark_grid,
    log_odometry,
    run_mapping,
    scan_points,
    usable_range_m,
)


@pytest.fixture(scope="module")
def stretch(freiburg_path):
    """The log's PARAM lines and its first 15 FLASER lines, mapped."""
    out, scans = [], 0
    with gzip.open(freiburg_path, "rt") as f:
        for line in f:
            scans += line.startswith("FLASER")
            out.append(line)
            if scans == 15:
                break
    log = parse_lines(out)
    _, mapper = run_mapping(scan_points(log), log_odometry(log))
    return out, log, mapper


def _cell(grid, xy):
    col, row = np.floor((np.asarray(xy) - grid.origin_xy) / grid.resolution_m).astype(int).T
    return grid.cells[row, col]


def test_usable_range_is_the_preprocessings(stretch):
    _, log, _ = stretch
    assert log.no_return_m() > PreprocessConfig().max_range_m  # freiburg writes 81.9 m
    assert usable_range_m(log) == PreprocessConfig().max_range_m
    assert usable_range_m(log, PreprocessConfig(max_range_m=100.0)) < log.no_return_m()


def test_a_no_return_beam_clears_and_unknown_cells_stay_unknown(stretch, tmp_path):
    _, log, mapper = stretch
    free = free_rays(log)
    assert sum(len(f) for f in free) > 100  # the corridor's open ends
    plain = landmark_grid(mapper, free=None, l_free=-0.6)
    rays = landmark_grid(mapper, free=free, l_free=-0.6)
    # points two thirds along every landmark's free rays, in the map's frame
    mids = np.vstack([transform_points(mapper.poses[lm.node], (2 / 3) * free[lm.node])
                      for lm in mapper.landmarks if len(free[lm.node])])
    before, after = _cell(plain, mids), _cell(rays, mids)
    # the hit-only map does not know most of these cells; the rays free them
    assert np.mean(before == UNKNOWN) > 0.5
    assert np.mean(after[before == UNKNOWN] == FREE) > 0.9
    # cells no beam reached stay unknown, through a save and load as well
    for grid in (plain, rays):
        assert grid.cells[0, 0] == UNKNOWN and grid.unknown.mean() > 0.2
        save_map(grid, tmp_path / "m.yaml")
        back = load_map(tmp_path / "m.yaml")
        assert np.array_equal(back.unknown, grid.unknown)
        assert np.array_equal(back.cells == FREE, grid.cells == FREE)


def test_cli_writes_the_logs_map(stretch, tmp_path):
    lines, _, mapper = stretch
    log = tmp_path / "short.log"
    log.write_text("".join(lines))
    rc = main(["carmen", str(log), "--out", str(tmp_path / "p.tsv"),
               "--map", str(tmp_path / "m.yaml")])
    assert rc == 0 and (tmp_path / "m.pgm").exists()
    got = load_map(tmp_path / "m.yaml")
    assert got.unknown.any() and (got.cells == FREE).any() and got.occupied.any()
    assert np.array_equal(got.cells, landmark_grid(mapper).cells)  # same run, same drawing
