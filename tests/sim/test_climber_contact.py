"""The climber's body is stopped at the wall's top and bottom and at obstacles
(sim_robot/climber/contact.py, kinematics.py); the board reports a contact, the
relay counts it and tells the desks; the navigation keeps the body on the wall
from the map and its estimate only (reach.py, moves.py)."""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np
import pytest

from app.comm import protocol as P
from app.comm.protocol import AlarmFlag
from app.core.planner.coverage.wall import Band, Disc, WallSpec, rasterise
from sim_robot.climber import kinematics as kinematics_module
from sim_robot.climber.contact import BOTTOM, TOP, WallContact
from sim_robot.climber.kinematics import ClimberBody, ClimberParams, ClimberState
from sim_robot.climber.mcu import ClimberMcu
from sim_robot.climber.moves import body_moves
from sim_robot.climber.reach import Reach
from sim_robot.climber.sim import ClimberSim
from sim_robot.climber.wall_world import WallWorld
from sim_robot.config import SimConfig

from .test_climber_link import TIME_SCALE, small_setup

P_ = ClimberParams()
LEAD = P_.length_m / 2
SPEC = WallSpec(3.0 / math.pi, 1.2, 0.1, nozzles=(Disc(2.2, 0.6, 0.3),))


def _contact(spec: WallSpec = SPEC) -> WallContact:
    return WallContact(spec, rasterise(spec), P_.length_m, P_.width_m)


def test_the_footprint_touches_the_edges_and_the_obstacles_it_reaches():
    c = _contact()
    assert c.touches(1.0, 0.6, 0.0) is None  # in the open
    # facing up with the probe on the bottom row: the body's rear is below the shell
    assert c.touches(1.0, 0.05 - LEAD, math.pi / 2) == BOTTOM
    assert c.touches(1.0, 0.05 + LEAD, -math.pi / 2) is None  # facing down there: it fits
    assert c.touches(1.0, 1.2 - 0.1, 0.0) == TOP  # along the top row: its side is above
    # beside the nozzle (blocked cells x 2.0–2.4): the body's side 3 cm into them
    assert c.touches(2.4 + 0.13 - 0.03, 0.6, math.pi / 2) == "nozzle"
    assert c.touches(2.4 + 0.13 + 0.01, 0.6, math.pi / 2) is None
    assert c.touches(2.4 + 0.13 + 0.01, 0.6, math.pi / 2, margin_m=0.02) == "nozzle"
    depth, what = c.depth(1.0, 0.05, 0.0)
    assert what == BOTTOM and depth == pytest.approx(0.13 - 0.05)
    # round the tank: the nozzle seen from the far side of the seam
    wrapped = WallSpec(3.0 / math.pi, 1.2, 0.1, nozzles=(Disc(0.1, 0.6, 0.2),))
    assert _contact(wrapped).touches(3.0 - 0.05, 0.6, math.pi / 2) == "nozzle"


def test_the_body_stops_at_the_bottom_edge_and_its_wheels_stall():
    c = _contact()
    body = ClimberBody(P_, ClimberState(1.0, 0.4, -math.pi / 2), 3.0, seed=1, contact=c.depth)
    wheels = 0.0
    for _ in range(200):  # 10 s down at 0.1 m/s: 1 m asked, 0.26 m of wall below the body
        vl, vr, _ = body.step(0.1, 0.0, 0.05)
        wheels += (vl + vr) / 2 * 0.05
    assert body.touching == BOTTOM
    assert body.s.y_m == pytest.approx(LEAD, abs=0.002)  # the front face on the edge
    assert c.depth(body.s.x_m, body.s.y_m, body.s.theta_rad)[0] <= 1e-9
    assert wheels < 0.3  # the encoders see the motion made, not the motion asked
    assert len(body.contacts) == 1 and body.contacts[0]["what"] == BOTTOM
    for _ in range(40):  # backing away is free
        body.step(-0.1, 0.0, 0.05)
    assert body.touching == "" and body.s.y_m > LEAD + 0.1
    for _ in range(100):  # down again after more than CONTACT_REARM_S: a second contact
        body.step(0.1, 0.0, 0.05)
    assert len(body.contacts) == 2


