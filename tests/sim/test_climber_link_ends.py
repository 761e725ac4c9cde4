"""Sure lane ends in the relay's executor (sim_robot/climber/link_ends.py): the
runs' ends judged by the estimate's height and its covariance, as inspect_wall
judges them (sim_robot/climber/sure_ends.py), one control period at a time."""

from __future__ import annotations

import math

import numpy as np

from app.comm.wall_protocol import CoverageState
from app.core.planner.coverage.wall import Band, Disc, WallSpec, rasterise
from sim_robot.climber.executor import InspectionExecutor
from sim_robot.climber.kinematics import ClimberParams
from sim_robot.climber.sure_ends import SureEnds

D = 0.1
CAMERA_M = 0.08  # the camera sees a seam or the shell's edge this near its image centre
SLIP = 0.03  # the belief runs this share of each climb above the truth ...
SIGMA_PER_M = 0.03  # ... and the estimate's σ_y grows by this per metre since a height fix


def _fly(ex: InspectionExecutor, spec: WallSpec, start: tuple[int, int],
         dt: float = 0.05, max_steps: int = 200_000) -> np.ndarray:
    """An ideal body driven by the executor on a belief that slips: climbing, the
    belief rises SLIP of the way above the truth, and its σ_y grows with the way
    driven since the last height fix; the camera (at the true probe point) fixes
    the belief's height on the shell's edges and the crossable girth seams within
    CAMERA_M, and the executor is told of the edges' fixes as the relay tells it.
    Returns where the probe truly passed (the simulator's trace)."""
    lead, height = ex.lead, spec.height_m
    girths = [b.y0_m for b in spec.seams if b.y0_m == b.y1_m and b.crossable]
    x, y, th = (start[1] + 0.5) * D - lead, (start[0] + 0.5) * D, 0.0
    err, sigma, t = 0.0, 0.005, 0.0
    probed = np.zeros(ex.blocked.shape, bool)
    ex.start(t)
    for _ in range(max_steps):
        if ex.state != CoverageState.RUNNING:
            break
        cov = np.diag([1e-4, sigma**2, 1e-6])
        belief = (x, y + err, th)
        ex.reading(belief, 9.0)
        v, w = ex.step(belief, t, t, cov)
        mid = th + w * dt / 2
        dx, dy = v * math.cos(mid) * dt, v * math.sin(mid) * dt
        x, y = (x + dx) % ex.circ_m, y + dy
        th = (th + w * dt + math.pi) % (2 * math.pi) - math.pi
        err += SLIP * max(dy, 0.0)
        sigma += SIGMA_PER_M * math.hypot(dx, dy)
        py = y + lead * math.sin(th)
        row = math.floor(py / D)
        if 0 <= row < probed.shape[0]:
            probed[row, math.floor(((x + lead * math.cos(th)) % ex.circ_m) / D)] = True
        for line in (0.0, height, *girths):
            if abs(py - line) <= CAMERA_M:  # a fix: the belief's height is the truth's
                err, sigma = 0.0, 0.005
                if line in (0.0, height):
                    ex.edge_fixed(line)
        t += dt
    assert ex.state == CoverageState.DONE
    return probed


def test_the_executor_seeks_the_edge_for_an_unsure_lane_end_and_probes_the_top_row():
    """A wall 1.2 m round and 3.6 m high with no girth seam: the up lanes climb
    3.5 m with no height landmark but the top edge, and the belief reaches the top
    row 10 cm too high, where the camera does not see the edge. Without the
    judgement of the ends the executor believes the top row read and truly misses
    it; with it the estimate's σ_y says the top end is not sure, the executor seeks
    the edge, comes back on the corrected belief, and every cell is truly probed."""
    spec = WallSpec(1.2 / math.pi, 3.6, D)
    blocked = rasterise(spec)
    before = InspectionExecutor(blocked, D, (0, 0), ClimberParams(), turns_in_place=True)
    probed = _fly(before, spec, (0, 0))
    assert before.covered.sum() == before.reachable  # believed read in full ...
    missed = ~probed & ~blocked
    assert missed[-1].sum() >= 5 and missed[:-1].sum() == 0  # ... yet its top row truly not
    ex = InspectionExecutor(blocked, D, (0, 0), ClimberParams(), turns_in_place=True,
                            sure_ends=True, seams=spec.seams)
    probed = _fly(ex, spec, (0, 0))
    ends = ex.sure.ends
    assert ends.seeks >= 5 and ex.seek.found >= ends.seeks and ends.unsure == set()
    assert (probed | blocked).all()


