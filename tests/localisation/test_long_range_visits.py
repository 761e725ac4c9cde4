"""Long-range ties per visit (long_range.py, 6.): a region seen again on a
later pass must not push out the one far view that ties it to the rest."""

import math

import numpy as np

from app.core.localisation.long_range import LongRangeConfig, _visits, long_range_ties
from tests.localisation.test_long_range import _ties_onto_start_are_right, _turned_start


def test_matches_split_into_visits_where_the_path_between_them_exceeds_the_gap():
    path = np.array([0.0, 2.0, 4.0, 30.0, 32.0, 60.0])
    found = [(j, None, None, 0.5) for j in (4, 0, 1, 5, 3)]  # any order
    visits = _visits(found, path, 20.0)
    assert [[f[0] for f in v] for v in visits] == [[0, 1], [3, 4], [5]]


def _start_seen_again(edmonton):
    """Edmonton's first 170 scans with the start (scans 0..59) turned 2°, then
    the start driven again 60 m of path later (nodes 170..229: its scans
    where the map draws the start, as the final pass's closures leave a
    revisit)."""
    poses, path, lms, ref, start = _turned_start(edmonton, 1, 2.0)
    n = len(poses)
    poses = np.vstack([poses, poses[:start]])
    ref = np.vstack([ref, ref[:start]])
    path = np.r_[path, path[-1] + 60.0 + path[:start]]
    lms = lms + [(n + k, lms[k][1]) for k in range(start)]
    return poses, path, lms, ref, start, n


def test_a_revisit_of_the_start_keeps_the_far_view_that_ties_it(edmonton):
    """The revisit's matches onto the start (exact, many) outnumber the far
    view of scans 140..160 (14 m off, 100 m of path later): with one group
    per region only the revisit's is kept and the start stays turned; with
    one group per visit the far view's ties are kept too, and every tie is
    right."""
    poses, path, lms, ref, start, n = _start_seen_again(edmonton)
    floor = np.diag([0.03, 0.03, math.radians(0.5)]) ** 2

    def far_view(per_visit: bool):
        ties = long_range_ties(poses, path, lms, 4.0, floor,
                               LongRangeConfig(chunk_m=60.0, per_visit=per_visit))
        onto_start = _ties_onto_start_are_right(ties, ref, start)
        return [c for c in onto_start if 140 <= c.new <= 160], ties

    largest_only, _ = far_view(False)
    assert largest_only == []
    per_visit, ties = far_view(True)
    assert len(per_visit) >= 3
    assert any(c.old < start and c.new >= n for c in ties)  # the revisit's group stays
