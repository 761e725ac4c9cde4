import math

import numpy as np
import pytest

from app.core.localisation.icp import IcpConfig, match, scan_normals, stacked_reference
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.preprocess import preprocess
from app.core.localisation.se2 import compose, relative
from app.core.localisation.submap_match import Submap, SubmapCache, match_submap, refine

# a 10 m × 6 m room with an off-centre pillar and a wall niche (no symmetry)
ROOM = [((0, 0), (10, 0)), ((10, 0), (10, 6)), ((10, 6), (4, 6)), ((4, 6), (4, 5)),
        ((4, 5), (2.5, 5)), ((2.5, 5), (2.5, 6)), ((2.5, 6), (0, 6)), ((0, 6), (0, 0)),
        ((6, 2), (7, 2)), ((7, 2), (7, 2.6)), ((7, 2.6), (6, 2.6)), ((6, 2.6), (6, 2))]


def _scan(pose, beams=180, noise_m=0.01, seed=0):
    """Ray-cast the room from ``pose`` over 360°: points in the sensor frame."""
    rng = np.random.default_rng(seed)
    out = []
    for a in np.linspace(-math.pi, math.pi, beams, endpoint=False):
        d = np.array([math.cos(pose[2] + a), math.sin(pose[2] + a)])
        best = math.inf
        for (x1, y1), (x2, y2) in ROOM:
            e = np.array([x2 - x1, y2 - y1])
            m = np.array([[d[0], -e[0]], [d[1], -e[1]]])
            if abs(np.linalg.det(m)) < 1e-12:
                continue
            t, u = np.linalg.solve(m, np.array([x1 - pose[0], y1 - pose[1]]))
            if t > 0 and 0 <= u <= 1:
                best = min(best, t)
        r = best + rng.normal(0, noise_m)
        out.append((r * math.cos(a), r * math.sin(a)))
    return np.array(out)


def _submap(poses):
    return Submap([(np.array(p), _scan(p, seed=i)) for i, p in enumerate(poses)])


def test_recovers_a_known_offset_in_a_synthetic_room():
    sub = _submap([(2.0, 2.0, 0.0), (3.0, 2.5, 0.3), (4.0, 2.0, 0.6)])
    truth = np.array([3.5, 3.0, 0.4])
    guess = compose(truth, [0.25, -0.2, math.radians(7)])
    r = match_submap(_scan(truth, seed=9), sub, guess, 0.4, math.radians(10))
    assert math.hypot(*(r.pose[:2] - truth[:2])) < 0.02
    assert abs(r.pose[2] - truth[2]) < math.radians(0.3)
    assert r.inlier_fraction > 0.9 and r.converged
    # from a guess 0.1 m and 1.5° off, the refinement (CS) alone gets there too
    x, score = refine(_scan(truth, seed=9), sub, compose(truth, [0.1, 0.0, 0.026]))
    assert math.hypot(*(x[:2] - truth[:2])) < 0.02 and abs(x[2] - truth[2]) < 0.005
    assert score > 0.8


def test_covariance_is_positive_and_long_along_a_corridor():
    x = np.linspace(-10, 10, 400)
    walls = np.r_[np.column_stack((x, np.full_like(x, 1.0))),
                  np.column_stack((x, np.full_like(x, -1.0)))]
    rng = np.random.default_rng(3)
    sub = Submap([(np.zeros(3), walls)])
    src = walls[::3] + rng.normal(0, 0.01, walls[::3].shape)
    r = match_submap(src, sub, np.array([0.0, 0.05, 0.01]))
    assert abs(r.pose[1]) < 0.01 and abs(r.pose[2]) < math.radians(0.2)
    w = np.linalg.eigvalsh(r.covariance)
    assert np.all(w > 0)
    sx, sy = math.sqrt(r.covariance[0, 0]), math.sqrt(r.covariance[1, 1])
    # along the corridor the likelihood is flat over the whole covariance grid
    # (± 3 fine cells): σ is that grid's spread, well above the across-σ
    assert sx > 4 * sy
    # in the room, where every direction is fixed, σ is about a cell
    room = match_submap(_scan((3.5, 3.0, 0.4), seed=9), _submap([(3.0, 2.5, 0.3)]),
                        np.array([3.5, 3.0, 0.4]))
    assert math.sqrt(room.covariance[0, 0]) < 0.03
    assert math.sqrt(room.covariance[2, 2]) < math.radians(0.5)


