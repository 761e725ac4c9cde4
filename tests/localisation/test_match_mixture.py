"""The ICP fit and the grid fit as two hypotheses of one match, weighed as the
PDAF weighs its measurements (match_mixture.py; MappingConfig.match_disagreement
"mixture")."""

import math

import numpy as np
import pytest

import app.core.localisation.mapping as mapping
from app.core.localisation.icp import IcpResult
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.match_mixture import association_weights, mixture_measurement
from app.core.localisation.se2 import compose, wrap

from .rooms import room_points

Q = np.diag([0.07 ** 2, 0.07 ** 2, math.radians(1.6) ** 2])  # odometry, a 1 m step
R = np.diag([0.02 ** 2, 0.02 ** 2, math.radians(0.35) ** 2])  # the match


def _deg(v):
    return np.array([0.0, 0.0, math.radians(v)])


def test_two_fits_as_far_from_the_prediction_weigh_alike_and_the_nearer_weighs_more():
    s = Q + R
    np.testing.assert_allclose(association_weights(_deg(1.0), _deg(-1.0), s), [0.5, 0.5])
    b = association_weights(_deg(6.0), _deg(1.0), s)  # the grid fit in a rival minimum
    assert b[1] > 0.99
    assert b.sum() == pytest.approx(1.0)


def test_the_measurement_is_the_weighted_mean_and_the_former_rule_where_one_fit_weighs_all():
    d = np.array([0.02, 0.0, math.radians(1.0)])
    grid = np.array([1.0, 2.0, 0.3])
    z, rz = mixture_measurement(grid, R, d, np.array([0.75, 0.25]), 2.25)
    np.testing.assert_allclose(z, grid - 0.25 * d)
    np.testing.assert_allclose(rz, R + (2.25 - 0.1875) * np.outer(d, d))
    z1, rz1 = mixture_measurement(grid, R, d, np.array([1.0, 0.0]), 2.25)
    np.testing.assert_allclose(z1, grid)  # the grid fit and k² d dᵀ, as "fusion"
    np.testing.assert_allclose(rz1, R + 2.25 * np.outer(d, d))
    z0, rz0 = mixture_measurement(grid, R, np.zeros(3), np.array([0.5, 0.5]), 2.25)
    np.testing.assert_allclose(rz0, R)  # fits that agree: the fit as it is


def test_the_former_rules_factor_is_kept_about_the_grid_fit_and_eased_towards_the_middle():
    """k² − β_g β_i = (k² − ¼) + (β_g − β_i)² / 4: the midpoint's part plus the
    offset of the weighted mean from it (the module docstring's model)."""
    d = np.array([0.0, 0.0, math.radians(1.0)])
    grid = np.array([1.0, 2.0, 0.3])
    for b_icp in (0.0, 0.2, 0.5, 0.9):
        _, rz = mixture_measurement(grid, R, d, np.array([1 - b_icp, b_icp]), 2.25)
        c = (rz - R)[2, 2] / d[2] ** 2
        assert c == pytest.approx(2.0 + (1 - 2 * b_icp) ** 2 / 4)


def _parting_step(mode, icp_off_deg, odo_off_deg, monkeypatch):
    """The heading error (degrees) of a step whose ICP fit is held
    ``icp_off_deg`` off (as on a scan whose pairings mislead it) while the
    grid fit finds the pose, odometry's turn ``odo_off_deg`` off."""
    rng = np.random.default_rng(4)
    truth = np.array([0.5, 0.1, 0.02])
    points = [room_points(np.zeros(3), rng), room_points(truth, rng)]
    icp_pose = truth + np.array([0.0, 0.0, math.radians(icp_off_deg)])

    def misled(*args, **kwargs):
        return IcpResult(icp_pose.copy(), np.diag([1e-5, 1e-5, 1e-7]), 0.01, 1.0, 5, True)

    monkeypatch.setattr(mapping, "match", misled)
    m = LaserMapper(MappingConfig(match_disagreement=mode, loop_closure=False))
    m.add_scan(np.zeros(3), points[0])
    est = m.add_scan(compose(truth, (0.0, 0.0, math.radians(odo_off_deg))), points[1])
    return math.degrees(float(wrap(est[2] - truth[2])))


def test_the_mappers_match_moves_towards_the_fit_odometry_agrees_with(monkeypatch):
    # odometry right; ICP held 0.8° off: the step lies between the two fits,
    # the grid fit (nearer odometry's guess) weighing more
    err = _parting_step("mixture", -0.8, 0.0, monkeypatch)
    assert -0.4 < err < 0.0


def test_the_mapper_still_holds_a_fit_in_a_rival_minimum_to_odometry(monkeypatch):
    # ICP 5° off, odometry right: ICP's far fit weighs next to nothing, and
    # the disagreement's size keeps the step near odometry and the grid fit
    fusion = _parting_step("fusion", 5.0, 0.0, monkeypatch)
    mixture = _parting_step("mixture", 5.0, 0.0, monkeypatch)
    assert abs(mixture) < 0.3
    assert abs(mixture) <= abs(fusion) + 0.05