def test_an_unsure_end_far_from_the_edge_drives_across_a_girth_seam_and_back():
    """The same wall with a girth seam at 1.2 m and a nozzle just above it: the
    lanes above the nozzle come down from the top edge and end on the nozzle 2 m
    from the nearest edge, σ_y grown by the way down. The executor inserts a route
    round the nozzle to the row just below the seam and back into its own route,
    the camera fixes the height crossing the seam, and back on the end the estimate
    judges it sure; the lane change comes after the route."""
    spec = WallSpec(1.2 / math.pi, 3.6, D, nozzles=(Disc(0.6, 1.5, 0.3),),
                    seams=(Band(0.0, 1.2, 1.2, 1.2, 0.01, crossable=True),))
    blocked = rasterise(spec)
    ex = InspectionExecutor(blocked, D, (0, 0), ClimberParams(), turns_in_place=True,
                            sure_ends=True, seams=spec.seams)
    planned = list(ex.cells)
    probed = _fly(ex, spec, (0, 0))
    ends = ex.sure.ends
    assert ends.fixes >= 2 and ends.unsure == set()
    assert (probed | blocked).all()
    # each route leaves from an end above the nozzle, crosses the seam (row 11 is
    # the row below it), and comes back to the end before the plan goes on
    near_edge = SureEnds(ex.rows, D).edge_side
    routes, k = [], 0
    for cell in planned:  # the plan's cells in order; a route is what lies between two
        start = k
        while ex.cells[k] != cell:
            k += 1
        if k > start:
            routes.append((ex.cells[start - 1], ex.cells[start:k]))
        k += 1
    assert len(routes) == ends.fixes and k == ex.planned
    for end, route in routes:
        assert not near_edge(end[0]) and end[0] > 12 and route[-1] == end
        assert min(r for r, _ in route) == 11


def test_a_route_to_a_height_landmark_keeps_the_body_off_the_nozzle():
    """Under a nozzle the fewest-step route from an unsure end to the girth seam runs
    along the row beside the nozzle, where the body facing along the row has its side
    over it; with the body's reach the route takes only steps the body fits along
    (reversing down the column is allowed) and goes to the bottom row instead."""
    from sim_robot.climber.contact import WallContact
    from sim_robot.climber.link_ends import body_steps
    from sim_robot.climber.reach import Reach

    p = ClimberParams()
    spec = WallSpec(6.0 / math.pi, 2.4, D, nozzles=(Disc(4.2, 1.2, 0.3),),
                    seams=(Band(0.0, 1.2, 6.0, 1.2, 0.01, crossable=True),))
    reach = Reach(WallContact(spec, rasterise(spec), p.length_m, p.width_m), p.length_m / 2)
    blocked = reach.body_blocked()
    end = (9, 41)  # the top of a short lane under the nozzle
    plain = SureEnds(blocked.shape[0], D, blocked=blocked, seams=spec.seams)
    there, _ = plain.fix_route(end)
    assert there[0] == (9, 40) and there[-1][0] == 12  # along the row, up beside it
    steps = body_steps(reach, D, blocked.shape[1])
    assert not steps(end, (9, 40))
    body = SureEnds(blocked.shape[0], D, blocked=blocked, seams=spec.seams, step_ok=steps)
    there, back = body.fix_route(end)
    assert there == [(r, 41) for r in range(8, -1, -1)] and back[-1] == end
    assert all(steps(a, b) for a, b in zip([end, *there], there, strict=False))


def test_the_mop_up_with_the_body_takes_only_steps_the_body_fits_along():
    """The plain mop-up (fewest steps) runs along the row beside the link bench's nozzle,
    where the body's side is over it; with the body's steps every leg is one the body fits
    along, and every missed cell it can reach so is visited."""
    from app.core.planner.coverage import mop_up_route
    from sim_robot.climber.contact import WallContact
    from sim_robot.climber.link_ends import body_mop_up, body_steps
    from sim_robot.climber.reach import Reach

    p = ClimberParams()
    spec = WallSpec(6.0 / math.pi, 2.4, D, nozzles=(Disc(4.2, 1.2, 0.3),))
    reach = Reach(WallContact(spec, rasterise(spec), p.length_m, p.width_m), p.length_m / 2)
    blocked = reach.body_blocked()
    steps = body_steps(reach, D, blocked.shape[1])
    missed = np.zeros_like(blocked)
    for cell in ((9, 40), (9, 45), (14, 44), (2, 38)):  # under, beside and off the nozzle
        missed[cell] = not blocked[cell]
    start = (0, 30)
    plain = mop_up_route(blocked, start, missed, wrap=True)
    legs = list(zip([start, *plain], plain, strict=False))
    assert not all(steps(a, b) for a, b in legs if abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1)
    route = body_mop_up(blocked, start, missed, steps)
    assert all(steps(a, b) for a, b in zip([start, *route], route, strict=False))
    assert not any(blocked[c] for c in route)
    reachable = {tuple(c) for c in np.argwhere(missed)}
    assert reachable <= set(route)


