"""The localisation bench's variants: which scans each keeps, in which order."""

import numpy as np

from bench.localisation_bench import VARIANTS, variant_indices


def test_every_second_scan_forwards_and_backwards_as_before():
    assert variant_indices(7, 2).tolist() == [0, 2, 4, 6]
    assert variant_indices(7, 2, back=True).tolist() == [6, 4, 2, 0]
    assert variant_indices(5, 1, back=True).tolist() == [4, 3, 2, 1, 0]


def test_an_offset_keeps_the_other_half():
    odd = variant_indices(8, 2, offset=1)
    assert odd.tolist() == [1, 3, 5, 7]
    even = variant_indices(8, 2)
    assert not set(odd) & set(even) and len(odd) + len(even) == 8
    assert variant_indices(8, 2, back=True, offset=1).tolist() == [6, 4, 2, 0]


def test_the_odd_half_variant_is_the_odd_scans_of_edmonton():
    fname, every, factor, back, offset = VARIANTS["edmonton-every2-odd-x1.25"]
    assert "edmonton" in fname and (every, factor, back, offset) == (2, 1.25, False, 1)
    idx = variant_indices(340, every, back, offset)
    assert np.all(idx % 2 == 1) and len(idx) == 170


def test_the_even_reversed_variant_is_edmontons_even_scans_last_first():
    fname, every, factor, back, offset = VARIANTS["edmonton-every2-even-reversed-x1.25"]
    assert "edmonton" in fname and (every, factor, back, offset) == (2, 1.25, True, 1)
    idx = variant_indices(340, every, back, offset)
    assert np.all(idx % 2 == 0) and len(idx) == 170 and idx[0] == 338 and np.all(np.diff(idx) < 0)


def test_the_held_out_reversed_x1_variant_is_edmontons_odd_scans_last_first():
    fname, every, factor, *extra = VARIANTS["edmonton-every2-reversed-x1"]
    assert "edmonton" in fname and (every, factor, extra) == (2, 1.0, [True])
    idx = variant_indices(340, every, *extra)
    assert np.all(idx % 2 == 1) and len(idx) == 170 and idx[0] == 339 and np.all(np.diff(idx) < 0)


def test_a_variant_of_passes_drives_the_path_there_and_back():
    assert variant_indices(4, 1, passes=3).tolist() == [0, 1, 2, 3, 2, 1, 0, 1, 2, 3]
    assert variant_indices(6, 2, back=True, passes=2).tolist() == [5, 3, 1, 3, 5]
    fname, every, factor, back, offset, passes = VARIANTS["edmonton-4passes"]
    idx = variant_indices(340, every, back, offset, passes)
    assert len(idx) == 340 + 3 * 339 and idx[0] == idx[678] == 0 and idx[339] == 339
    assert np.all(np.abs(np.diff(idx)) == 1)  # neighbours only: one path, driven round


def test_the_held_out_three_passes_drive_edmonton_backwards_there_and_back_and_back():
    fname, every, factor, back, offset, passes = VARIANTS["edmonton-reversed-3passes-x1.25"]
    idx = variant_indices(340, every, back, offset, passes)
    assert len(idx) == 340 + 2 * 339 and idx[0] == idx[678] == 339
    assert idx[339] == idx[-1] == 0
    assert np.all(np.abs(np.diff(idx)) == 1) and factor == 1.25


def test_the_held_out_forward_x1_5_variant_is_edmontons_first_half_and_refused_by_diagnosis():
    import pytest

    from bench.loop_edge_errors import HELD_OUT, load

    fname, every, factor = VARIANTS["edmonton-every2-x1.5"]
    assert "edmonton" in fname and (every, factor) == (2, 1.5)
    idx = variant_indices(340, every)
    assert np.all(idx % 2 == 0) and len(idx) == 170 and idx[0] == 0 and np.all(np.diff(idx) > 0)
    assert "edmonton-every2-x1.5" in HELD_OUT  # the diagnosis tools never load it
    with pytest.raises(SystemExit):
        load(None, "edmonton-every2-x1.5")
