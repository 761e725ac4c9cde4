"""A contact with the map taken as a position fix (app/core/localisation/contact_fix.py).

Through the link, in the tank's stair band the belief's x drifted 8–15 cm from the
truth (the band hides the vertical seams that fix it), more than the moves' 2 cm
margin: the body touched the band again and again and wedged under a nozzle by the
bottom edge (bench/climber_link_bench.py --wall tank, traced). A contact says the body
stands where its footprint touches the map; the belief is moved there."""

from __future__ import annotations

import math

import pytest

from app.core.localisation.contact_fix import contact_fix
from app.core.localisation.wall_ekf import WallEkf
from app.core.planner.coverage.wall import default_wall, rasterise
from sim_robot.climber.contact import WallContact
from sim_robot.climber.kinematics import ClimberParams

P_ = ClimberParams()
SPEC = default_wall()  # the tank: its stair band from (55, 0) to (72, 9.6), 0.9 m wide
CONTACT = WallContact(SPEC, rasterise(SPEC), P_.length_m, P_.width_m)


def _depth(x: float, y: float, th: float, grow: float = 0.0) -> float:
    return CONTACT.depth(x, y, th, grow)[0]


def _touching(x: float, y: float, th: float, step: float = 0.002) -> float:
    """The y at which a body climbing (or descending) at x stops against the map."""
    dy = step if math.sin(th) > 0 else -step
    while _depth(x, y + dy, th) <= 0.0:
        y += dy
    return y


def _belief(x: float, y: float, th: float, sx: float, sy: float) -> WallEkf:
    ekf = WallEkf(x, y, th)
    ekf.open_variance(0, sx)
    ekf.open_variance(1, sy)
    return ekf


# true poses where the body stops against the stair band: climbing into its lower side,
# descending onto its upper side (the lanes' ends there)
CASES = [(x, 1.0, math.pi / 2) for x in (62.03, 63.07, 64.0, 66.55, 68.31)] + \
        [(x, 9.0, -math.pi / 2) for x in (60.04, 61.5, 63.2)]


@pytest.mark.parametrize("err", [0.08, -0.13])
def test_a_contact_with_the_stair_band_brings_the_believed_x_back(err: float) -> None:
    """A belief off in x by ``err`` (σ_x 10 cm, σ_y 1.5 cm), the body stopped against the
    band: after the fix the believed x is on average within 5 cm of the truth (the
    raster's treads are 10–20 cm wide: one contact cannot say where on one the body
    is), and never more than 1.5 cm worse than before."""
    errors = []
    for xt, y_start, th in CASES:
        yt = _touching(xt, y_start, th)
        ekf = _belief(xt + err, yt, th, 0.10, 0.015)
        fix = contact_fix(ekf, _depth)
        assert fix.fixed, (xt, fix.why)
        errors.append(abs(ekf.pose[0] - xt))
        assert errors[-1] < abs(err) + 0.015, (xt, errors[-1])
        assert abs(ekf.pose[1] - yt) < 0.02
    assert sum(errors) / len(errors) < 0.05, errors


def test_an_over_sure_belief_that_cannot_explain_the_contact_is_opened() -> None:
    """A belief 13 cm off in x but sure of it to 2 cm finds no touching pose within its
    3 σ: its x variance is opened (to 5 cm) and the contact brings x within 5 cm."""
    for xt in (63.07, 64.0):
        yt = _touching(xt, 1.0, math.pi / 2)
        ekf = _belief(xt + 0.13, yt, math.pi / 2, 0.02, 0.015)
        assert contact_fix(ekf, _depth).fixed
        assert abs(ekf.pose[0] - xt) < 0.05


def test_a_contact_the_belief_cannot_explain_is_not_used() -> None:
    """In the open wall, far from every edge and obstacle, no pose near the belief
    touches anything: the contact (something not on the map) moves nothing."""
    ekf = _belief(30.0, 5.0, math.pi / 2, 0.05, 0.02)
    before = ekf.pose
    fix = contact_fix(ekf, _depth)
    assert not fix.fixed
    assert ekf.pose == before


def test_a_bottom_edge_contact_fixes_y_not_x() -> None:
    """Stopped against the shell's bottom (facing down, away from any obstacle): the
    contact set is a horizontal line; y comes to it and x stays where it was."""
    xt, th = 30.0, -math.pi / 2
    yt = _touching(xt, 0.6, th)
    ekf = _belief(xt + 0.08, yt + 0.03, th, 0.10, 0.03)
    contact_fix(ekf, _depth)
    assert abs(ekf.pose[1] - yt) < 0.01
    assert abs(ekf.pose[0] - (xt + 0.08)) < 0.005


def test_a_contact_again_at_the_last_fix_place_is_not_folded_in_twice() -> None:
    """The body pressed again against the same tread (a recoil, the same move): the
    second contact says nothing new and leaves the belief as the first fix left it; a
    contact farther along (another tread) is a fix again."""
    from app.core.localisation.contact_fix import ContactFixes

    fixes = ContactFixes()
    xt, th = 64.0, math.pi / 2
    yt = _touching(xt, 1.0, th)
    ekf = _belief(xt + 0.08, yt, th, 0.10, 0.015)
    assert fixes.on_contact(ekf, _depth).fixed
    after_first = (ekf.pose, ekf.covariance.copy())
    again = fixes.on_contact(ekf, _depth)
    assert not again.fixed and fixes.repeats == 1
    assert ekf.pose == after_first[0]
    assert (ekf.covariance == after_first[1]).all()
    # another tread, 0.6 m along: the belief moved there by odometry, a fix again
    x2 = 66.55
    y2 = _touching(x2, 1.0, th)
    ekf2 = _belief(x2 + 0.08, y2, th, 0.10, 0.015)
    assert fixes.on_contact(ekf2, _depth).fixed
