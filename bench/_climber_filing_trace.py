"""A trace of what files each cell in the relay executor's record, against the
simulator's truth (for bench/climber_link_bench.py ``--filing-log``; the robot never
reads it): every filing as the record goes (the believed and the true probe, the
probe's σ_x, the route's index and whether in the sweep), every x fix (the correction,
σ, the cells it kept, filed anew or took back that the probe had not truly read), and
every fix of any kind that moved the probe's believed x (seam either way, rim, contact),
and every filter update that moved it 3 mm or more (named by its caller), as lines of
JSON; each line with the belief's x error at the probe and at the axle, its heading
error, the filter's σ of both, and how far the relay's estimate lags the board's clock.
At the end, the events of each cell believed covered and never truly probed."""

from __future__ import annotations

import json
import math
import sys

from sim_robot.climber.sure_lanes import probe_sigma_x


def trace_filing(sim, path: str):
    """Wrap the executor's record and the relay's fixes; returns a function that writes
    the cells believed and not truly probed, with their events, at the end."""
    relay, ins, odom = sim.relay, sim.relay.inspection, sim.relay.odom
    out = open(path, "w", encoding="utf-8")  # noqa: SIM115 (open for the run's length)
    by_cell: dict[tuple[int, int], list[dict]] = {}
    lead = sim.body.p.length_m / 2
    circ = sim.wall.circ_m

    def true_probe() -> tuple[float, float]:
        b = sim.body.s
        return ((b.x_m + lead * math.cos(b.theta_rad)) % circ,
                b.y_m + lead * math.sin(b.theta_rad))

    def believed_probe() -> tuple[float, float]:
        return ins.probe_point(odom.ekf.pose)

    def put(rec: dict, cells=()) -> None:
        out.write(json.dumps(rec) + "\n")
        out.flush()
        for c in cells:
            by_cell.setdefault(tuple(c), []).append(rec)

    def base(kind: str) -> dict:
        bx, by = believed_probe()
        tx, ty = true_probe()
        ex = (bx - tx + circ / 2) % circ - circ / 2
        (ax, _, ath), b = odom.ekf.pose, sim.body.s
        lag = sim.model.t_s - (odom.t_s or 0.0)
        axle_err = (ax - b.x_m + circ / 2) % circ - circ / 2
        return {"lag": round(lag, 3), "axle_err_x": round(axle_err, 4),
                "th": round(ath, 3), "th_err": round(
                    (ath - b.theta_rad + math.pi) % (2 * math.pi) - math.pi, 4),
                "sth": round(math.sqrt(max(0.0, odom.ekf.covariance[2, 2])), 4),
                "t": round(relay.sim_time(), 2), "kind": kind, "index": ins.index,
                "sweep": ins.index < ins.planned, "believed": [round(bx, 3), round(by, 3)],
                "true": [round(tx, 3), round(ty, 3)], "err_x": round(ex, 3),
                "sx": round(probe_sigma_x(odom.ekf.covariance, odom.ekf.pose[2], lead), 4)}

    filed = ins.lanes.filed

    def lane_filed(cell, x_m, *args) -> None:
        rec = base("filed")
        rec.update(cell=list(cell), x_m=round(x_m, 3), probed=bool(sim.model.probed[cell]))
        put(rec, [cell])
        filed(cell, x_m, *args)

    ins.lanes.filed = lane_filed
    fixed = ins.x_fixed

    def x_fixed(dx_m=0.0, sigma_m=0.0) -> None:
        before = ins.covered.copy()
        since = {c for c, _ in ins.lanes.since}
        samples, dist = ins.lanes.samples, ins.lanes._dist
        fixed(dx_m, sigma_m)
        probed = sim.model.probed
        kept = [c for c in since if ins.covered[c] and not probed[c]]
        back = [c for c in since if not ins.covered[c]]
        anew = [(int(r), int(c)) for r, c in zip(*((ins.covered & ~before).nonzero()),
                                                  strict=True)]
        rec = base("x_fix")
        rec.update(dx=round(dx_m, 4), sigma=round(sigma_m, 4), since=len(since),
                   samples=samples, dist=round(dist, 2), kept_unprobed=sorted(kept),
                   back=len(back), anew=anew, anew_unprobed=[c for c in anew
                                                             if not probed[c]])
        put(rec, kept + [c for c in anew if not probed[c]])

    ins.x_fixed = x_fixed

    def moved(kind: str, call):
        def wrapped(*args, **kw):
            bx0, by0 = believed_probe()
            got = call(*args, **kw)
            bx1, by1 = believed_probe()
            dx = (bx1 - bx0 + circ / 2) % circ - circ / 2
            if abs(dx) >= 0.003 or abs(by1 - by0) >= 0.01:
                rec = base(kind)
                rec.update(dx=round(dx, 4), dy=round(by1 - by0, 4),
                           since=len(ins.lanes.since))
                if kind.startswith("seam"):
                    rec["horizontal"] = bool(args[1])
                put(rec)
            return got
        return wrapped

    ekf = odom.ekf
    update = ekf.update

    def ekf_update(*args, **kw):  # every update that moves the probe's believed x 3 mm
        bx0, by0 = believed_probe()
        got = update(*args, **kw)
        bx1, by1 = believed_probe()
        dx = (bx1 - bx0 + circ / 2) % circ - circ / 2
        if abs(dx) >= 0.003:
            rec = base("update")
            rec.update(dx=round(dx, 4), dy=round(by1 - by0, 4), since=len(ins.lanes.since),
                       by=sys._getframe(1).f_code.co_name)
            put(rec)
        return got

    ekf.update = ekf_update
    odom.seam_seen = moved("seam", odom.seam_seen)
    odom.rim_seen = moved("rim", odom.rim_seen)
    relay._contact_fix = moved("contact", relay._contact_fix)

    def report() -> list[str]:
        lines = []
        bad = ins.covered & ~sim.model.probed
        for r, c in zip(*bad.nonzero(), strict=True):
            ev = by_cell.get((int(r), int(c)), [])
            lines.append(f"  ({r}, {c}): " + "; ".join(
                f"{e['kind']} t={e['t']} idx={e['index']} sweep={e['sweep']} "
                f"err_x={e['err_x']} sx={e['sx']}" + (f" dx={e['dx']}" if "dx" in e else "")
                for e in ev))
        out.close()
        return lines

    return report
