"""The final pass, the long-range ties and the edge reweighting run a second
time from the poses the first round solved (``MappingConfig.final_rounds``),
replacing the first round's edges."""

import numpy as np
import pytest

from app.core.localisation.evaluate import drifting_odometry
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.se2 import relative
from app.core.localisation.slam import scan_points

pytestmark = pytest.mark.slow(20)


def _mapped(pts, odo, rounds: int):
    m = LaserMapper(MappingConfig(final_pass=True, final_rounds=rounds))
    for o, p in zip(odo, pts, strict=True):
        m.add_scan(o, p)
    online = {(e.i, e.j) for e in m.edges if e.loop}
    return m, m.finish(), online


def test_a_second_round_replaces_the_first_rounds_edges(edmonton):
    """Every second edmonton scan, the first 90 (the start's loop, the long
    way round the hall and back past the start), drifting odometry: the
    second round's graph holds the online closures and its own final-pass
    edges and ties only, not the first round's beside them, and it starts
    from the poses the first round solved (so its map differs). Its edges
    are not more accurate than the first round's (8.5 against 8.4 cm mean
    error here; docs/localisation.md), which is why it is off by default."""
    pts = scan_points(edmonton)[::2][:90]
    ref = np.array([s.pose for s in edmonton.scans])[::2][:90]
    ref = np.array([relative(ref[0], p) for p in ref])
    odo = drifting_odometry(ref, seed=8)
    m1, est1, online1 = _mapped(pts, odo, 1)
    m2, est2, online2 = _mapped(pts, odo, 2)
    assert online1 == online2  # the same drive: finish alone differs
    loops = [(e.i, e.j) for e in m2.edges if e.loop]
    assert len(loops) == len(set(loops))
    assert len(loops) <= len(online2) + m2.final_closures + m2.long_range_ties
    assert m2.final_closures > 20
    assert m1.final_closures > 20
    loops1 = [(e.i, e.j) for e in m1.edges if e.loop]
    assert len(loops1) <= len(online1) + m1.final_closures + m1.long_range_ties
    assert np.max(np.hypot(*(est2[:, :2] - est1[:, :2]).T)) > 0.005
    assert MappingConfig().final_rounds == 1
