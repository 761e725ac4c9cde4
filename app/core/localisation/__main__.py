"""Laser mapping on a recorded CARMEN log from the command line.

    python -m app.core.localisation carmen LOG --out POSES.tsv [--map OUT.yaml]
        [--backend graph|ekf] [--no-loop-closure] [--no-final-pass]

Reads LOG (plain or .gz; FLASER lines give the scans and their raw odometry,
PARAM lines the laser's field of view) and writes one line per FLASER scan,
in order: ``timestamp x y θ`` (metres, radians, in the frame of the log's
first pose), the SLAM estimate after loop closure and a final pass that
matches every landmark again against the places it overlaps
(loop_closure.py) and against whole earlier regions of the map
(long_range.py). ``--map`` also writes the occupancy grid as a ROS
map_server YAML + PGM. Bad lines (truncated, NaN, a negative range) are
reported on standard error with their line numbers and skipped. Exit 2 with
a one-line message when the log cannot be read or holds no usable scan.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from .carmen import read_log
from .map_io import save_map
from .mapping import MappingConfig
from .slam import landmark_grid, log_odometry, run_mapping, scan_points


def carmen(args: argparse.Namespace) -> int:
    path = Path(args.log)
    try:
        log = read_log(path)
    except OSError as e:
        print(f"error: cannot read {path}: {e}", file=sys.stderr)
        return 2
    for line_no, reason in log.bad_lines:
        print(f"{path}:{line_no}: skipped: {reason}", file=sys.stderr)
    if not log.scans:
        print(f"error: {path}: no usable FLASER line", file=sys.stderr)
        return 2
    cfg = MappingConfig(loop_closure=not args.no_loop_closure, backend=args.backend,
                        final_pass=not args.no_final_pass)
    poses, mapper = run_mapping(scan_points(log), log_odometry(log), cfg)
    out = Path(args.out)
    with out.open("w", encoding="utf-8") as f:
        for scan, (x, y, th) in zip(log.scans, poses, strict=True):
            f.write(f"{scan.timestamp:.6f}\t{x:.4f}\t{y:.4f}\t{th:.5f}\n")
    if args.map:
        save_map(landmark_grid(mapper, args.resolution), args.map)
    print(f"{len(log.scans)} scans, {len(log.bad_lines)} bad lines skipped, "
          f"{len(mapper.landmarks)} landmarks, {mapper.loop_closures} loop closures, "
          f"{mapper.final_closures} final-pass edges -> {out}",
          file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m app.core.localisation", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("carmen", help="map a CARMEN log, write the poses (and the map)")
    p.add_argument("log")
    p.add_argument("--out", required=True, help="poses, one 'timestamp x y θ' line per scan")
    p.add_argument("--map", help="also write the occupancy grid (ROS map_server .yaml)")
    p.add_argument("--resolution", type=float, default=0.05, help="map cell size, metres")
    p.add_argument("--no-loop-closure", action="store_true")
    p.add_argument("--no-final-pass", action="store_true",
                   help="skip the final pass that matches every landmark again "
                        "(and the long-range ties)")
    p.add_argument("--backend", choices=["graph", "ekf"], default="graph",
                   help="landmark poses by a pose graph (default) or seed 002's landmark EKF")
    p.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.ERROR,
                        format="%(levelname)s %(name)s: %(message)s")
    return carmen(args)


if __name__ == "__main__":
    sys.exit(main())