def test_a_level_body_on_the_bottom_edge_drives_along_it_instead_of_creeping_into_it():
    """Level on the bottom edge, the creep pulls the body into the edge at every
    step: the edge holds it there and the body drives on along the edge (it
    used to stall on any motion at all, and the inspection stayed pressed there
    for good)."""
    c = _contact()
    half_w = P_.width_m / 2
    body = ClimberBody(P_, ClimberState(1.0, half_w + 0.0005, 0.0), 3.0, seed=3,
                       contact=c.depth)
    assert c.depth(1.0, half_w + 0.0005, 0.0)[0] <= 0.0  # clear, 0.5 mm above the edge
    for sign in (1.0, -1.0):  # forward 0.4 m asked, then back 0.4 m
        x0 = body.s.x_m
        for _ in range(80):
            body.step(0.1 * sign, 0.0, 0.05)
        assert sign * (body.s.x_m - x0) > 0.3  # it went (a little slip)
        assert body.s.y_m == pytest.approx(half_w, abs=0.001)  # on the edge, not below it
        assert c.depth(body.s.x_m, body.s.y_m, body.s.theta_rad)[0] <= 1e-9
    # the same motion in the open creeps down: the edge is what held it
    free = ClimberBody(P_, ClimberState(1.0, 0.6, 0.0), 3.0, seed=3, contact=c.depth)
    for _ in range(80):
        free.step(0.1, 0.0, 0.05)
    assert free.s.y_m < 0.6 - 1e-4


def test_the_body_stops_at_a_nozzle_and_a_turn_in_place_there_too():
    c = _contact()
    body = ClimberBody(P_, ClimberState(1.6, 0.6, 0.0), 3.0, seed=2, contact=c.depth)
    for _ in range(200):
        body.step(0.1, 0.0, 0.05)
    assert body.touching == "nozzle"
    assert body.s.x_m + LEAD == pytest.approx(2.0, abs=0.005)  # the front face at its cells
    # turning in place there swings a corner into it: the turn stops too
    th = body.s.theta_rad
    for _ in range(100):
        body.step(0.0, 0.3, 0.05)
    assert body.touching == "nozzle" and abs(body.s.theta_rad - th) < 0.3
    assert [r["what"] for r in body.contacts] == ["nozzle"]  # the same contact


def test_the_board_raises_its_contact_flag_and_holds_it_briefly():
    world = WallWorld(SPEC, seed=1)
    c = _contact()
    body = ClimberBody(P_, ClimberState(1.0, 0.3, -math.pi / 2), world.circ_m, contact=c.depth)
    mcu = ClimberMcu(world, body, link_clock=lambda: 0.0)
    mcu.last_rx = 0.0
    mcu.target_v = 0.1
    t, flags = 0.0, []
    for _ in range(60):
        t += 0.05
        flags.append(bool(mcu.step(t, 0.05).alarm_flags & AlarmFlag.OBSTACLE_NEAR))
    assert not flags[0] and flags[-1]  # reached the edge, pressed against it
    mcu.target_v = -0.1
    for _ in range(4):  # backing away: still raised for CONTACT_HOLD_S
        t += 0.05
        assert mcu.step(t, 0.05).alarm_flags & AlarmFlag.OBSTACLE_NEAR
    for _ in range(20):
        t += 0.05
        rep = mcu.step(t, 0.05)
    assert not rep.alarm_flags & AlarmFlag.OBSTACLE_NEAR


def test_lane_changes_at_the_edges_keep_the_body_on_the_wall():
    """On the map: the bottom row is probed facing down only; a lane change along
    it backs off (if need be), turns along the row, steps one cell straight and
    turns to face down again; cells beside the nozzle where the body fits
    neither up nor down are planned round; a lane's cells up from the bottom
    edge are taken facing down (reversing) until the body fits behind the probe."""
    reach = Reach(_contact(), LEAD)
    assert reach.probe_heading(1.05, 0.05, math.pi / 2) == pytest.approx(-math.pi / 2)
    assert reach.probe_heading(1.05, 0.25, math.pi / 2) == pytest.approx(-math.pi / 2)
    assert reach.probe_heading(1.05, 0.35, math.pi / 2) == pytest.approx(math.pi / 2)
    assert reach.probe_heading(2.45, 0.55, math.pi / 2) is None  # beside the nozzle
    cells = [(1, 10), (0, 10), (0, 11), (1, 11)]
    pose = (1.05, 0.05 + LEAD, -math.pi / 2)  # the probe on (0, 10), facing down
    moves = body_moves(reach, cells, 2, pose, 0.1, 12, 30)
    assert moves == [("turn", 0.0), ("step", 0.1), ("turn", -math.pi / 2)]
    assert body_moves(reach, cells, 3, (1.15, 0.05 + LEAD, -math.pi / 2), 0.1, 12, 30) == []
    up = [(5, 10), (6, 10)]  # in the open: the lane's way, no turn
    assert body_moves(reach, up, 1, (1.05, 0.55 - LEAD, math.pi / 2), 0.1, 12, 30) == []
    # the turn's sweep would touch the bottom: the moves back off before it
    assert reach.sweep_depth(1.05, 0.05 + LEAD, -math.pi / 2, 0.0) > 0
    assert reach.sweep_depth(1.05, 0.05 + LEAD + 0.04, -math.pi / 2, 0.0) <= 0
    assert reach.back_off_way(1.05, 0.05 + LEAD, -math.pi / 2, 0.0) == -1.0
    planned = reach.body_blocked()
    blocked = rasterise(SPEC)
    assert (planned >= blocked).all()
    assert planned[5, 24] and not blocked[5, 24]  # beside the nozzle
    assert planned[0:4, 20].all()  # under it, 0.4 m: too low to turn in
    assert not planned[:, 10].any() and not planned[0, 15]


