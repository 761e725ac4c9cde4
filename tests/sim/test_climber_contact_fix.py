"""A contact with the map taken as a position fix (app/core/localisation/contact_fix.py).

Through the link, in the tank's stair band the belief's x drifted 8–15 cm from the
truth (the band hides the vertical seams that fix it), more than the moves' 2 cm
margin: the body touched the band again and again and wedged under a nozzle by the
bottom edge (bench/climber_link_bench.py --wall tank, traced). A contact says the body
stands where its footprint touches the map; the belief is moved there."""

from __future__ import annotations

import math

import pytest

from app.core.localisation.contact_fix import ContactFixes, contact_fix
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


def _band_y(x: float) -> float:
    """The stair band's centre line at x (from (55, 0) to (72, 9.6))."""
    return (x - 55.0) * 9.6 / 17.0


def _lane_contacts(err: float, cols=range(600, 628, 3)):
    """The band's real geometry: the belief on a lane's centre (the relay drives the
    lanes on the belief), the truth ``err`` away on the side from which the body can
    meet the band before the belief does — climbing or backing up into its lower
    side with the truth −x of the belief, descending or backing down onto its upper
    side with the truth +x — the body stopped where its footprint first touches, and
    only where the belief at that height is clear of the band by the moves' 2 cm
    (else the belief stops the lane first and the body never gets there). Yields
    (belief, truth (x, y), the sign of the speed)."""
    for col in cols:
        lane = (col + 0.5) * 0.1
        for lower, th, moving in ((True, math.pi / 2, 1.0), (True, -math.pi / 2, -1.0),
                                  (False, -math.pi / 2, 1.0)):
            xt = lane - err if lower else lane + err
            yt = _touching(xt, _band_y(xt) + (-0.9 if lower else 0.9), th)
            if _depth(lane, yt, th, 0.02) <= 0.0:
                yield (lane, yt, th), (xt, yt), moving


@pytest.mark.parametrize("err", [0.025, 0.03, 0.08])
def test_a_contact_with_the_stair_band_moves_x_toward_the_truth_never_past_it(
        err: float) -> None:
    """Logged through the link on the tank, the stair contacts came with the belief
    1–4.6 cm off on its clear side and σ_x 8–12 cm; the weighted mean of the touching
    tread (the fix before) put x 2–8 cm off on the other side in most of them. On the
    band's real geometry (above) with σ_x 8 cm, σ_y 1.5 cm, the fix moves x toward the
    truth and never more than 5 mm past it, and from 2.5–3 cm off to within 1 cm (the
    mean: 2.9–4.3 cm past it). From 8 cm off (an error larger than any logged) it moves
    x only to the nearest tread's corner, 2.25 cm on (the mean does better there, 1.2–2.1
    cm left: ``bench/contact_fix_replay.py --lanes``)."""
    n = 0
    for belief, (xt, yt), moving in _lane_contacts(err):
        ekf = _belief(*belief, 0.08, 0.015)
        fix = contact_fix(ekf, _depth, moving=moving)
        assert fix.fixed, (belief, fix.why)
        before, after = belief[0] - xt, ekf.pose[0] - xt
        assert abs(after) <= abs(before) + 1e-9, (belief, before, after)
        assert after * before >= 0.0 or abs(after) < 0.005, (belief, before, after)
        assert abs(after) < (0.01 if err <= 0.03 else err - 0.015), (belief, after)
        assert abs(ekf.pose[1] - yt) < 0.01
        n += 1
    assert n >= 5  # the geometry gives contacts at this error


def test_an_over_sure_belief_that_cannot_explain_the_contact_is_opened() -> None:
    """A belief 13 cm off in x but sure of it to 2 cm, on the band's real geometry: where
    no touching pose lies within 2 σ of it, its x variance is opened (to 5 cm) and the
    contact brings x to the truth's tread; where the nearest tread's corner is 2.25 cm
    away (1.1 σ, so the contact is explained, and the truth is on the tread before),
    x moves to that corner. Never past the truth; on average the error is more than
    halved."""
    errors = []
    for belief, (xt, _), moving in _lane_contacts(0.13, range(600, 615, 3)):
        ekf = _belief(*belief, 0.02, 0.015)
        assert contact_fix(ekf, _depth, moving=moving).fixed
        before, after = belief[0] - xt, ekf.pose[0] - xt
        assert abs(after) <= abs(before) and (after * before >= 0.0 or abs(after) < 0.005)
        errors.append(abs(after))
    assert sum(errors) / len(errors) < 0.065, errors


