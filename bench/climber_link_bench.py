"""The wall climber through the real link: sim-robot's climber in this process
(ClimberSim: MCU model on a pty, relay, TCP on port 0), a plain-socket desk
that signs ``start_inspection`` and keeps what arrives, until the robot reports
the inspection done (or the time runs out). Prints what the desk saw —
coverage, repetition, readings, the thinnest reading and where — beside the
simulator's truth (thinnest true cell), and the CPU time of this process.

    PYTHONPATH=$PWD python bench/climber_link_bench.py [--scale 40] [--wall 3x1.2|tank] [--stair]
        [--x-fix-lanes N] [--no-turns-in-place] [--seam-camera pixels] [--no-sure-ends]
        [--no-contact-fixes] [--manhole] [--first-fix-whole] [--filing-log FILE]
        [--heading-log FILE]

``--x-fix-lanes N``: the relay's detours to a vertical seam after N lanes without an x fix
(``sim_robot/climber/seam_detour.py``; 0 turns them off). ``--no-turns-in-place``: the
relay's executor steers the probe through the lane changes instead of turning in place
(``sim_robot/climber/turns.py``). ``--no-sure-ends``: the relay's executor does not judge
the runs' ends by the estimate's height and its covariance (``sim_robot/climber/
link_ends.py``; on by default where the detours are). ``--wall tank``: the simulator's own
24 m × 9.6 m tank (its stair, manholes and nozzles); ``--stair``: a stair band across a
smaller wall at the tank's slope. ``--no-contact-fixes``: a contact the board reports is
not taken as a position fix (``app/core/localisation/contact_fix.py``). ``--manhole``: a
smaller wall gets the tank's manhole near its bottom edge (0.6 m across, its centre 0.9 m
up, half way round). ``--first-fix-whole``: the estimate's first x fix takes back every
cell filed before it (``sim_robot/climber/sure_lanes.py``, an option, off).
``--filing-log FILE``: what filed each cell, beside the truth
(``bench/_climber_filing_trace.py``). ``--heading-log FILE``: the belief's heading and
σθ, the gravity heading and the learnt and true biases, beside the true heading
(``bench/_climber_heading_trace.py``). A long run prints its
progress each minute of wall time.
"""

from __future__ import annotations

import argparse
import json
import math
import socket
import sys
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from app.comm import auth  # noqa: E402
from app.comm import protocol as P  # noqa: E402
from app.comm.wall_protocol import CoverageState  # noqa: E402
from app.core.desk.wall import WallModel  # noqa: E402
from app.core.planner.coverage.wall import Band, Disc, WallSpec, plate_seams  # noqa: E402
from bench._climber_filing_trace import trace_filing  # noqa: E402
from bench._climber_heading_trace import trace_heading  # noqa: E402
from sim_robot.climber.seam_detour import X_FIX_LANES  # noqa: E402
from sim_robot.climber.sim import ClimberSetup, ClimberSim  # noqa: E402
from sim_robot.climber.wall_world import Patch  # noqa: E402
from sim_robot.config import SimConfig  # noqa: E402


def setup(size: str, stair: bool = False, manhole: bool = False) -> ClimberSetup:
    if size == "tank":  # sim-robot --robot climber's own wall: the whole 24 m × 9.6 m tank
        return ClimberSetup()
    circ, height = (float(v) for v in size.split("x"))
    d = circ / math.pi
    # a stair band climbing the wall at the tank's slope (9.6 m in 17 m), 0.9 m wide
    stairs = (Band(0.1 * circ, 0.0, 0.1 * circ + height * 17.0 / 9.6, height, 0.9),) \
        if stair else ()
    # the tank's manholes: 0.6 m across, their centres 0.9 m above the bottom edge
    manholes = (Disc(0.5 * circ, 0.9, 0.6),) if manhole else ()
    spec = WallSpec(d, height, 0.1, nozzles=(Disc(0.7 * circ, 0.5 * height, 0.3),),
                    manholes=manholes, stairs=stairs,
                    seams=plate_seams(d, height, course_m=height / 2, plates=2))
    patches = (Patch(0.35 * circ, 0.7 * height, 0.15, 3.0), Patch(0.85 * circ, 0.3 * height,
                                                                  0.2, 1.5))
    return ClimberSetup(spec, 10.0, 8.0, None, patches, f"bench-{size}")