def test_a_detour_lifted_off_the_bottom_row_leaves_and_rejoins_it_up_the_lanes_column():
    """A detour along the bottom row (to a vertical seam and back to the lane's
    end) runs on the row where the body fits facing along it; its legs to and
    from that row go straight along the lane's column. The return leg used to
    cut diagonally from the lifted row to the lane's end on the bottom row: the
    probe was then steered sideways next to the edge, the body's corners swung
    past it, and the body touched the edge again and again."""
    from sim_robot.climber.moves import lift_detour

    reach = Reach(_contact(), LEAD)
    blocked = rasterise(SPEC)
    route = [(0, 11), (0, 12), (0, 13), (0, 12), (0, 11), (0, 10)]  # from (0, 10) and back
    lifted = lift_detour(reach, route, blocked, 0.1)
    row = lifted[2][0]
    assert row >= 1 and all(reach.fits(1.05, (row + 0.5) * 0.1, h) for h in (0.0, math.pi))
    assert lifted[0] == (1, 10) and lifted[-1] == (0, 10)
    assert [c for c in lifted if c[1] == 10] == [
        *((r, 10) for r in range(1, row + 1)), *((r, 10) for r in range(row, -1, -1))]
    # every leg is one cell up, down or along: none crosses a row and a column at once
    steps = zip([(0, 10), *lifted[:-1]], lifted, strict=True)
    assert all(abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1 for a, b in steps)


def test_a_detour_the_body_cannot_face_along_is_not_driven():
    """From a lane's end inside the wall a detour keeps its row; where a cell of it
    lets the body face along the row neither way (its side over the nozzle) the
    detour is not driven (the executor leaves it for a later lane change)."""
    from sim_robot.climber.moves import lift_detour

    reach = Reach(_contact(), LEAD)
    blocked = reach.body_blocked()
    clear = [(5, 14), (5, 13), (5, 14), (5, 15)]
    assert lift_detour(reach, clear, blocked, 0.1) == clear
    beside = [(5, 17), (5, 18), (5, 17), (5, 16)]  # the nozzle spans x 2.05–2.35
    assert lift_detour(reach, beside, blocked, 0.1) == []


def test_a_detour_to_any_row_from_the_bottom_row_leaves_and_rejoins_it_up_the_column():
    """A detour to any row's seam cell from a lane's end on the bottom row is
    searched with the body's steps (:func:`.link_ends.body_steps`): it runs along
    a row where the body fits facing along it both ways, and its legs to and from
    that row go straight along the lane's column. A leg across a row and a column at
    once had the probe steered sideways next to the edge, the body's corners swung
    past it, and the body touched the edge again and again."""
    from app.core.planner.coverage.wall import plate_seams
    from sim_robot.climber.link_ends import body_steps
    from sim_robot.climber.seam_detour import SeamDetour

    reach = Reach(_contact(), LEAD)
    blocked = reach.body_blocked()
    seams = plate_seams(3.0 / math.pi, 1.2, 1.2, 2)  # vertical seams at x = 0 and 1.5 m
    det = SeamDetour(blocked, seams, 0.1, max_lanes=1, max_steps=15)
    det.any_row = True
    det.lane_changed()
    route = det.route((0, 10), body_steps(reach, 0.1, blocked.shape[1]))
    far = len(route) // 2 - 1  # the far end: the way there and the way back are as long
    row = route[far][0]
    assert route[far] == (row, 15) and row >= 1  # the seam's column, off the bottom row
    assert all(reach.fits(c * 0.1 + 0.05, (row + 0.5) * 0.1, h)
               for c in range(10, 16) for h in (0.0, math.pi))
    assert route[-1] == (0, 10)
    assert [c for c in route if c[1] == 10] == [
        *((r, 10) for r in range(1, row + 1)), *((r, 10) for r in range(row, -1, -1))]
    # every leg is one cell up, down or along: none crosses a row and a column at once
    steps = zip([(0, 10), *route[:-1]], route, strict=True)
    assert all(abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1 for a, b in steps)
    assert route == [*route[:far + 1], *route[far - 1::-1], (0, 10)]  # back the same way