def _points(log, k):
    s = log.scans[k]
    return preprocess(s.ranges_m, log.beam_angles(s.ranges_m.size), no_return_m=log.no_return_m())


@pytest.mark.parametrize("k", [94, 184])
def test_real_edmonton_keyframes_where_icp_lands_in_a_rival_minimum(edmonton, k):
    # five edmonton keyframes at their reference poses, the next scan from a guess
    # 0.3 m and 6° off: the point-to-line ICP of the local map (with its own
    # correlative fallback) stops ≥ 2° off; the submap's search and refinement
    # land within 0.05 m and 0.3° of the reference
    ref0 = np.array(edmonton.scans[0].pose)
    poses = [relative(ref0, np.array(edmonton.scans[j].pose)) for j in range(k - 5, k + 1)]
    pts = [_points(edmonton, j) for j in range(k - 5, k + 1)]
    truth = poses[-1]
    guess = compose(truth, [0.25, -0.2, math.radians(6)])
    keys = list(zip(poses[:-1], pts[:-1], strict=True))
    stack = stacked_reference([(p, q, *scan_normals(q, 6)) for p, q in keys], 6, 0.25)
    old = match(pts[-1], stack, guess, IcpConfig(), 0.5, math.radians(12), 0.45)
    assert abs(relative(truth, old.pose)[2]) > math.radians(1.5)
    new = match_submap(pts[-1], Submap(keys), guess, 0.4,
                       math.radians(8))
    d = relative(truth, new.pose)
    assert math.hypot(d[0], d[1]) < 0.05 and abs(d[2]) < math.radians(0.3)


def test_the_mapper_refines_its_matches_on_the_submap_when_asked():
    # a drive through the room with odometry 8 % long and turning 10 % short:
    # (odometry alone ends 0.5 m off): with the submap refinement every pose stays
    # within 8 cm and 0.5° of the truth
    truth = [np.array([1.5 + 0.5 * i, 1.5 + 0.2 * i, 0.05 * i]) for i in range(12)]
    odo = [np.zeros(3)]
    for a, b in zip(truth, truth[1:], strict=False):
        u = relative(a, b)
        odo.append(compose(odo[-1], [1.08 * u[0], 1.08 * u[1], 0.9 * u[2]]))
    m = LaserMapper(MappingConfig(submap=True, loop_closure=False))
    for i, (o, t) in enumerate(zip(odo, truth, strict=True)):
        m.add_scan(o, _scan(t, seed=i))
    # the mapper's cached submap is the render of its latest keyframes at their poses
    fresh = Submap([(m.poses[lm.node], lm.points)
                    for lm in m.landmarks[-m.cfg.local_landmarks:]], m.cfg.submap_cfg)
    np.testing.assert_array_equal(m._local_submap().fine.grid, fresh.fine.grid)
    est = m.finish()
    for e, t in zip(est, [relative(truth[0], t) for t in truth], strict=True):
        assert math.hypot(*(e[:2] - t[:2])) < 0.08
        assert abs(e[2] - t[2]) < math.radians(0.5)
    assert m.icp_failures == 0


def test_the_submap_cache_equals_a_fresh_render_and_follows_its_keyframes():
    poses = [np.array(p) for p in [(2.0, 2.0, 0.0), (3.0, 2.5, 0.3), (4.0, 2.0, 0.6),
                                   (5.0, 3.0, 0.9)]]
    scans = [_scan(p, seed=i) for i, p in enumerate(poses)]

    def fresh(keys):
        return Submap([(p, s) for _, p, s in keys])

    def same(a, b):
        np.testing.assert_array_equal(a.fine.grid, b.fine.grid)
        np.testing.assert_array_equal(a.fine.lo, b.fine.lo)

    cache = SubmapCache()
    first = [(i, poses[i], scans[i]) for i in range(3)]
    sub = cache.get(first)
    same(sub, fresh(first))
    # the same keyframes at the same poses: the grid is not rendered again
    assert cache.get([(i, p.copy(), s) for i, p, s in first]) is sub and cache.renders == 1
    # a new keyframe pushes the oldest out: rendered again, as a fresh render
    second = first[1:] + [(3, poses[3], scans[3])]
    sub2 = cache.get(second)
    assert cache.renders == 2 and sub2 is not sub
    same(sub2, fresh(second))
    assert sub2.fine.grid.shape != sub.fine.grid.shape or \
        not np.array_equal(sub2.fine.grid, sub.fine.grid)
    # a solve moves one keyframe by 5 cm: rendered again at the new pose
    moved = [(1, poses[1] + [0.05, 0.0, 0.0], scans[1])] + second[1:]
    sub3 = cache.get(moved)
    assert cache.renders == 3
    same(sub3, fresh(moved))