def trace_contacts(sim: ClimberSim, path: str) -> None:
    """Every contact the executor is told of, as a line of JSON in ``path`` (the true
    pose is the simulator's, for this trace only)."""
    ins = sim.relay.inspection
    told = ins.touched
    out = open(path, "w", encoding="utf-8")  # noqa: SIM115 (open for the run's length)

    def touched(t: float, last_v: float) -> None:
        o, b = sim.relay.odom, sim.body.s
        i = ins.index
        out.write(json.dumps({
            "t": round(t, 2), "index": i, "target": list(ins.cells[i]) if i < len(ins.cells)
            else None, "touches": ins._touches if ins._touched_at == i else 0,
            "moves": [[k, round(v, 3)] for k, v in ins.moves.queue[:3]],
            "last_v": round(last_v, 3),
            "believed": [round(o.x % sim.wall.circ_m, 3), round(o.y, 3), round(o.theta, 3)],
            "true": [round(b.x_m, 3), round(b.y_m, 3), round(b.theta_rad, 3)]}) + "\n")
        out.flush()
        told(t, last_v)

    ins.touched = touched
    trace_moves(sim, out)


MOVE_LOGGED_M = 0.03  # a fix that moves the belief at least this far is logged


def trace_moves(sim: ClimberSim, out) -> None:
    """Every seam, rim or contact fix that moved the belief by MOVE_LOGGED_M or more,
    or came with a reset of the filter, as a line of JSON in ``out``: its kind, the
    belief and its σ in x and y before and after, and the true pose (the simulator's,
    for this trace only)."""
    relay, odom = sim.relay, sim.relay.odom

    def logged(kind: str, call):
        def wrapped(*args, **kw):
            ekf = odom.ekf
            before, resets = ekf.pose, sum(ekf.resets.values())
            sd_before = [round(math.sqrt(max(0.0, ekf.covariance[k, k])), 4) for k in (0, 1)]
            got = call(*args, **kw)
            after = ekf.pose
            moved = math.hypot(after[0] - before[0], after[1] - before[1])
            reset = sum(ekf.resets.values()) != resets
            if moved >= MOVE_LOGGED_M or reset:
                b = sim.body.s
                out.write(json.dumps({
                    "t": round(sim.relay.sim_time(), 2), "fix": kind, "reset": reset,
                    "args": [round(v, 3) if isinstance(v, float) else v for v in args
                             if isinstance(v, (float, int, bool))],
                    "before": [round(before[0] % sim.wall.circ_m, 3), round(before[1], 3),
                               round(before[2], 3)],
                    "after": [round(after[0] % sim.wall.circ_m, 3), round(after[1], 3),
                              round(after[2], 3)],
                    "true": [round(b.x_m, 3), round(b.y_m, 3), round(b.theta_rad, 3)],
                    "sd_before": sd_before,
                    "sd_after": [round(math.sqrt(max(0.0, ekf.covariance[k, k])), 4)
                                 for k in (0, 1)]}) + "\n")
                out.flush()
            return got
        return wrapped

    odom.rim_seen = logged("rim", odom.rim_seen)
    odom.seam_seen = logged("seam", odom.seam_seen)
    relay._contact_fix = logged("contact", relay._contact_fix)