def test_a_detour_to_any_row_keeps_off_where_the_body_cannot_face_along_the_row():
    """Beside the nozzle (x 1.9-2.5 m) the body fits facing up or down but not
    along the row (its side over the nozzle): a detour searched with the body's
    steps does not run along such cells; with no way round within reach it is not
    driven (again at a later lane change)."""
    from sim_robot.climber.link_ends import body_steps
    from sim_robot.climber.seam_detour import SeamDetour

    reach = Reach(_contact(), LEAD)
    blocked = reach.body_blocked()
    steps = body_steps(reach, 0.1, blocked.shape[1])
    seam = Band(1.85, 0.0, 1.85, 1.2, 0.01, crossable=True)  # column 18, beside the nozzle
    det = SeamDetour(blocked, (seam,), 0.1, max_lanes=1, max_steps=4)
    det.any_row = True
    det.lane_changed()
    assert det.route((5, 16)) == [(5, 17), (5, 18), (5, 17), (5, 16)]  # (the probe's way)
    assert not reach.fits(1.75, 0.55, math.pi)  # (5, 17) facing back: over the nozzle
    assert det.route((5, 16), steps) == []
    det.max_steps = 15
    route = det.route((5, 16), steps)
    assert route and route[-1] == (5, 16)
    assert all(steps(a, b) for a, b in zip([(5, 16), *route[:-1]], route, strict=True))


def test_the_probe_is_not_steered_sideways_where_turning_would_swing_a_corner_past_the_edge():
    """Steering the probe onto a cell turns the body about its centre when the
    probe is off to the side; facing down over the bottom row that swings a front
    corner below the shell's edge. There the probe is driven along the heading
    only; in the open the same lateral error is steered out."""
    from sim_robot.climber.executor import InspectionExecutor

    reach = Reach(_contact(), LEAD)
    ex = InspectionExecutor(rasterise(SPEC), 0.1, (0, 10), P_, turns_in_place=True,
                            reach=reach)
    ex.start(0.0)

    def steer(target, probe_x, probe_y):
        ex.cells[:] = [(target[0] + 1, target[1]), target, (target[0], target[1] + 1)]
        ex.index = 1
        ex.moves.set(())
        ex._since = 0.0
        return ex.step((probe_x, probe_y + LEAD, -math.pi / 2), 0.0, 0.0)

    v, w = steer((0, 10), 1.05 + 0.03, 0.05 + 0.03)  # 3 cm aside, 3 cm above the cell
    assert v > 0 and w == 0.0
    v, w = steer((6, 10), 1.05 + 0.03, 0.65 + 0.03)  # the same in the open: turned in
    assert v > 0 and abs(w) > 0.05


def test_a_contact_over_the_link_is_reported_as_the_patrol_robots_collision(climber):
    """Driven down into the bottom edge by the desk, the simulated body stops there;
    the board's flag reaches the desk in telemetry, the relay counts the contact and
    sends the patrol robot's ``collision`` event, naming what its map has where its
    estimate puts the body."""
    from .desk import SocketDesk

    desk = SocketDesk(*climber.address)
    try:
        desk.wait_for(lambda: desk.of(P.MsgType.WALL_POSE), 10, "wall pose")
        body = climber.body

        def drive(v, w, until, what):
            sent = [0.0]

            def step():  # the drive renewed every 0.2 s, as the desk does while a key is held
                if time.monotonic() - sent[0] > 0.2:
                    sent[0] = time.monotonic()
                    desk.send(P.Command("drive", {"linear_mps": v, "angular_rps": w}))
                return until()
            return desk.wait_for(step, 60, what)

        drive(0.0, -0.5, lambda: abs(body.s.theta_rad + math.pi / 2) < 0.1, "facing down")
        drive(0.15, 0.0, lambda: desk.events("collision"), "a collision event")
        ev = desk.events("collision")[0]
        assert ev.level == "alarm" and ev.data["what"] == BOTTOM
        assert abs(ev.data["y_m"] - body.s.y_m) < 0.1  # the estimate's, near the truth
        assert body.touching == BOTTOM or body.contacts
        assert body.s.y_m >= LEAD - 0.005  # stopped: the front face not past the edge
        assert climber.relay.stats()["counters"]["contacts"] >= 1
        desk.wait_for(lambda: any(t.alarm_flags & AlarmFlag.OBSTACLE_NEAR
                                  for t in desk.of(P.MsgType.TELEMETRY)), 10, "the contact flag")
        assert [r["what"] for r in body.contacts][:1] == [BOTTOM]
    finally:
        desk.close()


# who may read the climber's true state (ClimberBody.s): the body itself, the board
# that moves it and samples its sensors, and the simulator's camera; never the relay's
# navigation (executor, moves, reach, odometry, relay)
TRUTH_READERS = {"kinematics.py", "mcu.py", "sim.py", "accelerometer.py", "climber_link_bench.py"}


