"""The final pass leaves free what its matches hardly hold
(LoopConfig.final_free_directions, on in the station's mapping mode)."""

import math

import numpy as np

from app.core.localisation.icp import scan_normals
from app.core.localisation.loop_closure import LoopConfig, ViewOverlap, final_pass
from app.core.localisation.mapping import MappingConfig
from app.core.localisation.se2 import relative, transform_points


def _wall(a, b, step=0.05):
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = max(int(round(np.linalg.norm(b - a) / step)), 1)
    return a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)


# a road 2 m wide along x, 30 m long; a post's near face at x = 4 (seven
# points) is all that holds the position along it
ROAD = np.vstack((_wall((-15.0, -1.0), (15.0, -1.0)), _wall((-15.0, 1.0), (15.0, 1.0)),
                  _wall((4.0, 0.6), (4.0, 0.9))))


def _edges(matcher: str, free: bool):
    """Keyframes every metre from x = 0 to 12 along the road at their true
    poses, each seeing it within 8 m with 1 cm of range noise."""
    cfg = MappingConfig(loop=LoopConfig(final_matcher=matcher, final_free_directions=free),
                        faces=True)
    rng = np.random.default_rng(3)
    truth = np.array([(x, 0.0, 0.0) for x in np.arange(0.0, 13.0)])
    landmarks = []
    for k, p in enumerate(truth):
        pts = transform_points(relative(p, np.zeros(3)), ROAD)
        r = np.hypot(pts[:, 0], pts[:, 1])
        near = r < 8.0
        pts = pts[near] * (1 + 0.01 * rng.standard_normal(near.sum()) / r[near])[:, None]
        landmarks.append((k, pts, *scan_normals(pts, cfg.icp.normal_neighbours)))
    floor = np.diag([cfg.edge_floor_xy_m ** 2, cfg.edge_floor_xy_m ** 2,
                     cfg.edge_floor_theta_rad ** 2])
    edges = final_pass(truth, truth[:, 0].copy(), landmarks, set(), cfg.icp, cfg.loop,
                       ViewOverlap(), cfg.cov_scale(), floor, cfg.submap_cfg, cfg.faces)
    assert len(edges) >= 5
    return truth, edges


def test_final_pass_edges_leave_a_road_s_axis_free_where_one_post_holds_it():
    truth, edges = _edges("icp", free=True)
    for c in edges:
        z_true = relative(truth[c.old], truth[c.new])
        along, across = math.sqrt(c.cov[0, 0]), math.sqrt(c.cov[1, 1])
        assert along >= 0.5, f"{c.old}->{c.new}: one post claims the axis to {along:.2f} m"
        assert across <= 0.05
        assert abs(c.z[1] - z_true[1]) < 0.02  # across the road: right
        assert abs(c.z[2] - z_true[2]) < math.radians(0.2)


def test_without_the_test_one_post_pins_the_axis():
    """As before (the logs' configuration): the same edges claim the road's
    axis to a decimetre or less, ICP's Hessian counting the post's seven points as
    it counts a wall's."""
    _, edges = _edges("icp", free=False)
    assert max(math.sqrt(c.cov[0, 0]) for c in edges) < 0.15


def test_the_logs_configuration_is_unchanged():
    assert not LoopConfig().final_free_directions
    assert not MappingConfig().final_pass and not MappingConfig().faces