def test_cells_put_into_the_route_before_a_pending_end_move_its_indices_on():
    """A way round (or any cells) put into the executor's route before the indices the
    sure ends keep: those indices move on with their cells; indices before stay."""
    from sim_robot.climber.edge_seek import EdgeSeek
    from sim_robot.climber.link_ends import LinkEnds

    ends = LinkEnds(SureEnds(10, 0.1), EdgeSeek(10, 1.0), 0.144)
    ends.start, ends.end, ends.again, ends.far = 20, 30, 29, 25
    ends.shift(22, 4)  # inside the route: its end and the indices after move on
    assert (ends.start, ends.end, ends.again, ends.far) == (20, 34, 33, 29)
    ends.shift(10, 3)  # before it all
    assert (ends.start, ends.end, ends.again, ends.far) == (23, 37, 36, 32)
    ends.shift(40, 5)  # after it all: nothing moves
    assert (ends.start, ends.end, ends.again, ends.far) == (23, 37, 36, 32)
    ends.reset()
    ends.shift(0, 2)  # nothing pending stays nothing pending
    assert (ends.start, ends.end, ends.again, ends.far) == (0, 0, -1, -1)


def _fly_sigma(ex: InspectionExecutor, spec: WallSpec, sweep_sigma: float, mop_sigma: float,
               dt: float = 0.05, max_steps: int = 200_000) -> None:
    """An ideal body whose belief is the truth, driven by the executor, with the
    estimate's σ_y ``sweep_sigma`` through the sweep and ``mop_sigma`` once the
    mop-up has begun; the camera sees the shell's edges within CAMERA_M."""
    lead, height = ex.lead, spec.height_m
    x, y, th, t = 0.5 * D - lead, 0.5 * D, 0.0, 0.0
    ex.start(t)
    for _ in range(max_steps):
        if ex.state != CoverageState.RUNNING:
            break
        sigma = sweep_sigma if ex.mop_ups == 0 else mop_sigma
        cov = np.diag([1e-4, sigma**2, 1e-6])
        ex.reading((x, y, th), 9.0)
        v, w = ex.step((x, y, th), t, t, cov)
        mid = th + w * dt / 2
        x, y = (x + v * math.cos(mid) * dt) % ex.circ_m, y + v * math.sin(mid) * dt
        th = (th + w * dt + math.pi) % (2 * math.pi) - math.pi
        py = y + lead * math.sin(th)
        for line in (0.0, height):
            if abs(py - line) <= CAMERA_M:
                ex.edge_fixed(line)
        t += dt
    assert ex.state == CoverageState.DONE


def test_an_end_never_judged_sure_is_taken_back_and_driven_to_again():
    """A wall 0.4 m round and 0.8 m high, every lane's end on an edge row. With the
    estimate's σ_y above half a cell through the sweep no end can be judged sure,
    not even after its edge seek: the record must not claim those cells (it did: they
    stayed covered, listed as never judged sure). Each is taken back before the mop-up,
    which drives to it again; judged sure there (σ_y small by then) it is filed and
    kept, else it is left out of the record and reported."""
    spec = WallSpec(0.4 / math.pi, 0.8, D)
    blocked = rasterise(spec)
    ex = InspectionExecutor(blocked, D, (0, 0), ClimberParams(), turns_in_place=True,
                            sure_ends=True, seams=spec.seams)
    _fly_sigma(ex, spec, 0.06, 0.06)
    ends = ex.sure.ends
    assert len(ends.unsure) >= 4  # the lanes' ends, none judged sure
    assert not any(ex.covered[c] for c in ends.unsure)  # not claimed ...
    assert set(ends.unsure) <= set(ex.cells[ex.planned:])  # ... and driven to again
    assert ex.covered.sum() == ex.reachable - len(ends.unsure)
    ex = InspectionExecutor(blocked, D, (0, 0), ClimberParams(), turns_in_place=True,
                            sure_ends=True, seams=spec.seams)
    _fly_sigma(ex, spec, 0.06, 0.005)
    assert ex.sure.taken_back >= 4 and ex.sure.ends.unsure == set()
    assert ex.covered.sum() == ex.reachable