def test_the_relay_steers_on_its_estimate_never_the_bodys_truth(monkeypatch):
    here = os.path.dirname(kinematics_module.__file__)
    reads: list[str] = []

    def get(self):
        caller = sys._getframe(1).f_code.co_filename
        if caller.startswith(here) and os.path.basename(caller) not in TRUTH_READERS:
            reads.append(caller)
        return self.__dict__["_s"]

    def put(self, value):
        self.__dict__["_s"] = value

    monkeypatch.setattr(ClimberBody, "s", property(get, put), raising=False)
    sim = ClimberSim(SimConfig(video=False, seed=2, time_scale=TIME_SCALE), small_setup())
    sim.start()
    from .desk import SocketDesk

    desk = SocketDesk(*sim.address)
    try:
        desk.wait_for(lambda: desk.of(P.MsgType.WALL_INFO), 10, "wall info")
        desk.send(P.Command("start_inspection", {}))
        desk.wait_for(lambda: (c := desk.of(P.MsgType.COVERAGE)) and c[-1].covered >= 40,
                      120, "40 cells covered")
    finally:
        desk.close()
        sim.close()
    assert sim.relay.inspection.moves.turns > 0
    assert reads == []
    # the guard sees a read from navigation code
    from sim_robot.climber import executor as executor_module

    eval(compile("b.s", executor_module.__file__, "eval"), {"b": sim.body})
    assert reads == [executor_module.__file__]
    assert np.isfinite(sim.body.s.x_m)


def test_the_wall_file_may_let_the_body_pass_through(tmp_path):
    from sim_robot.climber.sim import load_setup

    f = tmp_path / "w.toml"
    f.write_text("[wall]\ndiameter_m = 1.0\nheight_m = 1.0\n")
    assert load_setup(f).body_stops is True
    f.write_text("body_stops = false\n[wall]\ndiameter_m = 1.0\nheight_m = 1.0\n")
    setup = load_setup(f)
    assert setup.body_stops is False
    sim = ClimberSim(SimConfig(video=False), setup)
    try:
        assert sim.body.contact is None
    finally:
        sim.close()
    f.write_text('body_stops = "no"\n[wall]\ndiameter_m = 1.0\nheight_m = 1.0\n')
    with pytest.raises(ValueError, match="body_stops"):
        load_setup(f)


def test_a_reported_contact_backs_the_body_away_and_the_third_gives_the_target_up():
    from sim_robot.climber.executor import TOUCHES_PER_TARGET, InspectionExecutor

    spec = WallSpec(2.0 / math.pi, 0.6, 0.1)
    ex = InspectionExecutor(rasterise(spec), 0.1, (2, 3), P_, turns_in_place=True,
                            reach=Reach(_contact(spec), LEAD))
    ex.start(0.0)
    ex.index = 5
    ex.touched(1.0, 0.12)  # driving forward into it: back away
    assert ex.moves.queue == [("recoil", -0.05)] and ex.index == 5
    ex.moves.set([("turn", 0.0)])
    ex.touched(2.0, 0.0)  # pressed against it in a turn in place: back along the heading
    assert ex.moves.queue == [("recoil", -0.05)] and ex.index == 5
    for k in range(TOUCHES_PER_TARGET - 2):
        ex.touched(3.0 + k, -0.1)  # reversing into it: forward
    assert ex.moves.queue == [("recoil", 0.05)] and ex.index == 6


LINK_SPEC = WallSpec(6.0 / math.pi, 2.4, 0.1, nozzles=(Disc(4.2, 1.2, 0.3),))  # the link bench's


def test_a_lane_change_beside_the_nozzle_steps_on_before_turning_along_the_row():
    """Above the link bench's nozzle a lane's top end (15, 45) is left along row 15
    for (15, 44). Turning in place from facing up to facing along the row swings the
    probe a body's half-length down, into row 13, and steering it back up to row 15
    turned the body about its centre with its front corner into the nozzle (the
    relay's contacts there). The body now first drives that half-length on, over the
    probe, so that the turn leaves the probe on the row; where the body does not fit
    that far on (below the top edge), or where the step would bring the turn's sweep
    nearer the nozzle (the bottom end of a lane above it), the turn is made as before."""
    reach = Reach(_contact(LINK_SPEC), LEAD)
    cells = [(14, 45), (15, 45), (15, 44), (14, 44)]
    pose = (4.55, 1.55 - LEAD, math.pi / 2)  # the probe on (15, 45), facing up
    assert body_moves(reach, cells, 2, pose, 0.1, 24, 60) == [("step", LEAD), ("turn", math.pi)]
    # after the step the turn's sweep keeps the margin (before it, 6.7 cm into it), and
    # it leaves the probe on row 15
    assert reach.sweep_depth(4.55, 1.55, math.pi / 2, math.pi) <= 1e-9
    assert reach.sweep_depth(4.55, 1.55 - LEAD, math.pi / 2, math.pi) > 0.05
    assert math.floor(reach.probe((4.55, 1.55, math.pi))[1] / 0.1) == 15
    below_top = [(21, 10), (22, 10), (22, 9)]  # no room on below the top edge
    pose = (1.05, 2.25 - LEAD, math.pi / 2)
    assert body_moves(reach, below_top, 2, pose, 0.1, 24, 60) == [("turn", math.pi)]
    # a lane's bottom end above the nozzle, facing down: a step on would bring the turn's
    # sweep nearer the nozzle (into the margin where it was clear by 4 cm): no step
    down = [(15, 45), (14, 45), (14, 44)]
    pose = (4.55, 1.45 + LEAD, -math.pi / 2)
    assert body_moves(reach, down, 2, pose, 0.1, 24, 60) == [("turn", math.pi)]


