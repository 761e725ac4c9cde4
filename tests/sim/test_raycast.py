"""The world's compiled ray cast against the straightforward numpy march it
replaced (kept as :func:`sim_robot.raycast.cast_reference`): the same ranges
and materials on random grids and on the station, with people in the way."""

from __future__ import annotations

import math

import numpy as np

from sim_robot import raycast
from sim_robot.world import Walker, World


def _both(labels, res, x, y, angles, max_range, step, people, person_mat=9):
    runs = raycast.free_runs(labels)
    rng = np.empty(len(angles), np.float32)
    mat = np.empty(len(angles), np.uint8)
    c, s = np.cos(angles), np.sin(angles)
    raycast.cast(labels, runs, x, y, c.astype(np.float32), s.astype(np.float32), c, s,
                 raycast.march_steps(step, max_range), raycast.fine_offsets(step), res,
                 max_range, people, person_mat, rng, mat)
    ref = raycast.cast_reference(labels, res, x, y, angles, max_range, step, people,
                                 person_mat)
    return (rng, mat), ref


def test_kernel_matches_the_reference_on_random_grids_with_people():
    rng = np.random.default_rng(3)
    rays = hits = people_hits = 0
    for trial in range(60):
        h, w = rng.integers(20, 120, size=2)
        res = float(rng.choice([0.05, 0.1, 0.25]))
        labels = np.zeros((h, w), np.uint8)
        for _ in range(rng.integers(0, 12)):  # boxes of random materials
            r0, c0 = rng.integers(0, h), rng.integers(0, w)
            labels[r0:r0 + rng.integers(1, 15), c0:c0 + rng.integers(1, 15)] = rng.integers(1, 6)
        labels[rng.random((h, w)) < rng.choice([0.0, 0.002, 0.02])] = 7  # scattered posts
        # the sensor anywhere, also outside the grid looking in
        x = float(rng.uniform(-0.2, 1.2) * w * res)
        y = float(rng.uniform(-0.2, 1.2) * h * res)
        angles = rng.uniform(-math.pi, math.pi) + np.linspace(-math.pi, math.pi, 181)
        k = int(rng.integers(0, 6))
        people = None if trial % 5 == 0 else np.column_stack(
            [rng.uniform(0, w * res, k), rng.uniform(0, h * res, k), rng.uniform(0.2, 0.9, k)])
        max_range = float(rng.choice([4.0, 12.0]))
        step = float(rng.choice([res * 0.5, 0.02]))
        (r, m), (r_ref, m_ref) = _both(labels, res, x, y, angles, max_range, step, people)
        assert r.dtype == r_ref.dtype == np.float32 and m.dtype == m_ref.dtype == np.uint8
        np.testing.assert_array_equal(r, r_ref)
        np.testing.assert_array_equal(m, m_ref)
        rays += len(angles)
        hits += int(np.isfinite(r).sum())
        people_hits += int((m == 9).sum())
    assert hits > rays // 4 and people_hits > 100  # the cases cover walls and people


def test_world_raycast_matches_the_reference_on_the_station():
    w = World(seed=1)
    free = np.argwhere(~w.occupied)
    rng = np.random.default_rng(5)
    w.clock = lambda: 40.0
    people = w.people()
    for i in range(40):
        r, c = free[rng.integers(len(free))]
        x, y = (c + rng.random()) * w.res, (r + rng.random()) * w.res
        if i % 4 == 0 and len(people):  # beside a walker
            x, y = people[i % len(people), 0] + 0.6, people[i % len(people), 1]
        # plain floats, as the robot's pose is (numpy's march is then float32 throughout)
        x, y = float(x), float(y)
        angles = rng.uniform(-math.pi, math.pi) + np.linspace(-math.pi, math.pi, 360,
                                                              endpoint=False)
        for max_range, step in ((12.0, None), (4.0, 0.02)):
            got = w.raycast(x, y, angles, max_range, step_m=step)
            ref = raycast.cast_reference(w.labels, w.res, x, y, angles, max_range,
                                         step or w.res * 0.5, w.people(), w._person_mat)
            np.testing.assert_array_equal(got[0], ref[0])
            np.testing.assert_array_equal(got[1], ref[1])


def test_people_of_one_moment_are_asked_once_and_vehicles_still_move():
    w = World(seed=2)
    a = w.people(10.0)
    b = w.people(10.0)
    np.testing.assert_array_equal(a, b)
    b[:] = 0  # a caller's copy: the next answer is not changed by it
    np.testing.assert_array_equal(w.people(10.0), a)
    later = w.people(60.0)  # walkers and the cart move on
    assert not np.array_equal(later, a)
    fresh = World(seed=2)
    fresh.people(10.0)
    np.testing.assert_array_equal(fresh.people(60.0), later)


def test_movers_point_is_numpys_interp():
    rng = np.random.default_rng(11)
    for _ in range(200):
        n = int(rng.integers(2, 7))
        pts = rng.uniform(-50, 80, (n, 2))
        if rng.random() < 0.3:  # a repeated vertex: a segment of no length
            pts[1] = pts[0]
        m = Walker({"id": "w", "path": pts.tolist(), "speed_mps": 1.0, "pause_s": 1.0,
                    "radius_m": 0.3}, 0.0)
        s = np.concatenate([rng.uniform(-1, m.length + 1, 50), m.cum, [m.length, 0.0]])
        for v in s:
            x, y = m.point(float(v))
            assert x == float(np.interp(v, m.cum, m.pts[:, 0]))
            assert y == float(np.interp(v, m.cum, m.pts[:, 1]))