def test_a_contact_with_a_vertical_face_does_not_slide_the_belief_along_it() -> None:
    """The tank run's contact beside the manhole at (3.0, 0.9): facing −x, backing into
    its rastered side face, the belief 2–6 cm low in y (σ_y 10–20 cm). A vertical face
    tells x, not y: the mean of the touching poses along it lay 0.8 σ_y above the
    belief and moved y up past the truth (logged: 3.9 cm low to 8.9 cm high; replayed
    with σ_y 20 cm: 5.5–7.2 cm high). The fix leaves y no further from the truth than
    it was, and on the belief's side of it."""
    xt, yt, th = 2.557, 0.5, -3.131
    for dy in (-0.06, -0.039, -0.02):
        for sy in (0.1, 0.2):
            ekf = _belief(xt + 0.001, yt + dy, th, 0.05, sy)
            assert contact_fix(ekf, _depth, moving=-1.0).fixed
            after = ekf.pose[1] - yt
            assert dy - 1e-9 <= after <= 0.0, (dy, sy, after)
            assert abs(ekf.pose[0] - xt) < 0.01


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


# the tank run's end, its contact log: the body backing against the shell's bottom edge
# (true y 0.18–0.19), the belief 0.18 m higher beside the manhole at (3.0, 0.9) (belief,
# true (x, y))
STUCK = [((2.894, 0.36, 1.214), (2.892, 0.18)), ((2.894, 0.371, 1.03), (2.892, 0.19)),
         ((2.89, 0.358, 1.256), (2.888, 0.177)), ((2.89, 0.367, 1.143), (2.888, 0.185))]


def test_contacts_the_belief_cannot_explain_again_and_again_widen_the_search() -> None:
    """The tank run pressed ~900 times against the bottom edge there: no touching pose
    within the belief's σ (1–2 cm), so no contact fix, and the same targets again. Now
    the third unexplained contact at one believed place is searched with x and y opened
    to 10 cm: backing (the body's rear leads), only the bottom edge explains it, and y
    comes to within 1 cm of the truth."""
    fixes = ContactFixes()
    for k, (belief, _) in enumerate(STUCK[:3]):
        ekf = _belief(*belief, 0.02, 0.01)
        fix = fixes.on_contact(ekf, _depth, moving=-1.0)
        assert fix.fixed == (k == 2), (k, fix.why)
    xt, yt = STUCK[2][1]
    assert abs(ekf.pose[1] - yt) < 0.01 and abs(ekf.pose[0] - xt) < 0.01
    assert fixes.widened == fixes.widened_fixed == 1


def test_a_widened_search_never_jumps_to_an_ambiguous_explanation() -> None:
    """The same contacts during a turn in place (no speed along the heading: the front
    could have met the manhole above as well as the rear the bottom edge): the widened
    search finds both and fixes nothing, and leaves the filter's covariance as it was."""
    fixes = ContactFixes()
    for belief, _ in STUCK:
        ekf = _belief(*belief, 0.02, 0.01)
        p0 = ekf.covariance.copy()
        fix = fixes.on_contact(ekf, _depth, moving=0.0)
        assert not fix.fixed
        assert ekf.pose == belief
        if fix.why.startswith("ambiguous"):
            assert ekf.covariance[1, 1] <= p0[1, 1]
    assert fixes.widened == 1 and fixes.widened_fixed == 0


def test_only_a_face_the_body_drove_into_explains_a_contact() -> None:
    """Backing down below the manhole with σ_y 10 cm, both the bottom edge (rear) and
    the manhole (front) are within the belief's reach: without the speed's sign the
    contact is ambiguous; backing, the bottom edge alone explains it."""
    belief, (_, yt) = STUCK[0]
    ekf = _belief(*belief, 0.02, 0.10)
    assert contact_fix(ekf, _depth).why.startswith("ambiguous")
    ekf = _belief(*belief, 0.02, 0.10)
    assert contact_fix(ekf, _depth, moving=-1.0).fixed
    assert abs(ekf.pose[1] - yt) < 0.01


def test_a_staircases_treads_are_one_face_though_only_they_are_driven_into() -> None:
    """Climbing into the band, only its treads are poses the body was driving into (its
    risers, vertical, are not): taken alone they fall apart into one piece a tread, and
    the contact read as ambiguous — three of eight contact fixes of a tank run's log
    (main at ab84df0, after 9 836 s), the belief 2.0–2.4 cm +x of the truth with σ_x
    12–21 cm. The risers join the treads into one piece (with no weight), and each is
    fixed, x within 2 cm of the truth."""
    for belief, (xt, yt), sigma in (
            ((68.255, 6.654, 1.621), (68.231, 6.662), (0.1179, 0.0435)),
            ((61.582, 2.892, 1.814), (61.559, 2.906), (0.2108, 0.0298)),
            ((58.953, 1.382, 1.586), (58.933, 1.359), (0.164, 0.0711))):
        ekf = _belief(*belief, *sigma)
        fix = contact_fix(ekf, _depth, moving=1.0)
        assert fix.fixed, (belief, fix.why)
        assert abs(ekf.pose[0] - xt) < 0.02 and abs(ekf.pose[0] - xt) < belief[0] - xt
        assert abs(ekf.pose[1] - yt) < 0.02