def test_the_steering_guard_looks_along_the_whole_swing_not_only_where_it_ends():
    """A pose of the relay's contacts beside the link bench's nozzle (traced, seed 2):
    facing along row 14 to the left of the nozzle's corner, the probe steered up.
    Held for a second at the steering's ω (clamped by the board to its limit), the
    body ends clear of the nozzle, but on the way its front corner sweeps through it;
    the guard now samples the whole arc and drives the probe along the heading only."""
    from sim_robot.climber.executor import InspectionExecutor

    contact = _contact(LINK_SPEC)
    reach = Reach(contact, LEAD)
    x, y, th, v, w = 4.616, 1.416, 3.073, 0.037, -1.01
    end = th + w  # (where the former guard looked, with ω unclamped)
    mid = th + w / 2
    assert contact.depth(x + v * math.cos(mid), y + v * math.sin(mid), end, reach.margin)[0] <= 0
    assert reach.arc_depth(x, y, th, v, -0.5, 1.0, 6.0) > 0
    ex = InspectionExecutor(rasterise(LINK_SPEC), 0.1, (3, 4), P_, turns_in_place=True,
                            reach=reach)
    assert ex._would_touch((x, y, th), v, w)
    assert not ex._would_touch((2.0, 1.8, th), v, w)  # in the open


def _drive(ex, body, t_max: float, going, done=lambda: False) -> tuple[int, int]:
    """The relay's loop on the body model: the executor steers on the body's pose (the
    estimate is the truth), each probe reading is filed, and a contact is reported when
    it begins and again every second it lasts (the relay's cadence), while ``going()``
    and until ``done()`` after a reading. Returns (contact reports, contacts begun)."""
    t, told, was, reports, rises = 0.0, -9.0, False, 0, 0
    while t < t_max and going():
        s = body.s
        v, w = ex.step((s.x_m, s.y_m, s.theta_rad), t, t, None)
        body.step(v, w, 0.05)
        t += 0.05
        ex.reading((body.s.x_m, body.s.y_m, body.s.theta_rad), 10.0)
        if done():
            break
        touching = bool(body.touching)
        if touching and (not was or t - told >= 1.0):  # the relay's contact reports
            told, reports, rises = t, reports + 1, rises + (not was)
            ex.touched(t, v)
        was = touching
    return reports, rises


def test_after_a_target_given_up_the_body_goes_round_to_the_next_instead_of_into_the_nozzle(
        monkeypatch):
    """A tank's run: the body pressed against a nozzle on its left side while its route
    ran down the column on its right, and it gave up that whole lane, three contacts a
    cell, steering straight at each through the nozzle. The way round along the body's
    steps is now driven once a target is given up (route_round.py). The body model
    here stops the body as the simulator's does; the estimate is the truth."""
    from sim_robot.climber import executor as executor_module
    from sim_robot.climber.executor import InspectionExecutor

    spec = LINK_SPEC  # the nozzle at (4.2, 1.2), 0.3 m across
    c = _contact(spec)
    ex = InspectionExecutor(rasterise(spec), 0.1, (0, 0), P_, turns_in_place=True,
                            reach=Reach(c, LEAD))
    col = 46  # right of the nozzle: down from row 14 to 7 and up again to row 15
    route = [(r, col) for r in range(14, 6, -1)] + [(r, col) for r in range(8, 16)]
    assert not any(ex.blocked[cell] for cell in route)
    ex.start(0.0)
    ex.cells, ex.planned, ex.index = list(route), len(route), 0
    # (the side step, side_step.py, and the recoil's turn out of a wedge, off: this guards
    # the way round; with them the body here gets free before a target is given up)
    monkeypatch.setattr(executor_module, "side_step", lambda *a: None)
    ex.moves._free = lambda pose, d: None
    body = ClimberBody(P_, ClimberState(3.81, 1.28, -0.553), 6.0, seed=1, height_m=2.4,
                       contact=c.depth)  # left of the nozzle, facing down towards its right
    _, rises = _drive(ex, body, 200.0, lambda: ex.index < len(route) + ex.ways_round * 40,
                      lambda: all(ex.covered[cell] or not np.isnan(ex.filed[cell])
                                  for cell in route))
    probed = sum(bool(ex.covered[cell] or not np.isnan(ex.filed[cell])) for cell in set(route))
    assert probed == len(set(route))  # the old executor probed none of them (42 contacts)
    assert ex.ways_round >= 1 and rises <= 10


