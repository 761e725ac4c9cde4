"""Turns in place where the body has little room (sim_robot/climber/moves.py, reach.py),
from the relay's contacts on a wall with the tank's stair band and beside its nozzles
(bench/climber_link_bench.py --wall 8x2.4 --stair, --wall tank; traced).

- Under the stair band a lane's top end is left by a turn to face along the row. Against
  the map's cells the diagonal band is a staircase: the body's side lies along one of its
  steps, and backing off 2 cm leaves the turn's sweep as deep in it, so the back-off was
  not made at all and the turn went on into the stair (92 stair contacts in one run of
  the small wall). The back-off's way is now looked for out to its longest reach, and it
  goes on along such a step instead of stopping where the sweep does not shrink.
- A lane's first cells above the bottom edge are probed facing down, the body reversing
  up; beside a nozzle the turn to face up swung its corners into the nozzle. It goes on
  reversing, and turns round where there is room."""

from __future__ import annotations

import math

from app.core.planner.coverage.wall import Band, Disc, WallSpec, rasterise
from sim_robot.climber.contact import WallContact
from sim_robot.climber.kinematics import ClimberParams
from sim_robot.climber.moves import Moves, body_moves
from sim_robot.climber.reach import Reach

P_ = ClimberParams()
LEAD = P_.length_m / 2
# the link bench's 8 m × 2.4 m wall with --stair: the band at the tank's slope
STAIR = WallSpec(8.0 / math.pi, 2.4, 0.1, stairs=(Band(0.8, 0.0, 0.8 + 2.4 * 17 / 9.6, 2.4, 0.9),))


def _reach(spec: WallSpec) -> Reach:
    return Reach(WallContact(spec, rasterise(spec), P_.length_m, P_.width_m), LEAD)


def _drive(moves: Moves, pose, dt: float = 0.05, t_max: float = 60.0):
    """The moves on an ideal body (no slip, the estimate exact): the poses driven."""
    x, y, th = pose
    path, t = [pose], 0.0
    while t < t_max:
        u = moves.step((x, y, th), t)
        if u is None:
            return path
        v, w = u
        x, y, th = x + v * dt * math.cos(th), y + v * dt * math.sin(th), th + w * dt
        path.append((x, y, th))
        t += dt
    raise AssertionError("the moves did not end")


def test_below_the_stair_the_body_backs_off_along_a_step_of_the_band_before_turning():
    reach = _reach(STAIR)
    pose = (3.85, 0.887, math.pi / 2)  # a lane's top end under the band (traced)
    assert reach.sweep_depth(*pose, 0.0) > 0.01  # the turn along the row would touch
    # backing off 2 cm leaves the sweep as deep (the body's side along a step)
    down2 = reach.sweep_depth(pose[0], pose[1] - 0.02, pose[2], 0.0)
    assert down2 > reach.sweep_depth(*pose, 0.0) - 0.002
    assert reach.back_off_way(pose[0], pose[1], pose[2], 0.0) == -1.0
    moves = Moves(reach, STAIR.circumference_m)
    moves.set([("turn", 0.0)])
    path = _drive(moves, pose)
    # the turn is made where its sweep keeps the margin: the body never meets the stair
    assert all(reach.contact.depth(x, y, th)[0] <= 0.0 for x, y, th in path)
    assert abs(math.remainder(path[-1][2], 2 * math.pi)) < math.radians(3)
    assert moves.backoffs == 1 and moves.turns == 1
    assert path[-1][1] < pose[1] - 0.03


def test_beside_a_nozzle_a_lane_above_the_bottom_edge_reverses_on_instead_of_turning_round():
    spec = WallSpec(3.0 / math.pi, 1.2, 0.1, nozzles=(Disc(2.2, 0.5, 0.3),))
    reach = _reach(spec)
    for r in (3, 4):  # column 25 (x 2.5–2.6), beside the nozzle's right side
        cells = [(r - 1, 25), (r, 25), (r + 1, 25)]
        pose = (2.55, (r - 0.5) * 0.1 + LEAD, -math.pi / 2)  # probe on the cell before
        assert reach.sweep_depth(*pose, math.pi / 2) > 0.05  # turning round would touch
        assert body_moves(reach, cells, 1, pose, 0.1, 12, 30) == []
    # in the open the lane turns round to face its way, as before
    cells = [(2, 10), (3, 10), (4, 10)]
    pose = (1.05, 0.25 + LEAD, -math.pi / 2)
    assert body_moves(reach, cells, 1, pose, 0.1, 12, 30) == [("turn", math.pi / 2)]