def test_the_whole_cell_search_scores_as_the_shift_by_shift_search():
    """The correlative search over shifts of whole cells (a point's cell found
    once per heading) picks the same (shift, heading) with the same score,
    to the last bit, as the search that finds every shifted point's cell
    afresh — also for points on a cell's border (where rounding decides the
    cell) and points whose window leaves the grid."""
    from app.core.localisation.submap_match import _grid_search_cells, _grid_search_kernel

    sub = _submap([(2.0, 2.0, 0.0), (7.5, 4.0, 1.0)])
    rng = np.random.default_rng(2)
    for field, step in ((sub.coarse, sub.cfg.coarse_res_m), (sub.fine, sub.cfg.res_m)):
        lox, loy, res = float(field.lo[0]), float(field.lo[1]), float(field.res)
        for trial in range(6):
            src = _scan((3.0 + trial, 3.0, 0.3 * trial), seed=trial)[::2]
            n = int(rng.integers(3, 12))
            if trial % 2:  # points put on cell borders, at heading 0 and guess 0
                src[::3] = np.round((src[::3] - (lox, loy)) / res) * res + (lox, loy)
            offs = np.arange(-n, n + 1) * step
            dx, dy = np.meshgrid(offs, offs, indexing="ij")
            shifts = np.column_stack((dx.ravel(), dy.ravel()))
            dths = np.arange(-3, 4) * math.radians(1.0)
            guess = (0.0, 0.0, 0.0) if trial % 2 else rng.normal(0, (0.3, 0.3, 0.05))
            args = (np.ascontiguousarray(src), *map(float, guess))
            common = (field.grid, lox, loy, res)
            slow = _grid_search_kernel(*args, shifts, dths, *common)
            fast = _grid_search_cells(*args, dths, *common, n, step, int(round(step / res)))
            assert fast == slow
            assert slow[0] >= 0


def test_the_whole_cell_search_finds_a_border_points_cells_as_rounding_does():
    """A point on a cell's border, shifted, may land by rounding one cell
    off its own cell moved by the shift: the search then finds its cells
    shift by shift. On a field rising along x the best shift is the
    farthest right, and its score is the cell that point really lands in."""
    from app.core.localisation.submap_match import _grid_search_cells, _grid_search_kernel

    res, lo, n = 0.1, -3.0, 5
    grid = np.tile(np.arange(120, dtype=float), (80, 1)) + 0.001 * np.arange(80)[:, None]
    found = 0
    for m in range(20, 90):
        for x in (*np.nextafter(lo + m * res, [-np.inf, np.inf]).tolist(), lo + m * res):
            c = math.floor((x - lo) / res)
            if math.floor((x + n * res - lo) / res) == c + n:
                continue  # rounding leaves the farthest shift in its cell: not the case
            found += 1
            src = np.array([[x, 1.0]])
            offs = np.arange(-n, n + 1) * res
            dx, dy = np.meshgrid(offs, offs, indexing="ij")
            shifts = np.column_stack((dx.ravel(), dy.ravel()))
            dths = np.zeros(1)
            slow = _grid_search_kernel(src, 0.0, 0.0, 0.0, shifts, dths, grid, lo, lo, res)
            fast = _grid_search_cells(src, 0.0, 0.0, 0.0, dths, grid, lo, lo, res, n, res, 1)
            assert fast == slow
    assert found >= 3