def test_a_target_above_the_nozzle_beside_the_probe_is_reached_by_a_sideways_step():
    """A tank's run (the contact log, 27 000 s): the route ran along the row just above a
    low nozzle, the body beside the nozzle facing along the row with its probe a row low.
    Steering the probe up would swing a corner into the nozzle, so it was driven along
    the heading only, into the nozzle's top: each target beside the probe given up after
    three contacts. Now the body turns to face up, steps sideways by the lateral error
    and turns back (side_step.py). The traced pose, moved by the nozzles' offset to the
    link bench's nozzle; the body model stops the body as the simulator's does; the
    estimate is the truth."""
    from sim_robot.climber.executor import MOP_UPS, InspectionExecutor
    from sim_robot.climber.side_step import side_step

    c = _contact(LINK_SPEC)  # the nozzle's raster: x 4.0–4.4, y 1.0–1.4
    reach = Reach(c, LEAD)
    ex = InspectionExecutor(rasterise(LINK_SPEC), 0.1, (0, 0), P_, turns_in_place=True,
                            reach=reach)
    route = [(15, col) for col in range(43, 36, -1)]  # row 15 (y 1.5–1.6), right to left
    assert not any(ex.blocked[cell] for cell in route)
    start = (4.545, 1.396, 3.133)  # facing left, the probe at y 1.40 beside the nozzle's top
    # up is to the body's right; the body fits along row 15 only just (its side 2 cm over
    # the nozzle, the margin), so the step may go up to 2 cm further than the error
    lateral = 1.55 - reach.probe(start)[1]
    moves = side_step(reach, start, -lateral)
    # backing away from the nozzle first, until the turn to face up sweeps clear of it
    assert moves is not None and [m[0] for m in moves] == ["step", "turn", "step", "turn"]
    assert moves[0][1] < 0 and reach.sweep_depth(start[0] - moves[0][1], start[1], start[2],
                                                 moves[1][1]) <= 0
    assert abs(moves[1][1] - math.pi / 2) < 0.1 and moves[3][1] == start[2]
    assert lateral - 1e-9 <= moves[2][1] <= lateral + 0.02 + 1e-9
    ex.start(0.0)
    ex.cells, ex.planned, ex.index, ex.mop_ups = list(route), len(route), 0, MOP_UPS
    body = ClimberBody(P_, ClimberState(*start), 6.0, seed=1, height_m=2.4, contact=c.depth)
    _, rises = _drive(ex, body, 300.0, lambda: ex.index < len(ex.cells))
    ex.reading((0.0, -1.0, 0.0), None)  # (off the wall: the last visit is filed)
    probed = [cell for cell in route if ex.covered[cell]]
    assert probed == route  # the old executor: (15, 43) given up after 3 contacts
    assert rises <= 1


def test_a_body_wedged_between_the_stair_and_the_top_edge_turns_out_instead_of_recoiling_for_good():
    """The link bench's stair wall (traced, seed 1): at a lane's top end beside the stair
    band the body was pressed against the band behind it and the top edge ahead. Each
    contact's recoil went against the last motion, so into the other one: 5 cm back,
    5 cm on, for good (about 380 contacts in 400 s, a way round for every target given
    up). Where the recoil goes deeper on the map than the body is now, the other way or
    a small turn in place that does not is made instead: here a turn of 0.1 rad frees it."""
    from sim_robot.climber.executor import MOP_UPS, InspectionExecutor

    circ = 8.0
    spec = WallSpec(circ / math.pi, 2.4, 0.1, nozzles=(Disc(0.7 * circ, 1.2, 0.3),),
                    stairs=(Band(0.1 * circ, 0.0, 0.1 * circ + 2.4 * 17.0 / 9.6, 2.4, 0.9),))
    c = _contact(spec)
    wedged = (5.678, 2.211, 1.138)  # the traced true pose
    x, y, th = wedged
    assert c.depth(x - 0.01 * math.cos(th), y - 0.01 * math.sin(th), th)[0] > 0.004  # back
    assert c.depth(x + 0.01 * math.cos(th), y + 0.01 * math.sin(th), th)[0] > 0.004  # on
    ex = InspectionExecutor(rasterise(spec), 0.1, (0, 0), P_, turns_in_place=True,
                            reach=Reach(c, LEAD))
    route = [(23, 56), (23, 57)] + [(r, 57) for r in range(22, 14, -1)]  # down column 57
    ex.start(0.0)
    ex.cells, ex.planned, ex.index, ex.mop_ups = list(route), len(route), 1, MOP_UPS
    ex._replan = True  # (the lane change's moves planned from here)
    body = ClimberBody(P_, ClimberState(*wedged), circ, seed=1, height_m=2.4, contact=c.depth)
    reports, _ = _drive(ex, body, 120.0, lambda: ex.index < len(ex.cells))
    assert reports <= 5  # the old recoil: 451 in 120 s, still wedged
    assert ex.ways_round == 0 and body.s.y_m < 2.0  # down the column, out of the corner