def trace_fixes(sim: ClimberSim) -> dict[str, int]:
    """What each x fix did to the robot's record, judged against the simulator's truth
    (this bench only; the robot never reads it): the cells it took back and, of them,
    those the probe had in fact read by then; the cells it filed anew; and the cells the
    record filed as it went, with those the probe had not truly read by then."""
    ins = sim.relay.inspection
    fixed = ins.x_fixed
    got = {"taken_back": 0, "taken_back_probed": 0, "filed_anew": 0, "filed_anew_probed": 0}

    def x_fixed(*args, **kw) -> None:
        before = ins.covered.copy()
        fixed(*args, **kw)
        probed = sim.model.probed
        back, anew = before & ~ins.covered, ins.covered & ~before
        got["taken_back"] += int(back.sum())
        got["taken_back_probed"] += int((back & probed).sum())
        got["filed_anew"] += int(anew.sum())
        got["filed_anew_probed"] += int((anew & probed).sum())

    ins.x_fixed = x_fixed
    got["filed"] = got["filed_unprobed"] = 0
    filed = ins.lanes.filed

    def lane_filed(cell, *args) -> None:  # every reading the record files as it goes
        got["filed"] += 1
        got["filed_unprobed"] += int(not sim.model.probed[cell])
        filed(cell, *args)

    ins.lanes.filed = lane_filed
    return got


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=float, default=40.0, help="sim time scale")
    ap.add_argument("--wall", default="3x1.2",
                    help="circumference x height, m, or 'tank': the simulator's default tank "
                         "(24 m × 9.6 m, its stair, manholes, nozzles, random thin patches)")
    ap.add_argument("--stair", action="store_true",
                    help="a stair band across the wall at the tank's slope (not with 'tank', "
                         "which has its own)")
    ap.add_argument("--manhole", action="store_true",
                    help="the tank's manhole near the bottom edge of a smaller wall (0.6 m "
                         "across, its centre 0.9 m up, half way round)")
    ap.add_argument("--seam-camera", choices=("sightings", "pixels"), default="sightings",
                    help="pixels: the relay finds the seams in drawn camera frames")
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=120.0, help="wall seconds")
    ap.add_argument("--map", action="store_true", help="print where cells were missed")
    ap.add_argument("--x-fix-lanes", type=int, default=X_FIX_LANES, metavar="N",
                    help="lanes without an x fix before a detour to a vertical seam "
                         f"(0: none; default {X_FIX_LANES}, the relay's)")
    ap.add_argument("--detour-any-row", action="store_true",
                    help="a detour goes to the nearest cell any vertical seam crosses, on any "
                         "row, by the body's steps (SeamDetour.any_row, off by default)")
    ap.add_argument("--turns-in-place", action=argparse.BooleanOptionalAction, default=True,
                    help="turn in place at the lanes' ends and along the detours (the relay's "
                         "default)")
    ap.add_argument("--sure-ends", action=argparse.BooleanOptionalAction, default=None,
                    help="judge the runs' ends by the estimate's own height uncertainty "
                         "(default: on where the detours are, the relay's)")
    ap.add_argument("--contact-fixes", action=argparse.BooleanOptionalAction, default=True,
                    help="a contact the board reports taken as a position fix on the map "
                         "(the relay's default; app/core/localisation/contact_fix.py)")
    ap.add_argument("--contact-log", metavar="FILE",
                    help="write a line of JSON for every contact the executor is told of: "
                         "the route's index and target, the moves at hand, the believed and "
                         "the true pose (to trace runs of contacts); and for every seam, rim "
                         "or contact fix that moved the belief 3 cm or more, or reset the "
                         "filter, its kind, the belief before and after and the true pose")
    ap.add_argument("--first-fix-whole", action="store_true",
                    help="the estimate's first x fix takes back every cell filed before it "
                         "(a lean of the first lanes that fix does not show; "
                         "sim_robot/climber/sure_lanes.py)")
    ap.add_argument("--filing-log", metavar="FILE",
                    help="write a line of JSON for every cell the record files, every x fix "
                         "and every fix that moved the believed x, beside the true probe; "
                         "print the events of each cell believed covered and never truly "
                         "probed at the end (bench/_climber_filing_trace.py)")
    ap.add_argument("--heading-log", metavar="FILE",
                    help="write a line of JSON about every half second: the belief's heading "
                         "and σθ, the gravity heading, the learnt and the true accelerometer "
                         "bias, beside the true heading (bench/_climber_heading_trace.py)")
    a = ap.parse_args(argv)
    if a.detour_any_row:
        from sim_robot.climber.seam_detour import SeamDetour

        SeamDetour.any_row = True
    cpu0 = time.process_time()
    sim = ClimberSim(SimConfig(video=False, seed=a.seed, time_scale=a.scale),
                     setup(a.wall, a.stair, a.manhole), seam_camera=a.seam_camera)
    sim.relay.x_fix_lanes = a.x_fix_lanes
    sim.relay.turns_in_place = a.turns_in_place
    sim.relay.sure_ends = a.sure_ends
    sim.relay.contact_fixes = a.contact_fixes
    sim.relay.first_fix_whole = a.first_fix_whole
    sim.start()
    model = WallModel()
    lock = threading.Lock()
    sock = socket.create_connection(sim.address, timeout=5)
    enc = P.FrameEncoder(signer=auth.CommandSigner(auth.load_or_create_key()[0], "bench"))
    dec = P.FrameDecoder()
    stop = threading.Event()
    refused: dict[str, int] = {}  # wall messages the model refused, by reason
    closed: list[str] = []  # why the desk's stream ended, if it did (its figures are then old)
    acks: dict[int, P.CommandAck] = {}  # the relay's answers, by command seq
    send_lock = threading.Lock()

    def read():
        while not stop.is_set():
            try:
                data = sock.recv(65536)
            except TimeoutError:  # a quiet spell (the tank's plan takes longer than that)
                continue
            except OSError as e:
                closed.append(f"{e} at {time.monotonic() - t0:.0f} s wall")
                return
            if not data:
                closed.append(f"closed by the relay at {time.monotonic() - t0:.0f} s wall")
                return
            for fr in dec.feed(data):
                if fr.msg_type == P.MsgType.COMMAND_ACK:
                    acks[fr.message.cmd_seq] = fr.message
                if fr.msg_type in P.WALL_TYPES:
                    with lock:
                        try:
                            model.ingest(fr.message)
                        except ValueError as e:  # counted, as the desk pipeline does
                            refused[str(e)] = refused.get(str(e), 0) + 1

    def send(msg) -> int:
        """Encode and send as one step (two threads send); returns the frame's seq."""
        with send_lock:
            seq = enc.seq
            sock.sendall(enc.encode(msg))
        return seq

    def beat():
        while not stop.wait(0.25):
            send(P.Heartbeat(P.Heartbeat.ROLE_DESK))

    t0 = time.monotonic()
    threading.Thread(target=read, daemon=True).start()
    threading.Thread(target=beat, daemon=True).start()
    while not model.ready and time.monotonic() - t0 < 30:
        time.sleep(0.05)
    t_start = sim.clock.now()
    for _ in range(5):  # a relay busy past the command's freshness refuses it: again
        seq = send(P.Command("start_inspection", {}))
        t_sent = time.monotonic()
        while seq not in acks and time.monotonic() - t_sent < 30:
            time.sleep(0.05)
        ack = acks.get(seq)
        if ack is not None and ack.ok:
            break
        print(f"start_inspection {'refused: ' + ack.reason if ack else 'not answered in 30 s'}; "
              "sending it again", file=sys.stderr, flush=True)
    said = time.monotonic()
    fix_trace = trace_fixes(sim)
    filing_report = trace_filing(sim, a.filing_log) if a.filing_log else None
    if a.heading_log:
        trace_heading(sim, a.heading_log)
    if a.contact_log and sim.relay.inspection is not None:
        trace_contacts(sim, a.contact_log)
    while time.monotonic() - t0 < a.timeout:
        time.sleep(0.02)
        with lock:
            if model.progress and model.progress.state == CoverageState.DONE:
                break
            if time.monotonic() - said > 60 and model.progress:  # a long run says how it goes
                said = time.monotonic()
                ins, o, b = sim.relay.inspection, sim.relay.odom, sim.body.s
                desk = f"{model.summary()['coverage_pct']:.2f} % covered (as the robot " \
                    "believes)" if not closed else f"desk stream ended ({closed[0]}), the " \
                    f"robot's own belief {100 * ins.covered.sum() / ins.reachable:.2f} % covered"
                print(f"  {said - t0:.0f} s wall, {sim.clock.now() - t_start:.0f} s sim: "
                      f"{desk}; route cell {ins.index} of {len(ins.cells)}, moves "
                      f"{ins.moves.queue[:2]}; believed ({o.x:.2f}, {o.y:.2f}, "
                      f"{math.degrees(o.theta):.0f}°), true ({b.x_m:.2f}, {b.y_m:.2f}, "
                      f"{math.degrees(b.theta_rad):.0f}°); truly probed "
                      f"{int(sim.model.probed.sum())}; taken back {ins.lanes.unsure}; gravity "
                      f"refusals {ins.lanes.refusals} (runs counted {ins.lanes.counted}, mended "
                      f"{ins.lanes.mended}); contacts {len(sim.body.contacts)}; sim time "
                      f"held {sim.clock.held_s:.0f} s",
                      file=sys.stderr, flush=True)
    wall_s = time.monotonic() - t0
    sim_s = sim.clock.now()
    inspect_s = sim_s - t_start  # the inspection's own sim time (the clock runs from set-up)
    time.sleep(0.5)  # the last probe batch
    stop.set()
    ended_early = list(closed)  # (the relay closes the stream when the sim is closed below)
    with lock:
        model.new_thin_spots()  # what the desk pipeline alarms on
        s = model.summary()
    truth_mm, (tr, tc) = sim.wall.thinnest()
    body = sim.body.s
    lead = sim.body.p.length_m / 2
    px, py = body.x_m + lead * math.cos(body.theta_rad), body.y_m + lead * math.sin(body.theta_rad)
    o = sim.relay.odom
    bx, by = (o.x + lead * math.cos(o.theta)) % sim.wall.circ_m, o.y + lead * math.sin(o.theta)
    err = math.hypot(sim.wall.wrap_dx(bx - px), by - py)
    probed = sim.model.probed.copy()  # the simulator's trace (truth), never sent
    believed = sim.relay.inspection.covered.copy()
    det = sim.relay.inspection.detour
    detours = f"{det.driven} detours to a vertical seam ({det.cells} cells)" if det else \
        "no detours to a vertical seam"
    fixes = {k: sim.relay.counters[k] for k in ("seam_fixes", "rim_fixes", "contact_fixes")}
    turns = sim.relay.inspection.turns
    seek = sim.relay.inspection.seek
    sure = sim.relay.inspection.sure
    turn_visits = sim.relay.inspection.turn_visits
    ways_round = getattr(sim.relay.inspection, "ways_round", 0)
    mop_fixes = getattr(sim.relay.inspection, "mop_fixes", {})
    lanes = sim.relay.inspection.lanes
    contacts = list(sim.body.contacts)  # the simulator's record (truth)
    ekf = o.ekf
    head_err = (o.theta - body.theta_rad + math.pi) % (2 * math.pi) - math.pi
    sim.close()
    sock.close()
    rows, cols = sim.wall.blocked.shape
    print(f"wall {a.wall} m ({rows} × {cols} cells, {model.progress.reachable} reachable), "
          f"time scale {a.scale:g}, seed {a.seed}")
    print(f"state {s['state']} after {wall_s:.1f} s wall / {sim_s:.0f} s sim "
          f"({inspect_s:.0f} s sim from the start command; sim time held "
          f"{sim.clock.held_s:.0f} s for the robot's control loops); "
          f"coverage {s['coverage_pct']:.2f} %, repetition {s['repetition_pct']:.2f} % "
          f"(as the robot believes); readings placed {s['readings']}, unplaced {s['unplaced']}")
    th = s["thinnest"][0] if s["thinnest"] else None
    if th:
        off = max(abs(th["row"] - tr), abs(th["col"] - tc))
        print(f"thinnest reading {th['thickness_mm']:.2f} mm at cell ({th['row']}, {th['col']}); "
              f"true thinnest {truth_mm:.2f} mm at ({tr}, {tc}): {off} cell(s) off")
    print(f"thin-wall alarms (limit 8 mm): {len(model.alarmed)} at "
          + ", ".join(f"({p.row}, {p.col})" for p in model.alarmed))
    if refused:
        print(f"wall messages refused by the desk's model: {refused}")
    if ended_early:
        print(f"the desk's stream ended early ({ended_early[0]}): the desk figures above are "
              "from before then")
    print(f"{detours}; x fixes: {fixes['seam_fixes']} seams (all), {fixes['rim_fixes']} rims, "
          f"{fixes['contact_fixes']} contacts; "
          f"{turns} turns in place (their swing made {turn_visits} of the visits); "
          f"{ways_round} ways round after a target given up for contacts; "
          f"mop-up fixes before a target (routes by landmark): {mop_fixes}")
    print(f"edge seeks: {seek.seeks} started, {seek.found} found the edge, "
          f"{seek.given_up} gave up")
    if sure is None:
        print("sure ends off")
    else:
        e = sure.ends
        print(f"sure ends: {e.seeks} edge seeks and {e.fixes} routes to a girth seam or an "
              f"edge row ({e.fix_cells} cells) for unsure ends; ends never judged sure: "
              f"{len(e.unsure)} {sorted(e.unsure)[:20]}; their filings taken back from the "
              f"record {sure.taken_back}, covered at the end "
              f"{sum(bool(sim.relay.inspection.covered[c]) for c in e.unsure)}")
    print(f"sure lanes: {lanes.fixes} x fixes found {lanes.unsure} cells filed before them not "
          f"surely in their column (driven to again); largest correction of the believed x "
          f"{lanes.largest_m:.3f} m; gravity headings refused {lanes.refusals} (runs of them "
          f"counted {lanes.counted}, mended by the filter's reset and not counted "
          f"{lanes.mended}); kept on the corrected track {getattr(lanes, 'kept', 0)}, filed "
          f"anew there {getattr(sim.relay.inspection, 'anew', 0)}; mop-ups planned again "
          f"{getattr(sim.relay.inspection, 'mop_replans', 0)}")
    kinds: dict[str, int] = {}
    for c in contacts:
        kinds[c["what"]] = kinds.get(c["what"], 0) + 1
    print(f"contacts (the body stopped at an edge or obstacle, simulator's record): "
          f"{len(contacts)}" + (f" {kinds}" if kinds else ""))
    print(f"the wall EKF refused {ekf.rejected['gravity']} gravity headings "
          f"({ekf.resets['gravity']} ended by a reset: the belief's heading opened to the "
          f"measurement), {ekf.rejected['seam']} seam and {ekf.rejected['rim']} rim sightings "
          f"({ekf.resets['seam']} and {ekf.resets['rim']} resets); its covariance was "
          f"found indefinite and mended {getattr(ekf, 'repairs', 0)} times")
    print(f"believed − true heading at the end: {1000 * head_err:.1f} mrad")
    print(f"believed − true probe position at the end: {err:.3f} m; "
          f"CPU {time.process_time() - cpu0:.1f} s (this process: robot and desk)")
    planned = np.zeros_like(probed)
    for cell in set(sim.relay.inspection.cells):
        planned[cell] = True
    missed = planned & ~probed
    print(f"truly probed (simulator's trace): {int((probed & planned).sum())} of "
          f"{int(planned.sum())} reachable cells ({int(missed.sum())} missed); believed "
          f"covered {int(believed.sum())}, of them not truly probed "
          f"{int((believed & ~probed).sum())}")
    print(f"x fixes (against the truth): took back {fix_trace['taken_back']} cells, "
          f"{fix_trace['taken_back_probed']} of them truly probed by then; filed anew "
          f"{fix_trace['filed_anew']}, {fix_trace['filed_anew_probed']} of them truly probed; "
          f"the record filed {fix_trace['filed']} cells as it went, {fix_trace['filed_unprobed']}"
          f" of them not truly probed by then")
    if filing_report is not None:
        print("believed covered and not truly probed, with what filed them:")
        print("\n".join(filing_report()))
    cells = [(int(r), int(c)) for r, c in zip(*np.nonzero(missed), strict=True)]
    print(f"missed cells: {cells[:40]}{' ...' if len(cells) > 40 else ''}")
    if a.map:
        for r in range(rows - 1, -1, -1):  # top row first: '#' obstacle, 'x' truly unprobed,
            print("  " + "".join(  # 'o' probed but no reading filed there
                "#" if sim.wall.blocked[r, c] else "x" if planned[r, c] and not probed[r, c]
                else "o" if planned[r, c] and not believed[r, c] else "."
                for c in range(cols)))
    measured = np.isfinite(model.thickness)
    true_thin = (sim.wall.thickness < 8.0) & ~sim.wall.blocked
    print(f"true thin cells {int(true_thin.sum())}, of them measured thin "
          f"{int((true_thin & measured & (model.thickness < 8.0)).sum())}")


if __name__ == "__main__":
    main()
