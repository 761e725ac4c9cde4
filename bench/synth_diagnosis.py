"""Where the laser mapper errs on a drawn log of bench/synth_carmen.py: the
online steps by kind of place, the online estimate before the final pass,
and every loop edge against the drawn truth (issue 13).

    PYTHONPATH=$PWD python bench/synth_diagnosis.py station --draws 0,1,2
    PYTHONPATH=$PWD python bench/synth_diagnosis.py maze --draws 0 --held-out-seen
    PYTHONPATH=$PWD python bench/synth_diagnosis.py station --method full-scale

``--method``: a configuration of bench/localisation_bench.py's methods
("full", the command line's, by default; e.g. "full-scale", the distance
scale learnt; "full-faces", the references knowing which way each wall
faces; "full-faces-icpfinal", that with the final pass matching by ICP on
such references; "full-facegrid-ties-only", the final pass's and the ties'
submap grids knowing which way each wall faces, face_grid.py), to see
whether an existing option would mend a failure.

The log written by bench/synth_carmen.py (``--out``, /tmp/synth_carmen) is
read and run as the command line runs it (MappingConfig with the final pass), with
the graph kept: each loop edge's measured pose z is compared with the
drawn relative pose of its two scans; an edge off by more than 0.2 m or 1°
is counted as wrong. Edges found while driving ("online") and those the
final pass and the long-range ties added ("final") are counted apart, and
the wrong ones are listed with the path they span and where they lie.
Then the graph is solved again without the wrong edges (an oracle): if that
mends the map, wrong edges broke it; if not, the steps' own errors did.
A held-out log is refused unless ``--held-out-seen`` says that its once-
only figures have been taken (it is development data from then on).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.localisation.carmen import read_log  # noqa: E402
from app.core.localisation.evaluate import ate_m, rpe  # noqa: E402
from app.core.localisation.mapping import LaserMapper  # noqa: E402
from app.core.localisation.pose_graph import solve_pose_graph  # noqa: E402
from app.core.localisation.se2 import relative, wrap  # noqa: E402
from app.core.localisation.slam import log_odometry, scan_points  # noqa: E402
from bench.localisation_bench import method_config  # noqa: E402
from bench.synth_carmen import SPECS, draw, make_world  # noqa: E402
from bench.synth_scoring import place_kinds, step_errors  # noqa: E402


def run(spec, d: int, out_dir: Path, method: str = "full") -> None:
    drawn = draw(spec, make_world(spec))  # for the kinds of place only
    kinds, _ = place_kinds(drawn.true_ranges, drawn.angles)
    log = read_log(out_dir / f"{spec.name}-d{d}.log")
    ref = np.loadtxt(out_dir / f"{spec.name}-d{d}.ref.tsv", ndmin=2)
    odo, pts = log_odometry(log), scan_points(log)
    mapper = LaserMapper(method_config(method))
    online = []
    for o, p in zip(odo, pts, strict=True):
        online.append(np.array(mapper.add_scan(o, p), float))
    n_online = len(mapper.edges)
    before = np.array(mapper.poses)
    est = mapper.finish()
    path = np.r_[0.0, np.cumsum(np.hypot(*np.diff(ref[:, :2], axis=0).T))]
    r1, r10 = rpe(est, ref, 1.0), rpe(est, ref, 10.0)
    print(f"\n{spec.name} draw {d}, {method}: ATE {ate_m(est, ref):.3f} m (before the final pass "
          f"{ate_m(before, ref):.3f} m; odometry {ate_m(odo, ref):.3f} m), RPE 1 m "
          f"{100 * r1.trans_m:.1f} cm / {r1.rot_deg:.2f} deg, RPE 10 m "
          f"{100 * r10.trans_m:.1f} cm / {r10.rot_deg:.2f} deg; steps dead reckoned "
          f"{mapper.icp_failures}, partial fits fused {mapper.partial_matches}, "
          f"rejected {mapper.match_rejected}")
    step_errors(np.array(online), odo, ref, kinds)
    wrong, errs = [], {"online": [], "final": []}
    for idx, e in enumerate(mapper.edges):
        if not e.loop:
            continue
        t = relative(ref[e.i], ref[e.j])
        et = math.hypot(*(e.z[:2] - t[:2]))
        er = abs(math.degrees(float(wrap(e.z[2] - t[2]))))
        src = "online" if idx < n_online else "final"
        errs[src].append((et, er))
        if et > 0.2 or er > 1.0:
            wrong.append((idx, src, e.i, e.j, et, er))
    for src in ("online", "final"):
        ids = [k for k, e in enumerate(mapper.edges)
               if e.loop and (k < n_online) == (src == "online")]
        bad = [w for w in wrong if w[1] == src]
        a = np.array(errs[src]).reshape(-1, 2)
        hist = np.histogram(100 * a[:, 0], [0, 5, 10, 20, 1e9])[0]
        print(f"      {src} loop edges: {len(ids)}, wrong (> 0.2 m or 1 deg): {len(bad)}; "
              f"off by 0-5, 5-10, 10-20, over 20 cm: {', '.join(map(str, hist))}; "
              f"heading over 0.5 deg: {int(np.sum(a[:, 1] > 0.5))}")
        for _, _, i, j, et, er in sorted(bad, key=lambda w: -w[4])[:6]:
            print(f"        scans {i} ({path[i]:.0f} m, {kinds[i]}) - {j} ({path[j]:.0f} m, "
                  f"{kinds[j]}): {100 * et:.0f} cm / {er:.2f} deg off; the two poses "
                  f"{math.hypot(*(ref[i, :2] - ref[j, :2])):.1f} m apart")
    if wrong:
        drop = {w[0] for w in wrong}
        kept = [e for k, e in enumerate(mapper.edges) if k not in drop]
        fixed = solve_pose_graph(np.array(mapper.poses), kept)
        print(f"      oracle, wrong edges dropped and solved again: ATE "
              f"{ate_m(fixed, ref):.3f} m, RPE 10 m {100 * rpe(fixed, ref, 10.0).trans_m:.1f} cm")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log")
    ap.add_argument("--draws", default="0")
    ap.add_argument("--held-out-seen", action="store_true")
    ap.add_argument("--method", default="full", help="a localisation_bench.py method")
    ap.add_argument("--out", default="/tmp/synth_carmen", help="where synth_carmen.py wrote it")
    args = ap.parse_args()
    spec = next(s for s in SPECS if s.name == args.log)
    if spec.held_out and not args.held_out_seen:
        print("a held-out log: run bench/synth_carmen.py --held-out once first",
              file=sys.stderr)
        return 2
    for d in (int(x) for x in args.draws.split(",")):
        run(spec, d, Path(args.out), args.method)
    return 0


if __name__ == "__main__":
    sys.exit(main())