def test_a_recoil_beside_a_cells_corner_is_straight_not_a_turn_the_corner_clips():
    """The stair wall through the link (8 m × 2.4 m, seed 1, a contact log): pressed
    against the band's lower side in a turn in place, the body's rear corner 6 mm on one
    side of a band cell's corner, the estimate (after its contact fix, within 8 mm) on
    the other. The wedge recoil chose a turn of −0.1 rad over the straight recoil (both
    clear on the map: the turn's end 2 mm further from the bottom edge, 0.65 m away);
    truly that turn clips the cell's corner (2.4 mm) between the samples 0.05 rad apart
    the recoil checked, the body could not begin it, and the same turn was chosen at
    every contact report for 2 800 s. Every clear end is now alike, the straight recoil
    first, and an escape turn's sweep is checked every 5 mrad."""
    from sim_robot.climber.moves import Moves

    circ = 8.0
    spec = WallSpec(circ / math.pi, 2.4, 0.1, nozzles=(Disc(0.7 * circ, 1.2, 0.3),),
                    stairs=(Band(0.1 * circ, 0.0, 0.1 * circ + 2.4 * 17.0 / 9.6, 2.4, 0.9),))
    c = _contact(spec)
    true = (3.648, 0.781, 0.081)
    # the turn the estimate chose, from the true pose: clear at the old samples, not between
    assert c.depth(true[0], true[1], true[2] - 0.05)[0] <= 0.0
    assert c.depth(true[0], true[1], true[2] - 0.1)[0] <= 0.0
    assert c.depth(true[0], true[1], true[2] - 0.03)[0] > 0.002
    for belief in ((3.649, 0.789, 0.071), (3.654, 0.789, 0.071), true):
        moves = Moves(Reach(c, LEAD), circ)
        moves.recoil(0.0, True, belief)  # pressed in a turn in place
        kind, arg = moves.queue[0]
        assert kind == "recoil", (belief, moves.queue)  # before: ("turn!", -0.029)
        # ... and it leaves the true body's footprint clear all the way
        at = [c.depth(true[0] + arg * k / 10 * math.cos(true[2]),
                      true[1] + arg * k / 10 * math.sin(true[2]), true[2])[0]
              for k in range(1, 11)]
        assert max(at) <= max(0.0, c.depth(*true)[0]) + 1e-9, (belief, arg, at)


def test_a_recoil_from_a_contact_the_estimate_does_not_touch_backs_away():
    """The tank through the link (the contact logs, and a replay of a lane's bottom end
    above the stair band with the belief 3 cm off in x): the body touched the band while
    its estimate's footprint was clear of it, and each recoil went on into the band
    instead of back, 30 contact reports in 30 s and every target given up. The wedge
    recoil (Moves._free) took the depth of a clear footprint for a distance: backing up
    from the lower half of the wall "went deeper" towards the top edge metres away. A
    footprint clear on the map is now at depth 0, and the recoil goes against the last
    motion unless it would bring the footprint into something."""
    from sim_robot.climber.moves import Moves

    circ = 8.0
    spec = WallSpec(circ / math.pi, 2.4, 0.1, nozzles=(Disc(0.7 * circ, 1.2, 0.3),),
                    stairs=(Band(0.1 * circ, 0.0, 0.1 * circ + 2.4 * 17.0 / 9.6, 2.4, 0.9),))
    c = _contact(spec)
    # above the band at a lane's bottom end, as the estimate puts it, facing down (the upper
    # half of the wall: backing up nears the top edge); and low on the wall facing up
    for pose in ((2.92, 1.994, -math.pi / 2), (1.5, 2.0, -math.pi / 2), (6.0, 0.5, math.pi / 2)):
        assert c.depth(*pose)[0] < -0.1  # clear on the map
        moves = Moves(Reach(c, LEAD), circ)
        moves.recoil(0.08, False, pose)  # driving forward when the board reported it
        assert moves.queue == [("recoil", -0.05)]  # before: ("recoil", +0.05), on into it
        moves.recoil(-0.08, False, pose)
        assert moves.queue == [("recoil", 0.05)]
